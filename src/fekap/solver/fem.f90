!> The paper's finite element method as a stepper: per step, advance the
!> drives, predict, solve P(q) = 0 on the free dofs by Newton-Raphson with the
!> symmetric band tangent, check that the converged configuration is a
!> mechanism configuration (every element unstrained, every slave on its
!> line, no assembly-mode jump), then solve for velocities (47) and
!> accelerations (49) with the tangent of the converged configuration. A
!> step that fails is cut in halves (bounded) and retried.
!>
!> This module composes the parts, each a module of its own: the linear
!> system (linear_system), the predictor and its history (predictor),
!> slideline tracking (assembly/tracking), the branch check (branch), the
!> rates (rates), step control (step_control), the convergence tests
!> (convergence) and the result's fields (fields). What stays here is the
!> Newton iteration of a step, with its choices of tangent, and the
!> step-doubling verification that the branch check asks for.
!>
!> An exactly constrained kinematic model (assembly/strain_rate: as many
!> strain and gap rows as free dofs, no loads) solves its Newton
!> corrections, drive responses and rates in the square-root form, with the
!> band LU of the strain-rate operator B_f instead of the factor of K_ff =
!> B_f^T W B_f, whose condition number is the square of B_f's
!> (docs/theory.md, "Rates at scale"). The factor at the accepted
!> configuration (factor_current) is then B_f's, and the pivot ratio of the
!> listing's notes its square (strain_rate_type%pivot_ratio, on K's scale).
!> Kinetostatics and loaded models keep the tangent K throughout.
!>
!> Why one module of over 600 lines: the Newton iteration (solve_step), the
!> step loop (advance_to) and the verification by half steps (verify_step)
!> call one another recursively and act on the whole of the stepper's state
!> (the accepted state, the iterate, the factor's currency, the pending
!> verifications); split, each would take the whole stepper as an argument
!> and the recursion would cross modules, which plain Fortran modules cannot
!> do without a cycle.
module fekap_solver_fem
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, analysis_error
   use fekap_model, only: model_type, predictor_previous, predictor_taylor, &
      & convergence_paper, solver_dense, effects_kinematics
   use fekap_model_effects, only: planned_effects
   use fekap_model_results, only: step_result_type, note_length, has_note
   use fekap_assembly_mesh, only: describe_dof, dof_fixed
   use fekap_assembly_assemble, only: max_strain
   use fekap_assembly_tracking, only: relocate, check_gaps
   use fekap_solver_stepper, only: clock_seconds, phase_timed
   use fekap_solver_fem_setup, only: fem_base_type, new_fem_base, start_configuration, set_driven, mesh_plan_line
   use fekap_solver_convergence, only: convergence_type, is_converged, converged_by_estimate, estimate_margin, &
      & divergence_length
   use fekap_solver_linear_system, only: assemble_system, &
      & assemble_system_residual, factor_system, system_pivot, residual_norm, newton_correction, &
      & apply_correction, drive_response, drive_load_rhs, solve_system, apply_response, system_rcond
   use fekap_solver_predictor, only: predictor_history_type, new_predictor_history, extrapolate_history, &
      & taylor_predict, prediction_none, prediction_smooth, predictor_margin
   use fekap_solver_branch, only: branch_check_type, new_branch_check, drive_increment, branch_verdict, &
      & branch_reject, branch_verify, branch_unverifiable, max_verify_depth
   use fekap_solver_rates, only: pivot_note, solve_velocities, solve_accelerations, near_singular_drop, &
      & singular_floor, root_velocities, root_accelerations, root_drive_response
   use fekap_assembly_strain_rate, only: strain_rate_type, new_strain_rate, assemble_strain_rate, &
      & factor_strain_rate, solve_strain_rate, strain_rate_rcond
   use fekap_solver_step_control, only: step_cuts_type
   use fekap_solver_interrupt, only: interrupt_signal, interrupt_error
   use fekap_solver_fields, only: fill_nodes_links, fill_fields
   use fekap_solver_change_point, only: change_verdict, change_regular, hermite_fill, correct_fill, fill_order, &
      & rates_drop, fill_shift, response_trusted
   use fekap_output_format, only: es_text
   implicit none
   private

   public :: fem_stepper_type, new_fem_stepper, fem_state_type

   !> Element strain above which a converged configuration is not a mechanism
   !> configuration but a self-stressed equilibrium.
   !> It follows the Newton tolerance (a loose paper-style test leaves strains
   !> near the tolerance) but never reaches the strains of a self-stressed
   !> state, which are of order 0.1.
   real(dp), parameter :: min_admissible_strain = 1.0e-8_dp, max_admissible_strain = 1.0e-3_dp
   !> Newton's tangent leaves out the geometric stiffness at Gauss points
   !> strained less than this (see solve_step).
   real(dp), parameter :: geometric_strain = 3.0e-3_dp
   !> Iterations in a row with the residual below its floor after which
   !> Newton has stalled at round-off.
   integer, parameter :: stall_iterations = 3
   !> A verifying pair of half steps contradicts its step when their results
   !> differ by more than verify_agreement model sizes (or the admissible
   !> strain, if larger); see verify_step.
   real(dp), parameter :: verify_agreement = 1.0e-6_dp

   !> The accepted state of the stepper: everything a step changes, so that
   !> step-doubling verification saves and restores it by one assignment.
   type :: fem_state_type
      !> Time, configuration, velocity and acceleration over all dofs.
      real(dp) :: t = 0
      real(dp), allocatable :: q(:), v(:), a(:)
      !> Whether v (and a) belong to the configuration.
      logical :: has_velocity = .false., has_acceleration = .false.
      !> The last accepted configurations, for the predictor.
      type(predictor_history_type) :: history
      !> Master segment of each slideline.
      integer, allocatable :: seg(:)
      !> Linear response of every dof to unit changes of the drives, (ndof,
      !> ndriven), kept by the branch-jump check whatever rates the run
      !> computes, and whether it is known.
      real(dp), allocatable :: jump_response(:, :)
      logical :: has_jump_response = .false.
      !> Largest pivot ratio of a tangent at an accepted configuration so far
      !> (the reference for singular and near-singular configurations).
      real(dp) :: reference_pivot = 0
      !> Largest reciprocal condition number (system_rcond) of the material
      !> tangent at an accepted configuration so far: the reference of the
      !> change-point detection and of the trust in a drive response.
      real(dp) :: reference_rcond = 0
      !> Remark on the configuration for the listing (empty if none).
      character(len=note_length) :: note = ''
   end type fem_state_type

   !> A step awaiting verification: the state before it, and the hinged pair
   !> that crossed collinear (link, link, node) with its turn, for the messages.
   type :: verification_type
      type(fem_state_type) :: before
      integer :: crossing(3) = 0
      real(dp) :: turn = 0
   end type verification_type

   !> The model, mesh, linear system, drives' start values and scales are
   !> fem_base_type's (new_fem_base), as the dynamics stepper's.
   type, extends(fem_base_type) :: fem_stepper_type
      type(convergence_type) :: conv
      type(branch_check_type) :: branch
      type(fem_state_type) :: state
      !> Whether the system holds the factor of the tangent at (within
      !> tolerance of) the accepted configuration, and whether factoring the
      !> tangent there failed (a singular configuration).
      logical :: factor_current = .false., accepted_singular = .false.
      !> Quadratic-convergence constant M of Newton (c(k+1) = M c(k)**2) measured
      !> in the last step that showed it, for the estimated stop.
      real(dp) :: newton_constant = 0
      !> The last predictor, and whether it was a smooth (Hermite or Adams)
      !> extrapolation of the history.
      real(dp), allocatable :: q_predicted(:)
      logical :: smooth_prediction = .false.
      !> Pivot ratio of the factor behind the last drive response.
      real(dp) :: response_pivot = 0
      !> Whether the model has external loads (a flexible, stressed analysis).
      logical :: loaded = .false.
      !> Work over the dofs: a change or rate of the loads (mesh%loads).
      real(dp), allocatable :: load_work(:)
      !> Work arrays over the dofs, allocated once (nothing is allocated in the
      !> step loop): the iterate, scratch, and the responses to a step's drive
      !> increment at its two ends.
      real(dp), allocatable :: qt(:), work(:), dq_new(:), dq_old(:)
      !> The drives' increment over a step.
      real(dp), allocatable :: drive_step(:)
      !> Master segment of each slideline during the step.
      integer, allocatable :: seg(:)
      !> The drive response at the new configuration (swapped with the state's).
      real(dp), allocatable :: jump_response_new(:, :)
      !> Step cuts in the last advance, for the listing.
      integer :: last_cuts = 0
      !> Element strain (and gap per model size) above which a converged
      !> configuration is rejected: min(1e-3, max(1e-8, 100 tol)).
      real(dp) :: admissible_strain = min_admissible_strain
      !> Whether the step just accepted awaits step-doubling verification, and
      !> the number of halvings of the step being solved (0: a step of the caller's).
      logical :: verify_pending = .false.
      integer :: verify_depth = 0
      !> Whether a verification could not be completed (see advance_to).
      logical :: verify_failed = .false.
      !> The steps awaiting verification at each depth.
      type(verification_type) :: verification(0:max_verify_depth)
      !> Whether the predictor extrapolated: guard_extrapolation then checks it
      !> with the strains of the step's first assembly.
      logical :: guard_pending = .false.
      !> Steps advanced so far.
      integer :: advances = 0
      !> The strain-rate operator B_f and its factor (see the module header),
      !> and whether the square-root form is used (then factor_current refers
      !> to the factor of the stress-free B_f in root).
      type(strain_rate_type) :: root
      logical :: root_form = .false.
      !> Scratch over the equations for the square-root form's solves.
      real(dp), allocatable :: root_work(:)
      !> Change points (see step_over): whether the step being solved checks its
      !> predictor's tangent, whether it found it near singular, and that
      !> tangent's condition estimate.
      logical :: detect_change = .false., change_found = .false.
      real(dp) :: predictor_rcond = 0
      !> Whether this step's predictor was checked and found regular: its
      !> estimate then stands for the accepted configuration's in the
      !> branch-jump check (one estimate a step, not two).
      logical :: predictor_regular = .false.
      !> The regular states on either side of a change point stepped over: the
      !> state before it, and the one solved at the next output time, kept for
      !> the next advance with its iterations, residual and cuts.
      type(fem_state_type) :: before_change, ahead
      logical :: has_ahead = .false.
      integer :: ahead_iterations = 0, ahead_cuts = 0
      real(dp) :: ahead_residual = 0
   contains
      procedure :: start => fem_start
      procedure :: advance => fem_advance
      procedure :: plan_text => fem_plan_text
   end type fem_stepper_type

contains

   !> Build the mesh, the equation numbering and all storage for a validated model.
   subroutine new_fem_stepper(self, model)
      type(fem_stepper_type), intent(out) :: self
      type(model_type), intent(in) :: model
      call new_fem_base(self, model, dense=model%analysis%solver == solver_dense)
      associate (n => self%mesh%ndof, nd => self%mesh%ndriven, state => self%state)
         allocate (self%drive_step(nd), source=0.0_dp)
         allocate (state%q(n), state%v(n), state%a(n), self%qt(n), self%work(n), self%dq_new(n), self%dq_old(n), &
            & source=0.0_dp)
         call new_predictor_history(state%history, n)
         allocate (self%q_predicted(n), source=0.0_dp)
         allocate (state%jump_response(n, nd), self%jump_response_new(n, nd), source=0.0_dp)
         allocate (self%seg(size(self%mesh%slides)), state%seg(size(self%mesh%slides)), source=1)
      end associate
      self%loaded = self%mesh%loads%is_loaded()
      allocate (self%load_work(self%mesh%ndof), source=0.0_dp)
      call new_strain_rate(self%root, self%mesh)
      ! Kinetostatics solves its deflection with the factor of K at the accepted configuration.
      self%root_form = self%root%applies .and. .not. self%loaded .and. model%analysis%solver /= solver_dense .and. &
         & planned_effects(model) == effects_kinematics
      allocate (self%root_work(self%mesh%nfree), source=0.0_dp)
      self%conv%mode = model%analysis%convergence
      self%conv%tol = model%analysis%tol
      self%conv%length = model%analysis%length_tol*self%model_length
      self%admissible_strain = min(max_admissible_strain, max(min_admissible_strain, 100*model%analysis%tol))
      call new_branch_check(self%branch, model, self%mesh)
      self%conv%residual_floor = self%residual_floor
   end subroutine new_fem_stepper

   !> The mesh for the listing's plan: its size, band and slideline penalties.
   function fem_plan_text(self) result(text)
      class(fem_stepper_type), intent(in) :: self
      character(:), allocatable :: text
      character(len=160) :: line
      integer :: i
      text = mesh_plan_line(self)
      do i = 1, size(self%mesh%slides)
         write (line, '(a,a,a,a)') 'slideline '//self%model%slidelines(i)%name//': penalty ', &
            & es_text(self%mesh%slides(i)%kp, 12, 5), ', rotational tie ', es_text(self%mesh%slides(i)%kr, 12, 5)
         text = text//new_line('a')//'  '//trim(line)
      end do
   end function fem_plan_text

   !> The initial configuration (solved for the initial load, if loaded), and
   !> its velocities and accelerations when asked for.
   subroutine fem_start(self, result, error)
      class(fem_stepper_type), intent(inout) :: self
      type(step_result_type), intent(inout) :: result
      type(error_type), allocatable, intent(out) :: error
      integer :: info
      real(dp) :: clock, pivot, rcond
      clock = clock_seconds()
      self%system%timing = .true.
      call start_configuration(self, self%state%t, self%state%q, self%seg, error)
      if (allocated(error)) return
      self%state%seg = self%seg
      self%state%history%filled = 0
      self%factor_current = .false.
      self%state%has_jump_response = .false.
      self%has_ahead = .false.
      result%iterations = 0
      call assemble_system_residual(self%system, self%mesh, self%state%q, self%state%t, self%seg, self%counts)
      result%residual = residual_norm(self%system, self%mesh)
      if (self%loaded .and. result%residual > self%conv%residual_floor) then
         ! Loads at t_start /= 0: find the loaded configuration first.
         call solve_step(self, self%state%t, result%iterations, result%residual, error)
         if (allocated(error)) return
      else
         call accept(self, self%state%t, self%state%q)
      end if
      if (.not. self%loaded) then
         ! The response at the start: the branch-jump check's reference and the
         ! first velocity of the predictor's history.
         call refactor_at_accepted(self, info)
         self%state%has_jump_response = info == 0
         if (info == 0) then
            pivot = accepted_pivot(self)
            call note_response_pivot(self, pivot)
            call accepted_response(self, self%state%jump_response)
            call accepted_rcond(self, rcond)
            self%state%reference_rcond = rcond
         end if
         call record_velocity(self)
      end if
      call solve_rates(self)
      call fill_result(self, result)
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
      logical :: filled
      self%advances = self%advances + 1
      ! The phases are timed on a sample of the steps (and at the start); the
      ! summary scales them to the run (see phase_seconds).
      self%system%timing = phase_timed(self%advances)
      if (self%system%timing) clock = clock_seconds()
      if (self%has_ahead) then
         self%has_ahead = .false.
         if (t == self%ahead%t) then
            ! The step over a change point solved this time already (with its rates).
            call restore_state(self, self%ahead)
            result%iterations = self%ahead_iterations
            result%residual = self%ahead_residual
            self%last_cuts = self%ahead_cuts
            result%cuts = self%last_cuts
            call fill_result(self, result)
            if (self%system%timing) self%counts%seconds_sampled = self%counts%seconds_sampled + (clock_seconds() - clock)
            return
         end if
         ! Another time: from the regular state before the change point.
         call restore_state(self, self%before_change)
      end if
      ! The paper's `previous` predictor is the last configuration: its tangent
      ! says nothing about the new time's.
      self%detect_change = .not. self%loaded .and. self%model%analysis%predictor /= predictor_previous
      self%change_found = .false.
      call advance_to(self, t, 0, result%iterations, result%residual, cuts, error)
      self%detect_change = .false.
      if (allocated(error)) return
      if (self%change_found) then
         call step_over(self, t, result, cuts, filled, error)
         if (allocated(error)) return
         if (filled) then
            if (self%system%timing) self%counts%seconds_sampled = self%counts%seconds_sampled + (clock_seconds() - clock)
            return
         end if
      end if
      self%last_cuts = cuts%cuts
      result%cuts = self%last_cuts
      call solve_rates(self)
      if (allocated(cuts%first)) then
         ! The listing says why the step was cut (the first and the last rejection).
         if (has_note(self%state%note)) then
            self%state%note = cuts%note()//'; '//trim(self%state%note)
         else
            self%state%note = cuts%note()
         end if
      end if
      call fill_result(self, result)
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
      real(dp), allocatable :: v0(:), a0(:), v1(:), a1(:), q_fill(:)
      real(dp) :: t_next, rcond, rcond_fill, residual, correction
      integer :: its, order, info, i
      logical :: has_v0, has_a0, has_v1, has_a1, singular
      character(:), allocatable :: what
      character(len=360) :: text
      filled = .false.
      rcond = self%predictor_rcond
      self%change_found = .false.
      ! The tangent at the accepted state again (the drive increment's residual scale).
      self%factor_current = .false.
      call refactor_at_accepted(self, info)
      self%before_change = self%state
      t_next = next_output_time(self, t)
      call advance_to(self, t_next, 0, its, residual, over_cuts, over_error)
      if (allocated(over_error) .or. self%change_found) then
         ! The double step failed: solve at t itself, as without the detection.
         self%change_found = .false.
         call restore_state(self, self%before_change)
         call advance_to(self, t, 0, result%iterations, result%residual, cuts, error)
         return
      end if
      call solve_rates(self)
      if (allocated(over_cuts%first)) then
         if (has_note(self%state%note)) then
            self%state%note = over_cuts%note()//'; '//trim(self%state%note)
         else
            self%state%note = over_cuts%note()
         end if
      end if
      self%ahead = self%state
      self%ahead_iterations = its
      self%ahead_residual = residual
      self%ahead_cuts = over_cuts%cuts
      self%has_ahead = .true.
      ! The rates of the two sides: the solved ones, else the predictor's history velocities.
      associate (bf => self%before_change, n => self%ahead, q => self%qt)
         call side_rates(bf, v0, a0, has_v0, has_a0)
         call side_rates(n, v1, a1, has_v1, has_a1)
         order = fill_order(has_v0 .and. has_v1, has_a0 .and. has_a1)
         call hermite_fill(order, bf%t, bf%q, v0, a0, n%t, n%q, v1, a1, t, q)
         do i = 1, self%mesh%ndof
            if (self%mesh%status(i) == dof_fixed) q(i) = self%mesh%q0(i)
         end do
         call set_driven(self, t, q)
         self%seg = bf%seg
         call correct_fill(self%system, self%mesh, q, t, self%seg, self%dof_length, self%conv%length, fill_shift, &
            & its, correction, residual, self%counts)
         call fill_tangent(self, q, t, rcond_fill)
         q_fill = q
         singular = rcond_fill < rates_drop*bf%reference_rcond
      end associate
      if (.not. singular) then
         ! Near, not on, a change point (the tangent at the filled configuration
         ! is regular enough): solve the row itself as without the detection,
         ! from the state before it; the state at the next time stays ahead.
         call restore_state(self, self%before_change)
         call advance_to(self, t, 0, result%iterations, result%residual, cuts, near_error)
         if (.not. allocated(near_error)) then
            self%change_found = .false.
            return
         end if
         ! It failed: the fill, finished by plain Newton, with rates there.
         call correct_fill(self%system, self%mesh, q_fill, t, self%seg, self%dof_length, &
            & predictor_margin*self%conv%length, 0.0_dp, i, correction, residual, self%counts)
         its = its + i
         call fill_tangent(self, q_fill, t, rcond_fill)
      end if
      associate (bf => self%before_change, n => self%ahead)
         self%state = bf
         self%state%t = t
         self%state%q = q_fill
         self%state%has_velocity = .false.
         self%state%has_acceleration = .false.
         what = ': near a change point ('
         if (singular) what = ': singular configuration (a change point: '
         write (text, '(a,es12.5,a,es9.2,a,es9.2,a,es12.5,a,es12.5,a,i0,a,es9.2,a)') 't = ', t, &
            & what//'the tangent''s condition ', rcond/max(bf%reference_rcond, tiny(1.0_dp)), ' at the predictor, ', &
            & rcond_fill/max(bf%reference_rcond, tiny(1.0_dp)), ' at the configuration, of the run''s best): '// &
            & 'stepped over from t = ', bf%t, ' to ', n%t, '; positions interpolated from both sides (order ', order, &
            & ') and corrected (residual ', residual, ')'
         self%state%note = trim(text)
         if (singular) then
            if (self%model%analysis%velocities) self%state%note = trim(self%state%note)// &
               & ': velocities and accelerations are left out of this step'
         else if (self%model%analysis%velocities) then
            self%state%note = trim(self%state%note)//': velocities and accelerations are ill-conditioned'
            call self%model%drives%law%eval(t, self%law_value, self%law_rate, self%law_rate2)
            call solve_velocities(self%system, self%mesh, self%law_rate, self%state%v, self%counts)
            self%state%has_velocity = .true.
            if (self%model%analysis%accelerations) then
               call solve_accelerations(self%system, self%mesh, q_fill, self%state%v, self%seg, self%law_rate2, &
                  & self%state%a, self%work, self%counts)
               self%state%has_acceleration = .true.
            end if
         end if
      end associate
      self%factor_current = .false.
      result%iterations = its
      result%residual = residual
      result%cuts = 0
      self%last_cuts = 0
      call fill_result(self, result)
      filled = .true.
   end subroutine step_over

   !> Assemble and factor the material tangent at the filled configuration q
   !> at time t; its condition estimate (0 if singular), B_f's squared in the
   !> square-root form.
   subroutine fill_tangent(self, q, t, rcond)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), contiguous, intent(in) :: q(:)
      real(dp), intent(in) :: t
      real(dp), intent(out) :: rcond
      integer :: info
      integer :: root_info
      call assemble_system(self%system, self%mesh, q, t, self%seg, huge(1.0_dp), self%counts)
      call factor_system(self%system, info, self%counts)
      self%factor_current = .false.
      rcond = 0
      if (self%root_form) then
         ! On the scale of the run's best, which is B_f's in the square-root form.
         call factor_root(self, q, self%seg, root_info)
         if (root_info == 0) call strain_rate_rcond(self%root, rcond)
      else if (info == 0) then
         call system_rcond(self%system, rcond, self%counts)
      end if
   end subroutine fill_tangent

   !> Velocities and accelerations of an accepted state for the fill of a
   !> change point, as far as known: the solved rates, else the velocity of
   !> its newest history entry (a positions-only run), and whether each is known.
   subroutine side_rates(state, v, a, known_v, known_a)
      type(fem_state_type), intent(in) :: state
      real(dp), allocatable, intent(out) :: v(:), a(:)
      logical, intent(out) :: known_v, known_a
      allocate (v(size(state%q)), a(size(state%q)), source=0.0_dp)
      known_v = .false.
      known_a = .false.
      if (state%has_velocity) then
         v = state%v
         known_v = .true.
         if (state%has_acceleration) then
            a = state%a
            known_a = .true.
         end if
      else if (state%history%has_velocity(state%history%newest)) then
         v = state%history%velocity(:, state%history%newest)
         known_v = .true.
      end if
   end subroutine side_rates

   !> The output time after t of the run's uniform steps (as the time loop
   !> makes them: t_start + n dt, the last one t_end), or t plus the last
   !> step if t is not one of them or is the last.
   real(dp) function next_output_time(self, t) result(t_next)
      type(fem_stepper_type), intent(in) :: self
      real(dp), intent(in) :: t
      real(dp) :: span
      integer :: n, nsteps
      t_next = t + (t - self%state%t)
      associate (an => self%model%analysis)
         if (.not. an%dt > 0) return
         span = an%t_end - an%t_start
         nsteps = nint(span/an%dt)
         if (abs(nsteps*an%dt - span) > 1.0e-9_dp*an%dt) nsteps = ceiling(span/an%dt)
         nsteps = max(nsteps, 1)
         n = nint((t - an%t_start)/an%dt)
         if (n + 1 > nsteps .or. n < 0) return
         if (abs(an%t_start + n*an%dt - t) > 1.0e-9_dp*an%dt .and. t /= an%t_end) return
         if (n + 1 == nsteps) then
            t_next = an%t_end
         else
            t_next = an%t_start + (n + 1)*an%dt
         end if
      end associate
   end function next_output_time

   !> Advance the accepted state to time t under step control (cut after a
   !> failure, grow back after a success). A step that the branch check finds
   !> suspect is verified by two half steps (verify_step, which calls this
   !> again one level deeper); a step they contradict counts as cut and is
   !> replaced by them.
   recursive subroutine advance_to(self, t, depth, iterations, residual, cuts, error)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      !> Verification depth: 0 for a step of the run, k for a step halved k times.
      integer, intent(in) :: depth
      integer, intent(out) :: iterations
      !> Residual of the last accepted step.
      real(dp), intent(inout) :: residual
      type(step_cuts_type), intent(out) :: cuts
      type(error_type), allocatable, intent(out) :: error
      type(error_type), allocatable :: step_error
      character(:), allocatable :: rejection
      real(dp) :: t_try, step_residual
      integer :: it
      call cuts%begin(self%state%t, t)
      iterations = 0
      do while (self%state%t < t)
         t_try = cuts%next(self%state%t)
         self%verify_depth = depth
         call solve_step(self, t_try, it, step_residual, step_error)
         iterations = iterations + it
         if (allocated(step_error) .and. interrupt_signal() /= 0) then
            ! A signal stopped the step: no cut, the run stops.
            call move_alloc(step_error, error)
            return
         end if
         ! Only a run's step, at its first try, checks for a change point.
         self%detect_change = .false.
         if (self%change_found) return
         if (self%verify_pending) then
            ! The branch-jump check asked for the step to be confirmed by two half steps.
            self%verify_pending = .false.
            if (.not. allocated(step_error)) then
               call verify_step(self, t_try, depth, it, step_residual, rejection, step_error)
               iterations = iterations + it
            end if
         end if
         if (allocated(rejection)) then
            ! Contradicted by its half steps, which replaced it: a cut step.
            call cuts%replaced(rejection)
            deallocate (rejection)
         end if
         if (allocated(step_error)) then
            ! A verification that could not be completed ends every level above
            ! it at once (cutting there would repeat it); the run's step is cut.
            if (self%verify_failed .and. depth > 0) then
               call move_alloc(step_error, error)
               return
            end if
            self%verify_failed = .false.
            call cuts%reject(step_error, error)
            if (allocated(error)) return
            deallocate (step_error)
            cycle
         end if
         residual = step_residual
         if (self%state%t < t) then
            ! An intermediate point of a cut step: its rates feed the Taylor predictor only.
            if (self%model%analysis%predictor == predictor_taylor) call solve_rates(self)
            call cuts%grow()
         end if
      end do
   end subroutine advance_to

   !> Predict and solve P(q) = 0 at time t; accept the configuration if it is
   !> admissible. Leaves the accepted state untouched on failure.
   subroutine solve_step(self, t, iterations, residual, error)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      integer, intent(out) :: iterations
      real(dp), intent(out) :: residual
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: r0, increment_residual, correction, previous, strain, kg_above, stalled_correction, pivot, rcond
      integer :: i, info, element, pass, at_floor
      logical :: moved, by_estimate, at_predictor, root_solved
      character(len=300) :: msg
      associate (mesh => self%mesh, qt => self%qt, eqd => self%mesh%eq_dof, system => self%system)
         self%seg = self%state%seg
         self%predictor_regular = .false.
         call predict(self, t, qt)
         ! Scale of the residual: what the drive (and load) increment alone
         ! produces from the last configuration, to first order -K_fd dq_d +
         ! dlambda f, with the free-driven block of the last tangent (at the
         ! accepted configuration within tolerance). It does not depend on the predictor.
         increment_residual = 0
         if (self%conv%mode /= convergence_paper .and. self%model%analysis%predictor /= predictor_previous) then
            call drive_increment_residual(self, t, qt, increment_residual)
         end if
         self%factor_current = .false.
         self%accepted_singular = .false.
         iterations = 0
         r0 = 0
         previous = 0
         at_floor = 0
         stalled_correction = 0
         ! Newton's tangent leaves out the geometric stiffness where the iterate
         ! is strained less than geometric_strain. At a mechanism configuration
         ! the stresses vanish, so near it the material tangent is the exact
         ! tangent to first order and convergence stays quadratic (Gauss-Newton
         ! on a zero-residual problem), while the geometric stiffness of a
         ! predictor's small spurious strains, which can exceed the bending
         ! stiffness of slender links, no longer bends the path of the
         ! iteration (docs/performance.md has the iteration counts). Far from
         ! it (large strains) the full tangent is the more robust.
         kg_above = merge(0.0_dp, geometric_strain, self%loaded)
         ! Newton; then, if a slave has slid past its master segment, move it on
         ! to the neighbouring segment and iterate again from there; then, if
         ! the iteration stopped on its estimate, check it (see below).
         verification: do
            by_estimate = .false.
            relocations: do pass = 0, size(mesh%slides)*8
               at_predictor = .false.
               do i = 0, self%model%analysis%max_iter
                  ! A signal ends the step here (a slow step would delay the stop).
                  call interrupt_error(error)
                  if (allocated(error)) return
                  call newton_assembly(self, qt, t, kg_above)
                  ! The predictor's guard, once per step: it needs the strains of this first assembly.
                  if (self%guard_pending) then
                     self%guard_pending = .false.
                     if (guard_extrapolation(self, t, qt)) call newton_assembly(self, qt, t, kg_above)
                  end if
                  residual = residual_norm(system, mesh)
                  if (i == 0) then
                     r0 = residual
                     if (self%model%analysis%predictor == predictor_previous) increment_residual = r0
                  end if
                  if (self%conv%mode == convergence_paper) then
                     if (is_converged(self%conv, residual, r0, increment_residual, 0.0_dp)) exit
                  end if
                  if (i == self%model%analysis%max_iter) then
                     write (msg, '(a,es12.5,a,i0,a,es9.2)') 't = ', t, ': Newton did not converge in ', i, &
                        & ' iterations (residual ', residual
                     call analysis_error(error, trim(msg)//')')
                     return
                  end if
                  root_solved = .false.
                  if (self%root_form .and. system%assembled_strain < kg_above) then
                     call root_correction(self, qt, .false., correction, root_solved)
                     ! B_f singular at the iterate: K's Newton step (its tangent was not assembled).
                     if (.not. root_solved) call assemble_system(system, mesh, qt, t, self%seg, kg_above, self%counts)
                  end if
                  if (.not. root_solved) call factor_system(system, info, self%counts)
                  if (root_solved) info = 0
                  if (i == 0 .and. self%detect_change) then
                     ! A change point at the predictor: Newton does not iterate on a
                     ! near-singular tangent (see step_over). The estimate is of the
                     ! factor just made: B_f's (squared) or K's.
                     self%detect_change = .false.
                     rcond = 0
                     if (root_solved) then
                        call strain_rate_rcond(self%root, rcond)
                     else if (info == 0) then
                        call system_rcond(system, rcond, self%counts)
                     end if
                     self%predictor_rcond = rcond
                     self%predictor_regular = change_verdict(rcond, self%state%reference_rcond) == change_regular
                     if (.not. self%predictor_regular) then
                        self%change_found = .true.
                        return
                     end if
                  end if
                  if (.not. root_solved .and. info > 0 .and. kg_above > 0) then
                     ! The material tangent is singular at a stationary configuration;
                     ! the geometric stiffness of the iterate's stresses may still
                     ! carry Newton there (full Newton from here on in this step).
                     kg_above = 0
                     call assemble_system(system, mesh, qt, t, self%seg, kg_above, self%counts)
                     residual = residual_norm(system, mesh)
                     call factor_system(system, info, self%counts)
                  end if
                  if (info > 0) then
                     write (msg, '(a,es12.5,a)') 't = ', t, ': singular tangent stiffness at '
                     call analysis_error(error, trim(msg)//' '//describe_dof(mesh, self%model, eqd(info)))
                     return
                  end if
                  if (.not. root_solved) call newton_correction(system, mesh, self%dof_length, correction, self%counts)
                  if (correction > divergence_length*self%model_length) then
                     write (msg, '(a,es12.5,a,i0)') 't = ', t, ': Newton diverged at iteration ', i + 1
                     call analysis_error(error, trim(msg))
                     return
                  end if
                  ! Converged where this pass starts (the predictor, or an
                  ! iterate that a check below corrected): a first correction
                  ! below predictor_margin times the length tolerance (at
                  ! round-off with the default tolerance) leaves it as it is,
                  ! and the tangent just factored, material only (every Gauss
                  ! point strained less than kg_above), is the tangent at the
                  ! accepted configuration: the branch-jump check and the rates
                  ! need no assembly and factorisation of their own. Not near a
                  ! stationary configuration: the residual there hardly sees an
                  ! error along the near-singular direction (a predictor kept
                  ! past collinear is then rejected by the branch-jump check).
                  if (i == 0 .and. .not. self%loaded .and. self%conv%mode /= convergence_paper .and. &
                     & .not. root_solved) then
                     at_predictor = correction <= predictor_margin*self%conv%length .and. &
                        & system%assembled_strain < kg_above .and. &
                        & is_converged(self%conv, residual, r0, increment_residual, correction)
                     if (at_predictor) then
                        call system_pivot(system, pivot)
                        at_predictor = pivot >= near_singular_drop*self%state%reference_pivot
                     end if
                     if (at_predictor) exit
                  end if
                  call take_correction(self, qt, iterations)
                  if (self%conv%mode /= convergence_paper) then
                     if (is_converged(self%conv, residual, r0, increment_residual, correction)) exit
                     by_estimate = .not. self%loaded
                     if (by_estimate) by_estimate = converged_by_estimate(self%conv, self%model_length, &
                        & self%newton_constant, residual, r0, increment_residual, correction, previous)
                     if (by_estimate) exit
                     ! Round-off: a residual at its floor for stall_iterations
                     ! iterations gives corrections that are noise (the tangent's
                     ! sensitivity times the round-off), so the length test cannot
                     ! be met; the last correction is the accuracy left, reported
                     ! in the listing.
                     if (residual <= self%conv%residual_floor) then
                        at_floor = at_floor + 1
                     else
                        at_floor = 0
                     end if
                     if (at_floor >= stall_iterations) then
                        stalled_correction = correction
                        exit
                     end if
                  end if
                  previous = correction
               end do
               if (size(mesh%slides) == 0) exit relocations
               call relocate(mesh, self%model, t, qt, self%seg, moved, error)
               if (allocated(error)) return
               if (.not. moved) exit relocations
            end do relocations
            if (self%loaded .or. at_predictor) exit verification
            ! The material tangent at the new configuration: the branch-jump
            ! check's response (and from it the predictor's velocity) and, once
            ! accepted, the rates' tangent. The last Newton factor, one correction
            ! away, would give rates off by that correction times the ratio of
            ! axial to bending stiffness (EA L^2 / EI; docs/performance.md).
            call assemble_system(system, mesh, qt, t, self%seg, huge(1.0_dp), self%counts)
            ! The residual reported for the step is the one at the accepted configuration.
            residual = residual_norm(system, mesh)
            if (self%root_form) then
               ! The estimate is checked by one more correction of B_f; then the
               ! factor of the stress-free B_f at qt serves as K's does below.
               root_solved = .false.
               if (by_estimate) call root_correction(self, qt, .true., correction, root_solved)
               if (.not. root_solved .or. correction <= estimate_margin*self%conv%length) then
                  call factor_root(self, qt, self%seg, info)
                  exit verification
               end if
            else
               call factor_system(system, info, self%counts)
               if (.not. by_estimate .or. info /= 0) exit verification
               ! A stop on the estimate is checked with this factor (one back
               ! substitution): the correction it gives must pass the estimate's own
               ! margin, or it is applied as one more Newton iteration and Newton
               ! goes on (with a stiff slideline penalty the estimate can miss).
               call newton_correction(system, mesh, self%dof_length, correction, self%counts)
               if (correction <= estimate_margin*self%conv%length) exit verification
            end if
            call take_correction(self, qt, iterations)
            if (iterations >= self%model%analysis%max_iter) then
               write (msg, '(a,es12.5,a,i0,a,es9.2)') 't = ', t, ': Newton did not converge in ', iterations, &
                  & ' iterations (residual ', residual
               call analysis_error(error, trim(msg)//')')
               return
            end if
            previous = correction
         end do verification
         if (.not. self%loaded) then
            ! The strains of the material tangent's assembly at qt.
            strain = system%assembled_strain
            element = system%assembled_element
            if (strain > self%admissible_strain) then
               write (msg, '(a,es12.5,a,es9.2,a)') 't = ', t, &
                  & ': Newton converged to a self-stressed configuration (strain ', strain, ' in link '
               call analysis_error(error, trim(msg)//' '//self%model%links(mesh%elink(element))%name// &
                  & '), not a mechanism configuration')
               return
            end if
            if (size(mesh%slides) > 0) then
               call check_gaps(mesh, self%model, t, qt, self%seg, self%admissible_strain*self%model_length, error)
               if (allocated(error)) return
            end if
            call branch_jump(self, t, qt, info == 0, error)
            if (allocated(error)) return
            self%factor_current = info == 0
            self%accepted_singular = info /= 0
         end if
         call accept(self, t, qt)
         if (stalled_correction > 0) then
            write (msg, '(a,es12.5,a,es9.2,a,es9.2,a)') 't = ', t, ': Newton stopped at the round-off floor of the '// &
               & 'residual (', residual, '); the last correction, ', stalled_correction, &
               & ', bounds the error of this configuration'
            self%state%note = trim(msg)
         end if
         ! The velocity for the predictor's history comes from the branch-jump
         ! check's response (the same whatever rates the run computes, so
         ! positions do not depend on them).
         if (.not. self%loaded) call record_velocity(self)
      end associate
   end subroutine solve_step

   !> Add the correction in the system's right-hand side to q: one Newton iteration more.
   subroutine take_correction(self, q, iterations)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), contiguous, intent(inout) :: q(:)
      integer, intent(inout) :: iterations
      call apply_correction(self%system, self%mesh, q)
      iterations = iterations + 1
      self%counts%iterations = self%counts%iterations + 1
   end subroutine take_correction

   !> Norm of -K_fd (q_d(t) - q_d) + f(t) - f(t_q) over the free dofs, with
   !> the driven dofs at t taken from the predictor qt (set_driven's values).
   subroutine drive_increment_residual(self, t, qt, norm)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      real(dp), contiguous, intent(in) :: qt(:)
      real(dp), intent(out) :: norm
      associate (dqd => self%drive_step, dd => self%mesh%driven_dof)
         dqd = qt(dd) - self%state%q(dd)
         if (self%loaded) then
            call self%mesh%loads%change(self%state%t, t, self%load_work)
            call drive_load_rhs(self%system, self%mesh, dqd, self%load_work)
         else
            call drive_load_rhs(self%system, self%mesh, dqd)
         end if
      end associate
      norm = sqrt(sum(self%system%rhs(:, 1)**2))
   end subroutine drive_increment_residual

   !> Initial guess at time t: the paper's last configuration, extrapolation
   !> of the last ones (see extrapolate_history), or a Taylor series from the
   !> last rates. Without history (the first step) extrapolation and Taylor
   !> start from the tangent predictor, the linear response of the last
   !> configuration to the drive increment: rotating a driven link end alone
   !> would strain its element so much that Newton may leave the assembly branch.
   subroutine predict(self, t, qt)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      real(dp), contiguous, intent(inout) :: qt(:)
      integer :: i, made
      self%smooth_prediction = .false.
      self%guard_pending = .false.
      associate (state => self%state)
         select case (self%model%analysis%predictor)
         case (predictor_previous)
            qt = state%q
         case (predictor_taylor)
            if (state%has_acceleration) then
               call taylor_predict(state%q, state%v, state%a, t - state%t, qt)
            else
               call extrapolate_history(state%history, t, .false., self%conv%length, self%dof_length, qt, made)
               if (made == prediction_none) call tangent_predictor(self, t, qt)
            end if
         case default
            call extrapolate_history(state%history, t, .true., self%conv%length, self%dof_length, qt, made)
            self%smooth_prediction = made == prediction_smooth
            self%guard_pending = made /= prediction_none
            if (made == prediction_none) call tangent_predictor(self, t, qt)
         end select
      end associate
      do i = 1, self%mesh%ndof
         if (self%mesh%status(i) == dof_fixed) qt(i) = self%mesh%q0(i)
      end do
      call set_driven(self, t, qt)
      self%q_predicted = qt
   end subroutine predict

   !> Extrapolating positions over a large rotation (a quarter turn per step)
   !> distorts the links badly, and Newton from there may find another
   !> assembly branch. Keep the extrapolation qt (just assembled, so its
   !> strain is known) only if it strains the elements less than the last
   !> configuration with the new drive values does; else replace it by that
   !> (and return true).
   logical function guard_extrapolation(self, t, qt) result(replaced)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      real(dp), contiguous, intent(inout) :: qt(:)
      real(dp) :: strain_previous
      integer :: element
      replaced = .false.
      if (self%system%assembled_strain < 1.0e-2_dp) return
      self%work = self%state%q
      call set_driven(self, t, self%work)
      call max_strain(self%mesh, self%work, strain_previous, element)
      if (strain_previous < self%system%assembled_strain) then
         qt = self%work
         self%q_predicted = qt
         self%smooth_prediction = .false.
         replaced = .true.
      end if
   end function guard_extrapolation

   !> qt = q + dq with K_ff dq_f = -K_fd dq_d + f(t) - f(t_q): the tangent at
   !> the accepted configuration applied to the drive and load increments.
   subroutine tangent_predictor(self, t, qt)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      real(dp), contiguous, intent(inout) :: qt(:)
      integer :: info
      qt = self%state%q
      call set_driven(self, t, qt)
      if (self%root_form) then
         ! The drive response from B_f (if the configuration is not singular).
         if (.not. self%state%has_jump_response) return
         associate (dd => self%mesh%driven_dof)
            call apply_response(self%state%jump_response, qt(dd) - self%state%q(dd), self%work)
         end associate
         qt = self%state%q + self%work
         return
      end if
      ! At a singular configuration there is no tangent response: start from the last configuration.
      call refactor_at_accepted(self, info)
      if (info > 0) return
      associate (eqd => self%mesh%eq_dof, dd => self%mesh%driven_dof, rhs => self%system%rhs)
         rhs(:, 1) = -matmul(self%system%kfd, qt(dd) - self%state%q(dd))
         if (self%loaded) then
            call self%mesh%loads%change(self%state%t, t, self%load_work)
            rhs(:, 1) = rhs(:, 1) + self%load_work(eqd)
         end if
         call self%system%kff%solve(rhs)
         qt(eqd) = qt(eqd) + rhs(:, 1)
      end associate
   end subroutine tangent_predictor

   !> Make the system hold the factor of the tangent at the accepted
   !> configuration, unless it does already; info > 0 names the equation where
   !> it is singular. For a kinematic analysis this is the material tangent
   !> (46): the last Newton iterate's tangent will not do, because its
   !> residual stresses make a geometric stiffness comparable to the bending
   !> stiffness EI/L^3 of slender links, which spoils accelerations. A loaded
   !> model is stressed by design and uses the full tangent.
   subroutine refactor_at_accepted(self, info)
      type(fem_stepper_type), intent(inout) :: self
      integer, intent(out) :: info
      info = 0
      if (self%factor_current) return
      call assemble_system(self%system, self%mesh, self%state%q, self%state%t, self%seg, &
         & merge(0.0_dp, huge(1.0_dp), self%loaded), self%counts)
      if (self%root_form) then
         call factor_root(self, self%state%q, self%state%seg, info)
      else
         call factor_system(self%system, info, self%counts)
      end if
      self%factor_current = info == 0
      self%accepted_singular = info /= 0
   end subroutine refactor_at_accepted

   !> The assembly of a Newton iteration at qt: the residual and the tangent
   !> (K form), or the residual, B and the strains (square-root form), with
   !> the largest element strain in the system either way. The square-root
   !> form's correction is Newton's with the material tangent (K = B^T W B,
   !> B_f square), which is the K form's below kg_above; an iterate strained
   !> more takes the K form's full Newton step, as before (its path, e.g.
   !> from a poor predictor, stays the one the branch check was built on),
   !> and K is assembled too.
   subroutine newton_assembly(self, qt, t, kg_above)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), contiguous, intent(in) :: qt(:)
      real(dp), intent(in) :: t, kg_above
      if (.not. self%root_form) then
         call assemble_system(self%system, self%mesh, qt, t, self%seg, kg_above, self%counts)
         return
      end if
      call assemble_system_residual(self%system, self%mesh, qt, t, self%seg, self%counts)
      call assemble_strain_rate(self%root, self%mesh, qt, self%seg, .false., self%root_work, &
         & self%system%assembled_strain, self%system%assembled_element)
      if (self%system%assembled_strain >= kg_above) then
         call assemble_system(self%system, self%mesh, qt, t, self%seg, kg_above, self%counts)
      end if
   end subroutine newton_assembly

   !> The Newton correction of the square-root form at qt: B_f dq = -eps with
   !> B the exact gradient of the strains and gaps eps at qt (assembled here,
   !> or by newton_assembly with eps in root_work), into the system's
   !> right-hand side (as newton_correction), and its length; solved =
   !> .false. if B_f is singular there (the caller uses K).
   subroutine root_correction(self, qt, assemble, correction, solved)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), contiguous, intent(in) :: qt(:)
      logical, intent(in) :: assemble
      real(dp), intent(out) :: correction
      logical, intent(out) :: solved
      integer :: info, k
      correction = 0
      if (assemble) call assemble_strain_rate(self%root, self%mesh, qt, self%seg, .false., self%root_work)
      call factor_strain_rate(self%root, info)
      solved = info == 0
      if (.not. solved) return
      self%root_work = -self%root_work
      call solve_strain_rate(self%root, self%root_work)
      self%system%rhs(:, 1) = self%root_work
      do k = 1, self%mesh%nfree
         correction = max(correction, abs(self%root_work(k))*self%dof_length(self%mesh%eq_dof(k)))
      end do
   end subroutine root_correction

   !> Assemble and factor the stress-free B at q (slidelines on seg): the
   !> square-root form's factor at a configuration; info > 0 if B_f is singular there.
   subroutine factor_root(self, q, seg, info)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), contiguous, intent(in) :: q(:)
      integer, intent(in) :: seg(:)
      integer, intent(out) :: info
      call assemble_strain_rate(self%root, self%mesh, q, seg, .true.)
      call factor_strain_rate(self%root, info)
   end subroutine factor_root

   !> The pivot ratio of the factor at the accepted configuration (B_f's on
   !> K's scale in the square-root form, else K's).
   real(dp) function accepted_pivot(self) result(ratio)
      type(fem_stepper_type), intent(inout) :: self
      if (self%root_form) then
         ratio = self%root%pivot_ratio
      else
         call system_pivot(self%system, ratio)
      end if
   end function accepted_pivot

   !> The condition estimate of the factor at the accepted configuration, on
   !> K's scale: B_f's squared in the square-root form, else K's.
   subroutine accepted_rcond(self, rcond)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), intent(out) :: rcond
      if (self%root_form) then
         call strain_rate_rcond(self%root, rcond)
      else
         call system_rcond(self%system, rcond, self%counts)
      end if
   end subroutine accepted_rcond

   !> The drive response at the accepted configuration, whose factor the
   !> system (or root) holds: from B_f in the square-root form, else from K_ff.
   subroutine accepted_response(self, resp)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), contiguous, intent(inout) :: resp(:, :)
      if (self%root_form) then
         call root_drive_response(self%root, self%mesh, resp, self%root_work)
      else
         call drive_response(self%system, self%mesh, resp, self%counts)
      end if
   end subroutine accepted_response

   !> The branch check of the step to qt (see fekap_solver_branch), with the
   !> drive responses at its two ends: at the new configuration from the
   !> factor of its material tangent (one back substitution per drive; the
   !> same factor then serves the rates), at the last one kept from the last
   !> step. A suspect step is accepted with its state before saved for
   !> verify_step.
   subroutine branch_jump(self, t, qt, factored, error)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      real(dp), contiguous, intent(in) :: qt(:)
      !> Whether the system holds the factor of the material tangent at qt.
      logical, intent(in) :: factored
      type(error_type), allocatable, intent(out) :: error
      real(dp), allocatable :: swap(:, :)
      real(dp) :: step_floor, turn, pivot, rcond
      integer :: verdict, crossing(3)
      logical :: has_response
      associate (state => self%state, resp => self%jump_response_new)
         call drive_increment(self%branch, self%mesh, state%q, qt, self%drive_step, step_floor)
         ! Response at the new configuration, unless its tangent is near singular
         ! (against the run's best condition: at a change point the response is
         ! arbitrary in size and sign, and would reject the step after it).
         pivot = 0
         rcond = 0
         if (factored) then
            pivot = accepted_pivot(self)
            if (self%predictor_regular) then
               rcond = self%predictor_rcond
            else
               call accepted_rcond(self, rcond)
            end if
         end if
         has_response = factored .and. pivot >= singular_floor .and. response_trusted(rcond, state%reference_rcond)
         if (has_response) then
            if (self%root_form) then
               call root_drive_response(self%root, self%mesh, resp, self%root_work)
            else
               call drive_response(self%system, self%mesh, resp, self%counts)
            end if
         else
            resp = 0
         end if
         call note_response_pivot(self, merge(pivot, 0.0_dp, has_response))
         call apply_response(resp, self%drive_step, self%dq_new)
         if (state%has_jump_response) then
            call apply_response(state%jump_response, self%drive_step, self%dq_old)
         else
            self%dq_old = 0
         end if
         call branch_verdict(self%branch, self%mesh, self%model, t, state%q, qt, self%dq_old, self%dq_new, &
            & step_floor, self%smooth_prediction, self%q_predicted, self%verify_depth < max_verify_depth, verdict, &
            & error, crossing, turn)
         select case (verdict)
         case (branch_reject)
            return
         case (branch_unverifiable)
            self%verify_failed = .true.
            return
         case (branch_verify)
            associate (pending => self%verification(self%verify_depth))
               pending%before = state
               pending%crossing = crossing
               pending%turn = turn
            end associate
            self%verify_pending = .true.
         case default
            ! branch_accept: the step stands.
         end select
         state%has_jump_response = has_response
         state%reference_rcond = max(state%reference_rcond, rcond)
      end associate
      ! The new response becomes the accepted one (a swap of the two arrays, no copy).
      call move_alloc(self%state%jump_response, swap)
      call move_alloc(self%jump_response_new, self%state%jump_response)
      call move_alloc(swap, self%jump_response_new)
   end subroutine branch_jump

   !> Step-doubling verification of a step to time t that the branch check
   !> found suspect (a hinged pair crossed collinear turning by more than
   !> verify_turn): the step is accepted, the state before it is in
   !> self%verify(depth). The same interval is solved again from that state as
   !> two half steps (advance_to one level deeper: cut if they fail, verified
   !> if suspect) and the results are compared. The state after the half
   !> steps stays: on agreement it is the same configuration to the tolerance;
   !> otherwise the step was a jump and `rejection` says so. If the half steps
   !> cannot be solved, the state before the step is restored and the step is
   !> rejected (error). A jump over a near-toggle turns the pair that flips by
   !> its distances from collinear at both ends, so it stays suspect however
   !> often it is halved, while a real crossing turns less with every halving.
   recursive subroutine verify_step(self, t, depth, iterations, residual, rejection, error)
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
      type(error_type), allocatable, intent(out) :: error
      type(error_type), allocatable :: half_error
      type(step_cuts_type) :: half_cuts
      character(:), allocatable :: pair
      real(dp), allocatable :: q_whole(:)
      real(dp) :: t_end(2), distance, d
      integer :: i, half, it, worst_dof
      character(len=200) :: msg
      q_whole = self%state%q
      call restore_state(self, self%verification(depth)%before)
      associate (c => self%verification(depth)%crossing)
         pair = 'links '//self%model%links(c(1))%name//' and '//self%model%links(c(2))%name//' at node '// &
            & self%model%nodes(c(3))%name
      end associate
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
         call restore_state(self, self%verification(depth)%before)
         self%verify_failed = .true.
         if (depth > 0) then
            call move_alloc(half_error, error)
         else
            write (msg, '(a,es12.5,a,f7.4,a)') 't = ', t, ': possible assembly-mode jump rejected ('//pair// &
               & ' crossed collinear turning ', self%verification(depth)%turn, &
               & ' rad; two half steps could not confirm it: '
            call analysis_error(error, trim(msg)//' '//half_error%message//')')
         end if
         return
      end if
      ! Distance in model sizes (rotations times the model size).
      distance = 0
      worst_dof = 1
      do i = 1, self%mesh%ndof
         d = abs(q_whole(i) - self%state%q(i))*self%dof_length(i)/self%model_length
         if (d > distance) then
            distance = d
            worst_dof = i
         end if
      end do
      if (distance > max(verify_agreement, self%admissible_strain)) then
         write (msg, '(a,es12.5,a,es9.2,a)') 't = ', t, ': assembly-mode jump rejected (the step ends ', distance, &
            & ' model sizes from where two half steps end, at'
         rejection = trim(msg)//' '//describe_dof(self%mesh, self%model, worst_dof)//'; '//pair// &
            & ' crossed collinear); the half steps replace it'
      end if
   end subroutine verify_step

   !> Make `before` the accepted state again; the tangent (and its free-driven
   !> block, which scales the convergence test) is refactored there.
   subroutine restore_state(self, before)
      type(fem_stepper_type), intent(inout) :: self
      type(fem_state_type), intent(in) :: before
      integer :: info
      self%state = before
      self%seg = before%seg
      self%factor_current = .false.
      call refactor_at_accepted(self, info)
   end subroutine restore_state

   !> Record the pivot ratio of the factor behind a drive response (0 if
   !> none) in the run's reference: the predictor trusts a response as a
   !> velocity only away from stationary configurations.
   subroutine note_response_pivot(self, ratio)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: ratio
      self%response_pivot = ratio
      self%state%reference_pivot = max(self%state%reference_pivot, ratio)
   end subroutine note_response_pivot

   !> The velocity of the newest configuration of the predictor's history:
   !> the drive response times the drive rates, when the response is known
   !> and not near a stationary configuration.
   subroutine record_velocity(self)
      type(fem_stepper_type), intent(inout) :: self
      associate (state => self%state, history => self%state%history)
         history%has_velocity(history%newest) = state%has_jump_response .and. &
            & self%response_pivot >= near_singular_drop*state%reference_pivot
         if (.not. history%has_velocity(history%newest)) return
         call self%model%drives%law%eval(state%t, self%law_value, self%law_rate, self%law_rate2)
         call apply_response(state%jump_response, self%law_rate, history%velocity(:, history%newest))
      end associate
   end subroutine record_velocity

   !> Velocities and accelerations of the accepted configuration, as asked
   !> for (see fekap_solver_rates), with the tangent there (the material
   !> tangent, since the geometric part vanishes with the stresses), and the
   !> note on how close to singular it is.
   subroutine solve_rates(self)
      type(fem_stepper_type), intent(inout) :: self
      real(dp) :: ratio
      integer :: info
      logical :: regular
      ! The pivot ratio of the tangent at the configuration: a stationary one is
      ! noted also when only positions are computed (the tangent is factored
      ! for the branch-jump check anyway, so at no cost).
      if (self%model%analysis%velocities) call refactor_at_accepted(self, info)
      if (self%accepted_singular) then
         ratio = 0
      else if (self%factor_current) then
         ratio = accepted_pivot(self)
      else
         return
      end if
      associate (state => self%state, history => self%state%history)
         self%counts%min_pivot_ratio = min(self%counts%min_pivot_ratio, ratio)
         state%reference_pivot = max(state%reference_pivot, ratio)
         call pivot_note(state%t, ratio, state%reference_pivot, self%model%analysis%velocities, state%note, regular)
         if (.not. regular .or. .not. self%model%analysis%velocities) return
         call self%model%drives%law%eval(state%t, self%law_value, self%law_rate, self%law_rate2)
         if (self%root_form) then
            ! The square-root form, refined (see fekap_solver_rates).
            call root_velocities(self%root, self%mesh, self%law_rate, state%v, self%root_work)
            self%counts%velocity_solves = self%counts%velocity_solves + 1
            state%has_velocity = .true.
            if (.not. self%model%analysis%accelerations) return
            call root_accelerations(self%root, self%mesh, state%v, self%law_rate2, state%a, self%root_work)
            self%counts%acceleration_solves = self%counts%acceleration_solves + 1
            state%has_acceleration = .true.
            return
         end if
         if (history%has_velocity(history%newest)) then
            ! (47) is R vd with the drive response R of this factor: record_velocity
            ! made it already, for the predictor.
            state%v = history%velocity(:, history%newest)
         else if (state%has_jump_response .and. .not. self%loaded) then
            call apply_response(state%jump_response, self%law_rate, state%v)
         else
            if (self%loaded) then
               call self%mesh%loads%rate(state%t, 1, self%load_work)
               call solve_velocities(self%system, self%mesh, self%law_rate, state%v, self%counts, self%load_work)
            else
               call solve_velocities(self%system, self%mesh, self%law_rate, state%v, self%counts)
            end if
         end if
         self%counts%velocity_solves = self%counts%velocity_solves + 1
         state%has_velocity = .true.
         if (.not. self%model%analysis%accelerations) return
         ! The system holds the factor of the tangent at q (factor_current), so
         ! its last tangent assembly, whose section angles it keeps, was at q.
         if (self%loaded .and. size(self%mesh%loads%f, 2) > 1) then
            ! Loads with laws of their own have second rates (the load factor t has none).
            call self%mesh%loads%rate(state%t, 2, self%load_work)
            call solve_accelerations(self%system, self%mesh, state%q, state%v, self%seg, self%law_rate2, state%a, &
               & self%work, self%counts, self%load_work)
         else
            call solve_accelerations(self%system, self%mesh, state%q, state%v, self%seg, self%law_rate2, state%a, &
               & self%work, self%counts)
         end if
         self%counts%acceleration_solves = self%counts%acceleration_solves + 1
         state%has_acceleration = .true.
      end associate
   end subroutine solve_rates

   !> Make q at time t the accepted configuration and push it on the history.
   subroutine accept(self, t, q)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      real(dp), contiguous, intent(in) :: q(:)
      associate (state => self%state)
         call state%history%push(q, t)
         state%q = q
         state%t = t
         state%seg = self%seg
         if (has_note(state%note)) state%note = ''
         state%has_velocity = .false.
         state%has_acceleration = .false.
      end associate
      self%counts%steps = self%counts%steps + 1
   end subroutine accept

   !> The result of the accepted state: nodes and links, and the mesh's
   !> fields when VTK output is asked for.
   subroutine fill_result(self, result)
      type(fem_stepper_type), intent(in) :: self
      type(step_result_type), intent(inout) :: result
      associate (state => self%state)
         result%t = state%t
         if (has_note(state%note) .or. has_note(result%note)) result%note = state%note
         result%has_velocity = state%has_velocity
         result%has_acceleration = state%has_acceleration
         call fill_nodes_links(self%mesh, self%model, state%q, state%v, state%a, result)
         if (self%model%output%vtk) call fill_fields(self%mesh, state%q, state%v, state%a, result)
      end associate
   end subroutine fill_result

end module fekap_solver_fem
