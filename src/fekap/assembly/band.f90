!> Symmetric band matrices: assembly storage, LAPACK Cholesky factorisation
!> (dpbtrf/dpbtrs) and, when the matrix is not positive definite (the
!> geometric stiffness makes Newton tangents indefinite), a pivoting band LU
!> (dgbtrf/dgbtrs) of the same matrix. LAPACK has no symmetric indefinite
!> band solver.
!>
!> A matrix made with `dense=.true.` keeps the same band assembly storage but
!> factors and solves the matrix as a full n x n array with dgetrf/dgetrs: a
!> reference for the cost of the band solver, not a production path.
module fekap_assembly_band
   use fekap_kinds, only: dp
   use fekap_assembly_lapack, only: dpbtrf, dpbtrs, dgbtrf, dgbtrs, dgetrf, dgetrs
   implicit none
   private

   public :: band_matrix_type, new_band_matrix

   !> An n x n symmetric matrix of half-bandwidth kd and its factor.
   type :: band_matrix_type
      integer :: n = 0
      integer :: kd = 0
      !> Upper band as LAPACK stores it: A(i, j), i <= j, at a(kd + 1 + i - j, j).
      real(dp), allocatable :: a(:, :)
      !> Factor: Cholesky in rows 1:kd+1, or band LU in rows 1:3*kd+1.
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
   contains
      procedure :: zero => band_zero
      procedure :: add => band_add
      procedure :: factor => band_factor
      procedure :: solve => band_solve
      procedure :: pivot_ratio => band_pivot_ratio
   end type band_matrix_type

contains

   !> Allocate an n x n band matrix of half-bandwidth kd (all storage, once).
   pure subroutine new_band_matrix(self, n, kd, dense)
      type(band_matrix_type), intent(out) :: self
      integer, intent(in) :: n, kd
      !> Factor as a full matrix with dgetrf/dgetrs (default .false.).
      logical, intent(in), optional :: dense
      self%n = n
      self%kd = kd
      if (present(dense)) self%dense = dense
      if (self%dense) then
         allocate (self%a(kd + 1, n), self%f(0, 0), self%fd(n, n), source=0.0_dp)
      else
         allocate (self%a(kd + 1, n), self%f(3*kd + 1, n), source=0.0_dp)
      end if
      allocate (self%ipiv(n), source=0)
      allocate (self%diag(n), source=0.0_dp)
   end subroutine new_band_matrix

   pure subroutine band_zero(self)
      class(band_matrix_type), intent(inout) :: self
      self%a = 0
   end subroutine band_zero

   !> A(i, j) += value, for the upper triangle (i <= j); entries with i > j
   !> are ignored, since the lower triangle is their mirror image.
   pure subroutine band_add(self, i, j, value)
      class(band_matrix_type), intent(inout) :: self
      integer, intent(in) :: i, j
      real(dp), intent(in) :: value
      if (i <= j) self%a(self%kd + 1 + i - j, j) = self%a(self%kd + 1 + i - j, j) + value
   end subroutine band_add

   !> Factor the matrix: Cholesky first; if it is not positive definite, band
   !> LU with partial pivoting. On return `info` is 0, or the equation at
   !> which the matrix is singular (LU pivot zero).
   pure subroutine band_factor(self, info)
      class(band_matrix_type), intent(inout) :: self
      integer, intent(out) :: info
      integer :: i, j, kd, ld
      kd = self%kd
      ld = size(self%f, 1)
      self%diag = self%a(kd + 1, :)
      if (self%dense) then
         call dense_factor(self, info)
         return
      end if
      self%f(1:kd + 1, :) = self%a
      self%is_lu = .false.
      call dpbtrf('U', self%n, kd, self%f, ld, info)
      if (info == 0) return
      ! Not positive definite: expand to general band storage, rows kd+1:3kd+1.
      self%is_lu = .true.
      self%f = 0
      do j = 1, self%n
         do i = max(1, j - kd), min(self%n, j + kd)
            if (i <= j) then
               self%f(2*kd + 1 + i - j, j) = self%a(kd + 1 + i - j, j)
            else
               self%f(2*kd + 1 + i - j, j) = self%a(kd + 1 + j - i, i)
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
         end do
      end do
      call dgetrf(self%n, self%n, self%fd, self%n, self%ipiv, info)
   end subroutine dense_factor

   !> Solve A x = b in place with the factor (b may hold several columns).
   pure subroutine band_solve(self, b)
      class(band_matrix_type), intent(in) :: self
      real(dp), intent(inout) :: b(:, :)
      integer :: info
      if (self%n == 0) return
      if (self%dense) then
         call dgetrs('N', self%n, size(b, 2), self%fd, self%n, self%ipiv, b, size(b, 1), info)
      else if (self%is_lu) then
         call dgbtrs('N', self%n, self%kd, self%kd, size(b, 2), self%f, size(self%f, 1), self%ipiv, &
            & b, size(b, 1), info)
      else
         call dpbtrs('U', self%n, self%kd, size(b, 2), self%f, size(self%f, 1), b, size(b, 1), info)
      end if
   end subroutine band_solve

   !> Smallest pivot of the factor relative to the matrix's own diagonal entry:
   !> min_j U(j,j)^2 / A(j,j) for Cholesky, min_j |U(j,j)| / |A(j,j)| for LU.
   !> Invariant under a diagonal scaling of the unknowns, so stiffness ratios
   !> do not enter; it tends to 0 as the matrix becomes singular.
   pure real(dp) function band_pivot_ratio(self) result(ratio)
      class(band_matrix_type), intent(in) :: self
      integer :: j
      real(dp) :: pivot
      ratio = 1
      do j = 1, self%n
         if (self%dense) then
            pivot = abs(self%fd(j, j))
         else if (self%is_lu) then
            pivot = abs(self%f(2*self%kd + 1, j))
         else
            pivot = self%f(self%kd + 1, j)**2
         end if
         if (abs(self%diag(j)) > 0) then
            ratio = min(ratio, pivot/abs(self%diag(j)))
         else
            ratio = 0
         end if
      end do
   end function band_pivot_ratio

end module fekap_assembly_band
