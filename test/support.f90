!> Small helpers shared by the pFUnit suites: the message of a library error
!> (for an assertion that it is not set) and a reproducible random sequence.
module test_support
   use, intrinsic :: iso_fortran_env, only: int64
   use fekap_kinds, only: dp
   use fekap_error, only: error_type
   implicit none
   private

   public :: error_text, next_random

contains

   !> The message of `error`, or an empty string when it is not set.
   function error_text(error) result(text)
      type(error_type), allocatable, intent(in) :: error
      character(:), allocatable :: text
      text = ''
      if (allocated(error)) text = error%message
   end function error_text

   !> A reproducible pseudo-random number in [0, 1) (a linear congruential generator).
   real(dp) function next_random(state)
      integer, intent(inout) :: state
      ! Park and Miller's minimal standard generator; the state stays in
      ! 1 .. 2**31 - 2, so the product fits in 64 bits only: use a 64-bit
      ! intermediate.
      state = int(modulo(int(state, int64)*16807_int64, 2147483647_int64))
      next_random = real(state, dp)/2147483647.0_dp
   end function next_random

end module test_support
