!> Tests of fekap_deck_expression: values of the grammar's forms, and fields
!> that are not numbers or not finite, evaluated under floating-point traps.
module test_deck_expression
   use fekap_kinds, only: dp
   use fekap_testing, only: unittest_type, new_unittest, check, test_failed, error_type
   use fekap_deck_expression, only: evaluate_expression, evaluate_integer, msg_not_a_number, msg_not_finite
   implicit none
   private
   public :: collect_deck_expression

   real(dp), parameter :: pi = acos(-1.0_dp)

contains

   subroutine collect_deck_expression(tests)
      type(unittest_type), allocatable, intent(out) :: tests(:)
      tests = [ &
         & new_unittest('numbers', test_numbers), &
         & new_unittest('operators', test_operators), &
         & new_unittest('functions', test_functions), &
         & new_unittest('constants', test_constants), &
         & new_unittest('syntax_errors', test_syntax_errors), &
         & new_unittest('not_finite', test_not_finite), &
         & new_unittest('evaluate_integer', test_integer) &
         & ]
   end subroutine collect_deck_expression

   !> The field evaluates to want.
   subroutine expect(error, text, want)
      type(error_type), allocatable, intent(inout) :: error
      character(*), intent(in) :: text
      real(dp), intent(in) :: want
      type(error_type), allocatable :: failure
      real(dp) :: got
      if (allocated(error)) return
      call evaluate_expression(text, got, failure)
      if (allocated(failure)) then
         call test_failed(error, text//': '//failure%message)
         return
      end if
      call check(error, got, want, text, rel=1.0e-15_dp, abs=1.0e-300_dp)
   end subroutine expect

   !> The field fails with the headline `headline`.
   subroutine expect_failure(error, text, headline)
      type(error_type), allocatable, intent(inout) :: error
      character(*), intent(in) :: text, headline
      type(error_type), allocatable :: failure
      real(dp) :: got
      character(:), allocatable :: detail
      if (allocated(error)) return
      call evaluate_expression(text, got, failure, detail)
      if (.not. allocated(failure)) then
         call test_failed(error, text//': no error')
      else if (failure%message /= headline) then
         call test_failed(error, text//': got "'//failure%message//'", want "'//headline//'"')
      else if (len(detail) == 0) then
         call test_failed(error, text//': no detail')
      end if
   end subroutine expect_failure

   subroutine test_numbers(error)
      type(error_type), allocatable, intent(out) :: error
      call expect(error, '1', 1.0_dp)
      call expect(error, '1.5', 1.5_dp)
      call expect(error, '.25', 0.25_dp)
      call expect(error, '3.', 3.0_dp)
      call expect(error, '1e-3', 1.0e-3_dp)
      call expect(error, '1.5d0', 1.5_dp)
      call expect(error, '2.5E+2', 250.0_dp)
      call expect(error, '0.000123', 1.23e-4_dp)
      call expect(error, '1e-400', 0.0_dp)
      call expect(error, '1.7976931348623157e308', huge(1.0_dp))
      call expect(error, '0e999999999999', 0.0_dp)
   end subroutine test_numbers

   subroutine test_operators(error)
      type(error_type), allocatable, intent(out) :: error
      call expect(error, '5/6', 5.0_dp/6)
      call expect(error, '1+2*3', 7.0_dp)
      call expect(error, '(1+2)*3', 9.0_dp)
      call expect(error, '-2^2', -4.0_dp)
      call expect(error, '2**3', 8.0_dp)
      call expect(error, '2^3^2', 512.0_dp)
      call expect(error, '(-2)^3', -8.0_dp)
      call expect(error, '2^-1', 0.5_dp)
      call expect(error, '2*-3', -6.0_dp)
      call expect(error, '8/2/2', 2.0_dp)
      call expect(error, '1-2-3', -4.0_dp)
      call expect(error, '+4', 4.0_dp)
      call expect(error, '0^0', 1.0_dp)
   end subroutine test_operators

   subroutine test_functions(error)
      type(error_type), allocatable, intent(out) :: error
      call expect(error, 'sqrt(15)', sqrt(15.0_dp))
      call expect(error, '100*sqrt(10)', 100*sqrt(10.0_dp))
      call expect(error, 'atan2(-1,3)', atan2(-1.0_dp, 3.0_dp))
      call expect(error, 'sin(pi/6)', sin(pi/6))
      call expect(error, 'cos(0)', 1.0_dp)
      call expect(error, 'tan(1)', tan(1.0_dp))
      call expect(error, 'asin(1)', pi/2)
      call expect(error, 'acos(-1)', pi)
      call expect(error, 'atan(1)', pi/4)
      call expect(error, 'exp(1)', exp(1.0_dp))
      call expect(error, 'log(exp(2))', 2.0_dp)
      call expect(error, 'abs(-3)', 3.0_dp)
      call expect(error, 'SQRT(4)', 2.0_dp)
   end subroutine test_functions

   subroutine test_constants(error)
      type(error_type), allocatable, intent(out) :: error
      call expect(error, 'pi', pi)
      call expect(error, '2*pi', 2*pi)
      call expect(error, '60*deg', pi/3)
      call expect(error, 'PI', pi)
   end subroutine test_constants

   subroutine test_syntax_errors(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_failure(error, 'sqrt(1S)', msg_not_a_number)
      call expect_failure(error, 'abc', msg_not_a_number)
      call expect_failure(error, '2pi', msg_not_a_number)
      call expect_failure(error, '1.2.3', msg_not_a_number)
      call expect_failure(error, '(1+2', msg_not_a_number)
      call expect_failure(error, '1+', msg_not_a_number)
      call expect_failure(error, '1e', msg_not_a_number)
      call expect_failure(error, 'foo(1)', msg_not_a_number)
      call expect_failure(error, 'atan2(1)', msg_not_a_number)
      call expect_failure(error, '', msg_not_a_number)
      call expect_failure(error, '.', msg_not_a_number)
      call expect_failure(error, '1)', msg_not_a_number)
   end subroutine test_syntax_errors

   subroutine test_not_finite(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_failure(error, 'NaN', msg_not_finite)
      call expect_failure(error, 'Inf', msg_not_finite)
      call expect_failure(error, '-infinity', msg_not_finite)
      call expect_failure(error, '1e400', msg_not_finite)
      call expect_failure(error, '1.8e308', msg_not_finite)
      call expect_failure(error, '1e99999999999999', msg_not_finite)
      call expect_failure(error, '1/0', msg_not_finite)
      call expect_failure(error, '0/0', msg_not_finite)
      call expect_failure(error, 'sqrt(-1)', msg_not_finite)
      call expect_failure(error, 'log(0)', msg_not_finite)
      call expect_failure(error, 'log(-1)', msg_not_finite)
      call expect_failure(error, 'asin(2)', msg_not_finite)
      call expect_failure(error, 'exp(1000)', msg_not_finite)
      call expect_failure(error, '1e300*1e300', msg_not_finite)
      call expect_failure(error, '1e308+1e308', msg_not_finite)
      call expect_failure(error, '-1e308-1e308', msg_not_finite)
      call expect_failure(error, '1e300/1e-300', msg_not_finite)
      call expect_failure(error, '10^400', msg_not_finite)
      call expect_failure(error, '(-8)^(1/3)', msg_not_finite)
      call expect_failure(error, '0^-1', msg_not_finite)
      call expect_failure(error, 'atan2(0,0)', msg_not_finite)
      call expect(error, '10^-400', 0.0_dp)
      call expect(error, 'exp(-1000)', 0.0_dp)
      call expect(error, '1e-300*1e-300', 0.0_dp)
   end subroutine test_not_finite

   subroutine test_integer(error)
      type(error_type), allocatable, intent(out) :: error
      type(error_type), allocatable :: failure
      character(:), allocatable :: detail
      integer :: n
      call evaluate_integer('25', n, failure)
      call check(error, .not. allocated(failure), '25 is an integer')
      call check(error, n, 25)
      call evaluate_integer('2*8', n, failure)
      call check(error, n, 16)
      call evaluate_integer('2.5', n, failure)
      call check(error, allocated(failure), '2.5 is not an integer')
      call evaluate_integer('1e20', n, failure)
      call check(error, allocated(failure), '1e20 does not fit')
      call evaluate_integer('x.deck', n, failure, detail)
      call check(error, allocated(failure), 'x.deck is not an integer')
      if (allocated(failure)) call check(error, failure%message == 'expected an integer', 'headline')
      call check(error, allocated(detail), 'detail')
      if (allocated(detail)) call check(error, detail == "unknown name 'x' (constants: pi deg)", 'detail: '//detail)
   end subroutine test_integer

end module test_deck_expression
