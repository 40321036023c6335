!> A generalized-alpha step of the dynamics stepper: Newton
!> (fekap_stepping_newton's newton_solve, with the stepper's kept factor) on
!> the band iteration matrix K + c1 C + c2 M from the accepted state to the
!> step's end (fekap_dynamics_generalized_alpha's predictor and update).
module fekap_dynamics_alpha_step
   use fekap_kinds, only: dp
   use fekap_error, only: error_type
   use fekap_fem_linear_system, only: factor_system, residual_norm, newton_correction
   use fekap_stepping_newton, only: newton_system_type, newton_report_type, newton_solve
   use fekap_dynamics_generalized_alpha, only: alpha_coefficients_type, new_alpha_coefficients, alpha_predict, &
      & alpha_update
   use fekap_dynamics_dynamic_system, only: external_forces, assemble_dynamics
   use fekap_dynamics_dynamic_data, only: dynamic_data_type, drive_motion, hold_fixed
   use fekap_dynamics_step_contract, only: step_contract, newton_failure
   implicit none
   private

   public :: alpha_newton

   !> A generalized-alpha step's equations for newton_solve: the stepper
   !> (its iterate, system and counts; associated for one solve) and the
   !> step's coefficients.
   type, extends(newton_system_type) :: alpha_system_type
      class(dynamic_data_type), pointer :: s => null()
      type(alpha_coefficients_type) :: c
      real(dp) :: t_new = 0
   contains
      procedure :: assemble => alpha_assemble
      procedure :: factor => alpha_factor
      procedure :: correct => alpha_correct
   end type alpha_system_type

contains

   !> Newton on a step of generalized-alpha from the accepted state to
   !> t_new (fekap_stepping_newton's newton_solve on alpha_system_type,
   !> with the stepper's kept factor): the iterate into qt, vt, acct, at and
   !> the residual (the reactions) into system%r.
   subroutine alpha_newton(self, t_new, report, error)
      class(dynamic_data_type), target, intent(inout) :: self
      real(dp), intent(in) :: t_new
      type(newton_report_type), intent(out) :: report
      type(error_type), allocatable, intent(out) :: error
      type(alpha_system_type) :: newton
      associate (state => self%state, mesh => self%mesh, dyn => self%dynamics)
         newton%c = new_alpha_coefficients(self%model%analysis%rho_inf, t_new - state%t)
         newton%t_new = t_new
         newton%s => self
         call alpha_predict(newton%c, state%q, state%v, state%acc, state%a, self%qt, self%vt, self%acct, self%at)
         call hold_fixed(self)
         call drive_motion(self, t_new, self%qt, self%vt, self%acct)
         call external_forces(dyn, mesh, t_new, self%gt)
         call newton_solve(newton, step_contract(self), self%reuse, report, error)
         if (allocated(error)) call newton_failure(report, 'K + c1 C + c2 M', error)
      end associate
   end subroutine alpha_newton

   !> The residual R at generalized-alpha's iterate (with `matrix` the
   !> iteration matrix K + c1 C + c2 M), gathered for a correction, and its norm.
   subroutine alpha_assemble(self, matrix, norm)
      class(alpha_system_type), intent(inout) :: self
      logical, intent(in) :: matrix
      real(dp), intent(out) :: norm
      associate (s => self%s)
         if (matrix) then
            call assemble_dynamics(s%dynamics, s%system, s%mesh, s%qt, s%vt, s%acct, self%t_new, s%state%seg, &
               & s%counts, self%c%c1, self%c%c2)
         else
            call assemble_dynamics(s%dynamics, s%system, s%mesh, s%qt, s%vt, s%acct, self%t_new, s%state%seg, s%counts)
         end if
         norm = residual_norm(s%system, s%mesh)
      end associate
   end subroutine alpha_assemble

   subroutine alpha_factor(self, info)
      class(alpha_system_type), intent(inout) :: self
      integer, intent(out) :: info
      call factor_system(self%s%system, info, self%s%counts)
   end subroutine alpha_factor

   !> The correction of q with the factor in hand, and generalized-alpha's
   !> update of the rates with it.
   subroutine alpha_correct(self, length, error)
      class(alpha_system_type), intent(inout) :: self
      real(dp), intent(out) :: length
      type(error_type), allocatable, intent(out) :: error
      integer :: k, d
      associate (s => self%s)
         call newton_correction(s%system, s%mesh, s%dof_length, length, s%counts)
         do k = 1, s%mesh%nfree
            d = s%mesh%eq_dof(k)
            call alpha_update(self%c, s%system%rhs(k, 1), s%qt(d), s%vt(d), s%acct(d), s%at(d))
         end do
         s%counts%iterations = s%counts%iterations + 1
      end associate
   end subroutine alpha_correct

end module fekap_dynamics_alpha_step
