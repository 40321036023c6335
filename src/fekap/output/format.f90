!> Fast exact text of numbers for the output files: a real as the ES edit
!> descriptor writes it (correctly rounded, ties to even; with 17 digits the
!> text reads back to the same double), an integer as I writes it. Formatted
!> writes cost about a microsecond a number, which made writing two tracked
!> points ten times dearer than computing them.
!>
!> The digits themselves are exact: fast_digits here (the values of a
!> kinematic run, inlined into the writers) and fekap_output_exact_digits.
!> The module is over 600 lines because the digits, the text and the cache
!> of a real (append_reals' path) must be in one module for the compiler to
!> inline them into one another whatever the build's link-time
!> optimisation does (a call per number is a large part of its cost); the
!> integers' and the ES descriptors' writers share its digit tables.
module fekap_output_format
   use fekap_kinds, only: dp
   use fekap_strings, only: es_text
   use fekap_output_exact_digits, only: i8, i16, power10, decimal_digits, binary64, max_k_single, max_k_64, &
      & low62_mask, power5, power5_64, power10_threshold
   implicit none
   private

   public :: real_text, integer_text, append_real, append_integer, append_es, append_i, append_text
   public :: append_reals

   !> Longest text of append_real (es25.16e3 without its leading blank).
   integer, parameter, public :: real_width = 24

   !> "00" to "99": digits are produced two at a time.
   character(len=200), parameter :: digit_pairs = &
      & '0001020304050607080910111213141516171819'//'2021222324252627282930313233343536373839'// &
      & '4041424344454647484950515253545556575859'//'6061626364656667686970717273747576777879'// &
      & '8081828384858687888990919293949596979899'

   !> "0000" to "9999": digits written four at a time (put_8_digits_quads,
   !> put_short_es), a load and a store each. Its entries are made from
   !> digit_pairs by `quad`, an implied-do index only (a constant
   !> expression's index must be a variable of the scope).
   integer, private :: quad
   character(len=4), parameter :: digit_quads(0:9999) = [(digit_pairs(2*(quad/100) + 1:2*(quad/100) + 2) &
      & //digit_pairs(2*mod(quad, 100) + 1:2*mod(quad, 100) + 2), quad = 0, 9999)]

   !> Eight digits are made side by side in the lanes of one 64-bit integer
   !> and stored as its 8 bytes (put_8_digits), the first digit in the lowest
   !> byte: on a little-endian machine, which this tells.
   logical, parameter :: little_endian = transfer(1_i8, 'abcdefgh') == achar(1)//repeat(achar(0), 7)

   !> The exponents of es25.16e3 texts on fast_digits' path (E from -15 to
   !> 17 there), each copied whole as 8 characters (put_17_digits), of which
   !> the digits overwrite the first 3.
   character(len=8), parameter :: exponent_texts(-20:20) = [ &
      & '   E-020', '   E-019', '   E-018', '   E-017', '   E-016', '   E-015', '   E-014', &
      & '   E-013', '   E-012', '   E-011', '   E-010', '   E-009', '   E-008', '   E-007', &
      & '   E-006', '   E-005', '   E-004', '   E-003', '   E-002', '   E-001', '   E+000', &
      & '   E+001', '   E+002', '   E+003', '   E+004', '   E+005', '   E+006', '   E+007', &
      & '   E+008', '   E+009', '   E+010', '   E+011', '   E+012', '   E+013', '   E+014', &
      & '   E+015', '   E+016', '   E+017', '   E+018', '   E+019', '   E+020']

   !> Slots of real_text_cache_type (a power of two: the slot is a bit field).
   integer, parameter :: cache_bits = 8, cache_slots = 2**cache_bits

   !> The texts of the last reals written to the tables, by their bits. The
   !> rows of a run write the same values again and again: a fixed node's
   !> coordinates, a constant drive rate, exact zeros, a tracked point's
   !> position in points.csv and again in nodes.csv; copying a text costs a
   !> tenth of making it. Direct-mapped: each slot holds the last value whose
   !> hash fell in it (length 0: none yet), its text in 24 characters of
   !> which `length` count.
   !> Every slot starts as the text of +0.0 (bits 0), a valid entry: the
   !> lookup needs no test of whether a slot is filled.
   type, public :: real_text_cache_type
      integer(i8) :: bits(0:cache_slots - 1) = 0
      integer :: length(0:cache_slots - 1) = 23
      character(len=real_width) :: text(0:cache_slots - 1) = '0.0000000000000000E+000'
   end type real_text_cache_type

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
      logical :: fast
      call put_real(line, n, x, fast)
   end subroutine append_real

   !> `,v1,v2,...` of m values in a contiguous array, each as append_real
   !> writes it, through `cache` (append_cached_real). Explicit shape: the
   !> rows of the CSV tables pass their values without a descriptor, and
   !> nodes.csv every node's coordinates at once. Here, with the writer of
   !> a real, so that a row is one call and each value none (a call of
   !> another module is not inlined, and append_real's registers were
   !> saved and restored for each value).
   pure subroutine append_reals(text, n, values, m, cache)
      character(*), intent(inout) :: text
      integer, intent(inout) :: n
      integer, intent(in) :: m
      real(dp), intent(in) :: values(m)
      type(real_text_cache_type), intent(inout) :: cache
      integer :: i
      do i = 1, m
         text(n + 1:n + 1) = ','
         n = n + 1
         call append_cached_real(text, n, values(i), cache)
      end do
   end subroutine append_reals

   !> x as append_real writes it (a function of the bits of x), copied from
   !> `cache` where x is held there, else written and then held. The caller
   !> has reserved real_width characters for it.
   pure subroutine append_cached_real(text, n, x, cache)
      character(*), intent(inout) :: text
      integer, intent(inout) :: n
      real(dp), intent(in) :: x
      type(real_text_cache_type), intent(inout) :: cache
      integer(i8) :: bits
      integer :: slot, start
      logical :: fast
      bits = transfer(x, 0_i8)
      ! The slot: the last cache_bits bits of the significand (a computed
      ! value's are as good as random) folded with the exponent's and the
      ! significand's first (where a round number, an exact zero, 2, 0.5,
      ! 1e-4, differs from another), in three instructions: a product and
      ! a shift cost more than the hits they would add.
      slot = int(iand(ieor(bits, shiftr(bits, 45)), int(cache_slots - 1, i8)))
      if (n + real_width > len(text)) then
         call put_real(text, n, x, fast)
         return
      end if
      if (cache%bits(slot) == bits) then
         ! All real_width characters, one fixed-length copy; after a shorter
         ! text the rest is overwritten by what follows.
         text(n + 1:n + real_width) = cache%text(slot)
         n = n + cache%length(slot)
         return
      end if
      ! Only the texts of fast_digits' path, of known length (23 and the
      ! sign), are held: no test of the length written. One call of
      ! put_real (inlined where it is called from few places).
      start = n
      call put_real(text, n, x, fast)
      if (fast) then
         cache%bits(slot) = bits
         cache%length(slot) = n - start
         cache%text(slot) = text(start + 1:start + real_width)
      end if
   end subroutine append_cached_real

   !> append_real's work. Private: a public procedure of a module compiled
   !> as position-independent code is called even from its own module (it
   !> could be interposed), a private one is inlined (here into append_real
   !> and append_cached_real).
   pure subroutine put_real(line, n, x, fast)
      character(*), intent(inout) :: line
      integer, intent(inout) :: n
      real(dp), intent(in) :: x
      !> Whether x took fast_digits' path (put_17_digits: 23 characters and the sign).
      logical, intent(out) :: fast
      integer(i8) :: significand
      integer :: e10
      logical :: done
      call fast_digits(x, 17, significand, e10, done)
      fast = done .and. e10 >= lbound(exponent_texts, 1) .and. e10 <= ubound(exponent_texts, 1)
      if (fast) then
         call put_17_digits(line, n, x, significand, e10)
      else
         call append_other_real(line, n, x)
      end if
   end subroutine put_real

   !> append_real of the values off fast_digits' path: zeros, very small and
   !> very large magnitudes, subnormals, infinities.
   pure subroutine append_other_real(line, n, x)
      character(*), intent(inout) :: line
      integer, intent(inout) :: n
      real(dp), intent(in) :: x
      logical :: done
      if (x == 0) then
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
   end subroutine append_other_real

   !> Write [-]d.dddddddddddddddd E+ddd (the text of es25.16e3) of x, whose
   !> 17 digits are `significand` and decimal exponent e10 (within
   !> exponent_texts), after position n; advance n. Every position is fixed
   !> but the sign's.
   pure subroutine put_17_digits(line, n, x, significand, e10)
      character(*), intent(inout) :: line
      integer, intent(inout) :: n
      real(dp), intent(in) :: x
      integer(i8), intent(in) :: significand
      integer, intent(in) :: e10
      integer(i8) :: high
      integer :: lead
      ! The minus sign is written, and kept (n advanced by the sign bit) or
      ! overwritten by the digits (a branch on the sign would be
      ! mispredicted half the time).
      line(n + 1:n + 1) = '-'
      n = n + int(shiftr(transfer(x, 0_i8), 63))
      ! 1 + 8 + 8 digits: high < 10**9 has the first nine.
      high = significand/100000000_i8
      lead = int(high)/100000000
      line(n + 1:n + 1) = achar(iachar('0') + lead)
      line(n + 2:n + 2) = '.'
      ! The exponent first, as the 8 characters ending the text (one store
      ! of fixed length; a copy of 5 was several), its first 3 then
      ! overwritten by the last digits.
      line(n + 16:n + 23) = exponent_texts(e10)
      call put_8_digits_quads(line(n + 3:n + 10), int(high) - lead*100000000)
      call put_8_digits_quads(line(n + 11:n + 18), int(significand - high*100000000_i8))
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
      logical :: done
      ! The listing's step line (es20.11, es16.6), each a call of
      ! put_short_es with constant field sizes: fixed-length stores only.
      ! The other fields and values in append_other_es, whose formatted
      ! write's locals this one does not set up.
      done = .false.
      if (exponent_digits == 0 .and. width == 20 .and. decimals == 11) then
         call put_short_es(line, n, x, 20, 11, done)
      else if (exponent_digits == 0 .and. width == 16 .and. decimals == 6) then
         call put_short_es(line, n, x, 16, 6, done)
      end if
      if (.not. done) call append_other_es(line, n, x, width, decimals, exponent_digits)
   end subroutine append_es

   !> append_es of the fields and values off put_short_es' path.
   pure subroutine append_other_es(line, n, x, width, decimals, exponent_digits)
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
   end subroutine append_other_es

   !> Write x as esW.D writes it (W = width, D = decimals: 20 and 11 or 16
   !> and 6, the listing's fields; E+dd, as fast_digits' exponents are
   !> within +-99) after position n and advance n; done = .false. (nothing
   !> written) off fast_digits' path (zeros among them). The field is
   !> blanks, the sign where x < 0, the digits, E and the exponent's sign
   !> and two digits, each written at its fixed place from the field's
   !> end.
   pure subroutine put_short_es(line, n, x, width, decimals, done)
      character(*), intent(inout) :: line
      integer, intent(inout) :: n
      real(dp), intent(in) :: x
      integer, intent(in) :: width, decimals
      logical, intent(out) :: done
      integer(i8) :: significand, rest
      integer :: e10, lead, high, q, k
      call fast_digits(x, decimals + 1, significand, e10, done)
      if (.not. done .or. (decimals /= 11 .and. decimals /= 6) .or. width < decimals + 7 .or. &
         & width > decimals + 15) then
         done = .false.
         return
      end if
      ! The lead digit's place: the text without its sign is decimals + 6 long.
      q = n + width - decimals - 5
      line(n + 1:n + 8) = '        '
      line(n + width - 7:n + width) = '        '
      if (x < 0) line(q - 1:q - 1) = '-'
      lead = int(significand/power10(decimals))
      rest = significand - lead*power10(decimals)
      if (decimals == 11) then
         ! 3 + 8 digits: the 3 as a quad's last three, after its '0' which the
         ! point then overwrites.
         high = int(rest/100000000_i8)
         line(q + 1:q + 4) = digit_quads(high)
         call put_8_digits_quads(line(q + 5:q + 12), int(rest - high*100000000_i8))
      else
         ! 2 + 4 digits: the 2 as a quad's last two, after '00' which the
         ! lead digit and the point overwrite.
         high = int(rest)/10000
         line(q:q + 3) = digit_quads(high)
         line(q + 4:q + 7) = digit_quads(int(rest) - high*10000)
      end if
      line(q:q) = achar(iachar('0') + lead)
      line(q + 1:q + 1) = '.'
      k = abs(e10)
      line(q + decimals + 2:q + decimals + 3) = merge('E-', 'E+', e10 < 0)
      line(q + decimals + 4:q + decimals + 5) = digit_pairs(2*k + 1:2*k + 2)
      n = n + width
   end subroutine put_short_es

   !> Write i as the edit descriptor iW writes it after position n; advance n.
   pure subroutine append_i(line, n, i, width)
      character(*), intent(inout) :: line
      integer, intent(inout) :: n
      integer, intent(in) :: i, width
      character(len=12) :: buffer
      integer :: first, v, p
      integer(i8) :: digits
      integer(i8), parameter :: zeros_to_blanks = int(z'1010101010101010', i8), zeros = int(z'3030303030303030', i8)
      if (i >= 0 .and. i < 10 .and. width >= 4 .and. width <= 16) then
         ! One digit (the listing's iterations and cuts) in a field of 4 to
         ! 16: blanks as two overlapping stores of fixed length, then the
         ! digit (no loop over the blanks).
         if (width >= 8) then
            line(n + 1:n + 8) = '        '
            line(n + width - 7:n + width) = '        '
         else
            line(n + 1:n + 4) = '    '
            line(n + width - 3:n + width) = '    '
         end if
         line(n + width:n + width) = achar(iachar('0') + i)
         n = n + width
         return
      end if
      if (little_endian .and. i >= 10 .and. i < 100000000 .and. width >= 8 .and. width <= 16) then
         ! A step number or a count of two digits or more in the listing's
         ! 8- and 12-wide fields: its 8 digits with leading zeros as one
         ! 64-bit word (put_8_digits), the leading zeros made blanks (the
         ! digits less '0' are zero bytes up to the first digit that is
         ! not, whose place trailz gives: the first character is the lowest
         ! byte), stored as the field's last 8 characters after 8 blanks at
         ! its start (the field is 8 to 16 wide: both within it).
         call put_8_digits(buffer(1:8), i)
         digits = transfer(buffer(1:8), 0_i8)
         line(n + 1:n + 8) = '        '
         line(n + width - 7:n + width) = transfer(digits - iand(zeros_to_blanks, &
            & shiftl(1_i8, 8*(trailz(digits - zeros)/8)) - 1), buffer(1:8))
         n = n + width
         return
      end if
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
         if (width >= 8 .and. width - length <= 8) then
            ! Eight blanks at once, within the field; the digits overwrite
            ! those beyond its padding.
            line(n + 1:n + 8) = '        '
         else
            do p = n + 1, n + width - length
               line(p:p) = ' '
            end do
         end if
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
      ! Zeros and subnormals (biased 0: E = -308) and infinities and NaN
      ! (biased 2047: E = 308) are outside 0 <= k <= 31 for every ndigits.
      done = binary64 .and. ndigits >= 1 .and. ndigits <= 17 .and. k >= 0 .and. k <= max_k_single
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
      character(len=16) :: digits
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
      if (little_endian .and. ndigits >= 2 .and. ndigits <= 16) then
         ! The digits after the first, padded with zeros to 16 and made
         ! eight at a time (put_8_digits), the first ndigits - 1 of them
         ! copied (the listing's 12 and 7 digits): no loop, and no division
         ! per pair.
         lead = int(significand/power10(ndigits - 1))
         rest = (significand - lead*power10(ndigits - 1))*power10(17 - ndigits)
         high = rest/100000000_i8
         call put_8_digits(digits(1:8), int(high))
         if (ndigits > 9) call put_8_digits(digits(9:16), int(rest - high*100000000_i8))
         text(1:1) = achar(iachar('0') + lead)
         text(2:2) = '.'
         text(3:ndigits + 1) = digits(1:ndigits - 1)
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

   !> The 8 digits of 0 <= v < 10**8, leading zeros included. On a
   !> little-endian machine side by side in one 64-bit integer (SWAR): v as
   !> two 4-digit halves in its 32-bit lanes, each lane split into two 2-digit
   !> halves in 16-bit lanes, each of those into digits in bytes; a division
   !> in every lane at once is one product and a shift (x*10486/2**20 is
   !> x/100 floored for 0 <= x <= 9999, x*103/2**10 is x/10 floored for
   !> 0 <= x <= 99; no lane's product reaches the next lane), and the 8 bytes
   !> plus '0' are stored at once, without the digit pairs' table lookups
   !> and two-character stores below. Elsewhere: y = v/10**6 in 52-bit
   !> fixed point holds the first two digits in its integer part; its
   !> fraction times 100 the next two, and so on: one product a pair, no
   !> division. (The multiplier ceil(2**52/10**6) makes y too large by less
   !> than 10**8 2**-52 units; after the three products by 100 that is below
   !> 0.03 of a unit of the last pair, and the exact fractions are multiples
   !> of 10**-6, 10**-4, 10**-2: no digit comes out wrong.)
   pure subroutine put_8_digits(text, v)
      character(len=8), intent(inout) :: text
      integer, intent(in) :: v
      integer(i8), parameter :: fraction_mask = shiftl(1_i8, 52) - 1, multiplier = 4503599628_i8
      integer(i8), parameter :: lanes_7f = int(z'0000007F0000007F', i8), lanes_0f = int(z'000F000F000F000F', i8), &
         & zeros = int(z'3030303030303030', i8)
      integer(i8) :: y, high
      integer :: pair, half
      if (little_endian) then
         ! v/10**4 as v*ceil(2**40/10**4)/2**40 (exact below 10**8; no
         ! signed division's correction).
         half = int(shiftr(int(v, i8)*109951163_i8, 40))
         y = ior(int(half, i8), shiftl(int(v - half*10000, i8), 32))
         high = iand(shiftr(y*10486, 20), lanes_7f)
         y = ior(high, shiftl(y - high*100, 16))
         high = iand(shiftr(y*103, 10), lanes_0f)
         y = ior(high, shiftl(y - high*10, 8)) + zeros
         text = transfer(y, text)
         return
      end if
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

   !> The 8 digits of 0 <= v < 10**8, leading zeros included, as two
   !> entries of digit_quads: v/10**4 as v*ceil(2**40/10**4)/2**40 (exact
   !> below 10**8), and the rest. Fewer instructions than put_8_digits'
   !> lanes, for a table of 40 kB.
   pure subroutine put_8_digits_quads(text, v)
      character(len=8), intent(inout) :: text
      integer, intent(in) :: v
      integer :: half
      half = int(shiftr(int(v, i8)*109951163_i8, 40))
      text(1:4) = digit_quads(half)
      text(5:8) = digit_quads(v - half*10000)
   end subroutine put_8_digits_quads

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
