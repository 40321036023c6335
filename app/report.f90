!> What the program tells its user: lines to standard output, an error to
!> standard error with the exit code of its kind. The only place that
!> prints and sets the exit code.
module fekap_app_report
   use, intrinsic :: iso_c_binding, only: c_int
   use, intrinsic :: iso_fortran_env, only: error_unit, output_unit
   use fekap, only: error_type, fatal_error, error_input, error_analysis, error_output, interrupt_signal
   implicit none
   private

   public :: say, finish, stop_if_interrupted, c_exit

   interface
      !> C's exit: a status code that is a variable (F2008 `stop` takes constants only).
      subroutine c_exit(status) bind(C, name='exit')
         import :: c_int
         implicit none
         integer(c_int), value :: status
      end subroutine c_exit
   end interface

contains

   !> A line to standard output; a closed output is ignored.
   subroutine say(text)
      character(*), intent(in) :: text
      integer :: ios
      ! Nothing more to say to a closed output: the run goes on.
      write (output_unit, '(a)', iostat=ios) text
      if (ios /= 0) return
      flush (output_unit, iostat=ios)
      if (ios /= 0) return
   end subroutine say

   !> Stop with exit 1 and a message when a signal came before the run's
   !> files were opened (`when` says during what).
   subroutine stop_if_interrupted(deck, when)
      character(*), intent(in) :: deck, when
      type(error_type), allocatable :: error
      character(len=12) :: number
      if (interrupt_signal() == 0) return
      write (number, '(i0)') interrupt_signal()
      call fatal_error(error, 'fekap: '//deck//': interrupted by signal '//trim(number)//' '//when// &
         & '; nothing was run or written')
      call finish(error)
   end subroutine stop_if_interrupted

   !> Print the error and exit with the code of its kind.
   subroutine finish(error)
      type(error_type), intent(in) :: error
      integer :: ios
      ! A closed standard error loses the message, not the exit code.
      write (error_unit, '(a)', iostat=ios) error%message
      if (ios /= 0) continue
      select case (error%kind)
      case (error_input)
         call c_exit(2_c_int)
      case (error_analysis)
         call c_exit(3_c_int)
      case (error_output)
         call c_exit(4_c_int)
      case default
         call c_exit(1_c_int)
      end select
   end subroutine finish

end module fekap_app_report
