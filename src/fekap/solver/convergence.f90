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

   !> Lagrange extrapolation to time t through the configurations
   !> q(:, columns(k)) at times tk(columns(k)): as many points as columns
   !> (1: constant, 2: linear, 3: quadratic), in any order.
   pure subroutine extrapolate(q, tk, columns, t, qpred)
      real(dp), intent(in) :: q(:, :), tk(:), t
      integer, intent(in) :: columns(:)
      real(dp), intent(out) :: qpred(:)
      integer :: j, m
      real(dp) :: w
      qpred = 0
      do j = 1, size(columns)
         w = 1
         do m = 1, size(columns)
            if (m /= j) w = w*(t - tk(columns(m)))/(tk(columns(j)) - tk(columns(m)))
         end do
         qpred = qpred + w*q(:, columns(j))
      end do
   end subroutine extrapolate

   !> Hermite extrapolation to time t from the configurations q(:, columns(k))
   !> at times tk(columns(k)) and their velocities v(:, columns(k)), in any
   !> order: the polynomial of degree 2n - 1 through the n positions and
   !> velocities. With two (three, four) configurations its error is of order
   !> h**4 (h**6, h**8), against h**3 for quadratic extrapolation of positions.
   pure subroutine hermite_extrapolate(q, v, tk, columns, t, qpred)
      real(dp), intent(in) :: q(:, :), v(:, :), tk(:), t
      integer, intent(in) :: columns(:)
      real(dp), intent(out) :: qpred(:)
      real(dp) :: wq, wv
      integer :: k
      qpred = 0
      do k = 1, size(columns)
         call hermite_weights(tk, columns, k, t, wq, wv)
         qpred = qpred + wq*q(:, columns(k)) + wv*v(:, columns(k))
      end do
   end subroutine hermite_extrapolate

   !> Weights of the k-th position and velocity in the Hermite polynomial
   !> through the nodes tk(columns), at t: with the Lagrange basis polynomial l_k,
   !>   wq = (1 - 2 l_k'(t_k) (t - t_k)) l_k(t)**2,  wv = (t - t_k) l_k(t)**2,
   !>   l_k'(t_k) = sum over m /= k of 1 / (t_k - t_m).
   pure subroutine hermite_weights(tk, columns, k, t, wq, wv)
      real(dp), intent(in) :: tk(:), t
      integer, intent(in) :: columns(:), k
      real(dp), intent(out) :: wq, wv
      real(dp) :: l, slope, r, t_k
      integer :: m
      t_k = tk(columns(k))
      l = 1
      slope = 0
      do m = 1, size(columns)
         if (m == k) cycle
         r = 1/(t_k - tk(columns(m)))
         l = l*(t - tk(columns(m)))*r
         slope = slope + r
      end do
      wq = (1 - 2*slope*(t - t_k))*l**2
      wv = (t - t_k)*l**2
   end subroutine hermite_weights

end module fekap_solver_convergence
