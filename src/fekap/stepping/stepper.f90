!> The interface every analysis method offers to the time loop: start at the
!> initial configuration, then advance to each new time. The finite element
!> method and both constraint-equation methods extend `stepper_type`.
module fekap_stepping_stepper
   use, intrinsic :: iso_c_binding, only: c_int, c_long
   use, intrinsic :: iso_fortran_env, only: int64
   use fekap_kinds, only: dp
   use fekap_error, only: error_type
   use fekap_model_results, only: step_result_type
   use fekap_model_work, only: work_counts_type
   implicit none
   private

   public :: stepper_type, clock_seconds, coarse_clock_seconds, split_seconds
   ! The type of stepper_type's counts, for its users.
   public :: work_counts_type
   public :: phase_timed, split_timed

   !> The two samples of steps that the timers read the precise clock on (a
   !> read is not free next to a step of Example 1): a method times the
   !> phases of its analysis (assembly, factorisation, solves) on the first
   !> `sample` steps and every `sample`-th after them; the time loop splits
   !> its time into analysis and output as on the steps halfway between those,
   !> and on every step of a run of at most split_all steps. The two samples
   !> are kept apart: the phase timers' clock reads slow what follows them
   !> too: on Example 1 a split sampled on the same steps overstated the
   !> output's time (figures in docs/performance.md, "Timers").
   integer, parameter :: sample = 16, split_all = 256

   !> Linux's CLOCK_MONOTONIC_COARSE (<linux/time.h>).
   integer(c_int), parameter :: clock_monotonic_coarse = 6

   !> struct timespec of the C library (time_t and long are both long on Linux).
   type, bind(C) :: timespec_type
      integer(c_long) :: seconds = 0
      integer(c_long) :: nanoseconds = 0
   end type timespec_type

   interface
      !> clock_gettime(2) of the C library.
      integer(c_int) function clock_gettime(clock, time) bind(C, name='clock_gettime')
         import :: c_int, timespec_type
         implicit none
         integer(c_int), value :: clock
         type(timespec_type), intent(out) :: time
      end function clock_gettime
   end interface

   type, abstract :: stepper_type
      type(work_counts_type) :: counts
   contains
      !> Fill `result` with the initial configuration at the start time
      !> (and its velocities/accelerations when asked for).
      procedure(start_interface), deferred :: start
      !> Solve for the configuration at time t from the last accepted one.
      procedure(advance_interface), deferred :: advance
      !> Lines on the method's discretisation for the listing's plan ('' if none).
      procedure :: plan_text => stepper_plan_text
   end type stepper_type

   abstract interface
      subroutine start_interface(self, result, error)
         import :: stepper_type, step_result_type, error_type
         implicit none
         class(stepper_type), intent(inout) :: self
         type(step_result_type), intent(inout) :: result
         type(error_type), allocatable, intent(out) :: error
      end subroutine start_interface

      subroutine advance_interface(self, t, result, error)
         import :: stepper_type, step_result_type, error_type, dp
         implicit none
         class(stepper_type), intent(inout) :: self
         real(dp), intent(in) :: t
         type(step_result_type), intent(inout) :: result
         type(error_type), allocatable, intent(out) :: error
      end subroutine advance_interface
   end interface

contains

   !> No discretisation to describe: the default of plan_text.
   function stepper_plan_text(self) result(text)
      class(stepper_type), intent(in) :: self
      character(:), allocatable :: text
      text = ''
   end function stepper_plan_text

   !> Whether the phases of a method's n-th step (n >= 1) are timed.
   pure logical function phase_timed(n)
      integer, intent(in) :: n
      phase_timed = n <= sample .or. mod(n, sample) == 0
   end function phase_timed

   !> Whether step n (0: the start) of a run of nsteps is in the time loop's
   !> analysis/output sample: every step of a short run; else halfway between
   !> the steps of phase_timed (apart from them after the first `sample`).
   pure logical function split_timed(n, nsteps)
      integer, intent(in) :: n, nsteps
      split_timed = nsteps <= split_all .or. mod(n, sample) == sample/2
   end function split_timed

   !> Seconds in analysis and in output of a loop that took `total` seconds,
   !> split as in the sampled steps, which spent sampled(1) seconds in
   !> analysis and sampled(2) in output (all of it analysis without a sample).
   pure function split_seconds(sampled, total) result(seconds)
      real(dp), intent(in) :: sampled(2), total
      real(dp) :: seconds(2)
      seconds = [total, 0.0_dp]
      if (sum(sampled) > 0) seconds = sampled*(total/sum(sampled))
   end function split_seconds

   !> Wall-clock time in seconds, for the phase timers.
   real(dp) function clock_seconds() result(seconds)
      integer(int64) :: ticks, rate
      call system_clock(ticks, rate)
      seconds = real(ticks, dp)/real(rate, dp)
   end function clock_seconds

   !> Wall-clock time in seconds to a few milliseconds (the kernel's tick),
   !> for decisions on the scale of a tenth of a second, such as when to flush
   !> output: Linux's coarse monotonic clock, a fraction of clock_seconds'
   !> cost a read (docs/performance.md). Without it, clock_seconds.
   real(dp) function coarse_clock_seconds() result(seconds)
      type(timespec_type) :: time
      if (clock_gettime(clock_monotonic_coarse, time) /= 0) then
         seconds = clock_seconds()
         return
      end if
      seconds = real(time%seconds, dp) + 1.0e-9_dp*real(time%nanoseconds, dp)
   end function coarse_clock_seconds

end module fekap_stepping_stepper
