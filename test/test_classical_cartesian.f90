!> Tests of fekap_classical_cartesian: Example 1 against the closed form and
!> differences, Example 2's appendage point, Example 4's straight line,
!> Example 3's redundancy (refused, then removed), a slider-crank against its
!> closed form, Example 5's rates against differences, refusals and
!> non-convergence, work counts, and the iteration counts of Tables 1-3.
module test_classical_cartesian
   use fekap_kinds, only: dp
   use fekap_testing, only: unittest_type, new_unittest, check, test_failed, error_type
   use fekap_error, only: error_input, error_analysis
   use fekap_model, only: model_type, predictor_previous, predictor_extrapolate, predictor_taylor, &
      & convergence_paper, convergence_default, find_node
   use fekap_model_results, only: step_result_type
   use fekap_classical, only: cartesian_stepper_type, new_cartesian_stepper
   use classical_models, only: four_bar_model, appendage_model, double_crank_model, peaucellier_model, &
      & slider_crank_model, prismatic_slider_model, slider_drive_model, quick_return_model, four_bar_exact, &
      & slider_crank_exact, run_steps, pi, check_branch_jump_cut
   implicit none
   private
   public :: collect_classical_cartesian

contains

   subroutine collect_classical_cartesian(tests)
      type(unittest_type), allocatable, intent(out) :: tests(:)
      tests = [ &
         & new_unittest('example1_closed_form', test_closed_form), &
         & new_unittest('example1_differences', test_differences), &
         & new_unittest('example1_predictors', test_predictors), &
         & new_unittest('example2_appendage', test_appendage), &
         & new_unittest('example3_redundant_stop', test_redundant_stop), &
         & new_unittest('example3_redundant_remove', test_redundant_remove), &
         & new_unittest('example4_straight_line', test_peaucellier), &
         & new_unittest('slider_crank_closed_form', test_slider_crank), &
         & new_unittest('prismatic_slider', test_prismatic), &
         & new_unittest('coordinate_drive', test_coordinate_drive), &
         & new_unittest('example5_quick_return', test_quick_return), &
         & new_unittest('under_constrained', test_under_constrained), &
         & new_unittest('no_convergence', test_no_convergence), &
         & new_unittest('work_counts', test_work_counts), &
         & new_unittest('branch_jump_cut', test_branch_jump_cut), &
         & new_unittest('iterations_tables_1_3', test_iterations) &
         & ]
   end subroutine collect_classical_cartesian

   subroutine run_model(error, model, res)
      type(error_type), allocatable, intent(out) :: error
      type(model_type), intent(in) :: model
      type(step_result_type), allocatable, intent(out) :: res(:)
      type(cartesian_stepper_type) :: stepper
      call new_cartesian_stepper(stepper, model, error)
      if (allocated(error)) return
      call run_steps(stepper, model, res, error)
   end subroutine run_model

   !> Example 1: B and C equal the closed form to 1e-9 at every step.
   subroutine test_closed_form(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(step_result_type), allocatable :: res(:)
      call four_bar_model(model)
      call run_model(error, model, res)
      if (allocated(error)) return
      call check(error, size(res), 41, 'number of results')
      call check_four_bar(error, res)
   end subroutine test_closed_form

   subroutine check_four_bar(error, res)
      type(error_type), allocatable, intent(inout) :: error
      type(step_result_type), intent(in) :: res(0:)
      real(dp) :: b(2), vb(2), ab(2), c(2), vc(2), ac(2)
      integer :: k
      do k = 0, ubound(res, 1)
         call four_bar_exact(res(k)%t, b, vb, ab, c, vc, ac)
         call check_vectors(error, res(k), 2, b, vb, ab, 4.0_dp)
         call check_vectors(error, res(k), 3, c, vc, ac, 4.0_dp)
         call check(error, res(k)%angle(1), 2*pi*res(k)%t, 'crank angle', abs=1.0e-12_dp)
         call check(error, res(k)%omega(1), 2*pi, 'crank rate')
         if (allocated(error)) then
            error%message = 'at step '//int_str(k)//': '//error%message
            return
         end if
      end do
   end subroutine check_four_bar

   !> Compare node j of a result with exact x, v, a; tolerance 1e-9 of the length scale l.
   subroutine check_vectors(error, res, j, x, v, a, l)
      type(error_type), allocatable, intent(inout) :: error
      type(step_result_type), intent(in) :: res
      integer, intent(in) :: j
      real(dp), intent(in) :: x(2), v(2), a(2), l
      integer :: i
      do i = 1, 2
         call check(error, res%pos(i, j), x(i), 'position', rel=1.0e-9_dp, abs=1.0e-9_dp*l)
         call check(error, res%vel(i, j), v(i), 'velocity', rel=1.0e-9_dp, abs=1.0e-9_dp*l*2*pi)
         call check(error, res%acc(i, j), a(i), 'acceleration', rel=1.0e-9_dp, abs=1.0e-9_dp*l*(2*pi)**2)
      end do
   end subroutine check_vectors

   function int_str(k) result(s)
      integer, intent(in) :: k
      character(:), allocatable :: s
      character(len=12) :: buf
      write (buf, '(i0)') k
      s = trim(buf)
   end function int_str

   !> Velocities and accelerations of every node equal central differences of positions.
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
         do j = 1, size(res(k)%angle)
            v = (res(k + 1)%angle(j) - res(k - 1)%angle(j))/(2*h)
            call check(error, res(k)%omega(j), v, 'angular velocity by differences', abs=1.0e-5_dp*maxval(abs(res(1)%omega)))
         end do
      end do
   end subroutine check_differences

   subroutine test_differences(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(step_result_type), allocatable :: res(:)
      call four_bar_model(model)
      model%analysis%dt = 2.5e-4_dp
      model%analysis%t_end = 0.02_dp
      call run_model(error, model, res)
      if (allocated(error)) return
      call check_differences(error, res, model%analysis%dt)
   end subroutine test_differences

   !> Every predictor and both convergence tests give the closed-form motion.
   subroutine test_predictors(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(step_result_type), allocatable :: res(:)
      integer :: p, c
      do p = predictor_previous, predictor_taylor
         do c = convergence_paper, convergence_default
            call four_bar_model(model)
            model%analysis%predictor = p
            model%analysis%convergence = c
            call run_model(error, model, res)
            if (allocated(error)) return
            call check_four_bar(error, res)
            if (allocated(error)) then
               error%message = 'predictor '//int_str(p)//', convergence '//int_str(c)//': '//error%message
               return
            end if
         end do
      end do
   end subroutine test_predictors

   !> Example 2: P = M + 1.5 unit(B->C) rotated +90 deg, M the midpoint of B and C.
   subroutine test_appendage(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(step_result_type), allocatable :: res(:)
      real(dp) :: b(2), vb(2), ab(2), c(2), vc(2), ac(2), u(2), ud(2), udd(2), p(2), vp(2), ap(2)
      integer :: k, ip, i
      call appendage_model(model)
      call run_model(error, model, res)
      if (allocated(error)) return
      ip = find_node(model, 'P')
      do k = 0, ubound(res, 1)
         call four_bar_exact(res(k)%t, b, vb, ab, c, vc, ac)
         u = [-(c(2) - b(2)), c(1) - b(1)]/4
         ud = [-(vc(2) - vb(2)), vc(1) - vb(1)]/4
         udd = [-(ac(2) - ab(2)), ac(1) - ab(1)]/4
         p = (b + c)/2 + 1.5_dp*u
         vp = (vb + vc)/2 + 1.5_dp*ud
         ap = (ab + ac)/2 + 1.5_dp*udd
         call check_vectors(error, res(k), ip, p, vp, ap, 4.0_dp)
         do i = 1, 2
            call check(error, res(k)%pos(i, find_node(model, 'C')), c(i), 'C', abs=1.0e-9_dp*4)
         end do
         if (allocated(error)) then
            error%message = 'at step '//int_str(k)//': '//error%message
            return
         end if
      end do
   end subroutine test_appendage

   !> Example 3 without `redundant remove`: an input error naming the joints.
   subroutine test_redundant_stop(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(cartesian_stepper_type) :: stepper
      type(error_type), allocatable :: got
      call double_crank_model(model)
      call new_cartesian_stepper(stepper, model, got)
      if (.not. allocated(got)) then
         call test_failed(error, 'the redundant double crank was accepted')
         return
      end if
      write (*, '(6x,a)') got%message
      call check(error, got%kind, error_input, 'kind')
      call check(error, index(got%message, 'the constraint equations are redundant: the ') == 1, 'message: '//got%message)
      call check(error, index(got%message, ' at ') > 0, 'names a joint: '//got%message)
      call check(error, index(got%message, '(method fem)') > 0 .and. index(got%message, '`redundant remove`') > 0, &
         & 'suggests the remedies: '//got%message)
   end subroutine test_redundant_stop

   !> Example 3 with `redundant remove`: F = O3 + (cos, sin)(pi/2 + 2 pi t) to 1e-9.
   subroutine test_redundant_remove(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(step_result_type), allocatable :: res(:)
      real(dp) :: th, f(2), vf(2), af(2)
      real(dp), parameter :: e(2) = [2.0_dp, 0.0_dp]
      integer :: k, jf, je, i
      call double_crank_model(model)
      model%analysis%remove_redundant = .true.
      call run_model(error, model, res)
      if (allocated(error)) return
      jf = find_node(model, 'F')
      je = find_node(model, 'E')
      call check(error, size(res), 51, 'number of results')
      do k = 0, ubound(res, 1)
         th = pi/2 + 2*pi*res(k)%t
         f = [4.0_dp, 0.0_dp] + [cos(th), sin(th)]
         vf = 2*pi*[-sin(th), cos(th)]
         af = -(2*pi)**2*[cos(th), sin(th)]
         call check(error, norm2(res(k)%pos(:, jf) - [4.0_dp, 0.0_dp]), 1.0_dp, 'F on the unit circle about O3', abs=1.0e-9_dp)
         do i = 1, 2
            call check(error, res(k)%pos(i, jf), f(i), 'F', abs=1.0e-9_dp)
            call check(error, res(k)%pos(i, je), f(i) - e(i), 'E', abs=1.0e-9_dp)
            call check(error, res(k)%vel(i, jf), vf(i), 'F velocity', abs=1.0e-9_dp*2*pi)
            call check(error, res(k)%acc(i, jf), af(i), 'F acceleration', abs=1.0e-9_dp*(2*pi)**2)
         end do
         call check(error, res(k)%residual <= 1.0e-10_dp, 'all equations hold, the dropped ones too')
         if (allocated(error)) then
            error%message = 'at step '//int_str(k)//': '//error%message
            return
         end if
      end do
   end subroutine test_redundant_remove

   !> Example 4: P stays on x = 2.7 to 1e-9 at every step.
   subroutine test_peaucellier(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(step_result_type), allocatable :: res(:)
      integer :: k, jp
      call peaucellier_model(model)
      call run_model(error, model, res)
      if (allocated(error)) return
      jp = find_node(model, 'P')
      call check(error, size(res), 21, 'number of results')
      do k = 0, ubound(res, 1)
         call check(error, res(k)%pos(1, jp), 2.7_dp, 'P.x at step '//int_str(k), abs=1.0e-9_dp)
         call check(error, res(k)%vel(1, jp), 0.0_dp, 'P.vx at step '//int_str(k), abs=1.0e-9_dp)
         call check(error, res(k)%acc(1, jp), 0.0_dp, 'P.ax at step '//int_str(k), abs=1.0e-8_dp)
      end do
      ! P.y = 7.56 sin(phi)/|QA-direction intercept|: at t = 0.5, phi = 30 deg, A = Q + 1.4 (cos, sin) 30 deg.
      call check(error, res(10)%pos(2, jp), 2.7_dp*tan(pi/12), 'P.y at t = 0.5 (OA at 15 deg)', rel=1.0e-9_dp)
   end subroutine test_peaucellier

   !> Slider-crank: slider x, vx, ax equal the closed form to 1e-9.
   subroutine test_slider_crank(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(step_result_type), allocatable :: res(:)
      real(dp) :: x, vx, ax
      integer :: k, jb
      call slider_crank_model(model)
      call run_model(error, model, res)
      if (allocated(error)) return
      jb = find_node(model, 'B')
      do k = 0, ubound(res, 1)
         call slider_crank_exact(res(k)%t, x, vx, ax)
         call check(error, res(k)%pos(1, jb), x, 'x at step '//int_str(k), rel=1.0e-9_dp, abs=1.0e-9_dp*4)
         call check(error, res(k)%vel(1, jb), vx, 'vx at step '//int_str(k), rel=1.0e-9_dp, abs=1.0e-9_dp*2*pi)
         call check(error, res(k)%acc(1, jb), ax, 'ax at step '//int_str(k), rel=1.0e-9_dp, abs=1.0e-9_dp*(2*pi)**2)
         call check(error, res(k)%pos(2, jb), 0.0_dp, 'y at step '//int_str(k), abs=1.0e-12_dp)
      end do
   end subroutine test_slider_crank

   !> A prismatic slider block: the slider follows the closed form and the block keeps its angle.
   subroutine test_prismatic(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(step_result_type), allocatable :: res(:)
      real(dp) :: x, vx, ax
      integer :: k, jb, jk
      call prismatic_slider_model(model)
      call run_model(error, model, res)
      if (allocated(error)) return
      jb = find_node(model, 'B')
      jk = find_node(model, 'K')
      do k = 0, ubound(res, 1)
         call slider_crank_exact(res(k)%t, x, vx, ax)
         call check(error, res(k)%pos(1, jb), x, 'x at step '//int_str(k), rel=1.0e-9_dp, abs=1.0e-9_dp*4)
         call check(error, res(k)%acc(1, jb), ax, 'ax at step '//int_str(k), rel=1.0e-9_dp, abs=1.0e-9_dp*(2*pi)**2)
         call check(error, res(k)%pos(1, jk), x + 0.5_dp, 'block end x', abs=1.0e-9_dp)
         call check(error, res(k)%pos(2, jk), 0.0_dp, 'block end y', abs=1.0e-12_dp)
         call check(error, res(k)%angle(3), 0.0_dp, 'block angle', abs=1.0e-12_dp)
         call check(error, res(k)%omega(3), 0.0_dp, 'block angular velocity', abs=1.0e-12_dp)
      end do
   end subroutine test_prismatic

   !> The slider-crank driven by the slider's x: the crank follows the closed form.
   subroutine test_coordinate_drive(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(step_result_type), allocatable :: res(:)
      real(dp) :: x, c
      integer :: k, ja, jb
      call slider_drive_model(model)
      call run_model(error, model, res)
      if (allocated(error)) return
      ja = find_node(model, 'A')
      jb = find_node(model, 'B')
      do k = 0, ubound(res, 1)
         x = sqrt(8.0_dp) + 0.5_dp*sin(2*pi*res(k)%t)
         c = (x**2 - 8)/(2*x)
         call check(error, res(k)%pos(1, jb), x, 'B.x at step '//int_str(k), abs=1.0e-12_dp)
         call check(error, res(k)%vel(1, jb), pi*cos(2*pi*res(k)%t), 'B.vx at step '//int_str(k), abs=1.0e-10_dp)
         call check(error, res(k)%pos(1, ja), c, 'A.x at step '//int_str(k), abs=1.0e-9_dp)
         call check(error, res(k)%pos(2, ja), sqrt(1 - c**2), 'A.y at step '//int_str(k), abs=1.0e-9_dp)
      end do
      model%analysis%dt = 1.0e-4_dp
      model%analysis%t_end = 0.01_dp
      call run_model(error, model, res)
      if (allocated(error)) return
      call check_differences(error, res, model%analysis%dt)
   end subroutine test_coordinate_drive

   !> Example 5: P stays on y = 500, C on the lever, the stroke is 300, and the
   !> rates equal differences of positions (a slot on a moving link).
   subroutine test_quick_return(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(step_result_type), allocatable :: res(:)
      integer :: k, jp, jc, jb
      real(dp) :: b(2), c(2), xmin
      call quick_return_model(model)
      call run_model(error, model, res)
      if (allocated(error)) return
      jp = find_node(model, 'P')
      jc = find_node(model, 'C')
      jb = find_node(model, 'B')
      xmin = 0
      do k = 0, ubound(res, 1)
         b = res(k)%pos(:, jb)
         c = res(k)%pos(:, jc)
         call check(error, res(k)%pos(2, jp), 500.0_dp, 'P.y', rel=1.0e-12_dp)
         call check(error, (b(1)*c(2) - b(2)*c(1))/norm2(b), 0.0_dp, 'C on the lever', abs=1.0e-9_dp)
         xmin = min(xmin, res(k)%pos(1, jp))
      end do
      write (*, '(6x,a,f10.4)') 'quick return: leftmost P.x on the dt = 0.01 grid', xmin
      call check(error, xmin < -299.0_dp .and. xmin >= -300.0_dp - 1.0e-9_dp, 'stroke of 300')
      model%analysis%dt = 1.0e-4_dp
      model%analysis%t_end = 0.01_dp
      call run_model(error, model, res)
      if (allocated(error)) return
      call check_differences(error, res, model%analysis%dt)
   end subroutine test_quick_return

   !> A four-bar without its drive is not determined: an input error.
   subroutine test_under_constrained(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(cartesian_stepper_type) :: stepper
      type(error_type), allocatable :: got
      call four_bar_model(model)
      deallocate (model%drives)
      allocate (model%drives(0))
      call new_cartesian_stepper(stepper, model, got)
      if (.not. allocated(got)) then
         call test_failed(error, 'the undriven four-bar was accepted')
         return
      end if
      write (*, '(6x,a)') got%message
      call check(error, got%kind, error_input, 'kind')
      call check(error, index(got%message, '9 body coordinates but 8 independent') > 0, 'message: '//got%message)
   end subroutine test_under_constrained

   subroutine test_no_convergence(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(step_result_type), allocatable :: res(:)
      type(error_type), allocatable :: got
      call four_bar_model(model)
      model%analysis%dt = 0.25_dp
      model%analysis%max_iter = 1
      call run_model(got, model, res)
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

   subroutine test_work_counts(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(cartesian_stepper_type) :: stepper
      type(step_result_type), allocatable :: res(:)
      call four_bar_model(model)
      model%analysis%accelerations = .false.
      call new_cartesian_stepper(stepper, model, error)
      if (allocated(error)) return
      call run_steps(stepper, model, res, error)
      if (allocated(error)) return
      call check(error, stepper%counts%steps, 40, 'steps')
      call check(error, stepper%counts%iterations, sum(res%iterations), 'iterations')
      call check(error, stepper%counts%velocity_solves, 41, 'velocity solves')
      call check(error, stepper%counts%acceleration_solves, 0, 'acceleration solves')
      ! One more: the jump check's factor at the initial configuration.
      call check(error, stepper%counts%lu_factorisations, sum(res%iterations) + 41 + 1, 'LU factorisations')
      model%analysis%velocities = .false.
      call new_cartesian_stepper(stepper, model, error)
      if (allocated(error)) return
      call run_steps(stepper, model, res, error)
      if (allocated(error)) return
      call check(error, stepper%counts%velocity_solves, 0, 'velocity solves without velocities')
      call check(error, stepper%counts%lu_factorisations, sum(res%iterations) + 1, 'LU factorisations without rates')
      call check(error, .not. res(3)%has_velocity, 'no velocities in the result')
   end subroutine test_work_counts

   !> Example 1 at dt = 0.5, extrapolating predictor: the jump to the other
   !> branch is cut (check_branch_jump_cut).
   subroutine test_branch_jump_cut(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(cartesian_stepper_type) :: stepper
      call four_bar_model(model)
      model%analysis%dt = 0.5_dp
      model%analysis%predictor = predictor_extrapolate
      call new_cartesian_stepper(stepper, model, error)
      if (allocated(error)) return
      call check_branch_jump_cut(stepper, model, error)
   end subroutine test_branch_jump_cut

   !> Iterations per step of Example 1 at dt = 0.025, 0.25, 0.5 (Tables 1-3).
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
      type(cartesian_stepper_type) :: stepper
      type(step_result_type), allocatable :: res(:)
      type(error_type), allocatable :: got
      real(dp) :: b(2), vb(2), ab(2), c(2), vc(2), ac(2), dev
      integer :: k, last
      call four_bar_model(model)
      model%analysis%dt = dt
      model%analysis%predictor = predictor
      model%analysis%convergence = convergence
      call new_cartesian_stepper(stepper, model, error)
      if (allocated(error)) return
      call run_steps(stepper, model, res, got)
      last = ubound(res, 1)
      if (allocated(got)) last = stepper%counts%steps - 1
      write (*, '(6x,a,f5.3,a,a,*(1x,i0))') 'cartesian dt = ', dt, merge(' previous+paper     ', ' extrapolate+default', &
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
         write (*, '(8x,a)') got%message
         call check(error, got%kind, error_analysis, 'a failed step is an analysis error')
         return
      end if
      do k = 1, ubound(res, 1)
         ! A cut step counts the iterations of all its sub-steps.
         call check(error, res(k)%iterations > 0 .and. (res(k)%iterations <= model%analysis%max_iter .or. &
            & res(k)%cuts > 0), 'iteration count')
      end do
   end subroutine record

end module test_classical_cartesian
