!> Explicit interfaces to the LAPACK routines FEKAP calls.
module fekap_assembly_lapack
   use fekap_kinds, only: dp
   implicit none
   private

   public :: dpbtrf, dpbtrs, dgbtrf, dgbtrs, dpbcon, dgbcon, dgetrf, dgetrs, dgecon

   interface
      !> Cholesky factorisation of a symmetric positive definite band matrix.
      pure subroutine dpbtrf(uplo, n, kd, ab, ldab, info)
         import :: dp
         character, intent(in) :: uplo
         integer, intent(in) :: n, kd, ldab
         real(dp), intent(inout) :: ab(ldab, *)
         integer, intent(out) :: info
      end subroutine dpbtrf

      !> Solve with the factor of dpbtrf.
      pure subroutine dpbtrs(uplo, n, kd, nrhs, ab, ldab, b, ldb, info)
         import :: dp
         character, intent(in) :: uplo
         integer, intent(in) :: n, kd, nrhs, ldab, ldb
         real(dp), intent(in) :: ab(ldab, *)
         real(dp), intent(inout) :: b(ldb, *)
         integer, intent(out) :: info
      end subroutine dpbtrs

      !> LU factorisation with partial pivoting of a general band matrix.
      pure subroutine dgbtrf(m, n, kl, ku, ab, ldab, ipiv, info)
         import :: dp
         integer, intent(in) :: m, n, kl, ku, ldab
         real(dp), intent(inout) :: ab(ldab, *)
         integer, intent(out) :: ipiv(*)
         integer, intent(out) :: info
      end subroutine dgbtrf

      !> Solve with the factor of dgbtrf.
      pure subroutine dgbtrs(trans, n, kl, ku, nrhs, ab, ldab, ipiv, b, ldb, info)
         import :: dp
         character, intent(in) :: trans
         integer, intent(in) :: n, kl, ku, nrhs, ldab, ldb
         real(dp), intent(in) :: ab(ldab, *)
         integer, intent(in) :: ipiv(*)
         real(dp), intent(inout) :: b(ldb, *)
         integer, intent(out) :: info
      end subroutine dgbtrs

      !> Reciprocal condition number (1-norm) from the factor of dpbtrf.
      subroutine dpbcon(uplo, n, kd, ab, ldab, anorm, rcond, work, iwork, info)
         import :: dp
         character, intent(in) :: uplo
         integer, intent(in) :: n, kd, ldab
         real(dp), intent(in) :: ab(ldab, *), anorm
         real(dp), intent(out) :: rcond
         real(dp), intent(inout) :: work(*)
         integer, intent(inout) :: iwork(*)
         integer, intent(out) :: info
      end subroutine dpbcon

      !> Reciprocal condition number from the factor of dgbtrf.
      subroutine dgbcon(norm, n, kl, ku, ab, ldab, ipiv, anorm, rcond, work, iwork, info)
         import :: dp
         character, intent(in) :: norm
         integer, intent(in) :: n, kl, ku, ldab
         real(dp), intent(in) :: ab(ldab, *), anorm
         integer, intent(in) :: ipiv(*)
         real(dp), intent(out) :: rcond
         real(dp), intent(inout) :: work(*)
         integer, intent(inout) :: iwork(*)
         integer, intent(out) :: info
      end subroutine dgbcon

      !> LU factorisation with partial pivoting of a general (dense) matrix.
      pure subroutine dgetrf(m, n, a, lda, ipiv, info)
         import :: dp
         integer, intent(in) :: m, n, lda
         real(dp), intent(inout) :: a(lda, *)
         integer, intent(out) :: ipiv(*)
         integer, intent(out) :: info
      end subroutine dgetrf

      !> Solve with the factor of dgetrf.
      pure subroutine dgetrs(trans, n, nrhs, a, lda, ipiv, b, ldb, info)
         import :: dp
         character, intent(in) :: trans
         integer, intent(in) :: n, nrhs, lda, ldb
         real(dp), intent(in) :: a(lda, *)
         integer, intent(in) :: ipiv(*)
         real(dp), intent(inout) :: b(ldb, *)
         integer, intent(out) :: info
      end subroutine dgetrs

      !> Reciprocal condition number from the factor of dgetrf.
      subroutine dgecon(norm, n, a, lda, anorm, rcond, work, iwork, info)
         import :: dp
         character, intent(in) :: norm
         integer, intent(in) :: n, lda
         real(dp), intent(in) :: a(lda, *), anorm
         real(dp), intent(out) :: rcond
         real(dp), intent(inout) :: work(*)
         integer, intent(inout) :: iwork(*)
         integer, intent(out) :: info
      end subroutine dgecon
   end interface

end module fekap_assembly_lapack
