!> What both constraint-equation methods share around their Newton solves:
!> the history of converged configurations behind the predictors, the values
!> of drives relative to the initial configuration, the convergence settings
!> taken from the analysis, the step cutting (the advance of both steppers)
!> and the assembly-mode (branch) jump check, and the texts of their messages.
module fekap_classical_stepping
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, analysis_error, error_analysis, at_time
   use fekap_model, only: analysis_type, predictor_previous, predictor_taylor
   use fekap_model_drive_law, only: law_type
   use fekap_strings, only: int_text, short_real_text
   use fekap_model_results, only: step_result_type, new_step_result
   use fekap_stepping_stepper, only: stepper_type
   use fekap_fem_convergence, only: convergence_type, newton_contract
   use fekap_stepping_predictor, only: predictor_history_type, new_predictor_history, extrapolate_history, extrapolate, &
      & taylor_predict, prediction_none
   use fekap_stepping_step_control, only: step_cuts_type, advance_by_cuts, dead_point_advice, try_accepted, try_failed, &
      & try_ended
   use fekap_fem_branch, only: jump_ratio, jump_bound_ratio
   use fekap_stepping_newton, only: newton_system_type, newton_contract_type, newton_report_type, newton_solve, &
      & always_refactor_type, stop_spent, stop_diverged, stop_at_floor
   implicit none
   private

   public :: new_classical_history, drive_value, new_step_convergence, no_convergence_text
   public :: branch_state_type, branch_jump_text, magnitude_ratio, lu_determinant
   public :: classical_stepper_type, newton_positions, begin_result

   !> A change of sign of the Jacobian's determinant over a step is a
   !> legitimate passage through a singular configuration only if one end of
   !> the step is this close to singular: its conditioning measure (see
   !> branch_state_type) below this share of the largest one met in the run
   !> (the cuts close in on a singular configuration the step passed over).
   real(dp), parameter, public :: singular_share = 5.0e-2_dp
   !> What the jump check knows about an accepted configuration.
   type :: branch_state_type
      !> Whether the rest is known.
      logical :: known = .false.
      !> Sign of the determinant of the square Jacobian (+1, -1; 0 if singular).
      integer :: sign = 0
      !> Conditioning measure: |det| over the product of the Jacobian's row (or
      !> column) norms, in [0, 1]; zero at a singular configuration.
      real(dp) :: measure = 0
      !> (ncoord, ndrive): linear response of the coordinates to unit changes of the drives.
      real(dp), allocatable :: response(:, :)
   end type branch_state_type

   !> A constraint-equation method as a stepper. Its advance, the step-cut
   !> loop around the method's Newton solve, is shared; a method supplies the
   !> solve of one (sub-)step, the rates at an intermediate point of a cut
   !> step and the step's result.
   type, abstract, extends(stepper_type) :: classical_stepper_type
      type(analysis_type) :: analysis
      !> The convergence test of the Newton solves, and the model size (the unit of divergence).
      type(convergence_type) :: conv
      real(dp) :: model_length = 1
      !> The accepted configurations and their times, for the predictor.
      type(predictor_history_type) :: history
      !> Whether rate_v and rate_a hold the velocities and accelerations of
      !> the newest configuration (for the Taylor predictor).
      logical :: has_rates = .false.
      real(dp), allocatable :: rate_v(:), rate_a(:)
      !> Steps advanced so far.
      integer :: step = 0
      !> Whether the last Newton solve (newton_positions) stopped at the
      !> round-off floor with its residual above the tolerance, and the
      !> configurations accepted so in the step being advanced (steps.csv's
      !> `floor`; the run's are counted in counts%floor_steps).
      logical :: last_at_floor = .false.
      integer :: step_floor = 0
   contains
      procedure :: advance => classical_advance
      !> Make a converged configuration the accepted one (its rates unknown until set_rates).
      procedure :: accept => classical_accept
      !> Record the velocities and accelerations of the accepted configuration.
      procedure :: set_rates => classical_set_rates
      !> The predictor's guess at a new time.
      procedure :: predict => classical_predict
      !> Newton at time t from the predictor and the branch-jump check; the
      !> configuration is pushed on the history only if both succeed.
      procedure(try_step_interface), deferred :: try_step
      !> Rates of the accepted configuration at time t (for the Taylor predictor).
      procedure(rates_at_interface), deferred :: rates_at
      !> Rates at the accepted configuration (when asked for) and the step's result.
      procedure(finish_step_interface), deferred :: finish_step
      !> The residual of the position equations at time t and the current
      !> unknowns (kept for position_correction), counted, and its norm.
      procedure(position_residual_interface), deferred :: position_residual
      !> The Newton correction from the kept residual, applied to the
      !> unknowns, counted, and its length (translations in lengths).
      procedure(position_correction_interface), deferred :: position_correction
   end type classical_stepper_type

   !> A constraint-equation method's position equations at time t for
   !> newton_solve (the method associated for one solve): its residual, and
   !> its correction, which assembles, factors and solves the Jacobian itself.
   type, extends(newton_system_type) :: position_system_type
      class(classical_stepper_type), pointer :: s => null()
      real(dp) :: t = 0
   contains
      procedure :: assemble => position_assemble
      procedure :: factor => position_factor
      procedure :: correct => position_correct
   end type position_system_type

   abstract interface
      subroutine try_step_interface(self, t, iterations, error)
         import :: classical_stepper_type, dp, error_type
         implicit none
         class(classical_stepper_type), intent(inout) :: self
         real(dp), intent(in) :: t
         integer, intent(out) :: iterations
         type(error_type), allocatable, intent(out) :: error
      end subroutine try_step_interface

      subroutine rates_at_interface(self, t, error)
         import :: classical_stepper_type, dp, error_type
         implicit none
         class(classical_stepper_type), intent(inout) :: self
         real(dp), intent(in) :: t
         type(error_type), allocatable, intent(out) :: error
      end subroutine rates_at_interface

      subroutine finish_step_interface(self, t, iterations, result, error)
         import :: classical_stepper_type, dp, error_type, step_result_type
         implicit none
         class(classical_stepper_type), intent(inout) :: self
         real(dp), intent(in) :: t
         integer, intent(in) :: iterations
         type(step_result_type), intent(inout) :: result
         type(error_type), allocatable, intent(out) :: error
      end subroutine finish_step_interface

      subroutine position_residual_interface(self, t, norm)
         import :: classical_stepper_type, dp
         implicit none
         class(classical_stepper_type), intent(inout) :: self
         real(dp), intent(in) :: t
         real(dp), intent(out) :: norm
      end subroutine position_residual_interface

      subroutine position_correction_interface(self, t, correction, error)
         import :: classical_stepper_type, dp, error_type
         implicit none
         class(classical_stepper_type), intent(inout) :: self
         real(dp), intent(in) :: t
         real(dp), intent(out) :: correction
         type(error_type), allocatable, intent(out) :: error
      end subroutine position_correction_interface
   end interface

contains

   !> Newton on the method's position equations at time t from its current
   !> unknowns (newton_solve), under the shared convergence test: `default`,
   !> after each correction, the residual it was solved from at most tol times
   !> increment_residual (the scale) or at the floor, and the correction below
   !> the length tolerance; `paper`, the residual at the iterate below tol
   !> times the first. Iterations are counted as corrections.
   !> The FEM's Newton (fem_newton.f90) uses the same driver and contract and
   !> adds what these methods' exactly determined equations do not need: its
   !> tangent choice, the acceptance at the predictor, the estimated stop, the
   !> round-off stall, slideline relocation.
   subroutine newton_positions(self, t, increment_residual, iterations, error)
      class(classical_stepper_type), target, intent(inout) :: self
      real(dp), intent(in) :: t, increment_residual
      integer, intent(out) :: iterations
      type(error_type), allocatable, intent(out) :: error
      type(position_system_type) :: system
      type(newton_contract_type) :: contract
      type(always_refactor_type) :: full
      type(newton_report_type) :: report
      system%s => self
      system%t = t
      contract = newton_contract(self%conv, increment_residual, self%analysis%max_iter, self%model_length)
      call newton_solve(system, contract, full, report, error)
      iterations = report%iterations
      self%last_at_floor = report%stopped == stop_at_floor
      if (.not. allocated(error)) return
      select case (report%stopped)
      case (stop_spent)
         error%message = no_convergence_text(t, iterations, report%last_residual)
         call at_time(error, t)
      case (stop_diverged)
         error%message = 't = '//short_real_text(t)//': Newton diverged at iteration '//int_text(iterations)
         call at_time(error, t)
      case default
         ! The method's own error (a singular Jacobian), or an interrupt.
      end select
   end subroutine newton_positions

   subroutine position_assemble(self, matrix, norm)
      class(position_system_type), intent(inout) :: self
      logical, intent(in) :: matrix
      real(dp), intent(out) :: norm
      call self%s%position_residual(self%t, norm)
   end subroutine position_assemble

   !> Nothing: the method's correction factors its Jacobian.
   subroutine position_factor(self, info)
      class(position_system_type), intent(inout) :: self
      integer, intent(out) :: info
      info = 0
   end subroutine position_factor

   subroutine position_correct(self, length, error)
      class(position_system_type), intent(inout) :: self
      real(dp), intent(out) :: length
      type(error_type), allocatable, intent(out) :: error
      call self%s%position_correction(self%t, length, error)
      if (allocated(error)) return
      self%s%counts%iterations = self%s%counts%iterations + 1
   end subroutine position_correct

   !> Advance to time t: the method's Newton solve at t, the step cut in
   !> halves (at most max_cuts times) when Newton fails or the converged
   !> configuration is on another assembly branch; then velocities and
   !> accelerations. Errors other than analysis failures end the run at once.
   subroutine classical_advance(self, t, result, error)
      class(classical_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      type(step_result_type), intent(inout) :: result
      type(error_type), allocatable, intent(out) :: error
      type(step_cuts_type) :: cuts
      integer :: total
      self%step = self%step + 1
      self%counts%steps = self%counts%steps + 1
      self%step_floor = 0
      call advance_by_cuts(self, classical_try, classical_between, self%history%t(self%history%newest), t, 0, &
         & dead_point_advice, cuts, total, error)
      if (allocated(error)) return
      call self%finish_step(t, total, result, error)
      result%cuts = cuts%cuts
      result%note = cuts%note()
   end subroutine classical_advance

   !> The method's try of a step to time t (for advance_by_cuts): its Newton
   !> solve and branch-jump check (try_step). Unlike the FEM's, a try is never
   !> verified by half steps (the determinant's sign decides a jump at once),
   !> so depth is always 0; errors other than analysis failures (a bad model)
   !> end the run at once instead of cutting the step.
   recursive subroutine classical_try(stepper, t, depth, iterations, outcome, reason)
      class(stepper_type), intent(inout) :: stepper
      real(dp), intent(in) :: t
      integer, intent(in) :: depth
      integer, intent(out) :: iterations, outcome
      type(error_type), allocatable, intent(out) :: reason
      iterations = 0
      outcome = try_ended
      if (depth /= 0) return
      select type (self => stepper)
      class is (classical_stepper_type)
         call self%try_step(t, iterations, reason)
         outcome = try_accepted
         if (allocated(reason)) then
            outcome = try_failed
            if (reason%kind /= error_analysis) outcome = try_ended
         end if
      end select
   end subroutine classical_try

   !> An intermediate point of a cut step (for advance_by_cuts): its rates feed
   !> the Taylor predictor only (if they cannot be solved there, the predictor
   !> extrapolates instead: has_rates stays false).
   subroutine classical_between(stepper, t)
      class(stepper_type), intent(inout) :: stepper
      real(dp), intent(in) :: t
      type(error_type), allocatable :: rates_error
      select type (self => stepper)
      class is (classical_stepper_type)
         if (self%analysis%predictor == predictor_taylor) call self%rates_at(t, rates_error)
      end select
   end subroutine classical_between

   !> The head of a step's result at time t: its storage for nnode nodes and
   !> nlink links, the step, the time and the iterations, no note.
   subroutine begin_result(self, t, iterations, nnode, nlink, result)
      class(classical_stepper_type), intent(in) :: self
      real(dp), intent(in) :: t
      integer, intent(in) :: iterations, nnode, nlink
      type(step_result_type), intent(inout) :: result
      if (.not. allocated(result%pos)) call new_step_result(result, nnode, nlink)
      if (size(result%pos, 2) /= nnode .or. size(result%angle) /= nlink) call new_step_result(result, nnode, nlink)
      result%step = self%step
      result%t = t
      result%iterations = iterations
      result%floor = self%step_floor
      result%note = ''
   end subroutine begin_result

   !> An empty history and rates for ncoord coordinates.
   pure subroutine new_classical_history(self, ncoord)
      class(classical_stepper_type), intent(inout) :: self
      integer, intent(in) :: ncoord
      call new_predictor_history(self%history, ncoord)
      allocate (self%rate_v(ncoord), self%rate_a(ncoord), source=0.0_dp)
      self%has_rates = .false.
   end subroutine new_classical_history

   pure subroutine classical_accept(self, q, t)
      class(classical_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: q(:), t
      call self%history%push(q, t)
      self%has_rates = .false.
      if (self%last_at_floor) then
         self%step_floor = self%step_floor + 1
         self%counts%floor_steps = self%counts%floor_steps + 1
      end if
   end subroutine classical_accept

   pure subroutine classical_set_rates(self, qd, qdd)
      class(classical_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: qd(:), qdd(:)
      self%rate_v = qd
      self%rate_a = qdd
      self%has_rates = .true.
   end subroutine classical_set_rates

   !> Predictor at time t (the analysis's): predictor_previous takes the last
   !> converged configuration (the paper's (10)); predictor_extrapolate the
   !> Lagrange extrapolation through the last (up to) three; predictor_taylor
   !> q + dt q' + dt**2/2 q'' from the last rates, or extrapolation when
   !> velocities and accelerations were not both computed.
   subroutine classical_predict(self, t, q)
      class(classical_stepper_type), intent(in) :: self
      real(dp), intent(in) :: t
      real(dp), contiguous, intent(out) :: q(:)
      integer :: made
      associate (history => self%history)
         if (self%analysis%predictor == predictor_previous) then
            q = history%q(:, history%newest)
         else if (self%analysis%predictor == predictor_taylor .and. self%has_rates) then
            call taylor_predict(history%q(:, history%newest), self%rate_v, self%rate_a, t - history%t(history%newest), q)
         else
            call extrapolate_history(history, t, .false., 0.0_dp, [0.0_dp], q, made)
            ! One configuration: the constant extrapolation through it.
            if (made == prediction_none) call extrapolate(history%q, history%t, [history%newest], t, q)
         end if
      end associate
   end subroutine classical_predict

   !> Value and rates at time t of a driven quantity that starts at `initial`
   !> at t_start: initial + law(t) - law(t_start). For an absolute law that
   !> starts consistently this is law(t) itself.
   elemental subroutine drive_value(law, initial, t_start, t, f, df, ddf)
      type(law_type), intent(in) :: law
      real(dp), intent(in) :: initial, t_start, t
      real(dp), intent(out) :: f, df, ddf
      real(dp) :: f0, df0, ddf0
      call law%eval(t_start, f0, df0, ddf0)
      call law%eval(t, f, df, ddf)
      f = initial + (f - f0)
   end subroutine drive_value

   !> Convergence settings of a step from the analysis: mode and tolerance
   !> as given, the length tolerance scaled by the model size, and an absolute
   !> residual floor at rounding level (a step that starts converged).
   pure function new_step_convergence(analysis, model_length) result(conv)
      type(analysis_type), intent(in) :: analysis
      !> model_size(model).
      real(dp), intent(in) :: model_length
      type(convergence_type) :: conv
      conv%mode = analysis%convergence
      conv%tol = analysis%tol
      conv%length = analysis%length_tol*model_length
      conv%residual_floor = 1.0e-14_dp*model_length
   end function new_step_convergence

   !> The message of a step that hit max_iter.
   pure function no_convergence_text(t, iterations, residual) result(text)
      integer, intent(in) :: iterations
      real(dp), intent(in) :: t, residual
      character(:), allocatable :: text
      text = 't = '//short_real_text(t)//': Newton did not converge in '//int_text(iterations)//' iterations (residual '// &
         & short_real_text(residual)//')'
   end function no_convergence_text


   !> Magnitude part of the jump check: the largest ratio of |change| of an
   !> angle coordinate over the step to max(|dq_old|, |dq_new|, floor), the
   !> linear responses to the drive increment at the two ends and the drive
   !> increment itself (or Newton's resolution, jump_bound_ratio's); and the
   !> coordinate where it occurs (0 if none moved).
   pure subroutine magnitude_ratio(change, dq_old, dq_new, drive_floor, resolution, worst, where_)
      !> Changes of the angle coordinates and their linear responses.
      real(dp), intent(in) :: change(:), dq_old(:), dq_new(:)
      !> The drive increment (radians, or lengths of the shortest link).
      real(dp), intent(in) :: drive_floor
      !> The length tolerance, relative to the model size (radians).
      real(dp), intent(in) :: resolution
      real(dp), intent(out) :: worst
      integer, intent(out) :: where_
      real(dp) :: ratio
      integer :: i
      worst = 0
      where_ = 0
      do i = 1, size(change)
         ratio = jump_bound_ratio(change(i), dq_old(i), dq_new(i), drive_floor, resolution)
         if (ratio > worst) then
            worst = ratio
            where_ = i
         end if
      end do
   end subroutine magnitude_ratio

   !> The branch-jump decision between the accepted state `old` and the
   !> converged `new` one; text is '' when the step is accepted, otherwise the
   !> reason. worst is the magnitude ratio, change the change of the
   !> coordinate `what` where it occurs; reference the largest conditioning
   !> measure met in the run.
   pure function branch_jump_text(t, old, new, reference, worst, change, what) result(text)
      real(dp), intent(in) :: t
      type(branch_state_type), intent(in) :: old, new
      real(dp), intent(in) :: reference, worst, change
      character(*), intent(in) :: what
      character(:), allocatable :: text
      character(len=120) :: msg
      text = ''
      if (worst > jump_ratio) then
         write (msg, '(a,es9.2,a)') ' rad over the step, ', min(worst, huge(1.0_dp)), &
            & ' times what the drive increment explains) at '
         text = 't = '//short_real_text(t)//': assembly-mode jump rejected (rotation '//short_real_text(change)// &
            & trim(msg)//' '//what
      else if (old%known .and. new%known) then
         if (old%sign*new%sign < 0 .and. min(old%measure, new%measure) >= singular_share*reference) then
            text = 't = '//short_real_text(t)//': assembly-mode jump rejected (the determinant of the Jacobian '// &
               & 'changed sign over the step, away from any singular configuration)'
         end if
      end if
   end function branch_jump_text

   !> Sign of the determinant of a matrix from its LU factors (dgetrf) and
   !> log10 of |det| (-huge for a zero pivot).
   pure subroutine lu_determinant(lu, ipiv, sign_, log_abs)
      real(dp), intent(in) :: lu(:, :)
      integer, intent(in) :: ipiv(:)
      integer, intent(out) :: sign_
      real(dp), intent(out) :: log_abs
      integer :: k
      sign_ = 1
      log_abs = 0
      do k = 1, size(lu, 1)
         if (ipiv(k) /= k) sign_ = -sign_
         if (lu(k, k) < 0) sign_ = -sign_
         if (lu(k, k) == 0) then
            sign_ = 0
            log_abs = -huge(1.0_dp)
            return
         end if
         log_abs = log_abs + log10(abs(lu(k, k)))
      end do
   end subroutine lu_determinant

end module fekap_classical_stepping
