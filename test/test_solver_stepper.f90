!> Tests of fekap_solver_stepper: the phase times of a sample of the steps
!> scaled to the whole analysis.
module test_solver_stepper
   use fekap_kinds, only: dp
   use fekap_testing, only: unittest_type, new_unittest, check, error_type
   use fekap_solver_stepper, only: work_counts_type, phase_seconds
   implicit none
   private
   public :: collect_solver_stepper

contains

   subroutine collect_solver_stepper(tests)
      type(unittest_type), allocatable, intent(out) :: tests(:)
      tests = [ &
         & new_unittest('phase_seconds', test_phase_seconds) &
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

end module test_solver_stepper
