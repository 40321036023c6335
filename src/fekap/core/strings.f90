!> Small string helpers shared by the deck reader, the model, the methods' messages
!> and the command line: case, FEAP-style keyword abbreviations, numbers as text.
module fekap_strings
   use fekap_kinds, only: dp
   implicit none
   private

   public :: lower, upper, same_name, is_word_of, word_index, int_text, short_real_text, es_text

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

   !> Whether `field` names the word `word` (case-insensitive): in full, or as a
   !> prefix of at least `shortest` letters.
   pure logical function is_word_of(field, word, shortest)
      character(*), intent(in) :: field, word
      integer, intent(in) :: shortest
      is_word_of = .false.
      if (len(field) > len(word) .or. len(field) < min(shortest, len(word))) return
      is_word_of = lower(field) == lower(word(1:len(field)))
   end function is_word_of

   !> Position (1, 2, ...) of field among the blank-separated `words`; a word may be
   !> shortened to 4 letters. 0 if it is none of them.
   pure integer function word_index(field, words) result(idx)
      character(*), intent(in) :: field, words
      integer :: start, i, n
      idx = 0
      n = 0
      start = 1
      do i = 1, len(words) + 1
         if (i <= len(words)) then
            if (words(i:i) /= ' ') cycle
         end if
         n = n + 1
         if (is_word_of(field, words(start:i - 1), 4)) then
            idx = n
            return
         end if
         start = i + 1
      end do
   end function word_index

   !> An integer as text.
   pure function int_text(n) result(text)
      integer, intent(in) :: n
      character(:), allocatable :: text
      character(len=16) :: buf
      write (buf, '(i0)') n
      text = trim(buf)
   end function int_text

   !> A short text for a real, for messages: fixed notation without trailing zeros for
   !> moderate magnitudes, otherwise scientific with four digits.
   pure function short_real_text(x) result(text)
      real(dp), intent(in) :: x
      character(:), allocatable :: text
      character(len=32) :: buf
      integer :: k
      if (abs(x) < tiny(x)) then
         text = '0'
         return
      end if
      if (abs(x) >= 1.0e-3_dp .and. abs(x) < 1.0e6_dp) then
         write (buf, '(f0.6)') x
         text = trim(buf)
         k = len(text)
         do while (text(k:k) == '0')
            k = k - 1
         end do
         if (text(k:k) == '.') k = k - 1
         text = text(1:k)
         if (text(1:1) == '.') text = '0'//text
         if (text(1:2) == '-.') text = '-0'//text(2:)
      else
         write (buf, '(es11.4)') x
         text = trim(adjustl(buf))
      end if
   end function short_real_text

   !> x as esW.D writes it, except that an exponent of three digits keeps its
   !> E (esW.D writes 1e300 as 1.00000+300): then the text is esW.De3's,
   !> without its leading blank, and one character wider than W when it needs
   !> to be, rather than asterisks.
   pure function es_text(x, width, decimals) result(text)
      real(dp), intent(in) :: x
      integer, intent(in) :: width, decimals
      character(:), allocatable :: text
      character(len=80) :: buffer
      character(len=24) :: form
      write (form, '(a,i0,a,i0,a)') '(es', width, '.', decimals, ')'
      write (buffer(1:width), form) x
      text = buffer(1:width)
      ! Not a finite number, or an exponent of two digits: the E is there.
      if (.not. (x == x .and. abs(x) <= huge(x)) .or. index(text, 'E') > 0) return
      write (form, '(a,i0,a,i0,a)') '(es', width + 1, '.', decimals, 'e3)'
      write (buffer(1:width + 1), form) x
      text = buffer(1:width + 1)
      if (text(1:1) == ' ') text = text(2:)
   end function es_text

end module fekap_strings
