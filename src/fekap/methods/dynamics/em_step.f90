!> An energy-momentum step of the dynamics stepper: Newton
!> (fekap_stepping_newton's newton_solve, a fresh factor every iteration) on
!> the step's equations and band LU of fekap_dynamics_energy_momentum, from
!> the accepted state to the step's end.
module fekap_dynamics_em_step
   use fekap_kinds, only: dp
   use fekap_error, only: error_type
   use fekap_fem_linear_system, only: residual_norm
   use fekap_stepping_newton, only: newton_system_type, newton_report_type, newton_solve, always_refactor_type
   use fekap_dynamics_dynamic_system, only: external_forces
   use fekap_dynamics_energy_momentum, only: em_dissipation, assemble_em, factor_em, solve_em, em_free_velocities, &
      & em_increments
   use fekap_dynamics_dynamic_data, only: dynamic_data_type, drive_motion, hold_fixed
   use fekap_dynamics_step_contract, only: step_contract, newton_failure, singular_matrix
   implicit none
   private

   public :: em_newton

   !> An energy-momentum step's equations for newton_solve: the stepper
   !> (associated for one solve), the step's length and strain dissipation.
   type, extends(newton_system_type) :: em_newton_system_type
      class(dynamic_data_type), pointer :: s => null()
      real(dp) :: h = 0, chi = 0
   contains
      procedure :: assemble => em_assemble
      procedure :: factor => em_factor
      procedure :: correct => em_correct
   end type em_newton_system_type

contains

   !> Newton on a step of the energy-momentum integrator
   !> (fekap_dynamics_energy_momentum) from the accepted state to t_new
   !> (newton_solve on em_system_type, a fresh factor every iteration): the
   !> iterate into qt, vt (v1 = 2 (q1 - q0)/h - v0 on the free dofs) and acct
   !> (the step's mean acceleration (v1 - v0)/h; the drives' second rate on
   !> theirs), the residual (the step's reactions) into system%r. The
   !> predictor is q0 + h v0 + h^2/2 acc0.
   subroutine em_newton(self, t_new, report, error)
      class(dynamic_data_type), target, intent(inout) :: self
      real(dp), intent(in) :: t_new
      type(newton_report_type), intent(out) :: report
      type(error_type), allocatable, intent(out) :: error
      type(em_newton_system_type) :: newton
      type(always_refactor_type) :: full
      real(dp) :: h
      associate (state => self%state, mesh => self%mesh, dyn => self%dynamics)
         h = t_new - state%t
         newton%h = h
         newton%chi = em_dissipation(self%model%analysis%rho_inf)
         newton%s => self
         self%qt = state%q + h*state%v + 0.5_dp*h**2*state%acc
         call hold_fixed(self)
         call drive_motion(self, t_new, self%qt, self%vt, self%acct)
         call em_velocities(self, h)
         call external_forces(dyn, mesh, t_new, self%gt)
         call newton_solve(newton, step_contract(self), full, report, error)
         if (allocated(error)) then
            call newton_failure(report, 'dp/dq + C/h + 2 M/h^2', error)
            return
         end if
         self%acct = (self%vt - state%v)/h
         ! The step's mean rates z/h, for the next step's massless dofs.
         self%at = self%zt/h
         call drive_motion(self, t_new, self%qt, self%vt, self%acct)
      end associate
   end subroutine em_newton

   !> The energy-momentum step's residual at the iterate (with `matrix` its
   !> iteration matrix), gathered for a correction, and its norm.
   subroutine em_assemble(self, matrix, norm)
      class(em_newton_system_type), intent(inout) :: self
      logical, intent(in) :: matrix
      real(dp), intent(out) :: norm
      associate (s => self%s)
         call assemble_em(s%em, s%dynamics, s%mesh, s%state%q, s%qt, s%state%v, s%vt, s%state%g, s%gt, s%zt, s%dzt, &
            & self%h, self%chi, s%state%seg, s%system%r, tangent=matrix)
         if (matrix) then
            s%counts%tangent_assemblies = s%counts%tangent_assemblies + 1
         else
            s%counts%residual_assemblies = s%counts%residual_assemblies + 1
         end if
         norm = residual_norm(s%system, s%mesh)
      end associate
   end subroutine em_assemble

   subroutine em_factor(self, info)
      class(em_newton_system_type), intent(inout) :: self
      integer, intent(out) :: info
      call factor_em(self%s%em, info)
   end subroutine em_factor

   !> The correction of q with the factor, and the velocities of the new iterate.
   subroutine em_correct(self, length, error)
      class(em_newton_system_type), intent(inout) :: self
      real(dp), intent(out) :: length
      type(error_type), allocatable, intent(out) :: error
      integer :: info, k, d
      associate (s => self%s)
         length = 0
         call solve_em(s%em, s%system%rhs(:, 1), info)
         if (info /= 0) then
            call singular_matrix(error, 'dp/dq + C/h + 2 M/h^2', info)
            return
         end if
         do k = 1, s%mesh%nfree
            d = s%mesh%eq_dof(k)
            length = max(length, abs(s%system%rhs(k, 1))*s%dof_length(d))
            s%qt(d) = s%qt(d) + s%system%rhs(k, 1)
         end do
         call em_velocities(s, self%h)
         s%counts%iterations = s%counts%iterations + 1
      end associate
   end subroutine em_correct

   !> The iterate's increments zt, dzt (once per iterate: assemble_em, the
   !> step's work and the next step's mean rates use them) and its free dofs'
   !> velocities (em_free_velocities).
   subroutine em_velocities(self, h)
      class(dynamic_data_type), intent(inout) :: self
      real(dp), intent(in) :: h
      call em_increments(self%mesh, self%state%q, self%qt, self%zt, self%dzt)
      call em_free_velocities(self%mesh, self%massless, h, self%h_prev, self%state%v, self%state%a, self%zt, self%vt)
   end subroutine em_velocities

end module fekap_dynamics_em_step
