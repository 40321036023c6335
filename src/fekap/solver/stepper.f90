!> The interface every analysis method offers to the time loop: start at the
!> initial configuration, then advance to each new time. The finite element
!> method and both constraint-equation methods extend `stepper_type`.
module fekap_solver_stepper
   use fekap_kinds, only: dp
   use fekap_error, only: error_type
   use fekap_model_results, only: step_result_type
   implicit none
   private

   public :: stepper_type, work_counts_type, clock_seconds, phase_seconds

   !> Counts of the work done, for the listing's closing summary.
   type :: work_counts_type
      integer :: steps = 0
      integer :: iterations = 0
      integer :: residual_assemblies = 0
      integer :: tangent_assemblies = 0
      integer :: cholesky_factorisations = 0
      integer :: lu_factorisations = 0
      integer :: velocity_solves = 0
      integer :: acceleration_solves = 0
      integer :: slideline_evaluations = 0
      !> Smallest pivot ratio of the tangents used for velocities (1: none computed),
      !> a measure of how close the run came to a singular configuration.
      real(dp) :: min_pivot_ratio = 1
      !> Wall-clock seconds in residual/tangent assembly, factorisations and
      !> solves, measured on a sample of the steps (a clock read costs about
      !> 40 ns, a step of a small mechanism about 2 us), and the analysis
      !> seconds of those steps (0: no sample, the phases were not timed).
      !> phase_seconds scales them to the whole run.
      real(dp) :: seconds_assembly = 0
      real(dp) :: seconds_factorisation = 0
      real(dp) :: seconds_solves = 0
      real(dp) :: seconds_sampled = 0
   end type work_counts_type

   type, abstract :: stepper_type
      type(work_counts_type) :: counts
   contains
      !> Fill `result` with the initial configuration at the start time
      !> (and its velocities/accelerations when asked for).
      procedure(start_interface), deferred :: start
      !> Solve for the configuration at time t from the last accepted one.
      procedure(advance_interface), deferred :: advance
   end type stepper_type

   abstract interface
      subroutine start_interface(self, result, error)
         import :: stepper_type, step_result_type, error_type
         class(stepper_type), intent(inout) :: self
         type(step_result_type), intent(inout) :: result
         type(error_type), allocatable, intent(out) :: error
      end subroutine start_interface

      subroutine advance_interface(self, t, result, error)
         import :: stepper_type, step_result_type, error_type, dp
         class(stepper_type), intent(inout) :: self
         real(dp), intent(in) :: t
         type(step_result_type), intent(inout) :: result
         type(error_type), allocatable, intent(out) :: error
      end subroutine advance_interface
   end interface

contains

   !> Seconds in assembly, factorisation and solves over a run whose analysis
   !> took `analysis` seconds: the sampled steps' phase times times the ratio
   !> of the whole analysis time to theirs (zeros without a sample).
   pure function phase_seconds(counts, analysis) result(seconds)
      type(work_counts_type), intent(in) :: counts
      real(dp), intent(in) :: analysis
      real(dp) :: seconds(3)
      seconds = 0
      if (counts%seconds_sampled > 0) seconds = [counts%seconds_assembly, counts%seconds_factorisation, &
         & counts%seconds_solves]*(analysis/counts%seconds_sampled)
   end function phase_seconds

   !> Wall-clock time in seconds, for the phase timers.
   real(dp) function clock_seconds() result(seconds)
      integer(8) :: count, rate
      call system_clock(count, rate)
      seconds = real(count, dp)/real(rate, dp)
   end function clock_seconds

end module fekap_solver_stepper
