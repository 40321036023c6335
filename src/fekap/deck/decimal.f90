!> The value of a decimal number given by its significant digits and the
!> decimal exponent of its first one, correctly rounded, without the risk of
!> an overflow trap inside the run-time library (the tests run with
!> floating-point traps): the expression parser's numbers.
module fekap_deck_decimal
   use, intrinsic :: iso_fortran_env, only: int64
   use fekap_kinds, only: dp
   implicit none
   private

   public :: decimal_value

   !> Status of decimal_value: a value above huge(1.0_dp).
   integer, parameter, public :: decimal_too_large = -1

   !> 10**k, k = 0..22: every one an exact double.
   real(dp), parameter :: exact_powers(0:22) = [1.0e0_dp, 1.0e1_dp, 1.0e2_dp, 1.0e3_dp, 1.0e4_dp, 1.0e5_dp, &
      & 1.0e6_dp, 1.0e7_dp, 1.0e8_dp, 1.0e9_dp, 1.0e10_dp, 1.0e11_dp, 1.0e12_dp, 1.0e13_dp, 1.0e14_dp, 1.0e15_dp, &
      & 1.0e16_dp, 1.0e17_dp, 1.0e18_dp, 1.0e19_dp, 1.0e20_dp, 1.0e21_dp, 1.0e22_dp]

contains

   !> v = d.ddd * 10**decimal, where significant = 'dddd' (digits only, the
   !> first not zero). status: 0, decimal_too_large, or the iostat of a failed
   !> read (then v = 0).
   pure subroutine decimal_value(significant, decimal, v, status)
      character(*), intent(in) :: significant
      integer, intent(in) :: decimal
      real(dp), intent(out) :: v
      integer, intent(out) :: status
      integer :: scale, i
      integer(int64) :: significand
      character(len=16) :: exponent_text
      character(:), allocatable :: digits
      v = 0
      status = 0
      ! Most deck numbers have at most 15 digits and a small exponent: then
      ! the digits as an integer and 10**scale are exact doubles, and one
      ! product or quotient of them is the correctly rounded value, the same
      ! as the formatted read gives (Clinger's fast path), at a fraction of its
      ! cost (a 100,000-link deck has 200,000 coordinates).
      scale = decimal - (len(significant) - 1)
      if (len(significant) <= 15 .and. abs(scale) <= 22) then
         significand = 0
         do i = 1, len(significant)
            significand = 10*significand + (iachar(significant(i:i)) - iachar('0'))
         end do
         if (scale >= 0) then
            v = real(significand, dp)*exact_powers(scale)
         else
            v = real(significand, dp)/exact_powers(-scale)
         end if
         return
      end if
      if (decimal > 308 .or. (decimal == 308 .and. above_huge(significant))) then
         status = decimal_too_large
         return
      end if
      if (decimal < -400) return   ! underflows to zero
      write (exponent_text, '(i0)') decimal
      digits = significant(1:1)//'.'//significant(2:)//'e'//trim(exponent_text)
      read (digits, *, iostat=status) v
      if (status /= 0) v = 0
   end subroutine decimal_value

   !> Whether the significant digits d.ddd... of a number times 1e308 exceed
   !> huge(1.0_dp) = 1.7976931348623157e308 (a little conservatively: digits
   !> beyond these 17 that are not all zero count as too large).
   pure logical function above_huge(significant)
      character(*), intent(in) :: significant
      character(*), parameter :: top = '17976931348623157'
      character(len=len(top)) :: head
      head = significant   ! padded with blanks, compared as zeros below
      head = translate_blanks(head)
      above_huge = head > top
      if (head == top .and. len(significant) > len(top)) then
         above_huge = verify(significant(len(top) + 1:), '0') > 0
      end if
   end function above_huge

   pure function translate_blanks(text) result(out)
      character(*), intent(in) :: text
      character(len(text)) :: out
      integer :: i
      out = text
      do i = 1, len(text)
         if (out(i:i) == ' ') out(i:i) = '0'
      end do
   end function translate_blanks

end module fekap_deck_decimal
