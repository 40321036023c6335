!> Arithmetic expressions of deck fields: `sqrt(15)`, `100*sqrt(10)`,
!> `atan2(-1,3)`, `60*deg`, `5/6`, `2*pi`, `1.5d0`.
!>
!> Grammar (no blanks inside a field):
!>   expr    = term {("+" | "-") term}
!>   term    = unary {("*" | "/") unary}
!>   unary   = ("+" | "-") unary | power
!>   power   = primary [("^" | "**") unary]          (right associative: 2^3^2 = 2^9)
!>   primary = number | constant | function "(" expr {"," expr} ")" | "(" expr ")"
!> Constants pi and deg (= pi/180); functions sqrt sin cos tan asin acos atan
!> atan2(y,x) exp log abs; the deck's parameters (PARAmeters block), when the
!> caller passes them. Names are case-insensitive.
!>
!> Every operation is checked before it is carried out (the overflow-safe
!> arithmetic of fekap_deck_safe_arithmetic, numbers read by
!> fekap_deck_decimal), so that no NaN, no infinity and no overflow is ever
!> computed (the tests run with floating-point traps): a result that would
!> not be a finite number is reported instead.
module fekap_deck_expression
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, input_error
   use fekap_strings, only: lower, same_name
   use fekap_model, only: parameter_type
   use fekap_deck_name_index, only: name_index_type
   use fekap_deck_safe_arithmetic, only: safe_add, safe_multiply, safe_divide
   use fekap_deck_decimal, only: decimal_value, decimal_too_large
   implicit none
   private

   public :: evaluate_expression, evaluate_integer, known_names

   !> Headline of an error in the form of the field.
   character(*), parameter, public :: msg_not_a_number = 'expected a real number'
   !> Headline of an error in the value of the field.
   character(*), parameter, public :: msg_not_finite = 'not a finite number'

   real(dp), parameter :: pi = acos(-1.0_dp)
   !> Largest argument of exp (and b*log|a| of a**b) that is safely finite.
   real(dp), parameter :: log_huge = log(huge(1.0_dp)) - 1.0e-6_dp

   integer, parameter :: ok = 0, bad_syntax = 1, bad_value = 2

   !> Deepest nesting of parentheses, signs and powers in a field: far beyond
   !> any real deck, and a bound on the parser's recursion (20,000 nested
   !> parentheses once overflowed the stack).
   integer, parameter, public :: max_depth = 100

   !> Parsing state of one field.
   type :: parser_type
      character(:), allocatable :: text
      integer :: pos = 1
      integer :: status = ok
      character(:), allocatable :: detail
      !> Current nesting depth (see max_depth).
      integer :: depth = 0
   end type parser_type

contains

   !> Evaluate the expression `text`. On failure `error` holds the headline
   !> (msg_not_a_number or msg_not_finite) and `detail` (when present) a short label
   !> saying what is wrong, for the caret line of a diagnostic.
   pure subroutine evaluate_expression(text, value, error, detail, parameters, index)
      !> The field, without blanks.
      character(*), intent(in) :: text
      real(dp), intent(out) :: value
      type(error_type), allocatable, intent(out) :: error
      character(:), allocatable, intent(out), optional :: detail
      !> Named values the expression may use besides pi and deg: passed down
      !> the parser, not copied (a copy per field made a deck of many
      !> parameters quadratic to read).
      type(parameter_type), intent(in), optional :: parameters(:)
      !> An index of the names of `parameters` (their positions), for a
      !> lookup in constant time; without it the names are searched in turn.
      type(name_index_type), intent(in), optional :: index
      type(parser_type) :: p
      p%text = text
      p%detail = ''
      value = 0
      if (len(text) == 0) then
         call fail(p, bad_syntax, 'empty field')
      else
         call parse_sum(p, value, parameters, index)
         if (p%status == ok .and. p%pos <= len(p%text)) then
            call fail(p, bad_syntax, "unexpected '"//p%text(p%pos:p%pos)//"'")
         end if
      end if
      if (p%status == ok) return
      value = 0
      if (p%status == bad_syntax) then
         call input_error(error, msg_not_a_number)
      else
         call input_error(error, msg_not_finite)
      end if
      if (present(detail)) detail = p%detail
   end subroutine evaluate_expression

   !> Evaluate `text` as an expression whose value is a whole number that fits
   !> a default integer.
   pure subroutine evaluate_integer(text, value, error, detail, parameters, index)
      character(*), intent(in) :: text
      integer, intent(out) :: value
      type(error_type), allocatable, intent(out) :: error
      character(:), allocatable, intent(out), optional :: detail
      type(parameter_type), intent(in), optional :: parameters(:)
      type(name_index_type), intent(in), optional :: index
      real(dp) :: x
      character(:), allocatable :: why
      ! A local label: passing the optional deferred-length `detail` straight on
      ! loses its length with gfortran 12.
      call evaluate_expression(text, x, error, why, parameters, index)
      value = 0
      if (allocated(error)) then
         if (error%message == msg_not_a_number) error%message = 'expected an integer'
         if (present(detail)) detail = why
         return
      end if
      if (abs(x) > real(huge(value), dp)) then
         call input_error(error, 'expected an integer')
         if (present(detail)) detail = 'too large for an integer'
         return
      end if
      if (x /= aint(x)) then
         call input_error(error, 'expected an integer')
         if (present(detail)) detail = 'not a whole number'
         return
      end if
      value = nint(x)
   end subroutine evaluate_integer

   pure subroutine fail(p, status, detail)
      type(parser_type), intent(inout) :: p
      integer, intent(in) :: status
      character(*), intent(in) :: detail
      if (p%status /= ok) return
      p%status = status
      p%detail = detail
   end subroutine fail

   pure character function peek(p)
      type(parser_type), intent(in) :: p
      peek = ' '
      if (p%pos <= len(p%text)) peek = p%text(p%pos:p%pos)
   end function peek

   pure recursive subroutine parse_sum(p, v, prm, idx)
      type(parser_type), intent(inout) :: p
      real(dp), intent(out) :: v
      !> The deck's parameters and the index of their names (absent: none).
      type(parameter_type), intent(in), optional :: prm(:)
      type(name_index_type), intent(in), optional :: idx
      real(dp) :: w, r
      character :: op
      logical :: fine
      call parse_product(p, v, prm, idx)
      do while (p%status == ok)
         op = peek(p)
         if (op /= '+' .and. op /= '-') exit
         p%pos = p%pos + 1
         call parse_product(p, w, prm, idx)
         if (p%status /= ok) exit
         if (op == '-') w = -w
         call safe_add(v, w, r, fine)
         v = r
         if (.not. fine) call fail(p, bad_value, 'the sum overflows')
      end do
      if (p%status /= ok) v = 0
   end subroutine parse_sum

   pure recursive subroutine parse_product(p, v, prm, idx)
      type(parser_type), intent(inout) :: p
      real(dp), intent(out) :: v
      !> The deck's parameters and the index of their names (absent: none).
      type(parameter_type), intent(in), optional :: prm(:)
      type(name_index_type), intent(in), optional :: idx
      real(dp) :: w, r
      character :: op
      logical :: fine
      call parse_unary(p, v, prm, idx)
      do while (p%status == ok)
         op = peek(p)
         if (op /= '*' .and. op /= '/') exit
         if (op == '*' .and. p%pos < len(p%text)) then
            if (p%text(p%pos + 1:p%pos + 1) == '*') exit   ! '**' is a power, handled below
         end if
         p%pos = p%pos + 1
         call parse_unary(p, w, prm, idx)
         if (p%status /= ok) exit
         if (op == '*') then
            call safe_multiply(v, w, r, fine)
            v = r
            if (.not. fine) call fail(p, bad_value, 'the product overflows')
         else if (w == 0) then
            call fail(p, bad_value, 'division by zero')
         else
            call safe_divide(v, w, r, fine)
            v = r
            if (.not. fine) call fail(p, bad_value, 'the quotient overflows')
         end if
      end do
      if (p%status /= ok) v = 0
   end subroutine parse_product

   pure recursive subroutine parse_unary(p, v, prm, idx)
      type(parser_type), intent(inout) :: p
      real(dp), intent(out) :: v
      !> The deck's parameters and the index of their names (absent: none).
      type(parameter_type), intent(in), optional :: prm(:)
      type(name_index_type), intent(in), optional :: idx
      character(len=12) :: limit
      ! Every level of nesting (a sign, a parenthesis, a function argument, an
      ! exponent) passes through here.
      v = 0
      if (p%depth >= max_depth) then
         write (limit, '(i0)') max_depth
         call fail(p, bad_syntax, 'nested too deeply (more than '//trim(limit)//' levels of parentheses and signs)')
         return
      end if
      p%depth = p%depth + 1
      select case (peek(p))
      case ('-')
         p%pos = p%pos + 1
         call parse_unary(p, v, prm, idx)
         v = -v
      case ('+')
         p%pos = p%pos + 1
         call parse_unary(p, v, prm, idx)
      case default
         call parse_power(p, v, prm, idx)
      end select
      p%depth = p%depth - 1
      if (p%status /= ok) v = 0
   end subroutine parse_unary

   pure recursive subroutine parse_power(p, v, prm, idx)
      type(parser_type), intent(inout) :: p
      real(dp), intent(out) :: v
      !> The deck's parameters and the index of their names (absent: none).
      type(parameter_type), intent(in), optional :: prm(:)
      type(name_index_type), intent(in), optional :: idx
      real(dp) :: e, power
      call parse_primary(p, v, prm, idx)
      if (p%status /= ok) return
      if (peek(p) == '^') then
         p%pos = p%pos + 1
      else if (p%pos < len(p%text) .and. peek(p) == '*') then
         if (p%text(p%pos + 1:p%pos + 1) /= '*') return
         p%pos = p%pos + 2
      else
         return
      end if
      call parse_unary(p, e, prm, idx)
      if (p%status /= ok) then
         v = 0
         return
      end if
      call checked_power(p, v, e, power)
      v = power
   end subroutine parse_power

   !> a**b without ever computing an invalid or overflowing power.
   pure subroutine checked_power(p, a, b, v)
      type(parser_type), intent(inout) :: p
      real(dp), intent(in) :: a, b
      real(dp), intent(out) :: v
      real(dp) :: l
      logical :: fine, whole
      v = 0
      if (b == 0) then
         v = 1
         return
      end if
      whole = b == aint(b)
      if (a == 0) then
         if (b < 0) call fail(p, bad_value, 'zero to a negative power')
         return
      end if
      if (a < 0 .and. .not. whole) then
         call fail(p, bad_value, 'negative number to a non-integer power')
         return
      end if
      call safe_multiply(b, log(abs(a)), l, fine)
      if (.not. fine .or. l > log_huge) then
         if (fine .or. b*sign(1.0_dp, log(abs(a))) > 0) then
            call fail(p, bad_value, 'the power overflows')
            return
         end if
         return   ! underflows to zero
      end if
      if (l < -800) return   ! underflows to zero
      v = abs(a)**b
      if (a < 0 .and. mod(b, 2.0_dp) /= 0) v = -v
   end subroutine checked_power

   pure recursive subroutine parse_primary(p, v, prm, idx)
      type(parser_type), intent(inout) :: p
      real(dp), intent(out) :: v
      !> The deck's parameters and the index of their names (absent: none).
      type(parameter_type), intent(in), optional :: prm(:)
      type(name_index_type), intent(in), optional :: idx
      character :: c
      integer :: start
      character(:), allocatable :: name
      v = 0
      c = peek(p)
      if (c == '(') then
         p%pos = p%pos + 1
         call parse_sum(p, v, prm, idx)
         if (p%status /= ok) return
         call expect(p, ')')
      else if (is_digit(c) .or. c == '.') then
         call parse_number(p, v)
      else if (is_letter(c)) then
         start = p%pos
         do while (p%pos <= len(p%text))
            c = p%text(p%pos:p%pos)
            if (.not. (is_letter(c) .or. is_digit(c) .or. c == '_')) exit
            p%pos = p%pos + 1
         end do
         name = lower(p%text(start:p%pos - 1))
         if (peek(p) == '(') then
            call parse_call(p, name, v, prm, idx)
         else
            select case (name)
            case ('pi')
               v = pi
            case ('deg')
               v = pi/180
            case ('nan', 'inf', 'infinity')
               call fail(p, bad_value, "'"//p%text(start:p%pos - 1)//"' is not a finite number")
            case default
               call parameter_value(p, p%text(start:p%pos - 1), v, prm, idx)
            end select
         end if
      else if (c == ' ') then
         call fail(p, bad_syntax, 'expression ends too early')
      else
         call fail(p, bad_syntax, "unexpected '"//c//"'")
      end if
      if (p%status /= ok) v = 0
   end subroutine parse_primary

   !> The value of the parameter `name`, or an unknown-name failure that lists
   !> the names there are.
   pure subroutine parameter_value(p, name, v, prm, idx)
      type(parser_type), intent(inout) :: p
      character(*), intent(in) :: name
      real(dp), intent(out) :: v
      !> The deck's parameters and the index of their names (absent: none).
      type(parameter_type), intent(in), optional :: prm(:)
      type(name_index_type), intent(in), optional :: idx
      integer :: i
      v = 0
      if (.not. present(prm)) then
         call fail(p, bad_syntax, "unknown name '"//name//"' (constants: pi deg)")
         return
      end if
      if (size(prm) == 0) then
         call fail(p, bad_syntax, "unknown name '"//name//"' (constants: pi deg)")
         return
      end if
      if (present(idx)) then
         i = idx%find(name)
         if (i >= 1 .and. i <= size(prm)) then
            v = prm(i)%value
            return
         end if
      else
         do i = 1, size(prm)
            if (same_name(prm(i)%name, name)) then
               v = prm(i)%value
               return
            end if
         end do
      end if
      call fail(p, bad_syntax, "unknown name '"//name//"' (constants and parameters defined so far: "// &
         & known_names(prm)//')')
   end subroutine parameter_value

   !> 'pi deg' and the first names of `list`, with how many more there are:
   !> a message of a deck with 100,000 parameters stays short.
   pure function known_names(list) result(known)
      type(parameter_type), intent(in) :: list(:)
      character(:), allocatable :: known
      integer, parameter :: shown = 20
      character(len=12) :: more
      integer :: i
      known = 'pi deg'
      do i = 1, min(size(list), shown)
         known = known//' '//list(i)%name
      end do
      if (size(list) > shown) then
         write (more, '(i0)') size(list) - shown
         known = known//' and '//trim(more)//' more'
      end if
   end function known_names

   pure recursive subroutine parse_call(p, name, v, prm, idx)
      type(parser_type), intent(inout) :: p
      character(*), intent(in) :: name
      real(dp), intent(out) :: v
      !> The deck's parameters and the index of their names (absent: none).
      type(parameter_type), intent(in), optional :: prm(:)
      type(name_index_type), intent(in), optional :: idx
      real(dp) :: x, y
      v = 0
      select case (name)
      case ('sqrt', 'sin', 'cos', 'tan', 'asin', 'acos', 'atan', 'exp', 'log', 'abs', 'atan2')
      case default
         call fail(p, bad_syntax, "unknown function '"//name// &
            & "' (functions: sqrt sin cos tan asin acos atan atan2 exp log abs)")
         return
      end select
      p%pos = p%pos + 1   ! the '('
      call parse_sum(p, x, prm, idx)
      if (p%status /= ok) return
      if (name == 'atan2') then
         call expect(p, ',')
         if (p%status /= ok) return
         call parse_sum(p, y, prm, idx)
         if (p%status /= ok) return
      end if
      call expect(p, ')')
      if (p%status /= ok) return
      select case (name)
      case ('sqrt')
         if (x < 0) then
            call fail(p, bad_value, 'square root of a negative number')
         else
            v = sqrt(x)
         end if
      case ('sin')
         v = sin(x)
      case ('cos')
         v = cos(x)
      case ('tan')
         v = tan(x)
      case ('asin', 'acos')
         if (abs(x) > 1) then
            call fail(p, bad_value, name//' of a number outside [-1, 1]')
         else if (name == 'asin') then
            v = asin(x)
         else
            v = acos(x)
         end if
      case ('atan')
         v = atan(x)
      case ('atan2')
         if (x == 0 .and. y == 0) then
            call fail(p, bad_value, 'atan2(0,0) is undefined')
         else
            v = atan2(x, y)
         end if
      case ('exp')
         if (x > log_huge) then
            call fail(p, bad_value, 'exp overflows')
         else if (x > -800) then
            v = exp(x)
         end if
      case ('log')
         if (x <= 0) then
            call fail(p, bad_value, 'log of a number that is not positive')
         else
            v = log(x)
         end if
      case ('abs')
         v = abs(x)
      end select
      if (p%status /= ok) v = 0
   end subroutine parse_call

   !> A decimal number: digits [. digits] [(e|d) [+|-] digits], read without
   !> the risk of an overflow trap inside the run-time library.
   pure subroutine parse_number(p, v)
      type(parser_type), intent(inout) :: p
      real(dp), intent(out) :: v
      integer :: start, exponent, point, first, ndigits, ios
      character(:), allocatable :: mantissa
      logical :: negative_exponent
      v = 0
      start = p%pos
      mantissa = ''
      point = 0        ! digits before the decimal point
      first = 0        ! position in mantissa of the first non-zero digit
      ndigits = 0
      do while (p%pos <= len(p%text))
         if (is_digit(peek(p))) then
            mantissa = mantissa//peek(p)
            ndigits = ndigits + 1
            if (first == 0 .and. peek(p) /= '0') first = ndigits
         else if (peek(p) == '.' .and. point == 0) then
            point = ndigits + 1
         else
            exit
         end if
         p%pos = p%pos + 1
      end do
      if (point == 0) point = ndigits + 1
      if (ndigits == 0) then
         call fail(p, bad_syntax, "a lone '.'")
         return
      end if
      exponent = 0
      if (index('eEdD', peek(p)) > 0) then
         p%pos = p%pos + 1
         negative_exponent = peek(p) == '-'
         if (peek(p) == '-' .or. peek(p) == '+') p%pos = p%pos + 1
         if (.not. is_digit(peek(p))) then
            call fail(p, bad_syntax, 'exponent without digits')
            return
         end if
         do while (is_digit(peek(p)))
            exponent = min(10*exponent + (iachar(peek(p)) - iachar('0')), 100000)
            p%pos = p%pos + 1
         end do
         if (negative_exponent) exponent = -exponent
      end if
      if (is_letter(peek(p)) .or. is_digit(peek(p)) .or. peek(p) == '.' .or. peek(p) == '_') then
         call fail(p, bad_syntax, "unexpected '"//peek(p)//"' after the number "//p%text(start:p%pos - 1))
         return
      end if
      if (first == 0) return   ! zero
      call decimal_value(mantissa(first:), exponent + (point - 1) - first, v, ios)
      if (ios == decimal_too_large) then
         call fail(p, bad_value, 'the number is too large')
      else if (ios /= 0) then
         call fail(p, bad_syntax, 'not a number')
      end if
   end subroutine parse_number

   pure subroutine expect(p, c)
      type(parser_type), intent(inout) :: p
      character, intent(in) :: c
      if (peek(p) == c) then
         p%pos = p%pos + 1
      else if (peek(p) == ' ') then
         call fail(p, bad_syntax, "missing '"//c//"'")
      else
         call fail(p, bad_syntax, "expected '"//c//"' instead of '"//peek(p)//"'")
      end if
   end subroutine expect

   pure logical function is_digit(c)
      character, intent(in) :: c
      is_digit = c >= '0' .and. c <= '9'
   end function is_digit

   pure logical function is_letter(c)
      character, intent(in) :: c
      is_letter = (c >= 'a' .and. c <= 'z') .or. (c >= 'A' .and. c <= 'Z')
   end function is_letter


end module fekap_deck_expression
