!> Fast exact text of numbers for the output files: a real as the ES edit
!> descriptor writes it (correctly rounded, ties to even; with 17 digits the
!> text reads back to the same double), an integer as I writes it. Formatted
!> writes cost about a microsecond a number, which made writing two tracked
!> points ten times dearer than computing them.
!>
!> The n significant digits D of |x| = m 2**e (m < 2**53, read from the bits
!> of the double) with decimal exponent E are D = round(m 5**k 2**(e + k)),
!> k = n - 1 - E, computed exactly in 128-bit integers. E is floor((e + 52)
!> log10(2)) or one more, from the binary exponent.
!>
!> fast_digits takes the values of a kinematic run (0 <= k <= 31: |x| from
!> about 10**(n - 32) to 10**n): which of the two E is, one comparison with
!> a table of powers of ten tells; m 5**k is one product and 2**(e + k) a
!> shift; the code has no loop and no branch on the digits (a small fraction
!> of a formatted write's cost: docs/performance.md). decimal_digits takes the
!> rest of the exact path: m times the two 64-bit halves of 5**k up to
!> k = 54 (|x| down to about 1e-38), a 128-bit division for k < 0 (down to
!> -21, |x| < 1e38). Other values (subnormals, NaN, infinities, magnitudes
!> beyond these) go through the formatted write.
!>
!> Why one module of over 600 lines (just over): the exact digit paths, their
!> tables of powers and the writers that call them share private constants
!> and are tested together against the formatted write; split, the tables
!> would have to be public.
module fekap_output_format
   use fekap_kinds, only: dp
   use fekap_strings, only: es_text
   implicit none
   private

   public :: real_text, integer_text, append_real, append_integer, append_es, append_i, append_text

   integer, parameter :: i8 = selected_int_kind(18), i16 = selected_int_kind(38)
   !> The exact path reads the significand and exponent from the bits of an
   !> IEEE binary64 double; with any other real kind every value is formatted.
   logical, parameter :: binary64 = radix(1.0_dp) == 2 .and. digits(1.0_dp) == 53 .and. &
      & maxexponent(1.0_dp) == 1024 .and. bit_size(0_i8) == 64
   !> Range of k of the exact path, and its largest decimal exponent.
   integer, parameter :: min_k = -21, max_k = 54, max_exponent10 = 37
   !> k up to which m 5**k (< 2**125) is one 128-bit product.
   integer, parameter :: max_k_single = 31
   !> k up to which 5**k fits in 64 bits (m 5**k is then one 64-by-64-bit product).
   integer, parameter :: max_k_64 = 27
   integer(i16), parameter :: low64_mask = 18446744073709551615_i16, low62_mask = 4611686018427387903_i16
   !> Powers of five in 128 bits (kept out of the inner loops).
   integer(i16), parameter :: power5(0:max_k) = [ &
      & 1_i16, 5_i16, 25_i16, 125_i16, 625_i16, 3125_i16, 15625_i16, 78125_i16, 390625_i16, 1953125_i16, 9765625_i16, &
      & 48828125_i16, 244140625_i16, 1220703125_i16, 6103515625_i16, 30517578125_i16, 152587890625_i16, &
      & 762939453125_i16, 3814697265625_i16, 19073486328125_i16, 95367431640625_i16, 476837158203125_i16, &
      & 2384185791015625_i16, 11920928955078125_i16, 59604644775390625_i16, 298023223876953125_i16, &
      & 1490116119384765625_i16, 7450580596923828125_i16, 37252902984619140625_i16, 186264514923095703125_i16, &
      & 931322574615478515625_i16, 4656612873077392578125_i16, 23283064365386962890625_i16, &
      & 116415321826934814453125_i16, 582076609134674072265625_i16, 2910383045673370361328125_i16, &
      & 14551915228366851806640625_i16, 72759576141834259033203125_i16, 363797880709171295166015625_i16, &
      & 1818989403545856475830078125_i16, 9094947017729282379150390625_i16, 45474735088646411895751953125_i16, &
      & 227373675443232059478759765625_i16, 1136868377216160297393798828125_i16, 5684341886080801486968994140625_i16, &
      & 28421709430404007434844970703125_i16, 142108547152020037174224853515625_i16, &
      & 710542735760100185871124267578125_i16, 3552713678800500929355621337890625_i16, &
      & 17763568394002504646778106689453125_i16, 88817841970012523233890533447265625_i16, &
      & 444089209850062616169452667236328125_i16, 2220446049250313080847263336181640625_i16, &
      & 11102230246251565404236316680908203125_i16, 55511151231257827021181583404541015625_i16]
   integer(i8), parameter :: power5_64(0:max_k_64) = int(power5(0:max_k_64), i8)
   integer(i8), parameter :: power10(0:18) = [ &
      & 1_i8, 10_i8, 100_i8, 1000_i8, 10000_i8, 100000_i8, 1000000_i8, 10000000_i8, &
      & 100000000_i8, 1000000000_i8, 10000000000_i8, 100000000000_i8, 1000000000000_i8, &
      & 10000000000000_i8, 100000000000000_i8, 1000000000000000_i8, 10000000000000000_i8, &
      & 100000000000000000_i8, 1000000000000000000_i8]
   !> "00" to "99": digits are produced two at a time.
   character(len=200), parameter :: digit_pairs = &
      & '0001020304050607080910111213141516171819'//'2021222324252627282930313233343536373839'// &
      & '4041424344454647484950515253545556575859'//'6061626364656667686970717273747576777879'// &
      & '8081828384858687888990919293949596979899'
   !> The least double >= 10**j: |x| >= 10**j exactly when |x| >= this.
   real(dp), parameter :: power10_threshold(-30:17) = [ &
      & 1.0000000000000001e-30_dp, 1.0000000000000001e-29_dp, 1.0000000000000001e-28_dp, 1.0000000000000000e-27_dp, &
      & 1.0000000000000000e-26_dp, 1.0000000000000000e-25_dp, 1.0000000000000001e-24_dp, 1.0000000000000001e-23_dp, &
      & 1.0000000000000000e-22_dp, 1.0000000000000001e-21_dp, 1.0000000000000001e-20_dp, 1.0000000000000001e-19_dp, &
      & 1.0000000000000001e-18_dp, 1.0000000000000001e-17_dp, 1.0000000000000001e-16_dp, 1.0000000000000001e-15_dp, &
      & 1.0000000000000002e-14_dp, 1.0000000000000000e-13_dp, 1.0000000000000002e-12_dp, 1.0000000000000001e-11_dp, &
      & 1.0000000000000000e-10_dp, 1.0000000000000001e-9_dp, 1.0000000000000000e-8_dp, 1.0000000000000001e-7_dp, &
      & 1.0000000000000002e-6_dp, 1.0000000000000001e-5_dp, 1.0000000000000000e-4_dp, 1.0000000000000000e-3_dp, &
      & 1.0000000000000000e-2_dp, 1.0000000000000001e-1_dp, 1.0000000000000000e0_dp, 1.0000000000000000e1_dp, &
      & 1.0000000000000000e2_dp, 1.0000000000000000e3_dp, 1.0000000000000000e4_dp, 1.0000000000000000e5_dp, &
      & 1.0000000000000000e6_dp, 1.0000000000000000e7_dp, 1.0000000000000000e8_dp, 1.0000000000000000e9_dp, &
      & 1.0000000000000000e10_dp, 1.0000000000000000e11_dp, 1.0000000000000000e12_dp, 1.0000000000000000e13_dp, &
      & 1.0000000000000000e14_dp, 1.0000000000000000e15_dp, 1.0000000000000000e16_dp, 1.0000000000000000e17_dp]
   !> What lies below the last digit kept: nothing, less than half of it,
   !> exactly half, more than half.
   integer, parameter :: tail_zero = 0, tail_below_half = 1, tail_half = 2, tail_above_half = 3

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
      integer :: first
      call integer_digits(i, buffer, first)
      call append_text(line, n, buffer(first:))
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
      integer :: first
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
      if (len(text) > width) then
         line(n + 1:n + width) = repeat('*', width)
         n = n + width
         return
      end if
      line(n + 1:n + width - len(text)) = ''
      n = n + width - len(text)
      call append_text(line, n, text)
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

   !> The `ndigits` (<= 17) significant digits of x /= 0, correctly rounded
   !> (ties to even), and its decimal exponent, where m 5**k is one 128-bit
   !> product and 2**(e + k) a right shift: 0 <= k <= 31, 1 <= -(e + k) <=
   !> 126 (normal x from about 10**(ndigits - 32) to 10**ndigits: the values
   !> of a kinematic run). done = .false. (and nothing computed) otherwise.
   !> Straight-line code: no loop, and no branch on the digits; E from the
   !> binary exponent and one comparison with power10_threshold.
   pure subroutine fast_digits(x, ndigits, significand, e10, done)
      real(dp), intent(in) :: x
      integer, intent(in) :: ndigits
      integer(i8), intent(out) :: significand
      integer, intent(out) :: e10
      logical, intent(out) :: done
      integer(i16) :: wide_product
      integer(i8) :: bits, q2, sticky
      integer :: biased, e, k, s
      bits = transfer(x, 0_i8)
      biased = int(iand(shiftr(bits, 52), 2047_i8))
      e = biased - 1075
      ! |x| lies in [2**(e + 52), 2**(e + 53)), so E is floor((e + 52) log10(2))
      ! (78913/2**18 is log10(2) close enough over the whole exponent range)
      ! or one more: one more when |x| >= 10**(that + 1).
      e10 = shifta((e + 52)*78913, 18)
      k = ndigits - 1 - e10
      significand = 0
      done = binary64 .and. biased > 0 .and. biased < 2047 .and. ndigits >= 1 .and. ndigits <= 17 .and. &
         & k >= 0 .and. k <= max_k_single
      if (.not. done) return
      e10 = e10 + merge(1, 0, abs(x) >= power10_threshold(e10 + 1))
      k = ndigits - 1 - e10
      s = -(e + k)
      done = k >= 0 .and. s >= 1 .and. s <= 126
      if (.not. done) return
      ! m 5**k < 2**125, in one 64-by-64-bit multiplication where 5**k fits.
      if (k <= max_k_64) then
         wide_product = int(ior(iand(bits, shiftl(1_i8, 52) - 1), shiftl(1_i8, 52)), i16)*int(power5_64(k), i16)
      else
         wide_product = ior(iand(bits, shiftl(1_i8, 52) - 1), shiftl(1_i8, 52))*power5(k)
      end if
      ! x 10**k times two, floored (< 2 10**ndigits): its last bit is the
      ! rounding bit; sticky (0 or 1) tells whether anything lies below.
      q2 = int(shiftr(wide_product, s - 1), i8)
      if (s <= 63) then
         ! The bits below the rounding bit are in the low 62 (64-bit work).
         sticky = merge(1_i8, 0_i8, iand(int(iand(wide_product, low62_mask), i8), shiftl(1_i8, s - 1) - 1) /= 0)
      else
         sticky = merge(1_i8, 0_i8, iand(wide_product, shiftl(1_i16, s - 1) - 1) /= 0)
      end if
      ! Up on more than half, or on half with an odd last digit (computed,
      ! not branched on: the outcome is as random as the digits).
      significand = shiftr(q2, 1)
      significand = significand + shiftr(iand(q2, 1_i8) + ior(sticky, iand(significand, 1_i8)), 1)
      ! 9.99...95 rounds to the next power of ten.
      if (significand == power10(ndigits)) then
         significand = power10(ndigits - 1)
         e10 = e10 + 1
      end if
   end subroutine fast_digits

   !> The `ndigits` significant digits of x > 0, correctly rounded (ties to
   !> even), and its decimal exponent, for any x of the exact path (the
   !> general case of fast_digits); exact = .false. outside it.
   pure subroutine decimal_digits(x, ndigits, significand, e10, exact)
      real(dp), intent(in) :: x
      integer, intent(in) :: ndigits
      integer(i8), intent(out) :: significand
      integer, intent(out) :: e10
      logical, intent(out) :: exact
      integer(i8) :: bits, m, q, low, high
      integer :: e, k, pass, tail, last
      logical :: ok, round_up
      exact = .false.
      significand = 0
      e10 = 0
      if (.not. binary64 .or. ndigits < 1 .or. ndigits > 17) return
      if (.not. (x >= tiny(x) .and. x <= huge(x))) return
      bits = transfer(x, 0_i8)
      m = ior(iand(bits, shiftl(1_i8, 52) - 1), shiftl(1_i8, 52))
      e = int(shiftr(bits, 52)) - 1075
      low = power10(ndigits - 1)
      high = power10(ndigits)
      ! x lies in [2**(e + 52), 2**(e + 53)), so E is floor((e + 52) log10(2))
      ! (78913/2**18 is log10(2) close enough over the whole exponent range)
      ! or one more.
      e10 = shifta((e + 52)*78913, 18)
      do pass = 1, 3
         k = ndigits - 1 - e10
         if (k < min_k .or. k > max_k .or. e10 > max_exponent10) return
         call scaled_floor(m, e, k, q, tail, ok)
         if (.not. ok) return
         if (q >= 10*high) then
            e10 = e10 + 1
            cycle
         else if (q < low) then
            e10 = e10 - 1
            cycle
         else if (q >= high) then
            ! One digit too many: E is one more, and that digit is rounded off.
            last = int(mod(q, 10_i8))
            q = q/10
            round_up = last > 5 .or. (last == 5 .and. (tail /= tail_zero .or. mod(q, 2_i8) == 1))
            e10 = e10 + 1
         else
            round_up = tail == tail_above_half .or. (tail == tail_half .and. mod(q, 2_i8) == 1)
         end if
         if (round_up) q = q + 1
         ! 9.99...95 rounds to the next power of ten.
         if (q == high) then
            q = low
            e10 = e10 + 1
         end if
         significand = q
         exact = e10 <= max_exponent10
         return
      end do
   end subroutine decimal_digits

   !> q = floor(m 5**k 2**(e + k)) for min_k <= k <= max_k, and what lies
   !> below it (tail_*); ok = .false. where 128 bits do not suffice or q
   !> does not fit in 64 bits.
   pure subroutine scaled_floor(m, e, k, q, tail, ok)
      integer(i8), intent(in) :: m
      integer, intent(in) :: e, k
      integer(i8), intent(out) :: q
      integer, intent(out) :: tail
      logical, intent(out) :: ok
      integer(i16) :: wide_product, upper, lower, quotient, remainder, half, num, den
      integer :: s
      ok = .false.
      q = 0
      tail = tail_zero
      s = -(e + k)
      if (k > max_k_single) then
         ! m 5**k needs up to 179 bits: m times each 64-bit half of 5**k, the
         ! low 64 bits of the product kept apart; s > 64 here.
         upper = m*shiftr(power5(k), 64)
         lower = m*iand(power5(k), low64_mask)
         upper = upper + shiftr(lower, 64)
         lower = iand(lower, low64_mask)
         s = s - 64
         if (s < 1 .or. s > 120) return
         quotient = shiftr(upper, s)
         remainder = upper - shiftl(quotient, s)
         half = shiftl(1_i16, s - 1)
         if (remainder > half .or. (remainder == half .and. lower > 0)) then
            tail = tail_above_half
         else if (remainder == half) then
            tail = tail_half
         else if (remainder > 0 .or. lower > 0) then
            tail = tail_below_half
         end if
      else if (k >= 0) then
         ! A power of two divides: a shift.
         wide_product = m*power5(k)
         if (s <= 0) then
            ! An exact integer; it must stay below 2**126.
            if (-s >= 64) return
            if (shiftr(wide_product, 126 + s) /= 0) return
            quotient = shiftl(wide_product, -s)
         else
            if (s > 126) return
            quotient = shiftr(wide_product, s)
            remainder = wide_product - shiftl(quotient, s)
            half = shiftl(1_i16, s - 1)
            if (remainder > half) then
               tail = tail_above_half
            else if (remainder == half) then
               tail = tail_half
            else if (remainder > 0) then
               tail = tail_below_half
            end if
         end if
      else
         ! |x| >= 10**ndigits: divide by 5**-k (and a power of two).
         num = m
         den = power5(-k)
         if (e + k >= 0) then
            num = shiftl(num, e + k)
         else
            den = shiftl(den, -(e + k))
         end if
         quotient = num/den
         remainder = num - quotient*den
         if (2*remainder > den) then
            tail = tail_above_half
         else if (2*remainder == den) then
            tail = tail_half
         else if (remainder > 0) then
            tail = tail_below_half
         end if
      end if
      if (quotient < 0 .or. quotient >= huge(q)) return
      q = int(quotient, i8)
      ok = .true.
   end subroutine scaled_floor

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
