!> Overflow-safe arithmetic of deck values: each operation is checked before
!> it is carried out, so that no infinity or overflow trap is ever computed
!> (the tests run with floating-point traps); a result that would not be
!> finite is reported instead (ok = .false., c = 0).
module fekap_deck_safe_arithmetic
   use fekap_kinds, only: dp
   implicit none
   private

   public :: safe_add, safe_multiply, safe_divide

contains

   !> a + b, or ok = .false. if it would overflow.
   pure subroutine safe_add(a, b, c, ok_)
      real(dp), intent(in) :: a, b
      real(dp), intent(out) :: c
      logical, intent(out) :: ok_
      ! Halving is exact at this end of the range, so a/2 + b/2 rounds like a + b.
      c = a/2 + b/2
      ok_ = abs(c) <= huge(c)/2
      c = 0
      if (ok_) c = a + b
   end subroutine safe_add

   !> a * b, or ok = .false. if it would overflow.
   pure subroutine safe_multiply(a, b, c, ok_)
      real(dp), intent(in) :: a, b
      real(dp), intent(out) :: c
      logical, intent(out) :: ok_
      integer :: e
      c = 0
      ok_ = .true.
      if (a == 0 .or. b == 0) return
      e = exponent(a) + exponent(b)
      ok_ = e <= maxexponent(a)
      if (ok_ .and. e >= maxexponent(a) - 1) then
         c = (a/4)*b   ! below 2**1022: cannot overflow
         ok_ = abs(c) <= huge(c)/4
      end if
      c = 0
      if (ok_) c = a*b
   end subroutine safe_multiply

   !> a / b, or ok = .false. if b is zero or the quotient would overflow.
   pure subroutine safe_divide(a, b, c, ok_)
      real(dp), intent(in) :: a, b
      real(dp), intent(out) :: c
      logical, intent(out) :: ok_
      integer :: e
      c = 0
      ok_ = b /= 0
      if (.not. ok_ .or. a == 0) return
      e = exponent(a) - exponent(b)
      ok_ = e <= maxexponent(a)
      if (ok_ .and. e >= maxexponent(a) - 1) then
         c = (a/4)/b   ! below 2**1023: cannot overflow
         ok_ = abs(c) <= huge(c)/4
      end if
      c = 0
      if (ok_) c = a/b
   end subroutine safe_divide

end module fekap_deck_safe_arithmetic
