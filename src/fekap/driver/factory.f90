!> The stepper of a deck: the one place that names the concrete steppers.
!> A new method or integrator is built here, from the deck's method and the
!> effects it asks for (docs/architecture.md, "To add ...").
module fekap_driver_factory
   use fekap_error, only: error_type, input_error
   use fekap_model, only: model_type, method_fem, method_cartesian, effects_kinetostatics, effects_statics, &
      & effects_dynamics
   use fekap_model_effects, only: check_effects_request, planned_effects
   use fekap_stepping_stepper, only: stepper_type
   use fekap_fem, only: fem_stepper_type, new_fem_stepper
   use fekap_fem_determinacy, only: check_determined
   use fekap_reactions_reaction_stepper, only: reaction_stepper_type, new_reaction_stepper
   use fekap_dynamics_free_motion, only: check_free_motion
   use fekap_dynamics_dynamic_stepper, only: dynamic_stepper_type, new_dynamic_stepper
   use fekap_spatial_stepper, only: spatial_stepper_type, new_spatial_stepper
   use fekap_classical, only: angles_stepper_type, new_angles_stepper, cartesian_stepper_type, &
      & new_cartesian_stepper
   implicit none
   private

   public :: settle_model, make_stepper

contains

   !> Check the effects the deck asks for against its method, and settle the
   !> defaults that depend on them: without a mesh line, nodes.csv holds the
   !> meshed links' interior points where their bending is the result
   !> (statics and dynamics).
   subroutine settle_model(model, error)
      type(model_type), intent(inout) :: model
      type(error_type), allocatable, intent(out) :: error
      call check_effects_request(model, error)
      if (allocated(error)) return
      if (.not. model%output%mesh_nodes_given) model%output%mesh_nodes = any(model%links%nelem > 1) .and. &
         & any(planned_effects(model) == [effects_statics, effects_dynamics])
   end subroutine settle_model

   !> The stepper of the deck's method and effects.
   subroutine make_stepper(model, stepper, error)
      type(model_type), intent(in) :: model
      class(stepper_type), allocatable, intent(out) :: stepper
      type(error_type), allocatable, intent(out) :: error
      type(fem_stepper_type), allocatable :: fem
      type(reaction_stepper_type), allocatable :: reactions
      type(dynamic_stepper_type), allocatable :: dynamic
      type(cartesian_stepper_type), allocatable :: cartesian
      type(angles_stepper_type), allocatable :: angles
      type(spatial_stepper_type), allocatable :: spatial
      integer :: effects
      effects = planned_effects(model)
      if (model%analysis%spatial) then
         ! A spatial deck (kinematics only): joints as double nodes, SE(3) beams (docs/spatial.md).
         if (model%analysis%method /= method_fem) then
            call input_error(error, model%file//': a spatial deck runs with the finite element method only: '// &
               & 'leave out --method and the ANALysis method line')
            return
         end if
         allocate (spatial)
         call new_spatial_stepper(spatial, model, error)
         if (allocated(error)) return
         call move_alloc(spatial, stepper)
         return
      end if
      select case (model%analysis%method)
      case (method_fem)
         allocate (fem)
         call new_fem_stepper(fem, model)
         ! Dynamics moves a free part by its mass (check_free_motion below);
         ! the other analyses need every motion held.
         if (effects /= effects_dynamics) then
            call check_determined(fem%mesh, model, error)
            if (allocated(error)) return
         end if
         if (any(effects == [effects_kinetostatics, effects_statics])) then
            allocate (reactions)
            call new_reaction_stepper(reactions, fem, effects)
            call move_alloc(reactions, stepper)
         else if (effects == effects_dynamics) then
            ! Bad input first: a free motion with neither mass nor stiffness.
            call check_free_motion(fem%mesh, model, fem%mesh%q0, model%analysis%t_start, fem%seg, error)
            if (allocated(error)) return
            allocate (dynamic)
            call new_dynamic_stepper(dynamic, model)
            call move_alloc(dynamic, stepper)
         else
            call move_alloc(fem, stepper)
         end if
      case (method_cartesian)
         allocate (cartesian)
         call new_cartesian_stepper(cartesian, model, error)
         if (allocated(error)) then
            error%message = model%file//': '//error%message
            return
         end if
         call move_alloc(cartesian, stepper)
      case default
         allocate (angles)
         call new_angles_stepper(angles, model, error)
         if (allocated(error)) then
            error%message = model%file//': '//error%message
            return
         end if
         call move_alloc(angles, stepper)
      end select
   end subroutine make_stepper

end module fekap_driver_factory
