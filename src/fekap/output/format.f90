!> Fast exact text of numbers for the output files: a real as the ES edit
!> descriptor writes it (correctly rounded, ties to even; with 17 digits the
!> text reads back to the same double), an integer as I writes it. Formatted
!> writes cost about a microsecond a number, which made writing two tracked
!> points ten times dearer than computing them.
!>
!> The digits themselves are exact: fekap_output_exact_digits.
module fekap_output_format
   use fekap_kinds, only: dp
   use fekap_strings, only: es_text
   use fekap_output_exact_digits, only: i8, power10, fast_digits, decimal_digits
   implicit none
   private

   public :: real_text, integer_text, append_real, append_integer, append_es, append_i, append_text

   !> "00" to "99": digits are produced two at a time.
   character(len=200), parameter :: digit_pairs = &
      & '0001020304050607080910111213141516171819'//'2021222324252627282930313233343536373839'// &
      & '4041424344454647484950515253545556575859'//'6061626364656667686970717273747576777879'// &
      & '8081828384858687888990919293949596979899'

contains

   !> x as es25.16e3 writes it, without leading blanks.
   pure function real_text(x) result(text)
      real(dp), intent(in) :: x
      character(:), allocatable :: text
      character(len=25) :: buffer
      integer :: n
      n = 0
      call append_real(buffer, n, x)
      text = buffer(1:n)
   end function real_text

   !> i as i0 writes it.
   pure function integer_text(i) result(text)
      integer, intent(in) :: i
      character(:), allocatable :: text
      character(len=12) :: buffer
      integer :: n
      n = 0
      call append_integer(buffer, n, i)
      text = buffer(1:n)
   end function integer_text

   !> Write real_text(x) into line after position n and advance n (no allocation).
   pure subroutine append_real(line, n, x)
      character(*), intent(inout) :: line
      integer, intent(inout) :: n
      real(dp), intent(in) :: x
      integer(i8) :: significand
      integer :: e10
      logical :: done
      call fast_digits(x, 17, significand, e10, done)
      if (done) then
         call put_17_digits(line, n, x < 0, significand, e10)
         return
      else if (x == 0) then
         ! Exact zeros are common (a constant rate, a fixed coordinate).
         if (sign(1.0_dp, x) < 0) call append_text(line, n, '-')
         line(n + 1:n + 23) = '0.0000000000000000E+000'
         n = n + 23
         return
      end if
      call put_es(line, n, x, 16, 3, 0, done)
      if (.not. done) then
         call append_es(line, n, x, 25, 16, 3)
         call squeeze(line, n, 25)
      end if
   end subroutine append_real

   !> Write [-]d.dddddddddddddddd E+ddd (the text of es25.16e3) of the 17
   !> digits `significand` and the decimal exponent |e10| < 1000 after
   !> position n; advance n. Every position is fixed but the sign's.
   pure subroutine put_17_digits(line, n, negative, significand, e10)
      character(*), intent(inout) :: line
      integer, intent(inout) :: n
      logical, intent(in) :: negative
      integer(i8), intent(in) :: significand
      integer, intent(in) :: e10
      integer(i8) :: high
      integer :: lead, k
      ! The minus sign is written, and kept or overwritten by the digits
      ! (a branch on the sign would be mispredicted half the time).
      line(n + 1:n + 1) = '-'
      n = n + merge(1, 0, negative)
      high = significand/100000000_i8
      lead = int(high/100000000_i8)
      line(n + 1:n + 1) = achar(iachar('0') + lead)
      line(n + 2:n + 2) = '.'
      call put_8_digits(line(n + 3:n + 10), int(high - lead*100000000_i8))
      call put_8_digits(line(n + 11:n + 18), int(significand - high*100000000_i8))
      line(n + 19:n + 20) = merge('E-', 'E+', e10 < 0)
      k = abs(e10)
      line(n + 21:n + 21) = achar(iachar('0') + k/100)
      line(n + 22:n + 23) = digit_pairs(2*mod(k, 100) + 1:2*mod(k, 100) + 2)
      n = n + 23
   end subroutine put_17_digits

   !> Write integer_text(i) into line after position n and advance n.
   pure subroutine append_integer(line, n, i)
      character(*), intent(inout) :: line
      integer, intent(inout) :: n
      integer, intent(in) :: i
      character(len=12) :: buffer
      integer :: first, k, v, p
      if (i >= 0) then
         ! Its number of digits, then the digits from the last at their
         ! places, in 32-bit arithmetic (no buffer and no copy).
         k = 1
         do while (k < 10)
            if (i < power10(k)) exit
            k = k + 1
         end do
         v = i
         do p = n + k, n + 1, -1
            line(p:p) = achar(iachar('0') + mod(v, 10))
            v = v/10
         end do
         n = n + k
         return
      end if
      call integer_digits(i, buffer, first)
      ! A character at a time: a substring of variable length is a call of
      ! memmove, dearer than the few digits of a step number.
      do k = first, len(buffer)
         line(n + 1:n + 1) = buffer(k:k)
         n = n + 1
      end do
   end subroutine append_integer

   !> Write x as the edit descriptor esW.D (exponent_digits = 0) or esW.DeE
   !> writes it, W characters right-justified, after position n; advance n.
   pure subroutine append_es(line, n, x, width, decimals, exponent_digits)
      character(*), intent(inout) :: line
      integer, intent(inout) :: n
      real(dp), intent(in) :: x
      integer, intent(in) :: width, decimals, exponent_digits
      character(len=64) :: buffer
      character(len=16) :: form
      logical :: done
      call put_es(line, n, x, decimals, exponent_digits, width, done)
      if (done) return
      if (exponent_digits > 0) then
         write (form, '(a,i0,a,i0,a,i0,a)') '(es', width, '.', decimals, 'e', exponent_digits, ')'
         write (buffer(1:width), form) x
         call append_text(line, n, buffer(1:width))
      else
         call append_text(line, n, es_text(x, width, decimals))
      end if
   end subroutine append_es

   !> Write i as the edit descriptor iW writes it after position n; advance n.
   pure subroutine append_i(line, n, i, width)
      character(*), intent(inout) :: line
      integer, intent(inout) :: n
      integer, intent(in) :: i, width
      character(len=12) :: buffer
      integer :: first, v, p
      ! A count or a step number (0 <= i < 10**8, width >= 8, or a single
      ! digit): its digits from the field's end in 32-bit arithmetic, then
      ! the blanks, each a character at a time (the general path makes the
      ! digits in a buffer and copies them; twice the instructions).
      if (i >= 0 .and. (i < 10 .and. width >= 1 .or. i < 100000000 .and. width >= 8)) then
         v = i
         p = n + width
         do
            line(p:p) = achar(iachar('0') + mod(v, 10))
            v = v/10
            p = p - 1
            if (v == 0) exit
         end do
         do while (p > n)
            line(p:p) = ' '
            p = p - 1
         end do
         n = n + width
         return
      end if
      call integer_digits(i, buffer, first)
      call pad_and_put(line, n, buffer(first:), width)
   end subroutine append_i

   !> Write text into line after position n and advance n.
   pure subroutine append_text(line, n, text)
      character(*), intent(inout) :: line
      integer, intent(inout) :: n
      character(*), intent(in) :: text
      line(n + 1:n + len(text)) = text
      n = n + len(text)
   end subroutine append_text

   !> Write x as esW.D(eE) writes it after position n, right-justified in
   !> `width` characters (width = 0: without the leading blanks), and advance
   !> n; done = .false. (nothing written) when x is outside the exact path.
   pure subroutine put_es(line, n, x, decimals, exponent_digits, width, done)
      character(*), intent(inout) :: line
      integer, intent(inout) :: n
      real(dp), intent(in) :: x
      integer, intent(in) :: decimals, exponent_digits, width
      logical, intent(out) :: done
      integer(i8) :: significand
      integer :: e10, k, length, p
      logical :: negative
      significand = 0
      e10 = 0
      done = .true.
      if (x /= 0) then
         call fast_digits(x, decimals + 1, significand, e10, done)
         if (.not. done) call decimal_digits(abs(x), decimals + 1, significand, e10, done)
      end if
      k = abs(e10)
      ! An exponent wider than eE asked for: the formatted write's asterisks.
      if (exponent_digits > 0 .and. exponent_digits <= 18) done = done .and. k < power10(exponent_digits)
      if (.not. done) return
      negative = x < 0 .or. (x == 0 .and. sign(1.0_dp, x) < 0)
      ! [-]d.ddd then E+dd(d) with eE, else E+dd, or +ddd when two digits do
      ! not suffice: four characters either way. Written in place, no copy.
      length = merge(1, 0, negative) + decimals + 2 + merge(2 + exponent_digits, 4, exponent_digits > 0)
      if (width > 0) then
         if (length > width) then
            do p = n + 1, n + width
               line(p:p) = '*'
            end do
            n = n + width
            return
         end if
         do p = n + 1, n + width - length
            line(p:p) = ' '
         end do
         n = n + width - length
      end if
      if (negative) then
         line(n + 1:n + 1) = '-'
         n = n + 1
      end if
      call put_digits(line(n + 1:n + decimals + 2), significand, decimals + 1)
      n = n + decimals + 2
      if (exponent_digits > 0 .or. k <= 99) then
         line(n + 1:n + 1) = 'E'
         n = n + 1
      end if
      line(n + 1:n + 1) = merge('-', '+', e10 < 0)
      n = n + 1
      call put_decimal(line, n, k, merge(exponent_digits, merge(2, 3, k <= 99), exponent_digits > 0))
   end subroutine put_es

   !> The digits of i as i0 writes them, in buffer(first:).
   pure subroutine integer_digits(i, buffer, first)
      integer, intent(in) :: i
      character(len=12), intent(out) :: buffer
      integer, intent(out) :: first
      integer(i8) :: v
      ! In 64 bits, so that -huge(i) - 1 has an absolute value.
      v = abs(int(i, i8))
      first = len(buffer) + 1
      do
         first = first - 1
         buffer(first:first) = achar(iachar('0') + int(mod(v, 10_i8)))
         v = v/10
         if (v == 0) exit
      end do
      if (i < 0) then
         first = first - 1
         buffer(first:first) = '-'
      end if
   end subroutine integer_digits

   !> Write text right-justified in `width` characters (asterisks if it does
   !> not fit, as a formatted write does) after position n; advance n.
   pure subroutine pad_and_put(line, n, text, width)
      character(*), intent(inout) :: line
      integer, intent(inout) :: n
      character(*), intent(in) :: text
      integer, intent(in) :: width
      integer :: k
      if (len(text) > width) then
         line(n + 1:n + width) = repeat('*', width)
         n = n + width
         return
      end if
      ! A character at a time (no memset and memmove calls for a few
      ! characters: append_integer).
      do k = 1, width - len(text)
         line(n + 1:n + 1) = ' '
         n = n + 1
      end do
      do k = 1, len(text)
         line(n + 1:n + 1) = text(k:k)
         n = n + 1
      end do
   end subroutine pad_and_put

   !> Drop the leading blanks of the last `width` characters written before n.
   pure subroutine squeeze(line, n, width)
      character(*), intent(inout) :: line
      integer, intent(inout) :: n
      integer, intent(in) :: width
      integer :: k, blanks
      k = verify(line(n - width + 1:n), ' ')
      blanks = k - 1
      if (blanks <= 0) return
      line(n - width + 1:n - blanks) = line(n - width + 1 + blanks:n)
      n = n - blanks
   end subroutine squeeze

   !> The ndigits digits of significand as d.ddd (ndigits + 1 characters).
   pure subroutine put_digits(text, significand, ndigits)
      character(len=*), intent(inout) :: text
      integer(i8), intent(in) :: significand
      integer, intent(in) :: ndigits
      integer(i8) :: rest, high
      integer :: pos, pair, lead
      if (ndigits == 17) then
         ! The CSV's 17 digits as 1 + 8 + 8: two short chains, not one of eight.
         high = significand/100000000_i8
         lead = int(high/100000000_i8)
         text(1:1) = achar(iachar('0') + lead)
         text(2:2) = '.'
         call put_8_digits(text(3:10), int(high - lead*100000000_i8))
         call put_8_digits(text(11:18), int(significand - high*100000000_i8))
         return
      end if
      ! From the last digit, two at a time.
      rest = significand
      pos = ndigits + 1
      do while (pos >= 4)
         pair = int(mod(rest, 100_i8))
         rest = rest/100
         text(pos - 1:pos) = digit_pairs(2*pair + 1:2*pair + 2)
         pos = pos - 2
      end do
      if (pos == 3) then
         text(3:3) = achar(iachar('0') + int(mod(rest, 10_i8)))
         rest = rest/10
      end if
      text(1:1) = achar(iachar('0') + int(rest))
      text(2:2) = '.'
   end subroutine put_digits

   !> The 8 digits of 0 <= v < 10**8, leading zeros included. y = v/10**6 in
   !> 52-bit fixed point holds the first two digits in its integer part; its
   !> fraction times 100 the next two, and so on: one product a pair, no
   !> division. (The multiplier ceil(2**52/10**6) makes y too large by less
   !> than 10**8 2**-52 units; after the three products by 100 that is below
   !> 0.03 of a unit of the last pair, and the exact fractions are multiples
   !> of 10**-6, 10**-4, 10**-2: no digit comes out wrong.)
   pure subroutine put_8_digits(text, v)
      character(len=8), intent(inout) :: text
      integer, intent(in) :: v
      integer(i8), parameter :: fraction_mask = shiftl(1_i8, 52) - 1, multiplier = 4503599628_i8
      integer(i8) :: y
      integer :: pair
      y = int(v, i8)*multiplier
      pair = int(shiftr(y, 52))
      text(1:2) = digit_pairs(2*pair + 1:2*pair + 2)
      y = iand(y, fraction_mask)*100
      pair = int(shiftr(y, 52))
      text(3:4) = digit_pairs(2*pair + 1:2*pair + 2)
      y = iand(y, fraction_mask)*100
      pair = int(shiftr(y, 52))
      text(5:6) = digit_pairs(2*pair + 1:2*pair + 2)
      y = iand(y, fraction_mask)*100
      pair = int(shiftr(y, 52))
      text(7:8) = digit_pairs(2*pair + 1:2*pair + 2)
   end subroutine put_8_digits

   !> Write the last `width` decimal digits of v >= 0 after position n; advance n.
   pure subroutine put_decimal(line, n, v, width)
      character(*), intent(inout) :: line
      integer, intent(inout) :: n
      integer, intent(in) :: v, width
      integer :: k, rest
      if (width == 2 .and. v < 100) then
         line(n + 1:n + 2) = digit_pairs(2*v + 1:2*v + 2)
         n = n + 2
         return
      else if (width == 3 .and. v < 1000) then
         line(n + 1:n + 1) = achar(iachar('0') + v/100)
         line(n + 2:n + 3) = digit_pairs(2*mod(v, 100) + 1:2*mod(v, 100) + 2)
         n = n + 3
         return
      end if
      rest = v
      do k = n + width, n + 1, -1
         line(k:k) = achar(iachar('0') + mod(rest, 10))
         rest = rest/10
      end do
      n = n + width
   end subroutine put_decimal

end module fekap_output_format
