!> Symmetric band matrices: assembly storage, Cholesky factorisation and,
!> when the matrix is not positive definite (the geometric stiffness makes
!> Newton tangents indefinite), a pivoting band LU (LAPACK dgbtrf/dgbtrs) of
!> the same matrix. LAPACK has no symmetric indefinite band solver.
!>
!> Half-bandwidths up to `narrow_band` are factored by the in-house loops
!> band_ldlt and band_ldlt_solve below, the square-root-free Cholesky
!> A = U^T D U (U unit upper triangular, in the upper band storage, D on its
!> diagonal) in Crout's form within each column's envelope (profile, as
!> FEAP's datri); wider bands by LAPACK dpbtrf/dpbtrs (A = U^T U). The loops
!> exist because LAPACK makes BLAS calls per column (dscal and dsyr in
!> dpbtf2, two dtbsv per right-hand side), and for a small model (Example 1:
!> 9 equations, kd = 5) that overhead costs as much as the arithmetic. Such a
!> narrow factorisation or solve is a chain of dependent operations, row
!> after row; without the square root, with a unit diagonal, with the sums of
!> Crout's form and within the envelope (Example 1: 21 entries above the
!> diagonal instead of the band's 30) the chain is shorter. With the
!> reference BLAS the loops stay faster up to kd of about 100, but above
!> kd = 32 dpbtrf switches to its blocked algorithm, whose level-3 BLAS an
!> optimised BLAS makes much faster. So narrow_band = 32: every model in
!> decks/ and the scissor lifts take the loops. The timings behind this are
!> in docs/performance.md ("Narrow band loops against LAPACK").
!>
!> A matrix is symmetric unless something is added to it by add_general (a
!> damping force's exact tangent in dynamics): its lower triangle is then the
!> upper's mirror plus `asym`, and it is factored by the band LU at once.
!>
!> A matrix made with `dense=.true.` keeps the same band assembly storage but
!> factors and solves the matrix as a full n x n array with dgetrf/dgetrs: a
!> reference for the cost of the band solver, not a production path.
module fekap_linalg_band
   use fekap_kinds, only: dp
   use fekap_linalg_lapack, only: dpbtrf, dpbtrs, dgbtrf, dgbtrs, dgetrf, dgetrs, dlacn2, norm_estimate_step
   implicit none
   private

   public :: band_matrix_type, new_band_matrix
   public :: narrow_band, band_ldlt, band_ldlt_solve

   !> Largest half-bandwidth factored and solved by the in-house loops rather
   !> than LAPACK: dpbtrf's own switch to its blocked algorithm (see the module header).
   integer, parameter :: narrow_band = 32

   !> An n x n symmetric matrix of half-bandwidth kd and its factor.
   type :: band_matrix_type
      integer :: n = 0
      integer :: kd = 0
      !> Upper band as LAPACK stores it: A(i, j), i <= j, at a(kd + 1 + i - j, j).
      real(dp), allocatable :: a(:, :)
      !> Whether the lower triangle is the upper's mirror (nothing added by
      !> add_general since the last zero).
      logical :: symmetric = .true.
      !> A(j, i) - A(i, j) for i <= j at asym(kd + 1 + i - j, j), while not symmetric.
      real(dp), allocatable :: asym(:, :)
      !> Factor: Cholesky (U^T D U up to narrow_band, U^T U beyond) in rows
      !> 1:kd+1, or band LU in rows 1:3*kd+1; allocated by the first
      !> factorisation, with 3*kd+1 rows from the first LU on.
      real(dp), allocatable :: f(:, :)
      integer, allocatable :: ipiv(:)
      !> Whether the factor in f is an LU (the fallback) rather than a Cholesky factor.
      logical :: is_lu = .false.
      !> Dense mode: factor the full matrix with dgetrf into fd (every factor is an LU).
      logical :: dense = .false.
      !> Dense LU factor (dense mode only).
      real(dp), allocatable :: fd(:, :)
      !> Diagonal of the factored matrix, to measure its pivots against.
      real(dp), allocatable :: diag(:)
      !> 1 / D(j) of an in-house factor (band_ldlt_solve).
      real(dp), allocatable :: recip(:)
      !> Envelope: the first row of column j that may be nonzero (j - kd by
      !> default). Entries above it must stay zero; the in-house loops skip them.
      integer, allocatable :: top(:)
      !> Work of the condition estimate (see band_rcond): two vectors and signs.
      real(dp), allocatable :: cond_work(:, :)
      integer, allocatable :: cond_sign(:)
   contains
      procedure :: zero => band_zero
      procedure :: add => band_add
      procedure :: add_general => band_add_general
      procedure :: factor => band_factor
      procedure :: solve => band_solve
      procedure :: pivot_ratio => band_pivot_ratio
      !> The pivot of one column of the factor, on the matrix's scale.
      procedure :: column_pivot => band_column_pivot
      procedure :: rcond => band_rcond
   end type band_matrix_type

contains

   !> Allocate an n x n band matrix of half-bandwidth kd (all storage but the
   !> factor's, once).
   pure subroutine new_band_matrix(self, n, kd, dense, top)
      type(band_matrix_type), intent(out) :: self
      integer, intent(in) :: n, kd
      !> Factor as a full matrix with dgetrf/dgetrs (default .false.).
      logical, intent(in), optional :: dense
      !> The envelope (first row of each column that the assembly may fill),
      !> within the band; default the band itself, max(1, j - kd).
      integer, intent(in), optional :: top(:)
      integer :: j
      self%n = n
      self%kd = kd
      if (present(dense)) self%dense = dense
      ! The factor's storage f is allocated by the first factorisation
      ! (band_factor): a run in the square-root form never factors K, whose
      ! LU storage of (3 kd + 1) n numbers was the largest array of a large
      ! lift's run (docs/performance.md, "Scale in the square-root form"), and
      ! a Cholesky factor needs only kd + 1 rows.
      if (self%dense) then
         allocate (self%a(kd + 1, n), self%f(0, 0), self%fd(n, n), source=0.0_dp)
      else
         allocate (self%a(kd + 1, n), source=0.0_dp)
      end if
      allocate (self%ipiv(n), source=0)
      allocate (self%diag(n), self%recip(n), source=0.0_dp)
      allocate (self%top(n))
      allocate (self%cond_work(n, 2), source=0.0_dp)
      allocate (self%cond_sign(n), source=0)
      do j = 1, n
         self%top(j) = max(1, j - kd)
         if (present(top)) self%top(j) = min(j, max(self%top(j), top(j)))
      end do
   end subroutine new_band_matrix

   pure subroutine band_zero(self)
      class(band_matrix_type), intent(inout) :: self
      ! As one block: `self%a = 0` on the polymorphic self clears it column by column.
      call zero(self%a, size(self%a))
      if (.not. self%symmetric) call zero(self%asym, size(self%asym))
      self%symmetric = .true.
   end subroutine band_zero

   !> x(1:n) = 0.
   pure subroutine zero(x, n)
      integer, intent(in) :: n
      real(dp), intent(out) :: x(n)
      x = 0
   end subroutine zero

   !> A(i, j) += value, for the upper triangle (i <= j); entries with i > j
   !> are ignored, since the lower triangle is their mirror image.
   pure subroutine band_add(self, i, j, value)
      class(band_matrix_type), intent(inout) :: self
      integer, intent(in) :: i, j
      real(dp), intent(in) :: value
      if (i <= j) self%a(self%kd + 1 + i - j, j) = self%a(self%kd + 1 + i - j, j) + value
   end subroutine band_add

   !> A(i, j) += value for any entry in the band (i > j too): the matrix is
   !> then not symmetric until the next zero, and is factored by band LU.
   pure subroutine band_add_general(self, i, j, value)
      class(band_matrix_type), intent(inout) :: self
      integer, intent(in) :: i, j
      real(dp), intent(in) :: value
      integer :: kd
      kd = self%kd
      if (.not. allocated(self%asym)) allocate (self%asym(kd + 1, self%n), source=0.0_dp)
      self%symmetric = .false.
      if (i <= j) then
         self%a(kd + 1 + i - j, j) = self%a(kd + 1 + i - j, j) + value
         ! The lower mirror A(j, i) stays.
         if (i < j) self%asym(kd + 1 + i - j, j) = self%asym(kd + 1 + i - j, j) - value
      else
         self%asym(kd + 1 + j - i, i) = self%asym(kd + 1 + j - i, i) + value
      end if
   end subroutine band_add_general

   !> A(i, j) for i > j: the upper's mirror, plus asym when not symmetric.
   pure real(dp) function lower_entry(self, i, j) result(aij)
      type(band_matrix_type), intent(in) :: self
      integer, intent(in) :: i, j
      aij = self%a(self%kd + 1 + j - i, i)
      if (.not. self%symmetric) aij = aij + self%asym(self%kd + 1 + j - i, i)
   end function lower_entry

   !> Factor the matrix: Cholesky first; if it is not positive definite (or not
   !> symmetric: at once), band LU with partial pivoting. On return `info` is 0, or the equation at
   !> which the matrix is singular (LU pivot zero).
   pure subroutine band_factor(self, info)
      class(band_matrix_type), intent(inout) :: self
      integer, intent(out) :: info
      integer :: i, j, kd, ld
      kd = self%kd
      self%diag = self%a(kd + 1, :)
      if (self%dense) then
         call dense_factor(self, info)
         return
      end if
      self%is_lu = .false.
      if (.not. allocated(self%f)) allocate (self%f(kd + 1, self%n), source=0.0_dp)
      ld = size(self%f, 1)
      if (self%symmetric) then
         if (kd <= narrow_band) then
            call band_ldlt(self%a, self%f, self%n, kd, self%top, info, self%recip)
         else
            self%f(1:kd + 1, :) = self%a
            call dpbtrf('U', self%n, kd, self%f, ld, info)
         end if
         if (info == 0) return
      end if
      ! Not positive definite (or not symmetric): expand to general band storage, rows kd+1:3kd+1.
      self%is_lu = .true.
      if (size(self%f, 1) < 3*kd + 1) then
         deallocate (self%f)
         allocate (self%f(3*kd + 1, self%n))
         ld = size(self%f, 1)
      end if
      self%f = 0
      do j = 1, self%n
         do i = max(1, j - kd), min(self%n, j + kd)
            if (i <= j) then
               self%f(2*kd + 1 + i - j, j) = self%a(kd + 1 + i - j, j)
            else
               self%f(2*kd + 1 + i - j, j) = lower_entry(self, i, j)
            end if
         end do
      end do
      call dgbtrf(self%n, self%n, kd, kd, self%f, ld, self%ipiv, info)
   end subroutine band_factor

   !> Dense mode: expand the symmetric band into the full matrix and factor it
   !> by LU with partial pivoting (dgetrf).
   pure subroutine dense_factor(self, info)
      type(band_matrix_type), intent(inout) :: self
      integer, intent(out) :: info
      integer :: i, j, kd
      kd = self%kd
      self%is_lu = .true.
      self%fd = 0
      do j = 1, self%n
         do i = max(1, j - kd), j
            self%fd(i, j) = self%a(kd + 1 + i - j, j)
            self%fd(j, i) = self%a(kd + 1 + i - j, j)
            if (.not. self%symmetric) self%fd(j, i) = self%fd(j, i) + self%asym(kd + 1 + i - j, j)
         end do
      end do
      call dgetrf(self%n, self%n, self%fd, self%n, self%ipiv, info)
   end subroutine dense_factor

   !> Solve A x = b in place with the factor (b may hold several columns).
   pure subroutine band_solve(self, b)
      class(band_matrix_type), intent(in) :: self
      real(dp), contiguous, intent(inout) :: b(:, :)
      integer :: info
      if (self%n == 0) return
      if (self%dense) then
         call dgetrs('N', self%n, size(b, 2), self%fd, self%n, self%ipiv, b, size(b, 1), info)
      else if (self%is_lu) then
         call dgbtrs('N', self%n, self%kd, self%kd, size(b, 2), self%f, size(self%f, 1), self%ipiv, &
            & b, size(b, 1), info)
      else if (self%kd <= narrow_band) then
         if (size(b, 2) == 1) then
            call ldlt_solve_vector(self%f, size(self%f, 1), self%recip, self%top, self%n, self%kd, b(:, 1))
         else
            call band_ldlt_solve(self%f, self%recip, self%top, self%n, self%kd, b)
         end if
      else
         call dpbtrs('U', self%n, self%kd, size(b, 2), self%f, size(self%f, 1), b, size(b, 1), info)
      end if
   end subroutine band_solve

   !> Square-root-free Cholesky factorisation A = U^T D U of the symmetric
   !> positive definite band matrix in a (upper band, A(i, j) at
   !> a(kd + 1 + i - j, j)) whose column j is zero above row top(j), its
   !> envelope (j - kd <= top(j) <= j): U(i, j) (unit diagonal) into
   !> f(kd + 1 + i - j, j), D(j) into f(kd + 1, j), and 1/D(j) into recip; f
   !> above the envelope is not referenced (U keeps A's envelope: fill-in stays
   !> below the first nonzero of each column). Crout's column-by-column form,
   !> as FEAP's datri and Bathe's COLSOL: with G = D U, G(i, j) = A(i, j) -
   !> sum_k U(k, i) G(k, j), U(i, j) = G(i, j) / D(i) and D(j) = A(j, j) -
   !> sum_i G(i, j) U(i, j), sums over the envelopes: each sum runs down two
   !> columns in memory order, and its products are independent, so a narrow
   !> factorisation is fewer dependent operations in a row than in dpbtf2's
   !> right-looking form; and A is read where it is, without a copy into f
   !> first. info = 0, or the first j at which the pivot D(j) is not positive
   !> (f is then partly factored), as from dpbtrf.
   pure subroutine band_ldlt(a, f, n, kd, top, info, recip)
      !> The band (leading dimension kd + 1).
      real(dp), contiguous, intent(in) :: a(:, :)
      !> U and D on return (leading dimension at least kd + 1).
      real(dp), contiguous, intent(inout) :: f(:, :)
      integer, intent(in) :: n, kd
      !> First row of each column's envelope.
      integer, intent(in) :: top(:)
      integer, intent(out) :: info
      !> 1 / D(j), for band_ldlt_solve.
      real(dp), intent(out) :: recip(:)
      real(dp) :: d, g, s
      integer :: i, j, k, oi, oj
      info = 0
      do j = 1, n
         ! A(i, j) at a(oj + i, j) and f(oj + i, j); U(k, i) at f(oi + k, i).
         oj = kd + 1 - j
         do i = top(j), j - 1
            oi = kd + 1 - i
            s = 0
            ! The loops of this module run a few times each (kd = 5 in Example 1):
            ! vectorised, their set-up costs more than it saves (docs/performance.md).
            !GCC$ unroll 1
            !GCC$ novector
            do k = max(top(i), top(j)), i - 1
               s = s + f(oi + k, i)*f(oj + k, j)
            end do
            f(oj + i, j) = a(oj + i, j) - s
         end do
         d = a(kd + 1, j)
         !GCC$ unroll 1
         !GCC$ novector
         do i = top(j), j - 1
            g = f(oj + i, j)
            f(oj + i, j) = g*recip(i)
            d = d - g*f(oj + i, j)
         end do
         if (.not. d > 0) then
            info = j
            return
         end if
         f(kd + 1, j) = d
         recip(j) = 1/d
      end do
   end subroutine band_ldlt

   !> Solve U^T D U x = b in place with the factor of band_ldlt, column by
   !> column of b (ldlt_solve_vector).
   pure subroutine band_ldlt_solve(f, recip, top, n, kd, b)
      real(dp), contiguous, intent(in) :: f(:, :)
      !> 1 / D(j), from band_ldlt.
      real(dp), intent(in) :: recip(:)
      !> First row of each column's envelope, as given to band_ldlt.
      integer, intent(in) :: top(:)
      integer, intent(in) :: n, kd
      !> Right-hand sides on entry (columns), solutions on return.
      real(dp), contiguous, intent(inout) :: b(:, :)
      integer :: k
      do k = 1, size(b, 2)
         call ldlt_solve_vector(f, size(f, 1), recip, top, n, kd, b(:, k))
      end do
   end subroutine band_ldlt_solve

   !> Solve U^T D U x = b in place for one right-hand side: U^T y = b by dot
   !> products down the columns of U, then U x = D^-1 y by columns of U, both
   !> within the envelope top. With U's unit diagonal D^-1 is a product by the
   !> kept reciprocals, off the chain. Explicit-shape arrays: a small model's
   !> step makes several solves (Newton, the drive response, the rates, the
   !> condition estimate's), and array descriptors would cost as much as the
   !> arithmetic of 9 equations.
   pure subroutine ldlt_solve_vector(f, ld, recip, top, n, kd, b)
      integer, intent(in) :: ld, n, kd
      real(dp), intent(in) :: f(ld, n), recip(n)
      integer, intent(in) :: top(n)
      real(dp), intent(inout) :: b(n)
      real(dp) :: s, t
      integer :: i, j, oj
      do j = 1, n
         oj = kd + 1 - j
         s = 0
         !GCC$ unroll 1
         !GCC$ novector
         do i = top(j), j - 1
            s = s + f(oj + i, j)*b(i)
         end do
         b(j) = b(j) - s
      end do
      do j = 1, n
         b(j) = b(j)*recip(j)
      end do
      do j = n, 1, -1
         oj = kd + 1 - j
         t = b(j)
         !GCC$ unroll 1
         !GCC$ novector
         do i = top(j), j - 1
            b(i) = b(i) - f(oj + i, j)*t
         end do
      end do
   end subroutine ldlt_solve_vector

   !> The pivot of column j of the factor, on the matrix's scale: |U(j,j)| for
   !> LU (and the dense factor), D(j) for U^T D U, U(j,j)^2 for U^T U.
   pure real(dp) function band_column_pivot(self, j) result(pivot)
      class(band_matrix_type), intent(in) :: self
      integer, intent(in) :: j
      if (self%dense) then
         pivot = abs(self%fd(j, j))
      else if (self%is_lu) then
         pivot = abs(self%f(2*self%kd + 1, j))
      else if (self%kd <= narrow_band) then
         pivot = self%f(self%kd + 1, j)
      else
         pivot = self%f(self%kd + 1, j)**2
      end if
   end function band_column_pivot

   !> Smallest pivot of the factor relative to the matrix's own diagonal entry:
   !> min_j U(j,j)^2 / A(j,j) for Cholesky (D(j) / A(j,j) for U^T D U),
   !> min_j |U(j,j)| / |A(j,j)| for LU.
   !> Invariant under a diagonal scaling of the unknowns, so stiffness ratios
   !> do not enter; it tends to 0 as the matrix becomes singular.
   pure real(dp) function band_pivot_ratio(self) result(ratio)
      class(band_matrix_type), intent(in) :: self
      integer :: j
      real(dp) :: pivot
      ratio = 0
      ! Never factored: no pivots (as a zero factor's).
      if (.not. allocated(self%f)) return
      ratio = 1
      if (.not. self%dense .and. .not. self%is_lu .and. self%kd <= narrow_band) then
         ! U^T D U: band_column_pivot's D(j), without a call per column.
         do j = 1, self%n
            if (abs(self%diag(j)) > 0) then
               ratio = min(ratio, self%f(self%kd + 1, j)/abs(self%diag(j)))
            else
               ratio = 0
            end if
         end do
         return
      end if
      do j = 1, self%n
         pivot = band_column_pivot(self, j)
         if (abs(self%diag(j)) > 0) then
            ratio = min(ratio, pivot/abs(self%diag(j)))
         else
            ratio = 0
         end if
      end do
   end function band_pivot_ratio

   !> Reciprocal condition number of the factored matrix in the 1-norm,
   !> 1 / (||A||_1 ||A^-1||_1), with ||A^-1||_1 estimated by LAPACK's dlacn2
   !> from solves with the factor (the estimate of dpbcon and dgbcon, for
   !> every kind of factor this type makes; A is symmetric, so A^-T = A^-1):
   !> usually 4 or 5 solves. 0 when the factor has a zero pivot. Unlike the
   !> pivot ratio it tracks the smallest singular value (within a small factor).
   !> For a matrix made non-symmetric by add_general (dynamics, which does not
   !> ask for it) it is rougher: the norm of the upper triangle's mirror, A^-1 for A^-T.
   subroutine band_rcond(self, rcond)
      class(band_matrix_type), intent(inout) :: self
      real(dp), intent(out) :: rcond
      real(dp) :: anorm, est, column
      integer :: i, j, kase, isave(3), kd
      rcond = 0
      if (self%n == 0) then
         rcond = 1
         return
      end if
      ! Never factored: singular as far as the factor tells (a zero pivot).
      if (.not. allocated(self%f)) return
      if (.not. self%dense .and. .not. self%is_lu .and. self%kd <= narrow_band) then
         call ldlt_rcond(self, rcond)
         return
      end if
      kd = self%kd
      ! ||A||_1 of the symmetric band from its upper triangle.
      anorm = 0
      do j = 1, self%n
         column = 0
         do i = max(1, j - kd), j
            column = column + abs(self%a(kd + 1 + i - j, j))
         end do
         do i = j + 1, min(self%n, j + kd)
            column = column + abs(self%a(kd + 1 + j - i, i))
         end do
         anorm = max(anorm, column)
      end do
      if (.not. anorm > 0) return
      ! A zero pivot: the matrix is singular, its estimate stays 0.
      do j = 1, self%n
         if (.not. band_column_pivot(self, j) > 0) return
      end do
      est = 0
      kase = 0
      do
         call dlacn2(self%n, self%cond_work(:, 2), self%cond_work(:, 1), self%cond_sign, est, kase, isave)
         if (kase == 0) exit
         call self%solve(self%cond_work(:, 1:1))
      end do
      if (est > 0) rcond = (1/anorm)/est
   end subroutine band_rcond

   !> band_rcond of an in-house U^T D U factor (band_ldlt): the same norm and
   !> the same estimate, Higham's iteration as LAPACK's dlacn2 makes it
   !> (fekap_linalg_lapack's norm_estimate_step: the same vectors, sums,
   !> maxima and stops in the same order, so the same number), with the
   !> solves, sums and maxima as loops rather than calls to LAPACK and BLAS,
   !> whose overheads cost more than the arithmetic of a small model's
   !> estimate, which every step of a run makes.
   subroutine ldlt_rcond(self, rcond)
      type(band_matrix_type), intent(inout) :: self
      real(dp), intent(out) :: rcond
      real(dp) :: anorm, column, est
      integer :: i, j, n, kd, kase, isave(3)
      rcond = 0
      n = self%n
      kd = self%kd
      associate (a => self%a, x => self%cond_work(:, 1), isgn => self%cond_sign)
         ! ||A||_1 from the upper triangle, within the envelope (the entries
         ! above it are zero, so the sums are band_rcond's).
         anorm = 0
         do j = 1, n
            column = 0
            do i = self%top(j), j
               column = column + abs(a(kd + 1 + i - j, j))
            end do
            do i = j + 1, min(n, j + kd)
               if (self%top(i) <= j) column = column + abs(a(kd + 1 + j - i, i))
            end do
            anorm = max(anorm, column)
         end do
         if (.not. anorm > 0) return
         do j = 1, n
            if (.not. self%f(kd + 1, j) > 0) return
         end do
         ! dlacn2's iteration (Hager and Higham), the solves with this factor
         ! serving for A^-1 and A^-T alike (A is symmetric).
         est = 0
         kase = 0
         do
            call norm_estimate_step(n, x, isgn, est, kase, isave)
            if (kase == 0) exit
            call solve(x)
         end do
         if (est > 0) rcond = (1/anorm)/est
      end associate
   contains
      subroutine solve(b)
         real(dp), intent(inout) :: b(:)
         call ldlt_solve_vector(self%f, size(self%f, 1), self%recip, self%top, n, kd, b(1:n))
      end subroutine solve
   end subroutine ldlt_rcond

end module fekap_linalg_band
