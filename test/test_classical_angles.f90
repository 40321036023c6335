!> Tests of fekap_classical_angles: Example 1 against the closed-form four-bar
!> motion and against differences of its own positions, the refusal of
!> other mechanisms, non-convergence as an analysis error, work counts, and
!> the iteration counts of the paper's Tables 1-3 (printed for the record).
module test_classical_angles
   use fekap_kinds, only: dp
   use fekap_testing, only: unittest_type, new_unittest, check, test_failed, error_type
   use fekap_error, only: error_input, error_analysis
   use fekap_model, only: model_type, predictor_previous, predictor_extrapolate, convergence_paper, &
      & convergence_default
   use fekap_model_results, only: step_result_type
   use fekap_classical_angles, only: angles_stepper_type, new_angles_stepper
   use classical_models, only: four_bar_model, appendage_model, slider_crank_model, four_bar_exact, run_steps, pi, &
      & check_branch_jump_cut
   implicit none
   private
   public :: collect_classical_angles

contains

   subroutine collect_classical_angles(tests)
      type(unittest_type), allocatable, intent(out) :: tests(:)
      tests = [ &
         & new_unittest('example1_closed_form', test_closed_form), &
         & new_unittest('example1_differences', test_differences), &
         & new_unittest('refuses_non_four_bar', test_refuses), &
         & new_unittest('no_convergence', test_no_convergence), &
         & new_unittest('work_counts', test_work_counts), &
         & new_unittest('branch_jump_cut', test_branch_jump_cut), &
         & new_unittest('iterations_tables_1_3', test_iterations) &
         & ]
   end subroutine collect_classical_angles

   !> Positions, velocities and accelerations of B and C equal the closed form
   !> to 1e-9 (relative to each quantity's scale) at every step; link angles unwrapped.
   subroutine test_closed_form(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(angles_stepper_type) :: stepper
      type(step_result_type), allocatable :: res(:)
      real(dp) :: b(2), vb(2), ab(2), c(2), vc(2), ac(2)
      integer :: k
      call four_bar_model(model)
      call new_angles_stepper(stepper, model, error)
      if (allocated(error)) return
      call run_steps(stepper, model, res, error)
      if (allocated(error)) return
      call check(error, size(res), 41, 'number of results')
      do k = 0, ubound(res, 1)
         call four_bar_exact(res(k)%t, b, vb, ab, c, vc, ac)
         call check_vectors(error, res(k), 2, b, vb, ab)
         call check_vectors(error, res(k), 3, c, vc, ac)
         call check(error, res(k)%angle(1), 2*pi*res(k)%t, 'crank angle', rel=1.0e-12_dp, abs=1.0e-12_dp)
         call check(error, res(k)%omega(1), 2*pi, 'crank rate')
         call check(error, res(k)%angle(2), atan2(c(2) - b(2), c(1) - b(1)) + merge(2*pi, 0.0_dp, &
            & atan2(c(2) - b(2), c(1) - b(1)) < 0 .and. res(k)%angle(2) > pi), 'coupler angle', abs=1.0e-9_dp)
         if (allocated(error)) then
            error%message = 'at t = '//real_str(res(k)%t)//': '//error%message
            return
         end if
      end do
   end subroutine test_closed_form

   !> Compare node j of a result with the exact position, velocity and acceleration.
   subroutine check_vectors(error, res, j, x, v, a)
      type(error_type), allocatable, intent(inout) :: error
      type(step_result_type), intent(in) :: res
      integer, intent(in) :: j
      real(dp), intent(in) :: x(2), v(2), a(2)
      integer :: i
      do i = 1, 2
         call check(error, res%pos(i, j), x(i), 'position', rel=1.0e-9_dp, abs=1.0e-9_dp*4)
         call check(error, res%vel(i, j), v(i), 'velocity', rel=1.0e-9_dp, abs=1.0e-9_dp*4*2*pi)
         call check(error, res%acc(i, j), a(i), 'acceleration', rel=1.0e-9_dp, abs=1.0e-9_dp*4*(2*pi)**2)
      end do
   end subroutine check_vectors

   function real_str(x) result(s)
      real(dp), intent(in) :: x
      character(:), allocatable :: s
      character(len=24) :: buf
      write (buf, '(f0.4)') x
      s = trim(buf)
   end function real_str

   !> Velocities and accelerations equal central differences of the positions.
   subroutine test_differences(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(angles_stepper_type) :: stepper
      type(step_result_type), allocatable :: res(:)
      call four_bar_model(model)
      model%analysis%dt = 2.5e-4_dp
      model%analysis%t_end = 0.02_dp
      call new_angles_stepper(stepper, model, error)
      if (allocated(error)) return
      call run_steps(stepper, model, res, error)
      if (allocated(error)) return
      call check_differences(error, res, model%analysis%dt)
   end subroutine test_differences

   !> Central differences of positions against the velocities and accelerations of every node.
   subroutine check_differences(error, res, h)
      type(error_type), allocatable, intent(inout) :: error
      type(step_result_type), intent(in) :: res(0:)
      real(dp), intent(in) :: h
      integer :: k, j, i
      real(dp) :: v, a, vscale, ascale
      vscale = maxval(abs(res(1)%vel))
      ascale = maxval(abs(res(1)%acc))
      do k = 1, ubound(res, 1) - 1
         do j = 1, size(res(k)%pos, 2)
            do i = 1, 2
               v = (res(k + 1)%pos(i, j) - res(k - 1)%pos(i, j))/(2*h)
               a = (res(k + 1)%pos(i, j) - 2*res(k)%pos(i, j) + res(k - 1)%pos(i, j))/h**2
               call check(error, res(k)%vel(i, j), v, 'velocity by differences', abs=1.0e-5_dp*vscale)
               call check(error, res(k)%acc(i, j), a, 'acceleration by differences', abs=1.0e-5_dp*ascale)
            end do
         end do
      end do
   end subroutine check_differences

   subroutine test_refuses(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(angles_stepper_type) :: stepper
      type(error_type), allocatable :: got
      character(*), parameter :: prefix = 'method angles covers four-bar linkages only: '
      call slider_crank_model(model)
      call new_angles_stepper(stepper, model, got)
      if (.not. allocated(got)) then
         call test_failed(error, 'the slider-crank was accepted')
         return
      end if
      write (*, '(6x,a)') got%message
      call check(error, got%kind, error_input, 'kind')
      call check(error, index(got%message, prefix) == 1, 'message: '//got%message)
      call check(error, index(got%message, '2 links') > 0, 'says how many links: '//got%message)
      call check(error, index(got%message, '1 slideline') > 0, 'names the slideline: '//got%message)
      deallocate (got)
      call appendage_model(model)
      call new_angles_stepper(stepper, model, got)
      if (.not. allocated(got)) then
         call test_failed(error, 'the four-bar with appendage was accepted')
         return
      end if
      write (*, '(6x,a)') got%message
      call check(error, index(got%message, prefix//'found 5 links') == 1, 'message: '//got%message)
      call check(error, index(got%message, '1 weld') > 0, 'names the weld: '//got%message)
   end subroutine test_refuses

   !> One iteration at a quarter turn per step cannot converge: an analysis error, no garbage.
   subroutine test_no_convergence(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(angles_stepper_type) :: stepper
      type(step_result_type), allocatable :: res(:)
      type(error_type), allocatable :: got
      call four_bar_model(model)
      model%analysis%dt = 0.25_dp
      model%analysis%max_iter = 1
      call new_angles_stepper(stepper, model, error)
      if (allocated(error)) return
      call run_steps(stepper, model, res, got)
      if (.not. allocated(got)) then
         call test_failed(error, 'no error with max_iter = 1')
         return
      end if
      write (*, '(6x,a)') got%message
      call check(error, got%kind, error_analysis, 'kind')
      ! The step is cut max_cuts times before it is given up; the message says what to try.
      call check(error, index(got%message, 't = ') == 1 .and. &
         & index(got%message, ' did not converge in 1 iterations (residual ') > 0 .and. &
         & index(got%message, '(after 8 step cuts; try a smaller time step or another predictor)') > 0, &
         & 'message: '//got%message)
   end subroutine test_no_convergence

   !> No velocity solve without velocities, no acceleration solve without accelerations.
   subroutine test_work_counts(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(angles_stepper_type) :: stepper
      type(step_result_type), allocatable :: res(:)
      call four_bar_model(model)
      model%analysis%accelerations = .false.
      call new_angles_stepper(stepper, model, error)
      if (allocated(error)) return
      call run_steps(stepper, model, res, error)
      if (allocated(error)) return
      call check(error, stepper%counts%steps, 40, 'steps')
      call check(error, stepper%counts%velocity_solves, 41, 'velocity solves')
      call check(error, stepper%counts%acceleration_solves, 0, 'acceleration solves')
      call check(error, stepper%counts%iterations, sum(res%iterations), 'iterations')
      call check(error, .not. res(5)%has_acceleration .and. res(5)%has_velocity, 'result flags')
      model%analysis%velocities = .false.
      call new_angles_stepper(stepper, model, error)
      if (allocated(error)) return
      call run_steps(stepper, model, res, error)
      if (allocated(error)) return
      call check(error, stepper%counts%velocity_solves, 0, 'velocity solves without velocities')
   end subroutine test_work_counts

   !> Example 1 at dt = 0.5, extrapolating predictor: the jump to the other
   !> branch is cut (check_branch_jump_cut).
   subroutine test_branch_jump_cut(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(angles_stepper_type) :: stepper
      call four_bar_model(model)
      model%analysis%dt = 0.5_dp
      model%analysis%predictor = predictor_extrapolate
      call new_angles_stepper(stepper, model, error)
      if (allocated(error)) return
      call check_branch_jump_cut(stepper, model, error)
   end subroutine test_branch_jump_cut

   !> Iterations per step of Example 1 at dt = 0.025, 0.25, 0.5 (the paper's
   !> Tables 1-3), with the paper's predictor and test and with FEKAP's defaults.
   subroutine test_iterations(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp), parameter :: dts(3) = [0.025_dp, 0.25_dp, 0.5_dp]
      integer :: i, s
      do s = 1, 2
         do i = 1, 3
            call record(error, dts(i), merge(predictor_previous, predictor_extrapolate, s == 1), &
               & merge(convergence_paper, convergence_default, s == 1))
            if (allocated(error)) return
         end do
      end do
   end subroutine test_iterations

   subroutine record(error, dt, predictor, convergence)
      type(error_type), allocatable, intent(inout) :: error
      real(dp), intent(in) :: dt
      integer, intent(in) :: predictor, convergence
      type(model_type) :: model
      type(angles_stepper_type) :: stepper
      type(step_result_type), allocatable :: res(:)
      type(error_type), allocatable :: got
      real(dp) :: b(2), vb(2), ab(2), c(2), vc(2), ac(2), dev
      integer :: k, last
      call four_bar_model(model)
      model%analysis%dt = dt
      model%analysis%predictor = predictor
      model%analysis%convergence = convergence
      call new_angles_stepper(stepper, model, error)
      if (allocated(error)) return
      call run_steps(stepper, model, res, got)
      last = ubound(res, 1)
      if (allocated(got)) last = stepper%counts%steps - 1
      write (*, '(6x,a,f5.3,a,a,*(1x,i0))') 'angles dt = ', dt, merge(' previous+paper     ', ' extrapolate+default', &
         & predictor == predictor_previous), ' iterations:', (res(k)%iterations, k=1, last)
      dev = 0
      do k = 1, last
         call four_bar_exact(res(k)%t, b, vb, ab, c, vc, ac)
         dev = max(dev, norm2(res(k)%pos(:, 3) - c))
         if (norm2(res(k)%pos(:, 3) - c) > 1.0e-6_dp) write (*, '(8x,a,f5.3,a,2f9.4,a,2f9.4)') 'at t = ', res(k)%t, &
            & ' C = ', res(k)%pos(:, 3), ' is on the other assembly branch; the closed form is', c
      end do
      write (*, '(8x,a,es9.2)') 'largest distance of C from the closed form:', dev
      if (allocated(got)) then
         write (*, '(6x,a)') got%message
         call test_failed(error, got%message)
         return
      end if
      do k = 1, ubound(res, 1)
         ! A cut step counts the iterations of all its sub-steps.
         call check(error, res(k)%iterations > 0 .and. (res(k)%iterations <= model%analysis%max_iter .or. &
            & res(k)%cuts > 0), 'iteration count')
      end do
   end subroutine record

end module test_classical_angles
