!> A small assertion and test-runner module in the shape of test-drive.
module fekap_testing
   use, intrinsic :: iso_fortran_env, only: int64
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, fatal_error
   implicit none
   private

   public :: unittest_type, new_unittest, test_interface, check, test_failed, run_testsuite
   public :: error_type, next_random

   abstract interface
      subroutine test_interface(error)
         import :: error_type
         type(error_type), allocatable, intent(out) :: error
      end subroutine test_interface
   end interface

   !> One named test.
   type :: unittest_type
      character(:), allocatable :: name
      procedure(test_interface), pointer, nopass :: test => null()
      !> The test passes when it reports an error.
      logical :: should_fail = .false.
   end type unittest_type

   !> Compare got with want and fill error on a mismatch.
   interface check
      module procedure :: check_real, check_int, check_logical
   end interface check

contains

   function new_unittest(name, test, should_fail) result(self)
      character(*), intent(in) :: name
      procedure(test_interface) :: test
      logical, intent(in), optional :: should_fail
      type(unittest_type) :: self
      self%name = name
      self%test => test
      if (present(should_fail)) self%should_fail = should_fail
   end function new_unittest

   !> |got - want| <= max(abs, rel*|want|); by default rel = 1e-12.
   subroutine check_real(error, got, want, message, rel, abs)
      type(error_type), allocatable, intent(inout) :: error
      real(dp), intent(in) :: got, want
      character(*), intent(in), optional :: message
      real(dp), intent(in), optional :: rel, abs
      real(dp) :: tol
      character(len=160) :: line
      if (allocated(error)) return
      tol = 1.0e-12_dp*abs_(want)
      if (present(rel)) tol = rel*abs_(want)
      if (present(abs)) tol = max(merge(tol, 0.0_dp, present(rel)), abs)
      if (got /= got .or. abs_(got - want) > tol) then
         write (line, '(a,es24.16,a,es24.16,a,es9.2)') 'got ', got, ', want ', want, ', tolerance ', tol
         call fatal_error(error, prefix(message)//trim(line))
      end if
   end subroutine check_real

   subroutine check_int(error, got, want, message)
      type(error_type), allocatable, intent(inout) :: error
      integer, intent(in) :: got, want
      character(*), intent(in), optional :: message
      character(len=80) :: line
      if (allocated(error)) return
      if (got /= want) then
         write (line, '(a,i0,a,i0)') 'got ', got, ', want ', want
         call fatal_error(error, prefix(message)//trim(line))
      end if
   end subroutine check_int

   subroutine check_logical(error, condition, message)
      type(error_type), allocatable, intent(inout) :: error
      logical, intent(in) :: condition
      character(*), intent(in), optional :: message
      if (allocated(error)) return
      if (.not. condition) call fatal_error(error, prefix(message)//'condition is false')
   end subroutine check_logical

   !> Fail unconditionally with a message.
   subroutine test_failed(error, message)
      type(error_type), allocatable, intent(inout) :: error
      character(*), intent(in) :: message
      if (allocated(error)) return
      call fatal_error(error, message)
   end subroutine test_failed

   pure real(dp) function abs_(x)
      real(dp), intent(in) :: x
      abs_ = abs(x)
   end function abs_

   pure function prefix(message) result(text)
      character(*), intent(in), optional :: message
      character(:), allocatable :: text
      text = ''
      if (present(message)) text = message//': '
   end function prefix

   !> Run the tests of one suite (all, or only the one called `only`);
   !> print a line per test and add to the pass/fail counters.
   subroutine run_testsuite(suite, tests, passed, failed, only)
      character(*), intent(in) :: suite
      type(unittest_type), intent(in) :: tests(:)
      integer, intent(inout) :: passed, failed
      character(*), intent(in), optional :: only
      type(error_type), allocatable :: error
      integer :: i, np, nf
      logical :: ok
      np = 0
      nf = 0
      do i = 1, size(tests)
         if (present(only)) then
            if (len(only) > 0 .and. only /= tests(i)%name) cycle
         end if
         call tests(i)%test(error)
         ok = allocated(error) .eqv. tests(i)%should_fail
         if (ok) then
            np = np + 1
            write (*, '(2x,a,1x,a,a)') 'PASS', suite//'/', tests(i)%name
         else
            nf = nf + 1
            write (*, '(2x,a,1x,a,a)') 'FAIL', suite//'/', tests(i)%name
            if (allocated(error)) then
               write (*, '(6x,a)') error%message
            else
               write (*, '(6x,a)') 'expected an error, got none'
            end if
         end if
         if (allocated(error)) deallocate (error)
      end do
      write (*, '(a,": ",i0," passed, ",i0," failed")') suite, np, nf
      passed = passed + np
      failed = failed + nf
   end subroutine run_testsuite

   !> A reproducible pseudo-random number in [0, 1) (a linear congruential generator).
   real(dp) function next_random(state)
      integer, intent(inout) :: state
      ! Park and Miller's minimal standard generator; the state stays in
      ! 1 .. 2**31 - 2, so the product fits in 64 bits only: use a 64-bit
      ! intermediate.
      state = int(modulo(int(state, int64)*16807_int64, 2147483647_int64))
      next_random = real(state, dp)/2147483647.0_dp
   end function next_random

end module fekap_testing
