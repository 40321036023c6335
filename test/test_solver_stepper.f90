!> Tests of fekap_solver_stepper: the phase times of a sample of the steps
!> scaled to the whole analysis, the loop's time split as in its sample, and
!> the coarse clock.
module test_solver_stepper
   use fekap_kinds, only: dp
   use fekap_testing, only: unittest_type, new_unittest, check, error_type
   use fekap_model_work, only: work_counts_type, phase_seconds
   use fekap_solver_stepper, only: split_seconds, clock_seconds, &
      & coarse_clock_seconds, phase_timed, split_timed
   implicit none
   private
   public :: collect_solver_stepper

contains

   subroutine collect_solver_stepper(tests)
      type(unittest_type), allocatable, intent(out) :: tests(:)
      tests = [ &
         & new_unittest('phase_seconds', test_phase_seconds), &
         & new_unittest('split_seconds', test_split_seconds), &
         & new_unittest('phase_timed', test_phase_timed), &
         & new_unittest('split_timed', test_split_timed), &
         & new_unittest('coarse_clock_seconds', test_coarse_clock) &
         & ]
   end subroutine collect_solver_stepper

   !> Without a sample the phases are zero; with one, each phase's share of
   !> the sampled steps is its share of the analysis.
   subroutine test_phase_seconds(error)
      type(error_type), allocatable, intent(out) :: error
      type(work_counts_type) :: counts
      real(dp) :: seconds(3)
      seconds = phase_seconds(counts, 2.0_dp)
      call check(error, all(seconds == 0), 'no sample: zeros')
      if (allocated(error)) return
      counts%seconds_assembly = 0.1_dp
      counts%seconds_factorisation = 0.05_dp
      counts%seconds_solves = 0.025_dp
      counts%seconds_sampled = 0.25_dp
      seconds = phase_seconds(counts, 2.0_dp)
      call check(error, seconds(1), 0.8_dp, 'assembly scaled', rel=1.0e-14_dp)
      if (allocated(error)) return
      call check(error, seconds(2), 0.4_dp, 'factorisation scaled', rel=1.0e-14_dp)
      if (allocated(error)) return
      call check(error, seconds(3), 0.2_dp, 'solves scaled', rel=1.0e-14_dp)
   end subroutine test_phase_seconds

   !> Without a sample the loop counts as analysis; with one, the loop's time
   !> is shared as in the sample.
   subroutine test_split_seconds(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: seconds(2)
      seconds = split_seconds([0.0_dp, 0.0_dp], 3.0_dp)
      call check(error, seconds(1), 3.0_dp, 'no sample: analysis', rel=1.0e-15_dp)
      if (allocated(error)) return
      call check(error, seconds(2), 0.0_dp, 'no sample: no output')
      if (allocated(error)) return
      seconds = split_seconds([0.03_dp, 0.01_dp], 2.0_dp)
      call check(error, seconds(1), 1.5_dp, 'analysis scaled', rel=1.0e-14_dp)
      if (allocated(error)) return
      call check(error, seconds(2), 0.5_dp, 'output scaled', rel=1.0e-14_dp)
   end subroutine test_split_seconds

   !> The phases are timed on the first 16 steps and on one in 16 after them.
   subroutine test_phase_timed(error)
      type(error_type), allocatable, intent(out) :: error
      integer :: n, count
      call check(error, all([(phase_timed(n), n = 1, 16)]), 'the first 16 steps')
      if (allocated(error)) return
      count = 0
      do n = 17, 16016
         if (phase_timed(n)) count = count + 1
      end do
      call check(error, count, 1000, 'one step in 16 after them')
   end subroutine test_phase_timed

   !> The loop's split is sampled on every step of a short run; in a long one
   !> on one step in 16, never one on which the phases are timed (after the
   !> first 16).
   subroutine test_split_timed(error)
      type(error_type), allocatable, intent(out) :: error
      integer :: n, count
      call check(error, all([(split_timed(n, 256), n = 0, 256)]), 'every step of a run of 256')
      if (allocated(error)) return
      count = 0
      do n = 1, 16000
         if (.not. split_timed(n, 16000)) cycle
         count = count + 1
         if (n > 16) call check(error, .not. phase_timed(n), 'apart from the phase-timed steps')
         if (allocated(error)) return
      end do
      call check(error, count, 1000, 'one step in 16 of a long run')
   end subroutine test_split_timed

   !> The coarse clock keeps time with the precise one, to its resolution
   !> (a few milliseconds), and never runs backwards.
   subroutine test_coarse_clock(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: coarse0, coarse1, precise0, precise1, x
      integer :: i
      coarse0 = coarse_clock_seconds()
      precise0 = clock_seconds()
      x = 0
      do while (clock_seconds() - precise0 < 0.05_dp)
         do i = 1, 1000
            x = x + sqrt(real(i, dp))
         end do
      end do
      coarse1 = coarse_clock_seconds()
      precise1 = clock_seconds()
      call check(error, coarse1 >= coarse0, 'monotonic')
      if (allocated(error)) return
      call check(error, coarse1 - coarse0, precise1 - precise0, 'same elapsed time to 20 ms', abs=0.02_dp)
      if (allocated(error)) return
      call check(error, x > 0, 'work done')
   end subroutine test_coarse_clock

end module test_solver_stepper
