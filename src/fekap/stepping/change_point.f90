!> Change points shared by the methods' steppers (the planar FEM's
!> fekap_fem_change_point and fekap_fem_fill, the spatial stepper): configurations where
!> the tangent loses rank (every bar of a parallelogram chain horizontal, the
!> double crank's collinear positions). A stepper detects them by the
!> condition estimate of the tangent at a step's predictor against the best
!> of the run's accepted configurations (change_verdict), solves the next
!> output time from the last regular state as one double step
!> (next_output_time), and fills the skipped row from its two regular
!> neighbours (hermite_fill, of fill_order) before correcting it onto the
!> mechanism with the tangent shifted by fill_shift; where the tangent at
!> the filled row is singular against the run's best (rates_drop) its rates
!> are left out. docs/hard-cases.md (Change points) has the measurements
!> behind the thresholds.
module fekap_stepping_change_point
   use fekap_kinds, only: dp
   implicit none
   private

   public :: change_verdict, response_trusted, hermite_fill, fill_order, next_output_time

   !> A tangent whose reciprocal condition number is below change_drop times
   !> the largest of the run's accepted configurations is near singular.
   !> The threshold lies in the wide gap that docs/hard-cases.md measured at
   !> the predictors between the steps landing on a change point and every
   !> other step (lambda_min of K goes like the square of the distance to the
   !> change point, so the gap is wide).
   real(dp), parameter, public :: change_drop = 1.0e-4_dp
   !> A filled row whose tangent's reciprocal condition number is below
   !> rates_drop times the run's best is singular: its rates are left out.
   !> Above it (a row near, not on, a change point) they are solved there.
   real(dp), parameter, public :: rates_drop = 1.0e-10_dp
   !> The branch-jump check trusts the drive response of a factor whose
   !> reciprocal condition number is at least response_drop times the run's
   !> best: the square of the 1e-3 that the study found on B, since lambda_min
   !> of K goes like sigma_min(B)**2. Below it (at and next to a change point)
   !> the response's size and signs are arbitrary. Smaller than change_drop:
   !> one step from a collinear configuration the response is still right
   !> though the step is near singular (docs/hard-cases.md, the double crank).
   real(dp), parameter, public :: response_drop = 1.0e-6_dp
   !> Verdicts of change_verdict.
   integer, parameter, public :: change_regular = 0, change_near_singular = 1
   !> Shift of the filled row's position correction, relative to the largest
   !> diagonal entry of the tangent (Levenberg-Marquardt): the residual has
   !> no component in the tangent's kernel, so the shift leaves the range
   !> correction exact, and makes the singular tangent factorable.
   real(dp), parameter, public :: fill_shift = 1.0e-8_dp
   !> Corrections of a filled row's positions at most.
   integer, parameter, public :: fill_iterations = 4

contains

   !> Whether a tangent with reciprocal condition number rcond is near
   !> singular against the largest of the run so far, reference (a run
   !> without a reference yet has nothing to compare with: regular, unless
   !> the factor failed, rcond = 0).
   pure integer function change_verdict(rcond, reference) result(verdict)
      real(dp), intent(in) :: rcond, reference
      verdict = change_regular
      if (.not. rcond > 0) then
         verdict = change_near_singular
      else if (rcond < change_drop*reference) then
         verdict = change_near_singular
      end if
   end function change_verdict

   !> Whether the drive response of a factor with reciprocal condition number
   !> rcond is trusted against the run's best so far, reference.
   pure logical function response_trusted(rcond, reference) result(trusted)
      real(dp), intent(in) :: rcond, reference
      trusted = rcond > 0 .and. rcond >= response_drop*reference
   end function response_trusted

   !> The order of the two-sided interpolation that the neighbours' data
   !> allow: 5 (quintic Hermite) with velocities and accelerations at both,
   !> 3 (cubic Hermite) with velocities, else 1 (linear).
   pure integer function fill_order(velocities, accelerations) result(order)
      logical, intent(in) :: velocities, accelerations
      order = 1
      if (velocities) order = 3
      if (velocities .and. accelerations) order = 5
   end function fill_order

   !> q(t) by two-sided Hermite interpolation between (t0, q0, v0, a0) and
   !> (t1, q1, v1, a1), t0 < t < t1, of the given order (fill_order): exact for
   !> polynomials of that degree. Rates unused by the order may be anything.
   pure subroutine hermite_fill(order, t0, q0, v0, a0, t1, q1, v1, a1, t, q)
      integer, intent(in) :: order
      real(dp), intent(in) :: t0, t1, t
      real(dp), contiguous, intent(in) :: q0(:), v0(:), a0(:), q1(:), v1(:), a1(:)
      real(dp), contiguous, intent(out) :: q(:)
      real(dp) :: h, s, s2, s3, s4, s5
      h = t1 - t0
      s = (t - t0)/h
      s2 = s*s
      s3 = s2*s
      s4 = s3*s
      s5 = s4*s
      select case (order)
      case (5)
         q = (1 - 10*s3 + 15*s4 - 6*s5)*q0 + (10*s3 - 15*s4 + 6*s5)*q1 &
            & + h*((s - 6*s3 + 8*s4 - 3*s5)*v0 + (-4*s3 + 7*s4 - 3*s5)*v1) &
            & + h*h*((s2 - 3*s3 + 3*s4 - s5)/2*a0 + (s3 - 2*s4 + s5)/2*a1)
      case (3)
         q = (2*s3 - 3*s2 + 1)*q0 + (3*s2 - 2*s3)*q1 + h*((s3 - 2*s2 + s)*v0 + (s3 - s2)*v1)
      case default
         q = (1 - s)*q0 + s*q1
      end select
   end subroutine hermite_fill

   !> The output time after t of a run's uniform steps from t_start to t_end
   !> by dt (as the time loop makes them: t_start + n dt, the last one t_end),
   !> or t plus the last step (from t_from) if t is not one of them or is the last.
   pure real(dp) function next_output_time(t_start, t_end, dt, t_from, t) result(t_next)
      real(dp), intent(in) :: t_start, t_end, dt, t_from, t
      real(dp) :: span
      integer :: n, nsteps
      t_next = t + (t - t_from)
      if (.not. dt > 0) return
      span = t_end - t_start
      nsteps = nint(span/dt)
      if (abs(nsteps*dt - span) > 1.0e-9_dp*dt) nsteps = ceiling(span/dt)
      nsteps = max(nsteps, 1)
      n = nint((t - t_start)/dt)
      if (n + 1 > nsteps .or. n < 0) return
      if (abs(t_start + n*dt - t) > 1.0e-9_dp*dt .and. t /= t_end) return
      if (n + 1 == nsteps) then
         t_next = t_end
      else
         t_next = t_start + (n + 1)*dt
      end if
   end function next_output_time

end module fekap_stepping_change_point
