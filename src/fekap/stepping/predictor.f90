!> The predictor of a Newton step: a ring of the last accepted
!> configurations, their times and (where known) velocities, and the
!> extrapolations through them that give the starting point at a new time.
!> Where the velocities of the last configurations are known, Hermite through
!> their positions and velocities, or, when its estimated error is below
!> adams_margin times the length tolerance, Adams-Bashforth through the
!> newest position and the velocities; where they are not, Lagrange through
!> the positions. Hermite is of the higher order, Adams-Bashforth the less
!> sensitive to round-off (docs/performance.md has the measurements).
module fekap_stepping_predictor
   use fekap_kinds, only: dp
   implicit none
   private

   public :: predictor_history_type, new_predictor_history, extrapolate_history, taylor_predict
   public :: extrapolate, hermite_extrapolate, adams_weights

   !> Configurations kept for the extrapolating predictor: Hermite
   !> extrapolation through up to hermite_points positions and velocities
   !> (degree 7, error of order h**8), Adams-Bashforth through the newest
   !> position and adams_points velocities, or one more (history_depth), or
   !> Lagrange extrapolation through up to lagrange_points positions
   !> (quadratic) where velocities are not known. The Hermite degree is
   !> measured in docs/performance.md. (adams_weights takes up to six nodes:
   !> its Gauss rule is exact through them.)
   integer, parameter, public :: history_depth = 6, adams_points = 5, hermite_points = 4, lagrange_points = 3

   !> A step whose first Newton correction is at most predictor_margin times
   !> the length tolerance is accepted at its predictor (see the FEM's
   !> solve_step).
   real(dp), parameter, public :: predictor_margin = 1.0e-3_dp

   !> The Adams-Bashforth predictor is taken when its error, estimated by
   !> the difference between its predictions through the newest
   !> adams_points - 1 and adams_points velocities, is at most
   !> adams_margin times the length tolerance. Why above predictor_margin:
   !> the alternative, Hermite, extrapolates the positions with weights whose
   !> magnitudes add up to 158 at equal steps, which amplify their round-off
   !> (up to some 80 eps |q|). Where Adams-Bashforth's estimate lies between
   !> the two margins it is the nearer: on Example 1 at dt = 1e-4 the steps
   !> that took Hermite then had first corrections of up to a fifth of the
   !> length tolerance and a second factorisation each, 1,933 steps of
   !> 10,000; with this margin 32 (docs/performance.md). The prediction
   !> through history_depth velocities is held to the same bound.
   real(dp), parameter, public :: adams_margin = 1.0e-2_dp

   !> The prediction through history_depth velocities is made only where the
   !> first one's estimate is at most step_up_reach times its margin: its
   !> own (its distance from the first) is smaller by a factor of about the
   !> step over the motion's time scale. On Example 1 at dt = 5e-4 it passed
   !> where the first's was up to 61 times the margin (none above 61); at
   !> the scissor lift of N = 1,000 (dt = 0.01) the first estimates are 1e7
   !> times it, and the second prediction would only add its sums (1 % of
   !> the step).
   real(dp), parameter :: step_up_reach = 1.0e3_dp

   !> What extrapolate_history made: nothing (fewer than two configurations),
   !> a Lagrange extrapolation of positions, or a smooth one (Hermite or
   !> Adams-Bashforth) of positions and velocities.
   integer, parameter, public :: prediction_none = 0, prediction_lagrange = 1, prediction_smooth = 2

   !> The last accepted configurations and their times: a ring of
   !> history_depth columns, the newest in column `newest`, the k-th newest in
   !> self%column(k); `count` of them filled. Accepting a configuration writes
   !> one column instead of shifting the history.
   type :: predictor_history_type
      real(dp), allocatable :: q(:, :), t(:)
      integer :: filled = 0, newest = history_depth
      !> Their velocities, and whether each is known.
      real(dp), allocatable :: velocity(:, :)
      logical, allocatable :: has_velocity(:)
   contains
      !> Push a newly accepted configuration (over the oldest column); its velocity is unknown.
      procedure :: push => history_push
      !> The column of the k-th newest configuration.
      procedure :: column => history_column
   end type predictor_history_type

contains

   !> An empty history for n unknowns.
   pure subroutine new_predictor_history(self, n)
      type(predictor_history_type), intent(out) :: self
      integer, intent(in) :: n
      allocate (self%q(n, history_depth), self%t(history_depth), self%velocity(n, history_depth), source=0.0_dp)
      allocate (self%has_velocity(history_depth), source=.false.)
   end subroutine new_predictor_history

   pure subroutine history_push(self, q, t)
      class(predictor_history_type), intent(inout) :: self
      real(dp), intent(in) :: q(:), t
      self%newest = modulo(self%newest, history_depth) + 1
      self%q(:, self%newest) = q
      self%t(self%newest) = t
      self%has_velocity(self%newest) = .false.
      self%filled = min(self%filled + 1, history_depth)
   end subroutine history_push

   pure integer function history_column(self, k) result(column)
      class(predictor_history_type), intent(in) :: self
      integer, intent(in) :: k
      column = ring_column(self%newest, k)
   end function history_column

   !> The column of the k-th newest configuration of a ring whose newest is
   !> in column `newest` (private, so that the predictor's loops inline it).
   pure integer function ring_column(newest, k) result(column)
      integer, intent(in) :: newest, k
      ! modulo(newest - k, history_depth) + 1 for k = 1 .. history_depth
      ! (a compare instead of modulo's division and sign correction).
      column = newest - k + 1
      if (column < 1) column = column + history_depth
   end function ring_column

   !> The extrapolation of the history to time t into qt, and which it was
   !> (`kind`; qt is untouched for prediction_none). With `smooth`, the
   !> newest configurations whose velocities are known (at least two) give
   !> Adams-Bashforth or Hermite (see adams_prediction); else, or without
   !> velocities, Lagrange through the newest lagrange_points positions.
   !> length is the length tolerance, dof_length the length weight of each
   !> unknown (1 for translations, the model size for rotations).
   subroutine extrapolate_history(self, t, smooth, length, dof_length, qt, made)
      type(predictor_history_type), intent(in) :: self
      real(dp), intent(in) :: t
      logical, intent(in) :: smooth
      real(dp), intent(in) :: length
      real(dp), contiguous, intent(in) :: dof_length(:)
      real(dp), contiguous, intent(inout) :: qt(:)
      integer, intent(out) :: made
      integer :: i, n, columns(history_depth)
      ! The history's columns, newest first.
      do i = 1, self%filled
         columns(i) = ring_column(self%newest, i)
      end do
      n = 0
      if (smooth) then
         ! The newest configurations whose velocities are known.
         do while (n < self%filled)
            if (.not. self%has_velocity(columns(n + 1))) exit
            n = n + 1
         end do
      end if
      if (n > 1) then
         if (.not. adams_prediction(self, t, columns(1:n), length, dof_length, qt)) then
            call hermite_extrapolate(self%q, self%velocity, self%t, columns(1:min(n, hermite_points)), t, qt)
         end if
         made = prediction_smooth
      else if (self%filled > 1) then
         call extrapolate(self%q, self%t, columns(1:min(self%filled, lagrange_points)), t, qt)
         made = prediction_lagrange
      else
         made = prediction_none
      end if
   end subroutine extrapolate_history

   !> The Adams-Bashforth prediction at t through the adams_points newest
   !> velocities into qt (see adams_weights), if all of them are known
   !> (columns) and its error, estimated as its distance from the prediction
   !> through one velocity fewer (weighted by dof_length), is at most
   !> adams_margin times the length tolerance; else the prediction through
   !> history_depth velocities, if they are known, with its distance from
   !> the first as its error estimate (the first's error: it errs on the
   !> safe side), under the same bound. The higher order serves larger
   !> steps: on Example 1 at dt = 5e-4 the first prediction's estimate is
   !> above the margin at every step, and so are Hermite's first corrections
   !> above predictor_margin, where the second prediction passes at seven
   !> steps in ten (docs/performance.md). It is made only where the first
   !> does not serve, so that the smaller steps' predictions stay the first's.
   logical function adams_prediction(self, t, columns, length, dof_length, qt) result(taken)
      type(predictor_history_type), intent(in) :: self
      real(dp), intent(in) :: t
      integer, intent(in) :: columns(:)
      real(dp), intent(in) :: length
      real(dp), contiguous, intent(in) :: dof_length(:)
      real(dp), contiguous, intent(inout) :: qt(:)
      real(dp) :: beta(history_depth), drop(history_depth), estimate
      taken = .false.
      if (size(columns) < adams_points) return
      call full_adams_weights(self%t, columns(1:adams_points), t, beta, drop)
      ! The columns as arrays of their own (contiguous: not copied), whose
      ! addresses the loop need not compute from columns(k) at each unknown.
      call adams_sums(size(qt), beta, drop, self%q(:, columns(1)), self%velocity(:, columns(1)), &
         & self%velocity(:, columns(2)), self%velocity(:, columns(3)), self%velocity(:, columns(4)), &
         & self%velocity(:, columns(5)), dof_length, qt, estimate)
      taken = estimate <= adams_margin*length
      if (taken .or. size(columns) < history_depth .or. estimate > step_up_reach*adams_margin*length) return
      call adams_weights(self%t, columns(1:history_depth), t, beta, drop)
      call adams_step_up(size(qt), beta, self%q(:, columns(1)), self%velocity, columns(1:history_depth), dof_length, &
         & qt, estimate)
      taken = estimate <= adams_margin*length
   end function adams_prediction

   !> The prediction through history_depth velocities (q1 + sum beta(k) v_k,
   !> k = 1 to history_depth, in that order) into qt, which holds the one
   !> through adams_points velocities on entry, and the largest distance
   !> between the two (weighted by dof_length), its error estimate. Indexed
   !> through columns: made only at the steps the first does not serve.
   pure subroutine adams_step_up(n, beta, q1, velocity, columns, dof_length, qt, estimate)
      integer, intent(in) :: n
      real(dp), intent(in) :: beta(history_depth), q1(n), velocity(:, :), dof_length(n)
      integer, intent(in) :: columns(history_depth)
      real(dp), intent(inout) :: qt(n)
      real(dp), intent(out) :: estimate
      real(dp) :: higher
      integer :: i, k
      estimate = 0
      do i = 1, n
         higher = q1(i)
         do k = 1, history_depth
            higher = higher + beta(k)*velocity(i, columns(k))
         end do
         estimate = max(estimate, abs(higher - qt(i))*dof_length(i))
         qt(i) = higher
      end do
   end subroutine adams_step_up

   !> adams_prediction's sums over the unknowns (adams_points = 5 velocities
   !> v1, newest, to v5): qt = q1 + sum beta(k) v_k and the largest
   !> |sum drop(k) v_k| dof_length, each sum in the order k = 1 to 5.
   pure subroutine adams_sums(n, beta, drop, q1, v1, v2, v3, v4, v5, dof_length, qt, estimate)
      integer, intent(in) :: n
      real(dp), intent(in) :: beta(adams_points), drop(adams_points)
      real(dp), intent(in) :: q1(n), v1(n), v2(n), v3(n), v4(n), v5(n), dof_length(n)
      real(dp), intent(inout) :: qt(n)
      real(dp), intent(out) :: estimate
      real(dp) :: difference
      integer :: i
      estimate = 0
      do i = 1, n
         qt(i) = q1(i) + beta(1)*v1(i) + beta(2)*v2(i) + beta(3)*v3(i) + beta(4)*v4(i) + beta(5)*v5(i)
         ! From drop(1) v1 rather than 0 + drop(1) v1: they differ only in
         ! the sign of a zero, which abs takes away.
         difference = drop(1)*v1(i) + drop(2)*v2(i) + drop(3)*v3(i) + drop(4)*v4(i) + drop(5)*v5(i)
         estimate = max(estimate, abs(difference)*dof_length(i))
      end do
   end subroutine adams_sums

   !> The Taylor series q + h v + h**2/2 a from a configuration and its rates.
   pure subroutine taylor_predict(q, v, a, h, qt)
      real(dp), intent(in) :: h
      real(dp), contiguous, intent(in) :: q(:), v(:), a(:)
      real(dp), contiguous, intent(out) :: qt(:)
      qt = q + h*v + h**2/2*a
   end subroutine taylor_predict

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
   !> At most hermite_points configurations.
   !> One pass over the unknowns with all the weights (not a pass per
   !> configuration on a zeroed qpred): each sum is taken from +0 in the
   !> same order, ((0 + wq_1 q_1) + wv_1 v_1) + wq_2 q_2 ..., so the same
   !> to the bit.
   pure subroutine hermite_extrapolate(q, v, tk, columns, t, qpred)
      real(dp), contiguous, intent(in) :: q(:, :), v(:, :)
      real(dp), intent(in) :: tk(:), t
      integer, intent(in) :: columns(:)
      real(dp), intent(out) :: qpred(:)
      real(dp) :: wq(hermite_points), wv(hermite_points), sum
      integer :: i, k, c(hermite_points)
      do k = 1, size(columns)
         call hermite_weights(tk, columns, k, t, wq(k), wv(k))
         c(k) = columns(k)
      end do
      if (size(columns) == hermite_points) then
         ! The usual case: the columns as arrays of their own (contiguous,
         ! so not copied), which the compiler's loop takes two at a time.
         call hermite_sum4(size(qpred), wq, wv, q(:, c(1)), q(:, c(2)), q(:, c(3)), q(:, c(4)), &
            & v(:, c(1)), v(:, c(2)), v(:, c(3)), v(:, c(4)), qpred)
      else
         do i = 1, size(qpred)
            sum = 0
            do k = 1, size(columns)
               sum = sum + wq(k)*q(i, c(k)) + wv(k)*v(i, c(k))
            end do
            qpred(i) = sum
         end do
      end if
   end subroutine hermite_extrapolate

   !> qpred = sum over k of wq(k) q_k + wv(k) v_k (k = 1 to 4), each sum
   !> from +0 in hermite_extrapolate's order.
   pure subroutine hermite_sum4(n, wq, wv, q1, q2, q3, q4, v1, v2, v3, v4, qpred)
      integer, intent(in) :: n
      real(dp), intent(in) :: wq(4), wv(4)
      real(dp), intent(in) :: q1(n), q2(n), q3(n), q4(n), v1(n), v2(n), v3(n), v4(n)
      real(dp), intent(out) :: qpred(n)
      real(dp) :: zero
      integer :: i
      zero = 0
      do i = 1, n
         qpred(i) = zero + wq(1)*q1(i) + wv(1)*v1(i) + wq(2)*q2(i) + wv(2)*v2(i) + wq(3)*q3(i) + wv(3)*v3(i) &
            & + wq(4)*q4(i) + wv(4)*v4(i)
      end do
   end subroutine hermite_sum4

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

   !> adams_weights through adams_points nodes (the prediction's usual
   !> depth): the same operations in the same order on arrays of
   !> fixed size, which the compiler unrolls (adams_weights' loops of
   !> run-time length cost three times their arithmetic). Each difference
   !> t_k - t_m is formed once: t_m - t_k is its negative to the bit.
   pure subroutine full_adams_weights(tk, columns, t, beta, drop)
      real(dp), intent(in) :: tk(:), t
      integer, intent(in) :: columns(adams_points)
      real(dp), intent(out) :: beta(adams_points), drop(adams_points)
      integer, parameter :: n = adams_points
      ! Gauss points on [-1, 1] and weights as adams_weights' (3 points: n = 5).
      real(dp), parameter :: xg(3) = [-sqrt(0.6_dp), 0.0_dp, sqrt(0.6_dp)]
      real(dp), parameter :: wg(3) = [5.0_dp/9, 8.0_dp/9, 5.0_dp/9]
      real(dp) :: nodes(n), tau(3), w_all(3), w_drop(3), half, derivative, integral, quadrature, gap(n, n)
      integer :: k, m, g
      do k = 1, n
         nodes(k) = tk(columns(k))
      end do
      half = (t - nodes(1))/2
      do g = 1, 3
         tau(g) = nodes(1) + half*(1 + xg(g))
         w_drop(g) = 1
         do m = 1, n - 1
            w_drop(g) = w_drop(g)*(tau(g) - nodes(m))
         end do
         w_all(g) = w_drop(g)*(tau(g) - nodes(n))
      end do
      integral = 0
      do g = 1, 3
         integral = integral + wg(g)*w_drop(g)
      end do
      integral = half*integral
      do k = 1, n
         do m = k + 1, n
            gap(k, m) = nodes(k) - nodes(m)
            gap(m, k) = -gap(k, m)
         end do
      end do
      do k = 1, n
         derivative = 1
         do m = 1, n
            if (m /= k) derivative = derivative*gap(k, m)
         end do
         quadrature = 0
         do g = 1, 3
            quadrature = quadrature + wg(g)*w_all(g)/(tau(g) - nodes(k))
         end do
         beta(k) = half*quadrature/derivative
         drop(k) = integral/derivative
      end do
   end subroutine full_adams_weights

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

end module fekap_stepping_predictor
