!> A stop requested by a signal (SIGINT, SIGTERM, SIGHUP): the handler only records
!> it, which is all a signal handler may safely do; the time loop looks at the
!> record after every step and stops there, and the long loops inside a step
!> of the FEM and the dynamics integrators (Newton's iterations, the step
!> cuts, statics' load steps; not the constraint-equation methods, whose
!> steps are short) look at it too
!> and end the step with interrupt_error, so the listing and stderr can say
!> where and why, and every completed step's rows stay.
!>
!> The record is the one piece of module state in FEKAP: a signal handler has
!> no other place to leave it.
module fekap_stepping_interrupt
   use, intrinsic :: iso_c_binding, only: c_int, c_funptr, c_funloc
   use fekap_posix, only: c_signal
   use fekap_error, only: error_type, fatal_error
   implicit none
   private

   public :: catch_interrupts, interrupt_signal, interrupt_error, interrupt_reads

   interface
      !> siginterrupt(3): whether the signal interrupts a system call (read(2)
      !> returns EINTR) instead of restarting it.
      function c_siginterrupt(signum, flag) bind(C, name='siginterrupt') result(status)
         import :: c_int
         implicit none
         integer(c_int), value :: signum, flag
         integer(c_int) :: status
      end function c_siginterrupt
   end interface

   integer(c_int), parameter :: sighup = 1, sigint = 2, sigterm = 15

   !> The signal received, 0 if none.
   integer(c_int), volatile :: received = 0

contains

   !> Route SIGINT, SIGTERM and SIGHUP (the terminal closed) to the recorder.
   subroutine catch_interrupts()
      type(c_funptr) :: previous
      previous = c_signal(sighup, c_funloc(record_signal))
      previous = c_signal(sigint, c_funloc(record_signal))
      previous = c_signal(sigterm, c_funloc(record_signal))
   end subroutine catch_interrupts

   !> With `on`, the three signals interrupt a read that waits (a deck read
   !> from a terminal or a pipe, `fekap /dev/stdin`) instead of restarting
   !> it, so that the read ends and the run can stop; off again for the run.
   subroutine interrupt_reads(on)
      logical, intent(in) :: on
      integer(c_int) :: flag, status
      flag = merge(1_c_int, 0_c_int, on)
      status = c_siginterrupt(sighup, flag)
      status = c_siginterrupt(sigint, flag)
      status = c_siginterrupt(sigterm, flag)
   end subroutine interrupt_reads

   subroutine record_signal(signum) bind(C)
      integer(c_int), value :: signum
      received = signum
   end subroutine record_signal

   !> The signal that asked the run to stop (1 SIGHUP, 2 SIGINT, 15 SIGTERM), or 0.
   integer function interrupt_signal()
      interrupt_signal = received
   end function interrupt_signal

   !> The error that stops a step in progress when a signal has asked the run
   !> to stop (kind error_other: exit code 1, as a stop between steps); the
   !> time loop replaces its message with the step's. Not allocated if no
   !> signal came.
   subroutine interrupt_error(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=60) :: text
      if (received == 0) return
      write (text, '(a,i0,a)') 'interrupted by signal ', received, ' inside the step'
      call fatal_error(error, trim(text))
   end subroutine interrupt_error

end module fekap_stepping_interrupt
