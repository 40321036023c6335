!> The local error estimate of a dynamics step and the step length that
!> keeps it at a tolerance: Zienkiewicz and Xie's estimate from the change
!> of the acceleration over the step, with each integrator's constant, and
!> the standard controller of adaptive steps.
!>
!> A Newmark-type update q1 = q0 + h v0 + h^2 ((1/2 - beta) a0 + beta a1)
!> with exact rates misses q(t0 + h) by (beta - 1/6) h^3 q''' + O(h^4)
!> (Zienkiewicz and Xie 1991), and h q''' ~ a1 - a0. Generalized-alpha's a is
!> the acceleration at t + (alpha_m - alpha_f) h (Chung-Hulbert (25) with
!> alpha_m, alpha_f as in fekap_dynamics_generalized_alpha: M a_{n+1-alpha_m}
!> balances the forces at t_{n+1-alpha_f}), which adds (alpha_m - alpha_f)/2
!> h^3 q''': the constant is beta - 1/6 + (alpha_m - alpha_f)/2, 1/12 for
!> rho_inf = 1 (the trapezoidal rule). The midpoint rule of energy-momentum,
!> q1 = q0 + h/2 (v0 + v1) with exact v1 = v0 + h a + h^2/2 q''', misses by
!> (1/4 - 1/6) h^3 q''' = h^3 q'''/12; its step's acceleration is the mean
!> (v1 - v0)/h, the acceleration at the step's middle, so consecutive means
!> lie (h_prev + h)/2 apart (h/2 from the start's own acceleration).
module fekap_dynamics_local_error
   use fekap_kinds, only: dp
   use fekap_dynamics_generalized_alpha, only: alpha_coefficients_type
   implicit none
   private

   public :: alpha_error_constant, alpha_error_scale, midpoint_error_scale, largest_local_error, adapted_step

   !> The controller: the new step is h safety (tol/e)^(1/3) (local error
   !> ~ h^3), but never more than grow_most nor less than shrink_most times h.
   real(dp), parameter, public :: step_safety = 0.9_dp, grow_most = 2.0_dp, shrink_most = 0.2_dp
   !> The least adaptive step, relative to the run's span T1 - T0: a step
   !> that must be shorter to meet the tolerance ends the run (an error).
   real(dp), parameter, public :: least_step = 1.0e-12_dp

contains

   !> Generalized-alpha's constant of h^3 q''' in the local error of q:
   !> |beta - 1/6 + (alpha_m - alpha_f)/2|.
   pure real(dp) function alpha_error_constant(c) result(k)
      type(alpha_coefficients_type), intent(in) :: c
      k = abs(c%beta - 1.0_dp/6 + 0.5_dp*(c%am - c%af))
   end function alpha_error_constant

   !> The factor of |a1 - a0| (generalized-alpha's acceleration variable at
   !> the step's ends) in the local error of a step of length h.
   pure real(dp) function alpha_error_scale(c, h) result(s)
      type(alpha_coefficients_type), intent(in) :: c
      real(dp), intent(in) :: h
      s = alpha_error_constant(c)*h**2
   end function alpha_error_scale

   !> The factor of |a1 - a0| (the mean accelerations of this step and of
   !> the last one, h_prev long; h_prev 0: a0 is the start's acceleration)
   !> in the midpoint rule's local error: h^3/12 q''' with q''' the
   !> difference quotient of means (h_prev + h)/2 apart.
   pure real(dp) function midpoint_error_scale(h, h_prev) result(s)
      real(dp), intent(in) :: h, h_prev
      s = h**3/(6*(h + h_prev))
   end function midpoint_error_scale

   !> The largest local error over the free dofs (eq_dof): scale |a1 - a0|
   !> times each dof's weight (the stepper's: 1 on translations, 0 on
   !> rotations), and the dof where it is (0 if no dof is free).
   pure subroutine largest_local_error(scale, a0, a1, weight, eq_dof, estimate, dof)
      real(dp), intent(in) :: scale
      real(dp), intent(in) :: a0(:), a1(:), weight(:)
      integer, intent(in) :: eq_dof(:)
      real(dp), intent(out) :: estimate
      integer, intent(out) :: dof
      integer :: k, d
      real(dp) :: e
      estimate = 0
      dof = 0
      do k = 1, size(eq_dof)
         d = eq_dof(k)
         e = abs(a1(d) - a0(d))*weight(d)
         if (e > estimate .or. dof == 0) then
            estimate = e
            dof = d
         end if
      end do
      estimate = scale*estimate
   end subroutine largest_local_error

   !> The step after one of length h with local error estimate e, for the
   !> tolerance tol: h safety (tol/e)^(1/3) within [shrink_most h, grow_most h].
   pure real(dp) function adapted_step(h, estimate, tol) result(h_new)
      real(dp), intent(in) :: h, estimate, tol
      real(dp) :: factor
      if (estimate*grow_most**3 <= tol*step_safety**3) then
         factor = grow_most
      else
         factor = min(grow_most, max(shrink_most, step_safety*(tol/estimate)**(1.0_dp/3)))
      end if
      h_new = h*factor
   end function adapted_step

end module fekap_dynamics_local_error
