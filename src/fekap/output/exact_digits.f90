!> The correctly rounded decimal digits of a double and its decimal
!> exponent, for fekap_output_format's writers, computed exactly in integers.
!>
!> The n significant digits D of |x| = m 2**e (m < 2**53, read from the bits
!> of the double) with decimal exponent E are D = round(m 5**k 2**(e + k)),
!> k = n - 1 - E, computed exactly in 128-bit integers. E is floor((e + 52)
!> log10(2)) or one more, from the binary exponent.
!>
!> The values of a kinematic run (0 <= k <= 31: |x| from about 10**(n - 32)
!> to 10**n) take fekap_output_format's fast_digits, which lives there so
!> that the compiler inlines it into the writers (a call per number, with
!> its outputs through memory, is a large part of its cost); it uses the tables
!> below. decimal_digits takes the rest of the exact path: m times the two
!> 64-bit halves of 5**k up to k = 54 (|x| down to about 1e-38), a 128-bit
!> division for k < 0 (down to -21, |x| < 1e38). Other values (subnormals,
!> NaN, infinities, magnitudes beyond these) go through the formatted write.
module fekap_output_exact_digits
   use fekap_kinds, only: dp
   implicit none
   private

   public :: decimal_digits

   integer, parameter, public :: i8 = selected_int_kind(18)
   integer, parameter, public :: i16 = selected_int_kind(38)
   !> The exact path reads the significand and exponent from the bits of an
   !> IEEE binary64 double; with any other real kind every value is formatted.
   logical, parameter, public :: binary64 = radix(1.0_dp) == 2 .and. digits(1.0_dp) == 53 .and. &
      & maxexponent(1.0_dp) == 1024 .and. bit_size(0_i8) == 64
   !> Range of k of the exact path, and its largest decimal exponent.
   integer, parameter :: min_k = -21, max_k = 54, max_exponent10 = 37
   !> k up to which m 5**k (< 2**125) is one 128-bit product.
   integer, parameter, public :: max_k_single = 31
   !> k up to which 5**k fits in 64 bits (m 5**k is then one 64-by-64-bit product).
   integer, parameter, public :: max_k_64 = 27
   integer(i16), parameter :: low64_mask = 18446744073709551615_i16
   integer(i16), parameter, public :: low62_mask = 4611686018427387903_i16
   !> Powers of five in 128 bits (kept out of the inner loops).
   integer(i16), parameter, public :: power5(0:max_k) = [ &
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
   integer(i8), parameter, public :: power5_64(0:max_k_64) = int(power5(0:max_k_64), i8)
   !> 10**j in 64 bits, j = 0..18.
   integer(i8), parameter, public :: power10(0:18) = [ &
      & 1_i8, 10_i8, 100_i8, 1000_i8, 10000_i8, 100000_i8, 1000000_i8, 10000000_i8, &
      & 100000000_i8, 1000000000_i8, 10000000000_i8, 100000000000_i8, 1000000000000_i8, &
      & 10000000000000_i8, 100000000000000_i8, 1000000000000000_i8, 10000000000000000_i8, &
      & 100000000000000000_i8, 1000000000000000000_i8]
   !> The least double >= 10**j: |x| >= 10**j exactly when |x| >= this.
   real(dp), parameter, public :: power10_threshold(-30:17) = [ &
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

   !> The `ndigits` significant digits of x > 0, correctly rounded (ties to
   !> even), and its decimal exponent, for any x of the exact path (the
   !> general case of fekap_output_format's fast_digits); exact = .false.
   !> outside it.
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

end module fekap_output_exact_digits
