!> Explicit interfaces to the LAPACK routines FEKAP calls, and thin
!> assumed-shape wrappers of the dense ones that derive the leading dimensions
!> from the arrays.
module fekap_linalg_lapack
   use fekap_kinds, only: dp
   implicit none
   private

   public :: dpbtrf, dpbtrs, dgbtrf, dgbtf2, dgbtrs, dgetrf, dgetrs, dgeqp3, dlacn2
   public :: dense_lu_factor, dense_lu_solve, dense_pivoted_qr
   public :: band_lu_factor, band_lu_solve, band_lu_blocked, band_lu_factor_loops, band_lu_given_pivots, norm_estimate_step

   interface
      !> Cholesky factorisation of a symmetric positive definite band matrix.
      pure subroutine dpbtrf(uplo, n, kd, ab, ldab, info)
         import :: dp
         implicit none
         character, intent(in) :: uplo
         integer, intent(in) :: n, kd, ldab
         real(dp), intent(inout) :: ab(ldab, *)
         integer, intent(out) :: info
      end subroutine dpbtrf

      !> Solve with the factor of dpbtrf.
      pure subroutine dpbtrs(uplo, n, kd, nrhs, ab, ldab, b, ldb, info)
         import :: dp
         implicit none
         character, intent(in) :: uplo
         integer, intent(in) :: n, kd, nrhs, ldab, ldb
         real(dp), intent(in) :: ab(ldab, *)
         real(dp), intent(inout) :: b(ldb, *)
         integer, intent(out) :: info
      end subroutine dpbtrs

      !> LU factorisation with partial pivoting of a general band matrix.
      pure subroutine dgbtrf(m, n, kl, ku, ab, ldab, ipiv, info)
         import :: dp
         implicit none
         integer, intent(in) :: m, n, kl, ku, ldab
         real(dp), intent(inout) :: ab(ldab, *)
         integer, intent(out) :: ipiv(*)
         integer, intent(out) :: info
      end subroutine dgbtrf

      !> dgbtrf's unblocked code (the one it calls for narrow bands).
      pure subroutine dgbtf2(m, n, kl, ku, ab, ldab, ipiv, info)
         import :: dp
         implicit none
         integer, intent(in) :: m, n, kl, ku, ldab
         real(dp), intent(inout) :: ab(ldab, *)
         integer, intent(out) :: ipiv(*)
         integer, intent(out) :: info
      end subroutine dgbtf2

      !> LAPACK's tuning parameters (ispec 1: the block size of routine `name`).
      integer function ilaenv(ispec, name, opts, n1, n2, n3, n4)
         implicit none
         integer, intent(in) :: ispec, n1, n2, n3, n4
         character(*), intent(in) :: name, opts
      end function ilaenv

      !> Solve with the factor of dgbtrf.
      pure subroutine dgbtrs(trans, n, kl, ku, nrhs, ab, ldab, ipiv, b, ldb, info)
         import :: dp
         implicit none
         character, intent(in) :: trans
         integer, intent(in) :: n, kl, ku, nrhs, ldab, ldb
         real(dp), intent(in) :: ab(ldab, *)
         integer, intent(in) :: ipiv(*)
         real(dp), intent(inout) :: b(ldb, *)
         integer, intent(out) :: info
      end subroutine dgbtrs

      !> LU factorisation with partial pivoting of a general (dense) matrix.
      pure subroutine dgetrf(m, n, a, lda, ipiv, info)
         import :: dp
         implicit none
         integer, intent(in) :: m, n, lda
         real(dp), intent(inout) :: a(lda, *)
         integer, intent(out) :: ipiv(*)
         integer, intent(out) :: info
      end subroutine dgetrf

      !> Solve with the factor of dgetrf.
      pure subroutine dgetrs(trans, n, nrhs, a, lda, ipiv, b, ldb, info)
         import :: dp
         implicit none
         character, intent(in) :: trans
         integer, intent(in) :: n, nrhs, lda, ldb
         real(dp), intent(in) :: a(lda, *)
         integer, intent(in) :: ipiv(*)
         real(dp), intent(inout) :: b(ldb, *)
         integer, intent(out) :: info
      end subroutine dgetrs

      !> QR factorisation with column pivoting (rank-revealing).
      subroutine dgeqp3(m, n, a, lda, jpvt, tau, work, lwork, info)
         import :: dp
         implicit none
         integer, intent(in) :: m, n, lda, lwork
         real(dp), intent(inout) :: a(lda, *)
         integer, intent(inout) :: jpvt(*)
         real(dp), intent(out) :: tau(*)
         real(dp), intent(inout) :: work(*)
         integer, intent(out) :: info
      end subroutine dgeqp3

      !> Estimate of the 1-norm of a matrix by reverse communication (Hager and
      !> Higham; the estimator inside dpbcon, dgbcon and dgecon): call with kase
      !> = 0, then, while kase /= 0, overwrite x by A x (kase = 1) or A^T x
      !> (kase = 2) and call again; est is the estimate.
      pure subroutine dlacn2(n, v, x, isgn, est, kase, isave)
         import :: dp
         implicit none
         integer, intent(in) :: n
         real(dp), intent(inout) :: v(*), x(*)
         integer, intent(inout) :: isgn(*)
         real(dp), intent(inout) :: est
         integer, intent(inout) :: kase
         integer, intent(inout) :: isave(3)
      end subroutine dlacn2
   end interface

contains

   !> LU factorisation with partial pivoting of the square matrix a (dgetrf).
   !> info > 0: U(info, info) is exactly zero.
   subroutine dense_lu_factor(a, ipiv, info)
      !> The matrix on entry, its L and U factors on return.
      real(dp), contiguous, intent(inout) :: a(:, :)
      !> Row interchanges.
      integer, contiguous, intent(out) :: ipiv(:)
      integer, intent(out) :: info
      call dgetrf(size(a, 1), size(a, 2), a, max(1, size(a, 1)), ipiv, info)
   end subroutine dense_lu_factor

   !> Solve a x = b with the factors from dense_lu_factor (dgetrs); b becomes x.
   subroutine dense_lu_solve(a, ipiv, b, info)
      real(dp), contiguous, intent(in) :: a(:, :)
      integer, contiguous, intent(in) :: ipiv(:)
      real(dp), contiguous, intent(inout) :: b(:)
      integer, intent(out) :: info
      call dgetrs('N', size(a, 1), 1, a, max(1, size(a, 1)), ipiv, b, max(1, size(b)), info)
   end subroutine dense_lu_solve

   !> LU factorisation with partial pivoting of the square band matrix in ab
   !> (dgbtrf): kl subdiagonals, ku superdiagonals, A(i, j) at
   !> ab(kl + ku + 1 + i - j, j) with rows 1:kl of ab free for the fill.
   !> info > 0: U(info, info) is exactly zero.
   !> With `blocked` (band_lu_blocked of the matrix's shape, found once) the
   !> choice dgbtrf makes in every call is made by the caller: .false. calls
   !> its unblocked code dgbtf2 directly (the same arithmetic, without
   !> dgbtrf's query of ilaenv, which costs as much as the factorisation of
   !> a narrow band).
   subroutine band_lu_factor(ab, kl, ku, ipiv, info, blocked)
      !> (2 kl + ku + 1, n): the matrix on entry, its factors on return.
      real(dp), contiguous, intent(inout) :: ab(:, :)
      integer, intent(in) :: kl, ku
      integer, contiguous, intent(out) :: ipiv(:)
      integer, intent(out) :: info
      logical, intent(in), optional :: blocked
      if (present(blocked)) then
         if (.not. blocked) then
            call dgbtf2(size(ab, 2), size(ab, 2), kl, ku, ab, size(ab, 1), ipiv, info)
            return
         end if
      end if
      call dgbtrf(size(ab, 2), size(ab, 2), kl, ku, ab, size(ab, 1), ipiv, info)
   end subroutine band_lu_factor

   !> dgbtf2 (dgbtrf's unblocked code, which it takes for narrow bands) in
   !> loops: the same operations in the same order (the fill cleared, idamax's
   !> first largest magnitude as pivot, dswap's interchange along the rows,
   !> dscal's product with the pivot's reciprocal, dger's update a + x (-y)
   !> column by column, skipping a zero y), so the same factor and pivots to
   !> the last bit; without the BLAS call per column, whose set-up costs more
   !> than the arithmetic of a band a few entries wide (whose loops run a few
   !> times each, so they are neither unrolled nor vectorised: the set-up
   !> would cost more than it saves). ab as band_lu_factor's. With `first`
   !> (fekap_linalg_band_lu's refactor_nonzeros stopped there), columns 1 to
   !> first - 1 are eliminated already, with the pivots in ipiv(1:first - 1):
   !> the loops go on from column first, as they would have from their own.
   pure subroutine band_lu_factor_loops(ab, kl, ku, ipiv, info, first)
      real(dp), contiguous, intent(inout) :: ab(:, :)
      integer, intent(in) :: kl, ku
      integer, contiguous, intent(inout) :: ipiv(:)
      integer, intent(out) :: info
      integer, intent(in), optional :: first
      integer :: start
      start = 1
      if (present(first)) start = first
      call band_loops(ab, kl, ku, ipiv, info, start, start - 1, size(ab, 2))
   end subroutine band_lu_factor_loops

   !> Columns 1 to last of ab (as band_lu_factor_loops takes it) eliminated
   !> with the pivots ipiv(1:last) given (not idamax's choice): the loops'
   !> operations with those pivots, so that band_lu_factor_loops can go on
   !> from column last + 1 (fekap_linalg_band_lu's refactor_nonzeros, where
   !> its last pivots stop serving). Each given pivot must be nonzero.
   pure subroutine band_lu_given_pivots(ab, kl, ku, ipiv, last)
      real(dp), contiguous, intent(inout) :: ab(:, :)
      integer, intent(in) :: kl, ku, last
      integer, contiguous, intent(inout) :: ipiv(:)
      integer :: info
      if (last < 1) return
      call band_loops(ab, kl, ku, ipiv, info, 1, last, last)
   end subroutine band_lu_given_pivots

   !> dgbtf2's loops over columns start to last (columns 1 to start - 1
   !> eliminated already), the pivots of columns up to given those of ipiv.
   pure subroutine band_loops(ab, kl, ku, ipiv, info, start, given, last)
      real(dp), contiguous, intent(inout) :: ab(:, :)
      integer, intent(in) :: kl, ku, start, given, last
      integer, contiguous, intent(inout) :: ipiv(:)
      integer, intent(out) :: info
      real(dp) :: temp, largest, recip
      integer :: n, kv, i, j, jj, jp, ju, km
      n = size(ab, 2)
      kv = ku + kl
      info = 0
      ju = 1
      do j = 1, start - 1
         ju = max(ju, min(ku + ipiv(j), n))
      end do
      if (start == 1) then
         do j = ku + 2, min(kv, n)
            do i = kv - j + 2, kl
               ab(i, j) = 0
            end do
         end do
      end if
      do j = start, last
         if (j + kv <= n) then
            do i = 1, kl
               ab(i, j + kv) = 0
            end do
         end if
         km = min(kl, n - j)
         if (j <= given) then
            jp = ipiv(j) - j + 1
         else
            jp = 1
            largest = abs(ab(kv + 1, j))
            !GCC$ unroll 1
            !GCC$ novector
            do i = 2, km + 1
               if (abs(ab(kv + i, j)) > largest) then
                  jp = i
                  largest = abs(ab(kv + i, j))
               end if
            end do
            ipiv(j) = jp + j - 1
         end if
         if (ab(kv + jp, j) /= 0) then
            ju = max(ju, min(j + ku + jp - 1, n))
            if (jp /= 1) then
               ! Row j + jp - 1 and row j over columns j to ju.
               !GCC$ unroll 1
               !GCC$ novector
               do jj = 0, ju - j
                  temp = ab(kv + jp - jj, j + jj)
                  ab(kv + jp - jj, j + jj) = ab(kv + 1 - jj, j + jj)
                  ab(kv + 1 - jj, j + jj) = temp
               end do
            end if
            if (km > 0) then
               recip = 1/ab(kv + 1, j)
               !GCC$ unroll 1
               !GCC$ novector
               do i = kv + 2, kv + 1 + km
                  ab(i, j) = recip*ab(i, j)
               end do
               ! Rows j + 1 to j + km of columns j + 1 to ju, less the
               ! multipliers times row j (U(j, j + jj) at ab(kv + 1 - jj, j + jj)).
               do jj = 1, ju - j
                  if (ab(kv + 1 - jj, j + jj) /= 0) then
                     temp = -ab(kv + 1 - jj, j + jj)
                     !GCC$ unroll 1
                     !GCC$ novector
                     do i = 1, km
                        ab(kv + 1 + i - jj, j + jj) = ab(kv + 1 + i - jj, j + jj) + ab(kv + 1 + i, j)*temp
                     end do
                  end if
               end do
            end if
         else if (info == 0) then
            info = j
         end if
      end do
   end subroutine band_loops

   !> dlacn2 (the 1-norm estimator of dgbcon, Hager and Higham) in loops, by
   !> the same reverse communication: call with kase = 0, then, while kase /=
   !> 0, overwrite x by A^-1 x (kase = 1) or A^-T x (kase = 2) and call again;
   !> est is the estimate of ||A^-1||_1. The same vectors, sums (dasum's, in
   !> order), maxima (idamax's first largest) and stops in the same order as
   !> dlacn2, so the same estimate to the last bit, without its BLAS calls.
   !> isave(1) is the point to resume at, isave(2) the index of the last
   !> unit vector (0 before the first), isave(3) the iteration, as dlacn2's.
   !>
   !> `start` (a column, 1 to n; ignored, dlacn2's start taken, outside
   !> that or for n = 1): begin instead at the unit vector e_start, as
   !> dlacn2's second iteration begins at the column its first one chose,
   !> with no sign vector to repeat: the last unit vector of the last
   !> estimate of a nearby matrix (isave(2) on its return). Where the
   !> gradient z = A^-T sign(A^-1 e_start) has its largest entry at start,
   !> the estimate ends after one solve with A^-T and two with A^-1 (the last
   !> for the alternating vector), where dlacn2 makes four or five; otherwise
   !> it iterates on as dlacn2 does, up to the same itmax. Each value it takes
   !> is ||A^-1 v||_1 / ||v||_1 for a vector v, so it is still a lower bound
   !> of ||A^-1||_1 from the same local search (Higham, Accuracy and
   !> Stability of Numerical Algorithms, 2002, sec. 15.3), from another
   !> start: not dlacn2's value to the bit.
   subroutine norm_estimate_step(n, x, isgn, est, kase, isave, start)
      integer, intent(in) :: n
      real(dp), intent(inout) :: x(:)
      integer, intent(inout) :: isgn(:)
      real(dp), intent(inout) :: est
      integer, intent(inout) :: kase
      integer, intent(inout) :: isave(3)
      integer, intent(in), optional :: start
      !> dlacn2's limit on its main iterations.
      integer, parameter :: itmax = 5
      real(dp) :: estold, altsgn
      integer :: i, jlast
      if (kase == 0) then
         isave(2) = 0
         if (present(start)) then
            if (start >= 1 .and. start <= n .and. n > 1) then
               ! No sign vector yet (0 matches no sign), no estimate to grow from.
               isgn(1:n) = 0
               est = 0
               isave(2) = start
               isave(3) = 2
               call unit_vector()
               return
            end if
         end if
         x(1:n) = 1/real(n, dp)
         kase = 1
         isave(1) = 1
         return
      end if
      select case (isave(1))
      case (1)
         if (n == 1) then
            est = abs(x(1))
            kase = 0
            return
         end if
         est = asum(x)
         call signs()
         kase = 2
         isave(1) = 2
         return
      case (2)
         isave(2) = first_largest(x)
         isave(3) = 2
         call unit_vector()
         return
      case (3)
         estold = est
         est = asum(x)
         do i = 1, n
            if (merge(1, -1, x(i) >= 0) /= isgn(i)) then
               ! A new sign vector: go on unless the estimate did not grow.
               if (est <= estold) exit
               call signs()
               kase = 2
               isave(1) = 4
               return
            end if
         end do
         ! A repeated sign vector (converged), or no growth (cycling).
         call alternating()
         return
      case (4)
         jlast = isave(2)
         isave(2) = first_largest(x)
         if (x(jlast) /= abs(x(isave(2))) .and. isave(3) < itmax) then
            isave(3) = isave(3) + 1
            call unit_vector()
            return
         end if
         call alternating()
         return
      case default
         ! The alternating vector: a lower bound that catches what the iteration can miss.
         est = max(est, 2*(asum(x)/real(3*n, dp)))
         kase = 0
      end select
   contains
      !> dasum: the magnitudes summed in order.
      pure real(dp) function asum(b) result(total)
         real(dp), intent(in) :: b(:)
         integer :: k
         total = 0
         do k = 1, n
            total = total + abs(b(k))
         end do
      end function asum
      !> idamax: the first index of the largest magnitude.
      pure integer function first_largest(b) result(at)
         real(dp), intent(in) :: b(:)
         real(dp) :: largest
         integer :: k
         at = 1
         largest = abs(b(1))
         do k = 2, n
            if (abs(b(k)) > largest) then
               at = k
               largest = abs(b(k))
            end if
         end do
      end function first_largest
      !> x = sign(x) (+1 at zero) and the signs as integers.
      subroutine signs()
         integer :: k
         do k = 1, n
            if (x(k) >= 0) then
               x(k) = 1
            else
               x(k) = -1
            end if
            isgn(k) = nint(x(k))
         end do
      end subroutine signs
      !> x = e_j, j = isave(2), for A^-1.
      subroutine unit_vector()
         x(1:n) = 0
         x(isave(2)) = 1
         kase = 1
         isave(1) = 3
      end subroutine unit_vector
      !> x = (1, -(1 + 1/(n - 1)), ...), for A^-1.
      subroutine alternating()
         integer :: k
         altsgn = 1
         do k = 1, n
            x(k) = altsgn*(1 + real(k - 1, dp)/real(n - 1, dp))
            altsgn = -altsgn
         end do
         kase = 1
         isave(1) = 5
      end subroutine alternating
   end subroutine norm_estimate_step

   !> Whether dgbtrf factors an n x n band matrix of kl sub- and ku
   !> superdiagonals with its blocked code: its own test, the block size
   !> ilaenv gives (at most dgbtrf's nbmax, 64) above 1 and at most kl.
   logical function band_lu_blocked(n, kl, ku) result(blocked)
      integer, intent(in) :: n, kl, ku
      integer, parameter :: nbmax = 64
      integer :: nb
      nb = min(ilaenv(1, 'DGBTRF', ' ', n, n, kl, ku), nbmax)
      blocked = .not. (nb <= 1 .or. nb > kl)
   end function band_lu_blocked

   !> Solve A x = b with the factors from band_lu_factor (dgbtrs); b becomes x.
   subroutine band_lu_solve(ab, kl, ku, ipiv, b, info)
      real(dp), contiguous, intent(in) :: ab(:, :)
      integer, intent(in) :: kl, ku
      integer, contiguous, intent(in) :: ipiv(:)
      real(dp), contiguous, intent(inout) :: b(:)
      integer, intent(out) :: info
      call dgbtrs('N', size(ab, 2), kl, ku, 1, ab, size(ab, 1), ipiv, b, max(1, size(b)), info)
   end subroutine band_lu_solve

   !> QR factorisation with column pivoting of a (dgeqp3): a P = Q R.
   !> On return the upper triangle of a holds R and jpvt the column order.
   subroutine dense_pivoted_qr(a, jpvt, info)
      real(dp), contiguous, intent(inout) :: a(:, :)
      !> Column k of a P is column jpvt(k) of the original a.
      integer, contiguous, intent(out) :: jpvt(:)
      integer, intent(out) :: info
      real(dp), allocatable :: tau(:), work(:)
      real(dp) :: query(1)
      integer :: m, n
      m = size(a, 1)
      n = size(a, 2)
      jpvt = 0
      allocate (tau(max(1, min(m, n))))
      call dgeqp3(m, n, a, max(1, m), jpvt, tau, query, -1, info)
      if (info /= 0) return
      allocate (work(max(1, int(query(1)))))
      call dgeqp3(m, n, a, max(1, m), jpvt, tau, work, size(work), info)
   end subroutine dense_pivoted_qr

end module fekap_linalg_lapack
