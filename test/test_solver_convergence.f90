!> Tests of fekap_solver_convergence: the predictors' extrapolations are exact
!> for polynomials of their degree, and the convergence test's two modes.
module test_solver_convergence
   use fekap_kinds, only: dp
   use fekap_testing, only: unittest_type, new_unittest, check, error_type
   use fekap_model, only: convergence_paper
   use fekap_solver_convergence, only: convergence_type, is_converged
   use fekap_solver_predictor, only: extrapolate, hermite_extrapolate, &
      & adams_weights
   implicit none
   private
   public :: collect_solver_convergence

contains

   subroutine collect_solver_convergence(tests)
      type(unittest_type), allocatable, intent(out) :: tests(:)
      tests = [ &
         & new_unittest('is_converged', test_is_converged), &
         & new_unittest('extrapolate', test_extrapolate), &
         & new_unittest('hermite_extrapolate', test_hermite_extrapolate), &
         & new_unittest('adams_weights', test_adams_weights) &
         & ]
   end subroutine collect_solver_convergence

   !> A polynomial of degree `degree` with unequal coefficients, and its derivative.
   pure real(dp) function poly(t, degree)
      real(dp), intent(in) :: t
      integer, intent(in) :: degree
      integer :: k
      poly = 0
      do k = degree, 0, -1
         poly = poly*t + (1.5_dp - 0.3_dp*k)
      end do
   end function poly

   pure real(dp) function dpoly(t, degree)
      real(dp), intent(in) :: t
      integer, intent(in) :: degree
      integer :: k
      dpoly = 0
      do k = degree, 1, -1
         dpoly = dpoly*t + k*(1.5_dp - 0.3_dp*k)
      end do
   end function dpoly

   subroutine test_is_converged(error)
      type(error_type), allocatable, intent(out) :: error
      type(convergence_type) :: conv
      conv%tol = 1.0e-10_dp
      conv%length = 1.0e-12_dp
      conv%residual_floor = 1.0e-20_dp
      ! Default: the residual against the scale and the correction against the length.
      call check(error, is_converged(conv, 1.0e-11_dp, 1.0_dp, 1.0_dp, 1.0e-13_dp), 'both small')
      if (allocated(error)) return
      call check(error, .not. is_converged(conv, 1.0e-11_dp, 1.0_dp, 1.0_dp, 1.0e-11_dp), 'correction too long')
      if (allocated(error)) return
      call check(error, .not. is_converged(conv, 1.0e-9_dp, 1.0_dp, 1.0_dp, 1.0e-13_dp), 'residual too large')
      if (allocated(error)) return
      call check(error, is_converged(conv, 1.0e-21_dp, 1.0_dp, 0.0_dp, 1.0e-13_dp), 'below the floor')
      if (allocated(error)) return
      ! The paper's test: the residual ratio alone.
      conv%mode = convergence_paper
      call check(error, is_converged(conv, 1.0e-11_dp, 1.0_dp, 0.0_dp, 1.0_dp), 'paper: ratio small')
      if (allocated(error)) return
      call check(error, .not. is_converged(conv, 1.0e-9_dp, 1.0_dp, 0.0_dp, 0.0_dp), 'paper: ratio large')
   end subroutine test_is_converged

   !> Lagrange extrapolation through n points reproduces a polynomial of
   !> degree n - 1, whichever columns hold them and in whatever order.
   subroutine test_extrapolate(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: tk(4), q(1, 4), qpred(1)
      integer :: n, k
      ! Column 2 is a stale entry, never used.
      tk = [0.3_dp, 9.0_dp, 0.2_dp, 0.05_dp]
      q = 7
      do n = 1, 3
         do k = 1, 4
            if (k /= 2) q(1, k) = poly(tk(k), n - 1)
         end do
         call extrapolate(q, tk, columns(n), 0.45_dp, qpred)
         call check(error, qpred(1), poly(0.45_dp, n - 1), 'exact for degree n - 1', rel=1.0e-13_dp)
         if (allocated(error)) return
      end do
   end subroutine test_extrapolate

   !> The first n of the columns 4, 1, 3 (column 2 unused): a ring buffer's order.
   pure function columns(n)
      integer, intent(in) :: n
      integer :: columns(n)
      integer, parameter :: ring(3) = [4, 1, 3]
      columns = ring(1:n)
   end function columns

   !> Hermite extrapolation from n positions and velocities reproduces a
   !> polynomial of degree 2n - 1 (unequal steps), and misses one of degree
   !> 2n, with the nodes in the columns of a ring buffer (the rest stale).
   subroutine test_hermite_extrapolate(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: tk(4), q(2, 4), v(2, 4), qpred(2)
      integer :: n, k
      integer, parameter :: ring(4) = [3, 4, 1, 2]
      tk = [0.05_dp, 0.0_dp, 0.3_dp, 0.2_dp]
      do n = 2, 4
         q = 7
         v = 7
         do k = 1, n
            q(:, ring(k)) = [poly(tk(ring(k)), 2*n - 1), poly(tk(ring(k)), 2*n)]
            v(:, ring(k)) = [dpoly(tk(ring(k)), 2*n - 1), dpoly(tk(ring(k)), 2*n)]
         end do
         call hermite_extrapolate(q, v, tk, ring(1:n), 0.45_dp, qpred)
         call check(error, qpred(1), poly(0.45_dp, 2*n - 1), 'exact for degree 2n - 1', rel=1.0e-12_dp)
         if (allocated(error)) return
         call check(error, abs(qpred(2) - poly(0.45_dp, 2*n)) > 1.0e-6_dp, 'not exact for degree 2n')
         if (allocated(error)) return
      end do
   end subroutine test_hermite_extrapolate

   !> Adams-Bashforth extrapolation with these weights, from one position and
   !> n velocities, reproduces a polynomial of degree n (unequal steps, n = 1
   !> to 5) and misses one of degree n + 1, with the nodes in the columns of a
   !> ring buffer (the rest stale); the `drop` weights give its difference
   !> from the extrapolation without the oldest velocity.
   subroutine test_adams_weights(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: tk(6), q(2, 6), v(2, 6), qpred(2), qfewer(2), difference(2), unused(2)
      integer :: n, k
      integer, parameter :: ring(5) = [4, 5, 6, 1, 2]
      tk = [0.05_dp, 0.0_dp, 9.0_dp, 0.3_dp, 0.2_dp, 0.12_dp]
      do n = 1, 5
         q = 7
         v = 7
         do k = 1, n
            ! The second row: the first plus t**(n+1), of degree n + 1.
            q(:, ring(k)) = poly(tk(ring(k)), n) + [0.0_dp, tk(ring(k))**(n + 1)]
            v(:, ring(k)) = dpoly(tk(ring(k)), n) + [0.0_dp, (n + 1)*tk(ring(k))**n]
         end do
         call adams(ring(1:n), qpred, difference)
         call check(error, qpred(1), poly(0.45_dp, n), 'exact for degree n', rel=1.0e-12_dp)
         if (allocated(error)) return
         call check(error, abs(qpred(2) - poly(0.45_dp, n) - 0.45_dp**(n + 1)) > 1.0e-6_dp, &
            & 'not exact for degree n + 1')
         if (allocated(error)) return
         if (n < 2) cycle
         call adams(ring(1:n - 1), qfewer, unused)
         call check(error, maxval(abs(difference - (qpred - qfewer))), 0.0_dp, 'drop weights: the difference', &
            & abs=1.0e-13_dp)
         if (allocated(error)) return
      end do
   contains
      !> The extrapolation to 0.45 through the columns, and its drop-weighted sum.
      subroutine adams(columns, prediction, dropped)
         integer, intent(in) :: columns(:)
         real(dp), intent(out) :: prediction(2), dropped(2)
         real(dp) :: beta(size(columns)), drop(size(columns))
         integer :: j
         call adams_weights(tk, columns, 0.45_dp, beta, drop)
         prediction = q(:, columns(1))
         dropped = 0
         do j = 1, size(columns)
            prediction = prediction + beta(j)*v(:, columns(j))
            dropped = dropped + drop(j)*v(:, columns(j))
         end do
      end subroutine adams
   end subroutine test_adams_weights

end module test_solver_convergence
