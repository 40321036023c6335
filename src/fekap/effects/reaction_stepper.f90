!> The finite element method with the reactions of a kinetostatic or a
!> static analysis: each step is the FEM's, then the reactions in
!> fekap_model_reactions' rows. The FEM itself is untouched: a kinematics
!> run does not pass here.
!>
!> Kinetostatics: the FEM gives the motion (positions, velocities,
!> accelerations); the loads of the masses and gravity along it, the
!> elastic deflection they cause (solved with the FEM's factor of the
!> material tangent at the accepted configuration, the one its rates used)
!> and the reactions follow (fekap_effects_kinetostatics). The external loads
!> (LOADs) act in kinetostatics' loads, not on the motion: the stepper takes
!> them from the FEM's mesh, whose kinematics then runs unloaded.
!>
!> Statics: the FEM solves the loaded equilibrium at each time on its loaded
!> path; the reactions are those of that equilibrium (fekap_effects_statics).
module fekap_effects_reaction_stepper
   use fekap_kinds, only: dp
   use fekap_error, only: error_type
   use fekap_model, only: effects_statics
   use fekap_model_results, only: step_result_type
   use fekap_model_reactions, only: reaction_count
   use fekap_solver_stepper, only: stepper_type
   use fekap_solver_fem, only: fem_stepper_type
   use fekap_assembly_loads, only: load_set_type
   use fekap_effects_kinetostatics, only: kinetostatics_type, new_kinetostatics, kinetostatic_loads, &
      & kinetostatic_reactions
   use fekap_effects_statics, only: static_reactions
   implicit none
   private

   public :: reaction_stepper_type, new_reaction_stepper

   type, extends(stepper_type) :: reaction_stepper_type
      type(fem_stepper_type) :: fem
      !> Whether the analysis is statics (else kinetostatics).
      logical :: statics = .false.
      !> The masses and the reaction rows.
      type(kinetostatics_type) :: kinetostatics
      !> Work over the dofs: the loads (statics: the residual), the deflection
      !> (statics: zero accelerations), the external loads; over the
      !> equations: the right-hand side.
      real(dp), allocatable :: f(:), u(:), external(:), rhs(:, :)
      !> Kinetostatics: the external loads (LOADs), which the FEM's motion does not see.
      type(load_set_type) :: loads
   contains
      procedure :: start => reaction_start
      procedure :: advance => reaction_advance
      procedure :: plan_text => reaction_plan_text
   end type reaction_stepper_type

contains

   !> Kinetostatics, or statics if `effects` is effects_statics, on a new FEM
   !> stepper (new_fem_stepper) of the model.
   subroutine new_reaction_stepper(self, fem, effects)
      type(reaction_stepper_type), intent(out) :: self
      type(fem_stepper_type), intent(in) :: fem
      integer, intent(in) :: effects
      self%fem = fem
      self%statics = effects == effects_statics
      if (.not. self%statics) then
         ! The motion is the kinematic one: the loads leave the FEM for the reactions.
         self%loads = self%fem%mesh%loads
         self%fem%mesh%loads%f = 0
         self%fem%loaded = .false.
      end if
      call new_kinetostatics(self%kinetostatics, fem%model, fem%mesh)
      allocate (self%f(self%fem%mesh%ndof), self%u(self%fem%mesh%ndof), self%external(self%fem%mesh%ndof), &
         & source=0.0_dp)
      allocate (self%rhs(self%fem%mesh%nfree, 1), source=0.0_dp)
   end subroutine new_reaction_stepper

   !> The FEM's plan lines.
   function reaction_plan_text(self) result(text)
      class(reaction_stepper_type), intent(in) :: self
      character(:), allocatable :: text
      text = self%fem%plan_text()
   end function reaction_plan_text

   subroutine reaction_start(self, result, error)
      class(reaction_stepper_type), intent(inout) :: self
      type(step_result_type), intent(inout) :: result
      type(error_type), allocatable, intent(out) :: error
      call self%fem%start(result, error)
      self%counts = self%fem%counts
      if (allocated(error)) return
      call add_reactions(self, result)
   end subroutine reaction_start

   subroutine reaction_advance(self, t, result, error)
      class(reaction_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      type(step_result_type), intent(inout) :: result
      type(error_type), allocatable, intent(out) :: error
      call self%fem%advance(t, result, error)
      self%counts = self%fem%counts
      if (allocated(error)) return
      call add_reactions(self, result)
   end subroutine reaction_advance

   !> The reactions of the accepted step. Kinetostatics needs its
   !> accelerations (the FEM then holds the factor of the tangent there).
   !> Values near the deck's limits could overflow: such a step gets empty
   !> reaction columns, never an Inf or NaN.
   subroutine add_reactions(self, result)
      type(reaction_stepper_type), intent(inout) :: self
      type(step_result_type), intent(inout) :: result
      if (.not. allocated(result%reactions)) allocate (result%reactions(3, reaction_count(self%fem%model)))
      if (self%statics) then
         ! u is zero throughout: the zero accelerations of the elements' own weights.
         call static_reactions(self%kinetostatics, self%fem%mesh, self%fem%state%q, self%fem%state%t, &
            & self%fem%state%seg, self%f, self%u, result%reactions)
      else
         result%has_reactions = self%fem%state%has_acceleration .and. self%fem%factor_current
         if (.not. result%has_reactions) return
         call kinetostatic_step(self, result)
      end if
      result%has_reactions = all(abs(result%reactions) <= huge(1.0_dp))
   end subroutine add_reactions

   !> Kinetostatics' loads along the motion, the deflection they cause and the reactions.
   subroutine kinetostatic_step(self, result)
      type(reaction_stepper_type), intent(inout) :: self
      type(step_result_type), intent(inout) :: result
      integer :: k
      associate (mesh => self%fem%mesh)
         call kinetostatic_loads(self%kinetostatics, mesh, self%fem%state%a, self%f)
         if (self%loads%is_loaded()) then
            call self%loads%at(self%fem%state%t, self%external)
            self%f = self%f + self%external
         end if
         do k = 1, mesh%nfree
            self%rhs(k, 1) = self%f(mesh%eq_dof(k))
         end do
         call self%fem%system%kff%solve(self%rhs)
         self%u = 0
         do k = 1, mesh%nfree
            self%u(mesh%eq_dof(k)) = self%rhs(k, 1)
         end do
         call kinetostatic_reactions(self%kinetostatics, mesh, self%fem%state%q, self%fem%state%seg, &
            & self%fem%state%a, self%f, self%u, result%reactions)
      end associate
   end subroutine kinetostatic_step

end module fekap_effects_reaction_stepper
