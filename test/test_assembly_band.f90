!> Tests of fekap_assembly_band: the in-house narrow-band U^T D U factor and
!> solve against LAPACK (dpbtrf/dpbtrs) and against A x = b, for every
!> half-bandwidth up to a little past narrow_band, over full bands, bands with
!> zeros inside and random envelopes; the band matrix's envelope, its choice
!> of solver, its LU fallback and its dense mode.
module test_assembly_band
   use fekap_kinds, only: dp
   use fekap_testing, only: unittest_type, new_unittest, check, error_type, next_random
   use fekap_assembly_lapack, only: dpbtrf, dpbtrs
   use fekap_assembly_band, only: band_matrix_type, new_band_matrix, narrow_band, band_ldlt, band_ldlt_solve
   implicit none
   private
   public :: collect_assembly_band

   !> Orders tried for every half-bandwidth (besides kd + 1 and 2 kd + 3).
   integer, parameter :: orders(4) = [1, 2, 9, 70]

contains

   subroutine collect_assembly_band(tests)
      type(unittest_type), allocatable, intent(out) :: tests(:)
      tests = [ &
         & new_unittest('new_band_matrix', test_new), &
         & new_unittest('band_ldlt', test_ldlt), &
         & new_unittest('band_ldlt_not_positive_definite', test_not_positive_definite), &
         & new_unittest('band_ldlt_solve', test_ldlt_solve), &
         & new_unittest('band_factor', test_factor), &
         & new_unittest('band_solve', test_solve) &
         & ]
   end subroutine collect_assembly_band

   !> A random symmetric positive definite n x n matrix of half-bandwidth kd
   !> in upper band storage (off-diagonal entries in [-1, 1], the diagonal
   !> dominant by a random margin) and its envelope top (the band, or with
   !> `envelope` a random first row of each column, the entries above it zero);
   !> with `indefinite`, A(j, j) of that row made negative, so that the
   !> Cholesky factorisation stops there; with `sparse`, about half the
   !> entries inside the envelope zero.
   subroutine random_band(state, n, kd, a, top, indefinite, sparse, envelope)
      integer, intent(inout) :: state
      integer, intent(in) :: n, kd
      real(dp), allocatable, intent(out) :: a(:, :)
      integer, allocatable, intent(out) :: top(:)
      integer, intent(in), optional :: indefinite
      logical, intent(in), optional :: sparse, envelope
      real(dp) :: row(n)
      integer :: i, j
      allocate (a(kd + 1, n), source=0.0_dp)
      allocate (top(n))
      row = 0
      do j = 1, n
         top(j) = max(1, j - kd)
         if (present(envelope)) then
            if (envelope) top(j) = top(j) + int(next_random(state)*(j - top(j) + 1))
         end if
         do i = top(j), j - 1
            a(kd + 1 + i - j, j) = 2*next_random(state) - 1
            if (present(sparse)) then
               if (sparse .and. next_random(state) < 0.5_dp) a(kd + 1 + i - j, j) = 0
            end if
            row(i) = row(i) + abs(a(kd + 1 + i - j, j))
            row(j) = row(j) + abs(a(kd + 1 + i - j, j))
         end do
      end do
      do j = 1, n
         a(kd + 1, j) = row(j)*(1 + next_random(state)) + 0.1_dp
      end do
      if (present(indefinite)) a(kd + 1, indefinite) = -a(kd + 1, indefinite)
   end subroutine random_band

   !> y = A x for A in upper band storage (symmetric), x with several columns.
   function band_times(a, kd, x) result(y)
      real(dp), intent(in) :: a(:, :), x(:, :)
      integer, intent(in) :: kd
      real(dp) :: y(size(x, 1), size(x, 2))
      integer :: i, j
      y = 0
      do j = 1, size(x, 1)
         y(j, :) = y(j, :) + a(kd + 1, j)*x(j, :)
         do i = max(1, j - kd), j - 1
            y(i, :) = y(i, :) + a(kd + 1 + i - j, j)*x(j, :)
            y(j, :) = y(j, :) + a(kd + 1 + i - j, j)*x(i, :)
         end do
      end do
   end function band_times

   !> Order number `in` to try with half-bandwidth kd: orders, then kd + 1 and 2 kd + 3.
   pure integer function order(in, kd)
      integer, intent(in) :: in, kd
      integer :: all(size(orders) + 2)
      all = [orders, kd + 1, 2*kd + 3]
      order = all(in)
   end function order

   !> Random right-hand sides, n x nrhs, in [-1, 1].
   function random_columns(state, n, nrhs) result(b)
      integer, intent(inout) :: state
      integer, intent(in) :: n, nrhs
      real(dp) :: b(n, nrhs)
      integer :: i, k
      do k = 1, nrhs
         do i = 1, n
            b(i, k) = 2*next_random(state) - 1
         end do
      end do
   end function random_columns

   !> The band matrix type holding a (upper band storage, envelope top) through its add.
   subroutine band_from(a, kd, top, mat, dense)
      real(dp), intent(in) :: a(:, :)
      integer, intent(in) :: kd, top(:)
      type(band_matrix_type), intent(out) :: mat
      logical, intent(in) :: dense
      integer :: i, j
      call new_band_matrix(mat, size(a, 2), kd, dense, top)
      do j = 1, size(a, 2)
         do i = top(j), j
            call mat%add(i, j, a(kd + 1 + i - j, j))
            ! The lower triangle is ignored.
            if (i < j) call mat%add(j, i, 1.0e30_dp)
         end do
      end do
   end subroutine band_from

   !> The envelope of a new band matrix: the band by default, the given one
   !> where it lies inside the band, clamped to the band (and to the
   !> diagonal) where it does not.
   subroutine test_new(error)
      type(error_type), allocatable, intent(out) :: error
      type(band_matrix_type) :: mat
      integer :: j
      call new_band_matrix(mat, 6, 2)
      call check(error, all(mat%top == [(max(1, j - 2), j = 1, 6)]), 'default: the band')
      if (allocated(error)) return
      call new_band_matrix(mat, 6, 2, top=[1, 1, 3, 2, 5, 4])
      call check(error, all(mat%top == [1, 1, 3, 2, 5, 4]), 'inside the band: as given')
      if (allocated(error)) return
      call new_band_matrix(mat, 6, 2, top=[0, 1, 1, 7, 1, 6])
      call check(error, all(mat%top == [1, 1, 1, 4, 3, 6]), 'outside: clamped to the band and the diagonal')
      if (allocated(error)) return
      call check(error, size(mat%a, 1), 3, 'band storage rows')
      call check(error, size(mat%f, 1), 7, 'factor storage rows (room for the LU fallback)')
   end subroutine test_new

   !> The factor of band_ldlt is dpbtrf's without the square roots (D = the
   !> Cholesky diagonal squared, U = the Cholesky rows over their diagonal) to
   !> round-off, for full bands, bands with zeros inside and random envelopes
   !> (dpbtrf's factor is zero above the envelope too).
   subroutine test_ldlt(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp), allocatable :: a(:, :), f(:, :), g(:, :), recip(:)
      integer, allocatable :: top(:)
      integer :: state, kd, in, n, info, info_lapack, kind, m
      character(len=12), parameter :: kinds(3) = [character(len=12) :: '', ', sparse', ', envelope']
      character(len=64) :: label
      state = 2024
      m = size(orders) + 2
      do kd = 0, narrow_band + 2
         do in = 1, 3*m
            kind = (in - 1)/m + 1
            n = order(in - (kind - 1)*m, kd)
            call random_band(state, n, kd, a, top, sparse=kind == 2, envelope=kind == 3)
            ! Nonzero above the envelope, where band_ldlt leaves f as it is.
            f = spread(spread(7.0_dp, 1, kd + 1), 2, n)
            recip = spread(0.0_dp, 1, n)
            call band_ldlt(a, f, n, kd, top, info, recip)
            call clear_above(f, kd, top)
            g = a
            call dpbtrf('U', n, kd, g, kd + 1, info_lapack)
            g = ldlt_of_cholesky(g, kd)
            write (label, '(a,i0,a,i0,a)') 'n = ', n, ', kd = ', kd, trim(kinds(kind))
            call check(error, info, 0, 'info, '//trim(label))
            call check(error, info_lapack, 0, 'LAPACK info, '//trim(label))
            call check(error, maxval(abs(f - g))/maxval(abs(g)), 0.0_dp, 'factor vs dpbtrf, '//trim(label), &
               & abs=1.0e-13_dp)
            if (allocated(error)) return
            call check(error, all(recip == 1/f(kd + 1, :)), 'reciprocals of the pivots, '//trim(label))
            if (allocated(error)) return
         end do
      end do
   end subroutine test_ldlt

   !> Zero the entries of f above the envelope top (band storage).
   pure subroutine clear_above(f, kd, top)
      real(dp), intent(inout) :: f(:, :)
      integer, intent(in) :: kd, top(:)
      integer :: j
      do j = 1, size(f, 2)
         f(1:kd + top(j) - j, j) = 0
      end do
   end subroutine clear_above

   !> The U^T D U factor (band storage) of a Cholesky factor U_c^T U_c:
   !> D(j) = U_c(j, j)**2, U(j, j+q) = U_c(j, j+q) / U_c(j, j).
   pure function ldlt_of_cholesky(g, kd) result(f)
      real(dp), intent(in) :: g(:, :)
      integer, intent(in) :: kd
      real(dp) :: f(size(g, 1), size(g, 2))
      integer :: j, q
      f = g
      do j = 1, size(g, 2)
         f(kd + 1, j) = g(kd + 1, j)**2
         do q = 1, min(kd, size(g, 2) - j)
            f(kd + 1 - q, j + q) = g(kd + 1 - q, j + q)/g(kd + 1, j)
         end do
      end do
   end function ldlt_of_cholesky

   !> A matrix that is not positive definite: info is the equation whose pivot
   !> is not positive, as from dpbtrf.
   subroutine test_not_positive_definite(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp), allocatable :: a(:, :), f(:, :), recip(:)
      integer, allocatable :: top(:)
      integer :: state, kd, n, bad, info, info_lapack
      character(len=64) :: label
      state = 99
      do kd = 0, narrow_band + 2, 3
         n = kd + 12
         do bad = 1, n, 5
            call random_band(state, n, kd, a, top, indefinite=bad, envelope=mod(bad, 2) == 0)
            f = a
            recip = spread(0.0_dp, 1, n)
            call band_ldlt(a, f, n, kd, top, info, recip)
            write (label, '(a,i0,a,i0,a,i0)') 'n = ', n, ', kd = ', kd, ', negative pivot at ', bad
            call check(error, info, bad, trim(label))
            f = a
            call dpbtrf('U', n, kd, f, kd + 1, info_lapack)
            call check(error, info, info_lapack, 'same as dpbtrf, '//trim(label))
            if (allocated(error)) return
         end do
      end do
      ! A zero pivot is not positive either.
      call random_band(state, 5, 2, a, top)
      a(3, 1) = 0
      f = a
      recip = spread(0.0_dp, 1, 5)
      call band_ldlt(a, f, 5, 2, top, info, recip)
      call check(error, info, 1, 'zero pivot')
   end subroutine test_not_positive_definite

   !> band_ldlt_solve with 1 and 3 right-hand sides, over full bands and
   !> random envelopes: A x = b to round-off, and the same x as dpbtrs with
   !> dpbtrf's factor.
   subroutine test_ldlt_solve(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp), allocatable :: a(:, :), f(:, :), g(:, :), b(:, :), x(:, :), xl(:, :), recip(:)
      integer, allocatable :: top(:)
      integer :: state, kd, in, n, nrhs, info
      logical :: envelope
      character(len=80) :: label
      state = 7
      do kd = 0, narrow_band + 2
         do in = 1, size(orders) + 2
            n = order(in, kd)
            do nrhs = 1, 3
               envelope = nrhs == 2
               call random_band(state, n, kd, a, top, envelope=envelope)
               f = spread(spread(7.0_dp, 1, kd + 1), 2, n)
               recip = spread(0.0_dp, 1, n)
               call band_ldlt(a, f, n, kd, top, info, recip)
               b = random_columns(state, n, nrhs)
               x = b
               call band_ldlt_solve(f, recip, top, n, kd, x)
               g = a
               call dpbtrf('U', n, kd, g, kd + 1, info)
               xl = b
               call dpbtrs('U', n, kd, nrhs, g, kd + 1, xl, n, info)
               write (label, '(a,i0,a,i0,a,i0,a)') 'n = ', n, ', kd = ', kd, ', columns ', nrhs, &
                  & trim(merge(', envelope', '          ', envelope))
               call check(error, maxval(abs(band_times(a, kd, x) - b))/(maxval(abs(a))*maxval(abs(x))), 0.0_dp, &
                  & 'residual, '//trim(label), abs=1.0e-14_dp)
               call check(error, maxval(abs(x - xl))/maxval(abs(xl)), 0.0_dp, 'vs dpbtrs, '//trim(label), &
                  & abs=1.0e-13_dp)
               if (allocated(error)) return
            end do
         end do
      end do
   end subroutine test_ldlt_solve

   !> The band matrix factors by Cholesky (U^T D U by the in-house loops up to
   !> narrow_band, dpbtrf's U^T U beyond: the same factor to round-off), falls
   !> back to LU when the matrix is not positive definite, and in dense mode
   !> always uses LU.
   subroutine test_factor(error)
      type(error_type), allocatable, intent(out) :: error
      type(band_matrix_type) :: mat
      real(dp), allocatable :: a(:, :), g(:, :)
      integer, allocatable :: top(:)
      integer :: state, kd, n, info, info_lapack
      character(len=64) :: label
      state = 555
      do kd = max(0, narrow_band - 2), narrow_band + 2
         n = 3*kd + 5
         write (label, '(a,i0,a,i0)') 'n = ', n, ', kd = ', kd
         call random_band(state, n, kd, a, top, envelope=mod(kd, 2) == 0)
         call band_from(a, kd, top, mat, dense=.false.)
         call mat%factor(info)
         g = a
         call dpbtrf('U', n, kd, g, kd + 1, info_lapack)
         if (kd <= narrow_band) g = ldlt_of_cholesky(g, kd)
         call check(error, info, 0, 'info, '//trim(label))
         call check(error, .not. mat%is_lu, 'Cholesky, '//trim(label))
         call check(error, maxval(abs(mat%f(1:kd + 1, :) - g))/maxval(abs(g)), 0.0_dp, &
            & 'factor vs dpbtrf, '//trim(label), abs=1.0e-13_dp)
         call check(error, mat%pivot_ratio() > 0, 'pivot ratio, '//trim(label))
         call random_band(state, n, kd, a, top, indefinite=n/2, envelope=mod(kd, 2) == 0)
         call band_from(a, kd, top, mat, dense=.false.)
         call mat%factor(info)
         call check(error, info, 0, 'LU info, '//trim(label))
         call check(error, mat%is_lu, 'LU fallback, '//trim(label))
         call band_from(a, kd, top, mat, dense=.true.)
         call mat%factor(info)
         call check(error, info, 0, 'dense info, '//trim(label))
         call check(error, mat%is_lu, 'dense LU, '//trim(label))
         if (allocated(error)) return
      end do
   end subroutine test_factor

   !> The band matrix solves A x = b with one and several right-hand sides on
   !> every path: Cholesky in-house and LAPACK, LU fallback, dense.
   subroutine test_solve(error)
      type(error_type), allocatable, intent(out) :: error
      type(band_matrix_type) :: mat
      real(dp), allocatable :: a(:, :), b(:, :), x(:, :)
      integer, allocatable :: top(:)
      integer :: state, kd, n, info, nrhs, path
      character(len=80) :: label
      character(len=8), parameter :: paths(3) = [character(len=8) :: 'Cholesky', 'band LU', 'dense LU']
      state = 4711
      do kd = max(0, narrow_band - 2), narrow_band + 2
         n = 3*kd + 5
         do path = 1, 3
            do nrhs = 1, 3, 2
               if (path == 1) then
                  call random_band(state, n, kd, a, top, envelope=nrhs == 3)
               else
                  call random_band(state, n, kd, a, top, indefinite=n/2, envelope=nrhs == 3)
               end if
               call band_from(a, kd, top, mat, dense=path == 3)
               call mat%factor(info)
               b = random_columns(state, n, nrhs)
               x = b
               call mat%solve(x)
               write (label, '(a,i0,a,i0,a,i0,a,a)') 'n = ', n, ', kd = ', kd, ', columns ', nrhs, ', ', &
                  & trim(paths(path))
               call check(error, info, 0, 'info, '//trim(label))
               call check(error, maxval(abs(band_times(a, kd, x) - b))/(maxval(abs(a))*maxval(abs(x))), 0.0_dp, &
                  & 'residual, '//trim(label), abs=1.0e-13_dp)
               if (allocated(error)) return
            end do
         end do
      end do
   end subroutine test_solve

end module test_assembly_band
