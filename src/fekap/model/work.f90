!> Counts and sampled phase times of the work an analysis method does, for
!> the listing's closing summary: a record of the run, below the methods
!> that fill it and the writers that print it.
module fekap_model_work
   use fekap_kinds, only: dp
   implicit none
   private

   public :: work_counts_type, phase_seconds

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
      !> The square-root form (FEM): band LU factorisations of B_f, and the
      !> condition estimates made of them at the steps' predictors (the
      !> others are bounded from the last one, fekap_fem_fill's check_predictor).
      integer :: root_factorisations = 0
      integer :: condition_estimates = 0
      !> Steps accepted at the round-off floor with the residual above the
      !> tolerance (fekap_stepping_newton's stop_at_floor).
      integer :: floor_steps = 0
      !> Dynamics: the largest local error estimate of an accepted step
      !> (negative: none made), its time and where it is (a dof's name), and
      !> the adaptive steps rejected for an estimate above the tolerance.
      real(dp) :: largest_estimate = -1
      real(dp) :: largest_estimate_t = 0
      character(len=100) :: largest_estimate_where = ''
      integer :: rejected_steps = 0
      !> Smallest pivot ratio of the tangents used for velocities (1: none computed),
      !> a measure of how close the run came to a singular configuration.
      real(dp) :: min_pivot_ratio = 1
      !> Wall-clock seconds in residual/tangent assembly, factorisations and
      !> solves, measured on a sample of the steps (a clock read is not free
      !> next to a step of a small mechanism), and the analysis
      !> seconds of those steps (0: no sample, the phases were not timed).
      !> phase_seconds scales them to the whole run.
      real(dp) :: seconds_assembly = 0
      real(dp) :: seconds_factorisation = 0
      real(dp) :: seconds_solves = 0
      real(dp) :: seconds_sampled = 0
   end type work_counts_type

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

end module fekap_model_work
