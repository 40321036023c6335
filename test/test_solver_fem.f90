!> Tests of fekap_solver_fem on Example 1 against the closed-form four-bar.
module test_solver_fem
   use fekap_kinds, only: dp
   use fekap_testing, only: unittest_type, new_unittest, check, error_type
   use fekap_model, only: model_type, predictor_previous, predictor_extrapolate, predictor_taylor, &
      & convergence_paper
   use fekap_model_results, only: step_result_type, new_step_result
   use fekap_solver_fem, only: fem_stepper_type, new_fem_stepper
   use fekap_model_work, only: phase_seconds
   use test_mechanisms, only: fourbar_model, cantilever_model, slider_crank_model
   use classical_models, only: four_bar_exact, slider_crank_exact
   implicit none
   private
   public :: collect_solver_fem

contains

   subroutine collect_solver_fem(tests)
      type(unittest_type), allocatable, intent(out) :: tests(:)
      tests = [ &
         & new_unittest('fem_advance_fourbar_exact', test_fourbar_exact), &
         & new_unittest('fem_advance_predictors', test_predictors), &
         & new_unittest('fem_advance_rates_vs_differences', test_rates_fd), &
         & new_unittest('fem_advance_material_independence', test_material), &
         & new_unittest('fem_advance_several_elements', test_several_elements), &
         & new_unittest('fem_advance_full_integration', test_full_integration), &
         & new_unittest('fem_start', test_start), &
         & new_unittest('fem_advance_cantilever_rollup', test_rollup), &
         & new_unittest('fem_advance_rollup_convergence_rate', test_rollup_rate), &
         & new_unittest('fem_advance_slider_crank', test_slider_crank), &
         & new_unittest('fem_advance_slider_across_elements', test_slider_across), &
         & new_unittest('fem_advance_positions_only_work', test_positions_only), &
         & new_unittest('fem_advance_positions_independent_of_rates', test_bit_for_bit), &
         & new_unittest('fem_advance_phase_sample', test_phase_sample) &
         & ]
   end subroutine collect_solver_fem

   !> Run Example 1 over one revolution and return the largest errors of B and
   !> C (positions, velocities, accelerations), each relative to its largest
   !> exact magnitude, and the mean iterations per step.
   subroutine run_fourbar(model, err, iters, error)
      type(model_type), intent(in) :: model
      real(dp), intent(out) :: err(3), iters
      type(error_type), allocatable, intent(out) :: error
      type(fem_stepper_type) :: fem
      type(step_result_type) :: res
      real(dp) :: t, b(2), c(2), vb(2), vc(2), ab(2), ac(2)
      integer :: n, nsteps, total
      call new_fem_stepper(fem, model)
      call new_step_result(res, size(model%nodes), size(model%links))
      call fem%start(res, error)
      if (allocated(error)) return
      nsteps = nint(1/model%analysis%dt)
      err = 0
      total = 0
      do n = 0, nsteps
         if (n > 0) then
            t = n*model%analysis%dt
            call fem%advance(t, res, error)
            if (allocated(error)) return
            total = total + res%iterations
         end if
         call four_bar_exact(res%t, b, vb, ab, c, vc, ac)
         err(1) = max(err(1), maxval(abs(res%pos(:, 2) - b))/2, maxval(abs(res%pos(:, 3) - c))/4)
         if (model%analysis%velocities) err(2) = max(err(2), maxval(abs(res%vel(:, 2) - vb))/(4*acos(-1.0_dp)), &
            & maxval(abs(res%vel(:, 3) - vc))/(4*acos(-1.0_dp)))
         if (model%analysis%accelerations) err(3) = max(err(3), maxval(abs(res%acc(:, 2) - ab))/(8*acos(-1.0_dp)**2), &
            & maxval(abs(res%acc(:, 3) - ac))/(8*acos(-1.0_dp)**2))
      end do
      iters = real(total, dp)/nsteps
   end subroutine run_fourbar

   subroutine test_fourbar_exact(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      real(dp) :: err(3), iters
      call fourbar_model(model, 0.025_dp)
      call run_fourbar(model, err, iters, error)
      if (allocated(error)) return
      call check(error, err(1), 0.0_dp, 'positions of B, C', abs=1.0e-9_dp)
      call check(error, err(2), 0.0_dp, 'velocities of B, C', abs=1.0e-9_dp)
      call check(error, err(3), 0.0_dp, 'accelerations of B, C', abs=1.0e-9_dp)
   end subroutine test_fourbar_exact

   !> Every predictor, with the paper's and the default convergence test, at
   !> dt = 0.025 and at a quarter turn per step, reaches the exact solution.
   subroutine test_predictors(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      real(dp) :: err(3), iters, dts(2)
      integer, parameter :: predictors(3) = [predictor_previous, predictor_extrapolate, predictor_taylor]
      integer :: ip, id, ic
      character(len=80) :: label
      dts = [0.025_dp, 0.25_dp]
      do id = 1, 2
         do ip = 1, 3
            do ic = 1, 2
               call fourbar_model(model, dts(id))
               model%analysis%predictor = predictors(ip)
               if (ic == 1) model%analysis%convergence = convergence_paper
               call run_fourbar(model, err, iters, error)
               if (allocated(error)) return
               write (label, '(a,f6.3,a,i0,a,i0,a,f6.2)') 'dt ', dts(id), ' predictor ', ip, ' conv ', ic, &
                  & ' it/step ', iters
               ! The paper's residual-ratio test stops on the residual alone, which
               ! leaves position errors near 1e-8 here; the default test does not.
               call check(error, maxval(err), 0.0_dp, trim(label), abs=merge(1.0e-6_dp, 1.0e-9_dp, ic == 1))
               if (allocated(error)) return
               write (*, '(4x,a,es9.2)') trim(label)//' max error', maxval(err)
            end do
         end do
      end do
   end subroutine test_predictors

   !> Velocities and accelerations equal central differences of positions
   !> computed at neighbouring times.
   subroutine test_rates_fd(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(fem_stepper_type) :: fem
      type(step_result_type) :: res(-1:1)
      real(dp), parameter :: h = 1.0e-4_dp, t0 = 0.37_dp
      integer :: k
      call fourbar_model(model, 0.01_dp)
      do k = -1, 1
         call new_fem_stepper(fem, model)
         call new_step_result(res(k), 4, 3)
         call fem%start(res(k), error)
         if (allocated(error)) return
         call fem%advance(t0 - 0.01_dp, res(k), error)
         if (allocated(error)) return
         call fem%advance(t0 + k*h, res(k), error)
         if (allocated(error)) return
      end do
      call check(error, maxval(abs(res(0)%vel - (res(1)%pos - res(-1)%pos)/(2*h))), 0.0_dp, &
         & 'velocity vs central difference', abs=1.0e-6_dp)
      call check(error, maxval(abs(res(0)%acc - (res(1)%pos - 2*res(0)%pos + res(-1)%pos)/h**2)), 0.0_dp, &
         & 'acceleration vs second difference', abs=1.0e-4_dp)
      call check(error, maxval(abs(res(0)%omega - (res(1)%angle - res(-1)%angle)/(2*h))), 0.0_dp, &
         & 'angular velocity vs central difference', abs=1.0e-6_dp)
   end subroutine test_rates_fd

   !> Scaling E, G, A, I by 1e-3 .. 1e3 changes no converged result beyond 1e-9.
   subroutine test_material(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      real(dp) :: err(3), iters
      integer :: k
      character(len=40) :: label
      do k = -3, 3
         call fourbar_model(model, 0.05_dp, factor=10.0_dp**k)
         call run_fourbar(model, err, iters, error)
         if (allocated(error)) return
         write (label, '(a,i0)') 'section data scaled by 10**', k
         call check(error, maxval(err), 0.0_dp, trim(label), abs=1.0e-9_dp)
      end do
   end subroutine test_material

   !> Links meshed with several elements move as the rigid links do.
   subroutine test_several_elements(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      real(dp) :: err(3), iters
      call fourbar_model(model, 0.05_dp, nelem=4)
      call run_fourbar(model, err, iters, error)
      if (allocated(error)) return
      call check(error, maxval(err), 0.0_dp, 'four elements per link', abs=1.0e-9_dp)
   end subroutine test_several_elements

   !> Full (two-point) integration moves rigid links exactly too.
   subroutine test_full_integration(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      real(dp) :: err(3), iters
      call fourbar_model(model, 0.05_dp, nelem=2)
      model%analysis%gauss_points = 2
      call run_fourbar(model, err, iters, error)
      if (allocated(error)) return
      call check(error, maxval(err), 0.0_dp, 'two Gauss points, two elements per link', abs=1.0e-9_dp)
   end subroutine test_full_integration

   subroutine test_start(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(fem_stepper_type) :: fem
      type(step_result_type) :: res
      call fourbar_model(model, 0.025_dp)
      call new_fem_stepper(fem, model)
      call new_step_result(res, 4, 3)
      call fem%start(res, error)
      if (allocated(error)) return
      call check(error, res%pos(2, 3), sqrt(15.0_dp))
      call check(error, res%iterations, 0)
      call check(error, res%has_acceleration, 'accelerations at the start')
      call check(error, fem%mesh%nfree, 9, 'free dofs: x, y of B and C, five link-end rotations (the paper''s 9 x 9)')
   end subroutine test_start

   !> Tip of the cantilever under the end moment at time t (M = t*2*pi*EI/L),
   !> computed by FEKAP with nelem elements.
   subroutine rollup_tip(nelem, t_end, tip, error)
      integer, intent(in) :: nelem
      real(dp), intent(in) :: t_end
      real(dp), intent(out) :: tip(3)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(fem_stepper_type) :: fem
      type(step_result_type) :: res
      integer :: n
      call cantilever_model(model, nelem, 0.05_dp)
      model%analysis%t_end = t_end
      call new_fem_stepper(fem, model)
      call new_step_result(res, 2, 1)
      call fem%start(res, error)
      do n = 1, nint(t_end/0.05_dp)
         if (allocated(error)) return
         call fem%advance(n*0.05_dp, res, error)
      end do
      if (allocated(error)) return
      tip = [res%pos(:, 2), fem%state%q(fem%mesh%link_rot(2, 1))]
   end subroutine rollup_tip

   !> M = 2*pi*EI/L rolls the cantilever into a full circle: the tip returns to
   !> the root with a tip rotation of 2*pi (exact for the discrete beam too, whose
   !> nodes form a closed regular polygon); at M = pi*EI/L the tip reaches the
   !> exact half circle (0, 2/pi) within the discretisation error.
   subroutine test_rollup(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: tip(3), pi
      pi = acos(-1.0_dp)
      call rollup_tip(16, 1.0_dp, tip, error)
      if (allocated(error)) return
      call check(error, norm2(tip(1:2)), 0.0_dp, 'tip back at the root', abs=1.0e-9_dp)
      call check(error, tip(3), 2*pi, 'tip rotation', rel=1.0e-10_dp)
      call rollup_tip(16, 0.5_dp, tip, error)
      if (allocated(error)) return
      call check(error, tip(1), 0.0_dp, 'half circle: x', abs=1.0e-2_dp)
      call check(error, tip(2), 2/pi, 'half circle: y', rel=1.0e-2_dp)
   end subroutine test_rollup

   !> The tip error at M = pi*EI/L (a half circle, tip at (0, 2/pi)) falls as
   !> h^2 when elements are added: observed rate 2 within 0.05.
   subroutine test_rollup_rate(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: tip(3), err(4), pi, rate
      integer :: k
      character(len=80) :: label
      pi = acos(-1.0_dp)
      do k = 1, 4
         call rollup_tip(4*2**k, 0.5_dp, tip, error)
         if (allocated(error)) return
         err(k) = norm2(tip(1:2) - [0.0_dp, 2/pi])
      end do
      do k = 2, 4
         rate = log(err(k - 1)/err(k))/log(2.0_dp)
         write (label, '(a,i0,a,es10.3,a,f6.3)') 'elements ', 4*2**k, ' tip error ', err(k), ' rate ', rate
         write (*, '(4x,a)') trim(label)
         call check(error, rate, 2.0_dp, trim(label), abs=0.05_dp)
      end do
   end subroutine test_rollup_rate

   !> Run the slider-crank over one revolution: largest errors of the slider's
   !> x, vx, ax (relative to their largest exact magnitudes), largest |y|, and
   !> the largest jump of the velocity between steps (for smoothness).
   subroutine run_slider(model, err, error)
      type(model_type), intent(in) :: model
      real(dp), intent(out) :: err(4)
      type(error_type), allocatable, intent(out) :: error
      type(fem_stepper_type) :: fem
      type(step_result_type) :: res
      real(dp) :: x, v, a
      integer :: n
      call new_fem_stepper(fem, model)
      call new_step_result(res, size(model%nodes), size(model%links))
      call fem%start(res, error)
      err = 0
      do n = 1, nint(1/model%analysis%dt)
         if (allocated(error)) return
         call fem%advance(n*model%analysis%dt, res, error)
         if (allocated(error)) return
         call slider_crank_exact(res%t, x, v, a)
         err(1) = max(err(1), abs(res%pos(1, 3) - x)/4)
         err(2) = max(err(2), abs(res%vel(1, 3) - v)/(2*acos(-1.0_dp)*1.4_dp))
         err(3) = max(err(3), abs(res%acc(1, 3) - a)/(4*acos(-1.0_dp)**2*1.4_dp))
         err(4) = max(err(4), abs(res%pos(2, 3)))
      end do
   end subroutine run_slider

   !> The slider on a ground guide: x, vx, ax equal the closed form to 1e-9.
   subroutine test_slider_crank(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      real(dp) :: err(4)
      call slider_crank_model(model, 0.01_dp)
      call run_slider(model, err, error)
      if (allocated(error)) return
      call check(error, err(1), 0.0_dp, 'slider x', abs=1.0e-9_dp)
      call check(error, err(2), 0.0_dp, 'slider vx', abs=1.0e-9_dp)
      call check(error, err(3), 0.0_dp, 'slider ax', abs=1.0e-9_dp)
      call check(error, err(4), 0.0_dp, 'slider stays on the guide', abs=1.0e-9_dp)
   end subroutine test_slider_crank

   !> The guide is a grounded link of 5 elements: the slider crosses from one
   !> master element to the next, with the same exact results as on one guide.
   subroutine test_slider_across(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      real(dp) :: err(4)
      call slider_crank_model(model, 0.01_dp, nelem_guide=5)
      call run_slider(model, err, error)
      if (allocated(error)) return
      call check(error, err(1), 0.0_dp, 'slider x', abs=1.0e-9_dp)
      call check(error, err(2), 0.0_dp, 'slider vx', abs=1.0e-9_dp)
      call check(error, err(3), 0.0_dp, 'slider ax', abs=1.0e-9_dp)
      call check(error, err(4), 0.0_dp, 'slider stays on the guide', abs=1.0e-9_dp)
   end subroutine test_slider_across

   !> Run Example 1 for 40 steps with the given quantities; return the stepper.
   subroutine run_counted(velocities, accelerations, fem, final, error)
      logical, intent(in) :: velocities, accelerations
      type(fem_stepper_type), intent(out) :: fem
      type(step_result_type), intent(out) :: final
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      integer :: n
      call fourbar_model(model, 0.025_dp)
      model%analysis%velocities = velocities
      model%analysis%accelerations = accelerations
      call new_fem_stepper(fem, model)
      call new_step_result(final, 4, 3)
      call fem%start(final, error)
      do n = 1, 40
         if (allocated(error)) return
         call fem%advance(n*0.025_dp, final, error)
      end do
   end subroutine run_counted

   !> A positions-only run does no velocity or acceleration solve; a
   !> velocities-only run no acceleration work; no slideline is evaluated
   !> where there is none.
   subroutine test_positions_only(error)
      type(error_type), allocatable, intent(out) :: error
      type(fem_stepper_type) :: fem
      type(step_result_type) :: res
      call run_counted(.false., .false., fem, res, error)
      if (allocated(error)) return
      call check(error, fem%counts%velocity_solves, 0, 'positions only: velocity solves')
      call check(error, fem%counts%acceleration_solves, 0, 'positions only: acceleration solves')
      call check(error, .not. res%has_velocity, 'positions only: no velocities reported')
      call check(error, fem%counts%slideline_evaluations, 0, 'no slidelines: slideline evaluations')
      call run_counted(.true., .false., fem, res, error)
      if (allocated(error)) return
      call check(error, fem%counts%velocity_solves, 41, 'velocities: one solve per configuration')
      call check(error, fem%counts%acceleration_solves, 0, 'velocities only: acceleration solves')
      call run_counted(.true., .true., fem, res, error)
      if (allocated(error)) return
      call check(error, fem%counts%acceleration_solves, 41, 'accelerations: one solve per configuration')
   end subroutine test_positions_only

   !> With the default predictor, positions are bit for bit the same whether
   !> or not rates are computed, and velocities whether or not accelerations are.
   subroutine test_bit_for_bit(error)
      type(error_type), allocatable, intent(out) :: error
      type(fem_stepper_type) :: fem
      type(step_result_type) :: res(3)
      call run_counted(.false., .false., fem, res(1), error)
      if (allocated(error)) return
      call run_counted(.true., .false., fem, res(2), error)
      if (allocated(error)) return
      call run_counted(.true., .true., fem, res(3), error)
      if (allocated(error)) return
      call check(error, all(res(1)%pos == res(2)%pos) .and. all(res(1)%pos == res(3)%pos), &
         & 'positions identical with and without rates')
      call check(error, all(res(1)%angle == res(3)%angle), 'link angles identical with and without rates')
      call check(error, all(res(2)%vel == res(3)%vel), 'velocities identical with and without accelerations')
   end subroutine test_bit_for_bit

   !> The phases of the start, the first 16 steps and every 16th after them
   !> are timed: a 40-step run has a sample, its phases fit inside it, and
   !> scaled to a longer analysis they keep their shares.
   subroutine test_phase_sample(error)
      type(error_type), allocatable, intent(out) :: error
      type(fem_stepper_type) :: fem
      type(step_result_type) :: res
      real(dp) :: phases(3)
      call run_counted(.true., .true., fem, res, error)
      if (allocated(error)) return
      associate (c => fem%counts)
         call check(error, c%seconds_sampled > 0, 'a sample was timed')
         if (allocated(error)) return
         call check(error, min(c%seconds_assembly, c%seconds_factorisation, c%seconds_solves) >= 0 .and. &
            & c%seconds_assembly + c%seconds_factorisation + c%seconds_solves <= c%seconds_sampled, &
            & 'phases within the sampled steps')
         if (allocated(error)) return
         phases = phase_seconds(c, 2*c%seconds_sampled)
         call check(error, sum(phases) <= 2*c%seconds_sampled, 'scaled phases within the analysis')
      end associate
   end subroutine test_phase_sample

end module test_solver_fem
