!> The Newton convergence test shared by every method, so that iteration
!> counts are comparable, and the predictors' extrapolation.
module fekap_solver_convergence
   use fekap_kinds, only: dp
   use fekap_model, only: convergence_paper, convergence_default
   implicit none
   private

   public :: convergence_type, is_converged, extrapolate, hermite_extrapolate

   !> Settings of the test; see docs/theory.md, "Convergence".
   type :: convergence_type
      !> convergence_paper or convergence_default.
      integer :: mode = convergence_default
      !> Residual ratio tolerance.
      real(dp) :: tol = 1.0e-10_dp
      !> Absolute length tolerance on the last correction (length_tol * model size).
      real(dp) :: length = 1.0e-12_dp
      !> Absolute residual floor, below which a step counts as converged
      !> whatever its scale (a step that starts converged).
      real(dp) :: floor = 0
   end type convergence_type

contains

   !> The convergence test after a Newton solve.
   !>   paper:   ||P(i)|| / ||P(0)|| < tol (r0 is the residual at the predictor).
   !>   default: ||P(i)|| <= tol * scale, with scale the residual of the drive
   !>            increment alone (independent of the predictor), or ||P(i)|| <= floor;
   !>            and the correction computed from P(i) is below the length tolerance.
   pure logical function is_converged(self, r, r0, scale, correction) result(done)
      type(convergence_type), intent(in) :: self
      !> Residual norm at the current iterate, at the predictor, and the scale.
      real(dp), intent(in) :: r, r0, scale
      !> Max-norm of the translational part of the correction solved from r.
      real(dp), intent(in) :: correction
      if (self%mode == convergence_paper) then
         done = r < self%tol*r0 .or. r <= self%floor
      else
         done = (r <= self%tol*scale .or. r <= self%floor) .and. correction <= self%length
      end if
   end function is_converged

   !> Lagrange extrapolation to time t of the history q(:, k) at times tk(k)
   !> (k = 1 the newest); uses as many points as given (1: constant,
   !> 2: linear, 3: quadratic).
   pure subroutine extrapolate(q, tk, t, qpred)
      real(dp), intent(in) :: q(:, :), tk(:), t
      real(dp), intent(out) :: qpred(:)
      integer :: j, m, n
      real(dp) :: w
      n = size(tk)
      qpred = 0
      do j = 1, n
         w = 1
         do m = 1, n
            if (m /= j) w = w*(t - tk(m))/(tk(j) - tk(m))
         end do
         qpred = qpred + w*q(:, j)
      end do
   end subroutine extrapolate

   !> Hermite extrapolation to time t from configurations q(:, k) at times
   !> tk(k) (k = 1 the newest) and their velocities v(:, k): the polynomial of
   !> degree 2n - 1 through the n positions and velocities. With two (three,
   !> four) configurations its error is of order h**4 (h**6, h**8), against
   !> h**3 for quadratic extrapolation of positions.
   pure subroutine hermite_extrapolate(q, v, tk, t, qpred)
      real(dp), intent(in) :: q(:, :), v(:, :), tk(:), t
      real(dp), intent(out) :: qpred(:)
      real(dp) :: wq, wv
      integer :: k
      qpred = 0
      do k = 1, size(tk)
         call hermite_weights(tk, k, t, wq, wv)
         qpred = qpred + wq*q(:, k) + wv*v(:, k)
      end do
   end subroutine hermite_extrapolate

   !> Weights of the k-th position and velocity in the Hermite polynomial
   !> through the nodes tk, at t: with the Lagrange basis polynomial l_k,
   !>   wq = (1 - 2 l_k'(t_k) (t - t_k)) l_k(t)**2,  wv = (t - t_k) l_k(t)**2,
   !>   l_k'(t_k) = sum over m /= k of 1 / (t_k - t_m).
   pure subroutine hermite_weights(tk, k, t, wq, wv)
      real(dp), intent(in) :: tk(:), t
      integer, intent(in) :: k
      real(dp), intent(out) :: wq, wv
      real(dp) :: l, slope, r
      integer :: m
      l = 1
      slope = 0
      do m = 1, size(tk)
         if (m == k) cycle
         r = 1/(tk(k) - tk(m))
         l = l*(t - tk(m))*r
         slope = slope + r
      end do
      wq = (1 - 2*slope*(t - tk(k)))*l**2
      wv = (t - tk(k))*l**2
   end subroutine hermite_weights

end module fekap_solver_convergence
