!> Errors as values: library code fills an `error_type` and returns;
!> only the app prints it and turns its kind into an exit code.
module fekap_error
   use fekap_kinds, only: dp
   implicit none
   private

   public :: error_type, fatal_error, input_error, analysis_error, output_error, at_time

   !> Kinds of error, which the app maps to exit codes 1, 2, 3 and 4.
   integer, parameter, public :: error_other = 1
   integer, parameter, public :: error_input = 2
   integer, parameter, public :: error_analysis = 3
   !> An output file or directory could not be written (full disk, no permission).
   integer, parameter, public :: error_output = 4

   !> An error travelling up to the app.
   type :: error_type
      !> One of error_other, error_input, error_analysis, error_output.
      integer :: kind = error_other
      !> What went wrong, possibly several lines (deck diagnostics).
      character(:), allocatable :: message
      !> The analysis time the error happened at (a step's, or a cut
      !> step's try), when the message names it (it then begins with it):
      !> the time loop names the step alone. Not allocated: the message names
      !> no time.
      real(dp), allocatable :: time
   end type error_type

contains

   !> Allocate an error of kind error_other.
   pure subroutine fatal_error(error, message)
      type(error_type), allocatable, intent(out) :: error
      character(*), intent(in) :: message
      allocate (error)
      error%kind = error_other
      error%message = message
   end subroutine fatal_error

   !> Allocate an input error (bad deck or bad command line): exit code 2.
   pure subroutine input_error(error, message)
      type(error_type), allocatable, intent(out) :: error
      character(*), intent(in) :: message
      allocate (error)
      error%kind = error_input
      error%message = message
   end subroutine input_error

   !> Allocate an analysis error (no convergence, singular configuration): exit code 3.
   pure subroutine analysis_error(error, message, t)
      type(error_type), allocatable, intent(out) :: error
      character(*), intent(in) :: message
      !> The time the message names (error_type's time).
      real(dp), intent(in), optional :: t
      allocate (error)
      error%kind = error_analysis
      error%message = message
      if (present(t)) error%time = t
   end subroutine analysis_error

   !> Say that `error`'s message now names the time t (error_type's time).
   pure subroutine at_time(error, t)
      type(error_type), intent(inout) :: error
      real(dp), intent(in) :: t
      error%time = t
   end subroutine at_time

   !> Allocate an output error (a file or directory that cannot be written): exit code 4.
   pure subroutine output_error(error, message)
      type(error_type), allocatable, intent(out) :: error
      character(*), intent(in) :: message
      allocate (error)
      error%kind = error_output
      error%message = message
   end subroutine output_error

end module fekap_error
