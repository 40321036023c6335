!> A stop requested by a signal (SIGINT, SIGTERM, SIGHUP): the handler only records
!> it, which is all a signal handler may safely do; the time loop looks at the
!> record after every step and stops there, so the listing and stderr can say
!> where and why, and every completed step's rows stay.
!>
!> The record is the one piece of module state in FEKAP: a signal handler has
!> no other place to leave it.
module fekap_solver_interrupt
   use, intrinsic :: iso_c_binding, only: c_int, c_funptr, c_funloc
   use fekap_posix, only: c_signal
   implicit none
   private

   public :: catch_interrupts, interrupt_signal

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

   subroutine record_signal(signum) bind(C)
      integer(c_int), value :: signum
      received = signum
   end subroutine record_signal

   !> The signal that asked the run to stop (1 SIGHUP, 2 SIGINT, 15 SIGTERM), or 0.
   integer function interrupt_signal()
      interrupt_signal = received
   end function interrupt_signal

end module fekap_solver_interrupt
