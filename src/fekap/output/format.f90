!> Fast exact text of numbers for the output files: a real as the ES edit
!> descriptor writes it (correctly rounded, ties to even; with 17 digits the
!> text reads back to the same double), an integer as I writes it. Formatted
!> writes cost about a microsecond a number, which made writing two tracked
!> points ten times dearer than computing them.
!>
!> The n significant digits D of |x| = m 2**e (m < 2**53) with decimal
!> exponent E are D = round(m 2**e 10**k) = round(m 5**k 2**(e + k)),
!> k = n - 1 - E, computed exactly in 128-bit integers where they suffice
!> (-21 <= k <= 31, |x| < 1e38: m 5**31 < 2**125); other values go through
!> the formatted write.
module fekap_output_format
   use fekap_kinds, only: dp
   implicit none
   private

   public :: real_text, integer_text, append_real, append_integer, append_es, append_i

   integer, parameter :: i8 = selected_int_kind(18), i16 = selected_int_kind(38)
   !> Powers of five of the exact integer path, and its largest decimal exponent.
   integer, parameter :: min_k = -21, max_k = 31, max_exponent10 = 37
   !> Powers of five and of ten in 128 bits (kept out of the inner loops).
   integer(i16), parameter :: power5(0:max_k) = [ &
      & 1_i16, 5_i16, 25_i16, 125_i16, 625_i16, 3125_i16, 15625_i16, 78125_i16, 390625_i16, &
      & 1953125_i16, 9765625_i16, 48828125_i16, 244140625_i16, 1220703125_i16, 6103515625_i16, &
      & 30517578125_i16, 152587890625_i16, 762939453125_i16, 3814697265625_i16, 19073486328125_i16, &
      & 95367431640625_i16, 476837158203125_i16, 2384185791015625_i16, 11920928955078125_i16, &
      & 59604644775390625_i16, 298023223876953125_i16, 1490116119384765625_i16, &
      & 7450580596923828125_i16, 37252902984619140625_i16, 186264514923095703125_i16, &
      & 931322574615478515625_i16, 4656612873077392578125_i16]
   integer(i16), parameter :: power10(0:17) = [ &
      & 1_i16, 10_i16, 100_i16, 1000_i16, 10000_i16, 100000_i16, 1000000_i16, 10000000_i16, &
      & 100000000_i16, 1000000000_i16, 10000000000_i16, 100000000000_i16, 1000000000000_i16, &
      & 10000000000000_i16, 100000000000000_i16, 1000000000000000_i16, 10000000000000000_i16, &
      & 100000000000000000_i16]

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
      call append_es(line, n, x, 25, 16, 3)
      call squeeze(line, n, 25)
   end subroutine append_real

   !> Write integer_text(i) into line after position n and advance n.
   pure subroutine append_integer(line, n, i)
      character(*), intent(inout) :: line
      integer, intent(inout) :: n
      integer, intent(in) :: i
      call append_i(line, n, i, 12)
      call squeeze(line, n, 12)
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
      integer(i16) :: significand
      integer :: e10, k, used
      logical :: exact
      exact = .false.
      significand = 0
      e10 = 0
      if (x /= 0) call decimal_digits(abs(x), decimals + 1, significand, e10, exact)
      if (x /= 0 .and. .not. exact) then
         if (exponent_digits > 0) then
            write (form, '(a,i0,a,i0,a,i0,a)') '(es', width, '.', decimals, 'e', exponent_digits, ')'
         else
            write (form, '(a,i0,a,i0,a)') '(es', width, '.', decimals, ')'
         end if
         write (buffer(1:width), form) x
         call put(line, n, buffer(1:width))
         return
      end if
      ! [-]d.ddd followed by E+dd(d) (or +ddd when two digits do not suffice).
      used = 0
      if (x < 0 .or. (x == 0 .and. sign(1.0_dp, x) < 0)) call put(buffer, used, '-')
      call put_digits(significand, decimals + 1, buffer(used + 1:used + decimals + 2))
      used = used + decimals + 2
      k = abs(e10)
      if (exponent_digits > 0 .or. k <= 99) call put(buffer, used, 'E')
      call put(buffer, used, merge('-', '+', e10 < 0))
      call put_decimal(buffer, used, k, merge(exponent_digits, merge(2, 3, k <= 99), exponent_digits > 0))
      call pad_and_put(line, n, buffer(1:used), width)
   end subroutine append_es

   !> Write i as the edit descriptor iW writes it after position n; advance n.
   pure subroutine append_i(line, n, i, width)
      character(*), intent(inout) :: line
      integer, intent(inout) :: n
      integer, intent(in) :: i, width
      character(len=12) :: buffer
      integer :: k, v
      if (i == -huge(i) - 1) then
         write (buffer, '(i12)') i
         k = verify(buffer, ' ')
      else
         k = len(buffer) + 1
         v = abs(i)
         do
            k = k - 1
            buffer(k:k) = achar(iachar('0') + mod(v, 10))
            v = v/10
            if (v == 0) exit
         end do
         if (i < 0) then
            k = k - 1
            buffer(k:k) = '-'
         end if
      end if
      call pad_and_put(line, n, buffer(k:), width)
   end subroutine append_i

   !> Write text right-justified in `width` characters (asterisks if it does
   !> not fit, as a formatted write does) after position n; advance n.
   pure subroutine pad_and_put(line, n, text, width)
      character(*), intent(inout) :: line
      integer, intent(inout) :: n
      character(*), intent(in) :: text
      integer, intent(in) :: width
      integer :: k
      if (len(text) > width) then
         do k = 1, width
            line(n + k:n + k) = '*'
         end do
         n = n + width
         return
      end if
      do k = 1, width - len(text)
         line(n + k:n + k) = ' '
      end do
      n = n + width - len(text)
      call put(line, n, text)
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

   !> Write text into line after position n and advance n.
   pure subroutine put(line, n, text)
      character(*), intent(inout) :: line
      integer, intent(inout) :: n
      character(*), intent(in) :: text
      line(n + 1:n + len(text)) = text
      n = n + len(text)
   end subroutine put

   !> The `ndigits` significant digits of x > 0, correctly rounded (ties to
   !> even), and its decimal exponent; exact = .false. outside the integer path.
   pure subroutine decimal_digits(x, ndigits, significand, e10, exact)
      real(dp), intent(in) :: x
      integer, intent(in) :: ndigits
      integer(i16), intent(out) :: significand
      integer, intent(out) :: e10
      logical, intent(out) :: exact
      integer(i16) :: m, low, high
      integer :: e, pass, k
      logical :: round_up
      exact = .false.
      significand = 0
      e10 = 0
      if (.not. (x >= tiny(x) .and. x <= huge(x)) .or. ndigits > 17) return
      low = power10(ndigits - 1)
      high = power10(ndigits)
      m = int(scale(fraction(x), digits(x)), i16)
      e = exponent(x) - digits(x)
      e10 = floor(log10(x))
      ! log10 may miss by one next to a power of ten: the truncated digits
      ! tell, and the exponent is corrected before rounding.
      do pass = 1, 3
         k = ndigits - 1 - e10
         if (k < min_k .or. k > max_k .or. e10 > max_exponent10) return
         call scaled_quotient(m, e, k, significand, round_up)
         if (significand >= high) then
            e10 = e10 + 1
         else if (significand < low) then
            e10 = e10 - 1
         else
            if (round_up) significand = significand + 1
            ! 9.99...95 rounds to the next power of ten.
            if (significand == high) then
               significand = low
               e10 = e10 + 1
            end if
            exact = e10 <= max_exponent10
            return
         end if
      end do
   end subroutine decimal_digits

   !> q = floor(m 5**k 2**(e + k)), and whether rounding it to nearest (ties
   !> to even) adds one, for the ranges of decimal_digits.
   pure subroutine scaled_quotient(m, e, k, q, round_up)
      integer(i16), intent(in) :: m
      integer, intent(in) :: e, k
      integer(i16), intent(out) :: q
      logical, intent(out) :: round_up
      integer(i16) :: num, den, rem
      integer :: p2
      num = m
      den = 1
      if (k >= 0) then
         num = num*power5(k)
      else
         den = power5(-k)
      end if
      p2 = e + k
      if (p2 >= 0) then
         num = shiftl(num, p2)
      else
         den = shiftl(den, -p2)
      end if
      q = num/den
      rem = num - q*den
      round_up = 2*rem > den .or. (2*rem == den .and. mod(q, 2_i16) == 1)
   end subroutine scaled_quotient

   !> The ndigits digits of significand as d.ddd (ndigits + 1 characters).
   pure subroutine put_digits(significand, ndigits, text)
      integer(i16), intent(in) :: significand
      integer, intent(in) :: ndigits
      character(len=*), intent(out) :: text
      integer(i8) :: rest
      integer :: k
      ! The first digit, then the others from a 64-bit remainder (< 10**16).
      rest = int(mod(significand, power10(ndigits - 1)), i8)
      text(1:1) = achar(iachar('0') + int(significand/power10(ndigits - 1)))
      text(2:2) = '.'
      do k = ndigits + 1, 3, -1
         text(k:k) = achar(iachar('0') + int(mod(rest, 10_i8)))
         rest = rest/10
      end do
   end subroutine put_digits

   !> Write the last `count` decimal digits of v >= 0 after position n; advance n.
   pure subroutine put_decimal(line, n, v, count)
      character(*), intent(inout) :: line
      integer, intent(inout) :: n
      integer, intent(in) :: v, count
      integer :: k, rest
      rest = v
      do k = n + count, n + 1, -1
         line(k:k) = achar(iachar('0') + mod(rest, 10))
         rest = rest/10
      end do
      n = n + count
   end subroutine put_decimal

end module fekap_output_format
