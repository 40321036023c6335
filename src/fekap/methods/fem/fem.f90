!> The paper's finite element method as a stepper: per step, advance the
!> drives, predict, solve P(q) = 0 on the free dofs by Newton-Raphson with the
!> symmetric band tangent, check that the converged configuration is a
!> mechanism configuration (every element unstrained, every slave on its
!> line, no assembly-mode jump), then solve for velocities (47) and
!> accelerations (49) with the tangent of the converged configuration. A
!> step that fails is cut in halves (bounded) and retried.
!>
!> This module composes the parts, each a module of its own: setup
!> (fem_setup, shared with dynamics), data (fem_state), the tangent at the
!> accepted configuration and the square-root form of exactly constrained
!> models (fem_factor; docs/theory.md, "Rates at scale"), the predictor
!> (fem_predict), the checks and rates of a converged configuration
!> (fem_converged), change points (fem_fill), the Newton workspace of a step
!> for the shared driver newton_solve (fem_newton), the step loop shared
!> with the other methods (step_control's advance_by_cuts). What stays here
!> wraps them: the solve of a step (solve_step: Newton, slideline
!> relocation, the check of an estimated stop, acceptance), the try of a
!> step with the step-doubling verification that the branch check asks
!> for, and the step over a change point: they call one another recursively.
module fekap_fem
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, analysis_error
   use fekap_model, only: model_type, predictor_previous, predictor_taylor, convergence_paper
   use fekap_model_results, only: step_result_type
   use fekap_assembly_mesh, only: describe_dof
   use fekap_assembly_tracking, only: relocate
   use fekap_stepping_stepper, only: stepper_type, clock_seconds, phase_timed
   use fekap_fem_setup, only: start_configuration
   use fekap_fem_convergence, only: estimate_margin
   use fekap_fem_linear_system, only: assemble_system, assemble_system_residual, assemble_system_drive_block, &
      & factor_system, residual_norm, newton_correction
   use fekap_stepping_newton, only: newton_contract_type, newton_report_type, always_refactor_type, newton_solve, &
      & stop_spent, stop_diverged, stop_singular, stop_at_floor
   use fekap_stepping_step_control, only: step_cuts_type, advance_by_cuts, try_accepted, try_replaced, try_failed, &
      & try_ended
   use fekap_fem_state, only: fem_state_type, fem_core_type, new_fem_core, accept, fill_result, &
      & prepend_cuts_note, model_distance, no_convergence_error
   use fekap_fem_factor, only: refactor_at_accepted, root_correction, factor_root, take_correction, restore_state, &
      & carry_factor
   use fekap_fem_predict, only: predict, drive_increment_residual, record_velocity
   use fekap_fem_converged, only: branch_jump, solve_rates, check_mechanism, start_response
   use fekap_fem_fill, only: interpolate_fill, finish_fill, filled_state, next_output_time
   use fekap_fem_newton, only: fem_newton_type, fem_contract
   use fekap_fem_rates, only: near_singular_drop, root_drive_block
   use fekap_fem_branch, only: branch_accept, branch_verify, branch_unverifiable
   use fekap_fem_determinacy, only: check_free_motion
   implicit none
   private

   public :: fem_stepper_type, new_fem_stepper, fem_state_type

   !> A verifying pair of half steps contradicts its step when their results
   !> differ by more than verify_agreement model sizes (or the admissible
   !> strain, if larger); see verify_step.
   real(dp), parameter :: verify_agreement = 1.0e-6_dp

   !> The FEM stepper: the composition of the parts (see the module header)
   type, extends(fem_core_type) :: fem_stepper_type
      !> Residual of the last accepted try (see advance_to).
      real(dp) :: try_residual = 0
      !> Configurations accepted at the round-off floor (Newton's
      !> stop_at_floor) while solving the row of this start or advance:
      !> steps.csv's `floor` (the run's are counted in counts%floor_steps).
      integer :: advance_floor = 0
   contains
      procedure :: start => fem_start
      procedure :: advance => fem_advance
   end type fem_stepper_type

contains

   !> Build the mesh, the equation numbering and all storage for a validated model.
   subroutine new_fem_stepper(self, model)
      type(fem_stepper_type), intent(out) :: self
      type(model_type), intent(in) :: model
      call new_fem_core(self, model)
   end subroutine new_fem_stepper

   !> The initial configuration (solved for the initial load, if loaded), and
   !> its velocities and accelerations when asked for.
   subroutine fem_start(self, result, error)
      class(fem_stepper_type), intent(inout) :: self
      type(step_result_type), intent(inout) :: result
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: clock
      integer :: verdict
      logical :: ahead
      clock = clock_seconds()
      self%system%timing = .true.
      start: block
         call start_configuration(self, self%state%t, self%state%q, self%seg, error)
         if (allocated(error)) exit start
         self%state%seg = self%seg
         self%state%history%filled = 0
         call self%factor%invalidate()
         self%state%has_jump_response = .false.
         call self%change%take_ahead(ahead)
         self%advance_floor = 0
         result%iterations = 0
         call assemble_system_residual(self%system, self%mesh, self%state%q, self%state%t, self%seg, self%counts)
         result%residual = residual_norm(self%system, self%mesh)
         if (self%loaded .and. result%residual > self%conv%residual_floor) then
            ! Loads at t_start /= 0: find the loaded configuration first.
            call solve_step(self, self%state%t, 0, result%iterations, result%residual, verdict, error)
            if (allocated(error)) exit start
         else
            call accept(self, self%state%t, self%state%q)
         end if
         if (.not. self%loaded) call start_response(self)
         call solve_rates(self)
         result%floor = self%advance_floor
         call fill_result(self, result)
      end block start
      ! Sampled whatever its outcome: the phases it timed are (fem_advance).
      self%counts%seconds_sampled = self%counts%seconds_sampled + (clock_seconds() - clock)
   end subroutine fem_start

   !> Advance to time t, cutting the step in halves when Newton fails or
   !> converges to an inadmissible configuration, and verifying suspect steps
   !> (see advance_to); then the rates and the listing note.
   subroutine fem_advance(self, t, result, error)
      class(fem_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      type(step_result_type), intent(inout) :: result
      type(error_type), allocatable, intent(out) :: error
      type(step_cuts_type) :: cuts
      real(dp) :: clock
      logical :: filled, ahead
      self%advances = self%advances + 1
      ! The phases are timed on a sample of the steps (and at the start); the
      ! summary scales them to the run (see phase_seconds) by the sampled
      ! steps' time, a failed step's included (else a stopped run's phases
      ! came to 90 times its whole time).
      self%system%timing = phase_timed(self%advances)
      clock = 0
      if (self%system%timing) clock = clock_seconds()
      step: block
         self%advance_floor = 0
         call self%change%take_ahead(ahead)
         if (ahead) then
            if (t == self%change%ahead%t) then
               ! The step over a change point solved this time already (with its rates).
               call restore_state(self, self%change%ahead)
               result%iterations = self%change%ahead_iterations
               result%residual = self%change%ahead_residual
               self%last_cuts = self%change%ahead_cuts
               result%cuts = self%last_cuts
               result%floor = self%change%ahead_floor
               call fill_result(self, result)
               exit step
            end if
            ! Another time: from the regular state before the change point.
            call restore_state(self, self%change%before)
         end if
         ! The paper's `previous` predictor is the last configuration: its tangent
         ! says nothing about the new time's.
         call self%change%begin_advance(.not. self%loaded .and. self%model%analysis%predictor /= predictor_previous)
         call advance_to(self, t, 0, result%iterations, result%residual, cuts, error)
         call self%change%stop_detecting()
         if (allocated(error)) exit step
         if (self%change%found) then
            call step_over(self, t, result, cuts, filled, error)
            if (allocated(error) .or. filled) exit step
         end if
         self%last_cuts = cuts%cuts
         result%cuts = self%last_cuts
         result%floor = self%advance_floor
         call solve_rates(self)
         ! The listing says why the step was cut (the first and the last rejection).
         call prepend_cuts_note(self%state%note, cuts)
         call fill_result(self, result)
      end block step
      if (self%system%timing) self%counts%seconds_sampled = self%counts%seconds_sampled + (clock_seconds() - clock)
   end subroutine fem_advance

   !> The step onto time t found its predictor's tangent near singular (a
   !> change point; detected in solve_step): instead of iterating there, solve
   !> the next output time from the last regular state as one double step
   !> (the usual predictor, Newton, branch-jump check and rates), keep that
   !> state for the next advance, and fill the row at t for output only, from
   !> both sides: positions by Hermite interpolation through the two regular
   !> states (quintic with their velocities and accelerations, cubic with
   !> velocities), corrected onto the mechanism (correct_fill). The filled
   !> row never enters the predictor's history. Its rates are left out: at a
   !> bifurcation they are fixed only by the second-order (bifurcation)
   !> equations, which this does not solve (docs/hard-cases.md). Where the
   !> tangent at the filled configuration is regular enough (near, not on, a
   !> change point), the row is solved as without the detection instead
   !> (filled false), its interpolation being no closer than a nearby branch;
   !> and so it is if the double step fails.
   subroutine step_over(self, t, result, cuts, filled, error)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      type(step_result_type), intent(inout) :: result
      type(step_cuts_type), intent(out) :: cuts
      logical, intent(out) :: filled
      type(error_type), allocatable, intent(out) :: error
      type(error_type), allocatable :: over_error, near_error
      type(step_cuts_type) :: over_cuts
      real(dp), allocatable :: q_fill(:)
      real(dp) :: rcond, rcond_fill, residual
      integer :: its, order, info, floor_before
      logical :: singular
      filled = .false.
      rcond = self%change%predictor_rcond
      call self%change%clear_found()
      ! The tangent at the accepted state again (the drive increment's residual scale).
      call self%factor%invalidate()
      call refactor_at_accepted(self, info)
      call self%change%keep_before(self%state)
      floor_before = self%advance_floor
      call advance_to(self, next_output_time(self, t), 0, its, residual, over_cuts, over_error)
      if (allocated(over_error) .or. self%change%found) then
         ! The double step failed: solve at t itself, as without the detection.
         call self%change%clear_found()
         call restore_state(self, self%change%before)
         call advance_to(self, t, 0, result%iterations, result%residual, cuts, error)
         return
      end if
      call solve_rates(self)
      call prepend_cuts_note(self%state%note, over_cuts)
      ! The floor steps of the double step are the row ahead's.
      call self%change%keep_ahead(self%state, its, residual, over_cuts%cuts, self%advance_floor - floor_before)
      self%advance_floor = floor_before
      call interpolate_fill(self, t, q_fill, its, residual, order, rcond_fill, singular)
      if (.not. singular) then
         ! Near, not on, a change point (the tangent at the filled configuration
         ! is regular enough): solve the row itself as without the detection,
         ! from the state before it; the state at the next time stays ahead.
         call restore_state(self, self%change%before)
         call advance_to(self, t, 0, result%iterations, result%residual, cuts, near_error)
         if (.not. allocated(near_error)) then
            call self%change%clear_found()
            return
         end if
         call finish_fill(self, t, q_fill, its, residual, rcond_fill)
      end if
      call filled_state(self, t, q_fill, order, rcond, rcond_fill, residual, singular)
      call self%factor%invalidate()
      result%iterations = its
      result%residual = residual
      result%cuts = 0
      result%floor = self%advance_floor
      self%last_cuts = 0
      call fill_result(self, result)
      filled = .true.
   end subroutine step_over

   !> Advance the accepted state to time t under step control (the shared
   !> advance_by_cuts: cut after a failure, grow back after a success), each
   !> try being fem_try's; a run's step then looks for free motion (determinacy).
   recursive subroutine advance_to(self, t, depth, iterations, residual, cuts, error)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      !> Verification depth: 0 for a step of the run, k for a step halved k times.
      integer, intent(in) :: depth
      integer, intent(out) :: iterations
      !> Residual of the last accepted step (unchanged if none was).
      real(dp), intent(inout) :: residual
      type(step_cuts_type), intent(out) :: cuts
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: t_from
      t_from = self%state%t
      call advance_by_cuts(self, fem_try, fem_between, t_from, t, depth, self%cut_advice, cuts, iterations, error)
      if (.not. allocated(error) .and. self%state%t > t_from) residual = self%try_residual
      if (depth == 0) call check_free_motion(self, t_from, error)
   end subroutine advance_to

   !> The FEM's try of a step to time t (for advance_by_cuts): Newton
   !> (solve_step); a step that the branch check finds suspect is verified by
   !> two half steps (verify_step, which calls advance_to one level deeper),
   !> and a step they contradict is replaced by them. A change point at the
   !> predictor ends the advance (step_over takes it from there).
   recursive subroutine fem_try(stepper, t, depth, iterations, outcome, reason)
      class(stepper_type), intent(inout) :: stepper
      real(dp), intent(in) :: t
      integer, intent(in) :: depth
      integer, intent(out) :: iterations, outcome
      type(error_type), allocatable, intent(out) :: reason
      character(:), allocatable :: rejection
      real(dp) :: residual
      integer :: it, verdict
      logical :: incomplete
      iterations = 0
      outcome = try_ended
      select type (self => stepper)
      type is (fem_stepper_type)
         call solve_step(self, t, depth, iterations, residual, verdict, reason)
         ! Only a run's step, at its first try, checks for a change point.
         call self%change%stop_detecting()
         if (self%change%found) return
         incomplete = verdict == branch_unverifiable
         if (verdict == branch_verify .and. .not. allocated(reason)) then
            ! The branch-jump check asked for the step to be confirmed by two half steps.
            call verify_step(self, t, depth, it, residual, rejection, incomplete, reason)
            iterations = iterations + it
         end if
         if (allocated(reason)) then
            ! A verification that could not be completed ends every level above
            ! it at once (cutting there would repeat it); the run's step is cut.
            if (incomplete .and. depth > 0) return
            outcome = try_failed
            return
         end if
         self%try_residual = residual
         outcome = try_accepted
         if (allocated(rejection)) then
            ! Contradicted by its half steps, which replaced it: a cut step.
            outcome = try_replaced
            call analysis_error(reason, rejection, t=t)
         end if
      end select
   end subroutine fem_try

   !> An intermediate point of a cut step at time t (for advance_by_cuts, the
   !> accepted state's time): its rates feed the Taylor predictor only.
   subroutine fem_between(stepper, t)
      class(stepper_type), intent(inout) :: stepper
      real(dp), intent(in) :: t
      select type (self => stepper)
      type is (fem_stepper_type)
         if (self%model%analysis%predictor /= predictor_taylor .or. self%state%t /= t) return
         call solve_rates(self)
      end select
   end subroutine fem_between

   !> Predict and solve P(q) = 0 at time t; accept the configuration if it is
   !> admissible. Leaves the accepted state untouched on failure. Newton is
   !> the shared driver's (newton_solve on the step's fekap_fem_newton
   !> workspace); around it: if a slave has slid past its master segment, it
   !> moves on to the neighbouring segment and Newton goes on from there; then,
   !> if Newton stopped on its estimate, the estimate is checked (see below).
   subroutine solve_step(self, t, depth, iterations, residual, verdict, error)
      type(fem_stepper_type), target, intent(inout) :: self
      real(dp), intent(in) :: t
      !> The halvings of the step (0: a step of the run), for its verification.
      integer, intent(in) :: depth
      integer, intent(out) :: iterations
      real(dp), intent(out) :: residual
      !> The branch check's verdict on an accepted step (branch_accept when
      !> not checked; branch_verify: verify it by half steps).
      integer, intent(out) :: verdict
      type(error_type), allocatable, intent(out) :: error
      type(fem_newton_type) :: newton
      type(newton_contract_type) :: contract
      type(always_refactor_type) :: full
      type(newton_report_type) :: report
      real(dp) :: increment_residual, correction
      integer :: info, pass
      logical :: moved, root_solved, guard
      character(len=300) :: msg
      iterations = 0
      verdict = branch_accept
      associate (mesh => self%mesh, qt => self%qt, system => self%system)
         self%seg(:) = self%state%seg
         call self%change%forget_predictor()
         call predict(self, t, qt, guard)
         ! Scale of the residual: what the drive (and load) increment alone
         ! produces from the last configuration, to first order -K_fd dq_d +
         ! dlambda f, with the free-driven block of the last tangent (at the
         ! accepted configuration within tolerance). It does not depend on the predictor.
         increment_residual = 0
         if (self%conv%mode /= convergence_paper .and. self%model%analysis%predictor /= predictor_previous) then
            call drive_increment_residual(self, t, qt, increment_residual)
         end if
         call self%factor%reset()
         contract = fem_contract(self, increment_residual)
         call newton%begin_step(self, t, contract, guard)
         info = 0
         verification: do
            newton%by_estimate = .false.
            relocations: do pass = 0, size(mesh%slides)*8
               call newton%begin_pass()
               call newton_solve(newton, contract, full, report, error)
               iterations = newton%iterations
               if (allocated(error)) then
                  call newton_failure(self, t, report, error)
                  return
               end if
               if (size(mesh%slides) == 0) exit relocations
               call relocate(mesh, self%model, t, qt, self%seg, moved, error)
               if (allocated(error)) return
               if (.not. moved) exit relocations
            end do relocations
            residual = newton%residual
            if (self%loaded) exit verification
            if (newton%at_predictor) then
               ! The factor at the predictor serves (fem_correct). The square-root
               ! form took its correction, of round-off size, and B's geometry
               ! stays the predictor's, its factor's: K's free-driven block
               ! (the next step's residual scale, drive_increment_residual) is
               ! B_f^T W B_d from the predictor's B_d and section angles
               ! (root_drive_block), round-off away from K's at the corrected
               ! configuration, and so are the rates' residuals where they are
               ! not refined (solve_rates moves the geometry there where they
               ! are: the factor record's keep_predictor); unrefined
               ! velocities are the drive response of the predictor's factor.
               ! K is not assembled, nor the residual at the corrected
               ! configuration. The residual reported is the predictor's, from
               ! which the correction of round-off size was solved
               ! (newton%residual).
               if (self%root_form) then
                  call self%factor%keep_predictor()
                  call root_drive_block(self%root, mesh, system%kfd, self%root_work)
               end if
               exit verification
            end if
            ! The material tangent at the new configuration: the branch-jump
            ! check's response (and from it the predictor's velocity) and, once
            ! accepted, the rates' tangent. The last Newton factor, one correction
            ! away, would give rates off by that correction times the ratio of
            ! axial to bending stiffness (EA L^2 / EI; docs/performance.md).
            ! The square-root form factors B_f instead and needs of K its
            ! free-driven block alone (the next step's residual scale).
            if (self%root_form) then
               call assemble_system_drive_block(system, mesh, qt, t, self%seg, huge(1.0_dp), self%counts)
            else
               call assemble_system(system, mesh, qt, t, self%seg, huge(1.0_dp), self%counts)
            end if
            ! The residual reported for the step is the one at the accepted configuration.
            residual = residual_norm(system, mesh)
            if (self%root_form) then
               ! The estimate is checked by one more correction of B_f; then the
               ! factor of the stress-free B_f at qt serves as K's does below.
               ! The check is made first with that factor (B_f stress-free at
               ! qt, eps the residual): where B_f is regular there (its pivot
               ! ratio not near singular against the run's best), a correction
               ! within the margin leaves qt as it is, and the factor is the
               ! rates' (no second assembly and factorisation of B_f).
               ! Otherwise it is made again with Newton's B_f (the strains'
               ! exact gradient), whose correction is the one applied: near a
               ! singular B_f the two corrections can fall on either side of
               ! the margin.
               ! First Newton's own factor, where it serves at qt (carry_factor),
               ! whether Newton stopped on its estimate or converged by the contract.
               root_solved = .false.
               if (newton%root_solved) then
                  call carry_factor(self, qt, root_solved)
                  if (root_solved) then
                     info = 0
                     exit verification
                  end if
               end if
               if (newton%by_estimate) then
                  call root_correction(self, qt, .true., correction, root_solved, system%section)
                  if (root_solved .and. correction <= estimate_margin*self%conv%length .and. &
                     & self%root%pivot_ratio >= near_singular_drop*self%state%reference_pivot) then
                     info = 0
                     exit verification
                  end if
                  call root_correction(self, qt, .true., correction, root_solved)
               end if
               if (.not. root_solved .or. correction <= estimate_margin*self%conv%length) then
                  call factor_root(self, qt, self%seg, info, system%section)
                  exit verification
               end if
            else
               call factor_system(system, info, self%counts)
               if (.not. newton%by_estimate .or. info /= 0) exit verification
               ! A stop on the estimate is checked with this factor (one back
               ! substitution): the correction it gives must pass the estimate's own
               ! margin, or it is applied as one more Newton iteration and Newton
               ! goes on (with a stiff slideline penalty the estimate can miss).
               call newton_correction(system, mesh, self%dof_length, correction, self%counts)
               if (correction <= estimate_margin*self%conv%length) exit verification
            end if
            call take_correction(self, qt, newton%iterations)
            iterations = newton%iterations
            if (iterations >= self%model%analysis%max_iter) then
               call no_convergence_error(t, iterations, residual, error)
               return
            end if
            newton%previous = correction
         end do verification
         if (.not. self%loaded) then
            call check_mechanism(self, t, qt, error)
            if (allocated(error)) return
            call branch_jump(self, t, qt, info == 0, depth, verdict, error)
            if (allocated(error)) return
            call self%factor%mark(info)
         end if
         call accept(self, t, qt)
         if (report%stopped == stop_at_floor) then
            ! The last resort of the contract (or the FEM's round-off stall), reported.
            self%advance_floor = self%advance_floor + 1
            self%counts%floor_steps = self%counts%floor_steps + 1
         end if
         if (newton%stalled_correction > 0) then
            write (msg, '(a,es12.5,a,es9.2,a,es9.2,a)') 't = ', t, ': Newton stopped at the round-off floor of the '// &
               & 'residual (', residual, '); the last correction, ', newton%stalled_correction, &
               & ', bounds the error of this configuration'
            self%state%note = trim(msg)
         end if
         ! The velocity for the predictor's history comes from the branch-jump
         ! check's response (the same whatever rates the run computes, so
         ! positions do not depend on them).
         if (.not. self%loaded) call record_velocity(self)
      end associate
   end subroutine solve_step

   !> A step's Newton that did not converge (newton_solve's error): the
   !> FEM's messages, or no error at a change point at the predictor
   !> (change%found: step_over takes it from there).
   subroutine newton_failure(self, t, report, error)
      type(fem_stepper_type), intent(in) :: self
      real(dp), intent(in) :: t
      type(newton_report_type), intent(in) :: report
      type(error_type), allocatable, intent(inout) :: error
      character(len=300) :: msg
      select case (report%stopped)
      case (stop_spent)
         deallocate (error)
         call no_convergence_error(t, report%iterations, report%last_residual, error)
      case (stop_diverged)
         deallocate (error)
         write (msg, '(a,es12.5,a,i0)') 't = ', t, ': Newton diverged at iteration ', report%iterations
         call analysis_error(error, trim(msg), t=t)
      case (stop_singular)
         deallocate (error)
         if (self%change%found) return
         write (msg, '(a,es12.5,a)') 't = ', t, ': singular tangent stiffness at '
         call analysis_error(error, trim(msg)//' '//describe_dof(self%mesh, self%model, self%mesh%eq_dof(report%info)), t=t)
      case default
         ! An interrupt keeps its message.
      end select
   end subroutine newton_failure

   !> Step-doubling verification of a step to time t that the branch check
   !> found suspect (a hinged pair crossed collinear turning by more than
   !> verify_turn): the step is accepted, the state before it is on the
   !> verification stack at `depth`. The same interval is solved again from that state as
   !> two half steps (advance_to one level deeper: cut if they fail, verified
   !> if suspect) and the results are compared. The state after the half
   !> steps stays: on agreement it is the same configuration to the tolerance;
   !> otherwise the step was a jump and `rejection` says so. If the half steps
   !> cannot be solved, the state before the step is restored and the step is
   !> rejected (error). A jump over a near-toggle turns the pair that flips by
   !> its distances from collinear at both ends, so it stays suspect however
   !> often it is halved, while a real crossing turns less with every halving.
   recursive subroutine verify_step(self, t, depth, iterations, residual, rejection, failed, error)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      !> Verification depth of the step (0: a step of the run).
      integer, intent(in) :: depth
      !> Newton iterations of the half steps (and of their verification).
      integer, intent(out) :: iterations
      !> Residual of the last half step.
      real(dp), intent(inout) :: residual
      !> Why the step was replaced by its half steps (not allocated if it was confirmed).
      character(:), allocatable, intent(out) :: rejection
      !> Whether the half steps could not be solved (error allocated): the
      !> verification is incomplete.
      logical, intent(out) :: failed
      type(error_type), allocatable, intent(out) :: error
      type(error_type), allocatable :: half_error
      type(step_cuts_type) :: half_cuts
      character(:), allocatable :: pair
      real(dp), allocatable :: q_whole(:)
      real(dp) :: t_end(2), distance
      integer :: half, it, worst_dof
      character(len=200) :: msg
      failed = .false.
      q_whole = self%state%q
      call restore_state(self, self%verification%level(depth)%before)
      pair = self%verification%pair_text(depth, self%model)
      t_end = [self%state%t + (t - self%state%t)/2, t]
      iterations = 0
      do half = 1, 2
         call advance_to(self, t_end(half), depth + 1, it, residual, half_cuts, half_error)
         iterations = iterations + it
         if (allocated(half_error)) exit
         ! The midpoint's rates feed the Taylor predictor, as at a cut step's intermediate points.
         if (half == 1 .and. self%model%analysis%predictor == predictor_taylor) call solve_rates(self)
      end do
      if (allocated(half_error)) then
         call restore_state(self, self%verification%level(depth)%before)
         failed = .true.
         if (depth > 0) then
            call move_alloc(half_error, error)
         else
            write (msg, '(a,es12.5,a,f7.4,a)') 't = ', t, ': possible assembly-mode jump rejected ('//pair// &
               & ' crossed collinear turning ', self%verification%level(depth)%turn, &
               & ' rad; two half steps could not confirm it: '
            call analysis_error(error, trim(msg)//' '//half_error%message//')', t=t)
         end if
         return
      end if
      call model_distance(self, q_whole, self%state%q, distance, worst_dof)
      if (distance > max(verify_agreement, self%admissible_strain)) then
         write (msg, '(a,es12.5,a,es9.2,a)') 't = ', t, ': assembly-mode jump rejected (the step ends ', distance, &
            & ' model sizes from where two half steps end, at'
         rejection = trim(msg)//' '//describe_dof(self%mesh, self%model, worst_dof)//'; '//pair// &
            & ' crossed collinear); the half steps replace it'
      end if
   end subroutine verify_step

end module fekap_fem
