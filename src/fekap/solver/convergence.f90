!> The Newton convergence test shared by every method, so that iteration
!> counts are comparable, and the predictors' extrapolation.
module fekap_solver_convergence
   use fekap_kinds, only: dp
   use fekap_model, only: convergence_paper, convergence_default
   implicit none
   private

   public :: convergence_type, is_converged, extrapolate, hermite_extrapolate, adams_weights

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

   !> Adams-Bashforth extrapolation to time t is the configuration at t_1 =
   !> tk(columns(1)) plus sum_k beta(k) v_k, the integral from t_1 to t of the
   !> polynomial through the velocities v_k at the times t_k = tk(columns(k)),
   !> k = 1..n (n up to 6, in any order; degree n - 1, so exact for
   !> configurations that are polynomials of degree n, error of order
   !> h**(n+1)). Against Hermite extrapolation it has one configuration in
   !> it, with weight 1, where Hermite's weights amplify the round-off of all
   !> of them (the position weights of degree 7 at equal steps add up to
   !> 158): at small steps its prediction is the more accurate. These are the
   !> weights beta(k), for t after every node: the integrals of the Lagrange
   !> basis polynomials l_k = w / ((tau - t_k) w'(t_k)), w = prod (tau - t_m),
   !> by Gauss quadrature (2 points, exact through 4 nodes; 3 through 5 or 6).
   !> And `drop`: the weights of the difference between this prediction and
   !> the one through all nodes but the oldest (an estimate of the latter's
   !> error), the next term of Newton's form: the integral of
   !> prod_{m < n} (tau - t_m) times the divided difference, whose weights
   !> are 1 / w'(t_k). (The sums are the caller's: the FEM forms both in one
   !> pass over the unknowns.)
   pure subroutine adams_weights(tk, columns, t, beta, drop)
      real(dp), intent(in) :: tk(:), t
      integer, intent(in) :: columns(:)
      real(dp), intent(out) :: beta(:), drop(:)
      ! Gauss points on [-1, 1] and weights: 2 points in 1:2, 3 in 3:5.
      real(dp), parameter :: xg(5) = [-1/sqrt(3.0_dp), 1/sqrt(3.0_dp), -sqrt(0.6_dp), 0.0_dp, sqrt(0.6_dp)]
      real(dp), parameter :: wg(5) = [1.0_dp, 1.0_dp, 5.0_dp/9, 8.0_dp/9, 5.0_dp/9]
      real(dp) :: nodes(6), tau(5), w_all(5), w_drop(5), half, derivative, integral, quadrature
      integer :: k, m, g, g1, g2, n
      n = size(columns)
      do k = 1, n
         nodes(k) = tk(columns(k))
      end do
      g1 = merge(1, 3, n <= 4)
      g2 = merge(2, 5, n <= 4)
      half = (t - nodes(1))/2
      do g = g1, g2
         tau(g) = nodes(1) + half*(1 + xg(g))
         w_drop(g) = 1
         do m = 1, n - 1
            w_drop(g) = w_drop(g)*(tau(g) - nodes(m))
         end do
         w_all(g) = w_drop(g)*(tau(g) - nodes(n))
      end do
      integral = 0
      do g = g1, g2
         integral = integral + wg(g)*w_drop(g)
      end do
      integral = half*integral
      do k = 1, n
         derivative = 1
         do m = 1, n
            if (m /= k) derivative = derivative*(nodes(k) - nodes(m))
         end do
         quadrature = 0
         do g = g1, g2
            quadrature = quadrature + wg(g)*w_all(g)/(tau(g) - nodes(k))
         end do
         beta(k) = half*quadrature/derivative
         drop(k) = integral/derivative
      end do
   end subroutine adams_weights

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
