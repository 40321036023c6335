!> Small string helpers shared by the deck reader, the model and the command line.
module fekap_strings
   implicit none
   private

   public :: lower, upper, same_name

contains

   !> `text` in lower case (ASCII letters only).
   pure function lower(text) result(low)
      character(*), intent(in) :: text
      character(len(text)) :: low
      integer :: i
      low = text
      do i = 1, len(text)
         if (text(i:i) >= 'A' .and. text(i:i) <= 'Z') low(i:i) = achar(iachar(text(i:i)) + 32)
      end do
   end function lower

   !> `text` in upper case (ASCII letters only).
   pure function upper(text) result(up)
      character(*), intent(in) :: text
      character(len(text)) :: up
      integer :: i
      up = text
      do i = 1, len(text)
         if (text(i:i) >= 'a' .and. text(i:i) <= 'z') up(i:i) = achar(iachar(text(i:i)) - 32)
      end do
   end function upper

   !> Names compare case-insensitively.
   pure logical function same_name(a, b)
      character(*), intent(in) :: a, b
      same_name = len(a) == len(b)
      if (same_name) same_name = lower(a) == lower(b)
   end function same_name

end module fekap_strings
