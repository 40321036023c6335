!> The generalized-alpha integrator of Chung & Hulbert (A time integration
!> algorithm for structural dynamics with improved numerical dissipation: the
!> generalized-alpha method, J. Appl. Mech. 60, 1993), in the form of Arnold &
!> Bruls (Convergence of the generalized-alpha scheme for constrained
!> mechanical systems, Multibody Syst. Dyn. 18, 2007) for nonlinear equations
!> of motion M qdd + C qd + f(q) = g(t): the equations hold at t_n+1, and an
!> acceleration-like variable a carries the averaging of Chung & Hulbert,
!>   (1 - am) a_n+1 + am a_n = (1 - af) qdd_n+1 + af qdd_n,
!>   q_n+1 = q_n + h qd_n + h^2 (1/2 - beta) a_n + h^2 beta a_n+1,     CH (2a)
!>   qd_n+1 = qd_n + h (1 - gamma) a_n + h gamma a_n+1,                 CH (2b)
!> with am, af from rho_inf (CH (25)), gamma = 1/2 - am + af (CH (17)) and
!> beta = (1 - am + af)^2 / 4 (CH (20)): second order, unconditionally stable,
!> high frequencies damped to rho_inf. For linear equations the scheme is the
!> one of CH's (3); rho_inf = 1 gives am = af = 1/2, gamma = 1/2, beta = 1/4,
!> the trapezoidal rule.
module fekap_dynamics_generalized_alpha
   use fekap_kinds, only: dp
   implicit none
   private

   public :: alpha_coefficients_type, new_alpha_coefficients, alpha_predict, alpha_update

   !> The parameters of a step of length h and the derivatives of qd_n+1 and
   !> qdd_n+1 by q_n+1: the iteration matrix is K + c1 C + c2 M.
   type :: alpha_coefficients_type
      real(dp) :: rho_inf = 0.8_dp
      real(dp) :: am = 0, af = 0, beta = 0.25_dp, gamma = 0.5_dp
      real(dp) :: h = 0
      !> d qd_n+1 / d q_n+1 = gamma / (beta h) and d qdd_n+1 / d q_n+1 = (1 - am) / ((1 - af) beta h^2).
      real(dp) :: c1 = 0, c2 = 0
   end type alpha_coefficients_type

contains

   !> The coefficients for rho_inf in [0, 1] and a step h > 0.
   pure function new_alpha_coefficients(rho_inf, h) result(self)
      real(dp), intent(in) :: rho_inf, h
      type(alpha_coefficients_type) :: self
      self%rho_inf = rho_inf
      self%am = (2*rho_inf - 1)/(rho_inf + 1)                  ! CH (25)
      self%af = rho_inf/(rho_inf + 1)
      self%gamma = 0.5_dp - self%am + self%af                  ! CH (17)
      self%beta = 0.25_dp*(1 - self%am + self%af)**2           ! CH (20)
      self%h = h
      self%c1 = self%gamma/(self%beta*h)
      self%c2 = (1 - self%am)/((1 - self%af)*self%beta*h**2)
   end function new_alpha_coefficients

   !> The predictor of a step: q, qd, qdd and a at n+1 from n, with the
   !> acceleration kept, qdd_n+1 = qdd_n, and a_n+1 from CH's averaging
   !> (the relation above). On a smooth motion its first Newton correction
   !> is of order h^3 (the change of qdd over the step, times beta h^2),
   !> where qdd_n+1 = 0 starts h^2 beta qdd away; either converges to the
   !> same step (the predictor only starts Newton).
   pure subroutine alpha_predict(self, q0, v0, acc0, a0, q, v, acc, a)
      type(alpha_coefficients_type), intent(in) :: self
      real(dp), intent(in) :: q0(:), v0(:), acc0(:), a0(:)
      real(dp), intent(out) :: q(:), v(:), acc(:), a(:)
      acc = acc0
      a = (acc0 - self%am*a0)/(1 - self%am)
      q = q0 + self%h*v0 + self%h**2*((0.5_dp - self%beta)*a0 + self%beta*a)
      v = v0 + self%h*((1 - self%gamma)*a0 + self%gamma*a)
   end subroutine alpha_predict

   !> A Newton correction dq of q_n+1 and what it changes: qd by c1 dq, qdd
   !> by c2 dq, a by dq / (beta h^2).
   elemental subroutine alpha_update(self, dq, q, v, acc, a)
      type(alpha_coefficients_type), intent(in) :: self
      real(dp), intent(in) :: dq
      real(dp), intent(inout) :: q, v, acc, a
      q = q + dq
      v = v + self%c1*dq
      acc = acc + self%c2*dq
      a = a + dq/(self%beta*self%h**2)
   end subroutine alpha_update

end module fekap_dynamics_generalized_alpha
