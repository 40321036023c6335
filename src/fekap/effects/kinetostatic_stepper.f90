!> The finite element method with kinetostatics: each step is the FEM's
!> (positions, velocities, accelerations), then the loads of the masses and
!> gravity along that motion, the elastic deflection they cause (solved with
!> the FEM's factor of the material tangent at the accepted configuration,
!> the one its rates used) and the reactions (fekap_effects_kinetostatics).
!> The FEM itself is untouched: a kinematics run does not pass here. The
!> external loads (LOADs) act in kinetostatics' loads, not on the motion: the
!> stepper takes them from the FEM's mesh, whose kinematics then runs unloaded.
module fekap_effects_kinetostatic_stepper
   use fekap_kinds, only: dp
   use fekap_error, only: error_type
   use fekap_model_results, only: step_result_type
   use fekap_solver_stepper, only: stepper_type
   use fekap_solver_fem, only: fem_stepper_type
   use fekap_effects_kinetostatics, only: kinetostatics_type, new_kinetostatics, kinetostatic_loads, &
      & kinetostatic_reactions
   use fekap_model_reactions, only: reaction_count
   use fekap_assembly_loads, only: load_set_type
   implicit none
   private

   public :: kinetostatic_stepper_type, new_kinetostatic_stepper

   type, extends(stepper_type) :: kinetostatic_stepper_type
      type(fem_stepper_type) :: fem
      type(kinetostatics_type) :: kinetostatics
      !> Work over the dofs: the loads and the deflection; over the equations: the right-hand side.
      real(dp), allocatable :: f(:), u(:), rhs(:, :), external(:)
      !> The external loads (LOADs), which the FEM's motion does not see.
      type(load_set_type) :: loads
   contains
      procedure :: start => kinetostatic_start
      procedure :: advance => kinetostatic_advance
      procedure :: plan_text => kinetostatic_plan_text
   end type kinetostatic_stepper_type

contains

   !> Kinetostatics on a new FEM stepper (new_fem_stepper) of the model.
   subroutine new_kinetostatic_stepper(self, fem)
      type(kinetostatic_stepper_type), intent(out) :: self
      type(fem_stepper_type), intent(in) :: fem
      self%fem = fem
      ! The motion is the kinematic one: the loads leave the FEM for the reactions.
      self%loads = self%fem%mesh%loads
      self%fem%mesh%loads%f = 0
      self%fem%loaded = .false.
      call new_kinetostatics(self%kinetostatics, fem%model, fem%mesh)
      allocate (self%f(self%fem%mesh%ndof), self%u(self%fem%mesh%ndof), self%external(self%fem%mesh%ndof), &
         & source=0.0_dp)
      allocate (self%rhs(self%fem%mesh%nfree, 1), source=0.0_dp)
   end subroutine new_kinetostatic_stepper

   !> The FEM's plan lines.
   function kinetostatic_plan_text(self) result(text)
      class(kinetostatic_stepper_type), intent(in) :: self
      character(:), allocatable :: text
      text = self%fem%plan_text()
   end function kinetostatic_plan_text

   subroutine kinetostatic_start(self, result, error)
      class(kinetostatic_stepper_type), intent(inout) :: self
      type(step_result_type), intent(inout) :: result
      type(error_type), allocatable, intent(out) :: error
      call self%fem%start(result, error)
      self%counts = self%fem%counts
      if (allocated(error)) return
      call add_reactions(self, result)
   end subroutine kinetostatic_start

   subroutine kinetostatic_advance(self, t, result, error)
      class(kinetostatic_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      type(step_result_type), intent(inout) :: result
      type(error_type), allocatable, intent(out) :: error
      call self%fem%advance(t, result, error)
      self%counts = self%fem%counts
      if (allocated(error)) return
      call add_reactions(self, result)
   end subroutine kinetostatic_advance

   !> The reactions of the accepted step, when its accelerations are known
   !> (the FEM then holds the factor of the tangent there).
   subroutine add_reactions(self, result)
      type(kinetostatic_stepper_type), intent(inout) :: self
      type(step_result_type), intent(inout) :: result
      integer :: k
      if (.not. allocated(result%reactions)) allocate (result%reactions(3, reaction_count(self%fem%model)))
      result%has_reactions = self%fem%state%has_acceleration .and. self%fem%factor_current
      if (.not. result%has_reactions) return
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
         ! Loads near the deck's limits on sections near theirs could overflow the
         ! deflection: such a step gets empty reaction columns, never an Inf or NaN.
         result%has_reactions = all(abs(result%reactions) <= huge(1.0_dp))
      end associate
   end subroutine add_reactions

end module fekap_effects_kinetostatic_stepper
