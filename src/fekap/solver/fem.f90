!> The paper's finite element method as a stepper: per step, advance the
!> drives, predict, solve P(q) = 0 on the free dofs by Newton-Raphson with the
!> symmetric band tangent, check that the converged configuration is a
!> mechanism configuration (every element unstrained), then solve for
!> velocities (47) and accelerations (49) with the tangent of the converged
!> configuration. A step that fails is cut in halves (bounded) and retried.
module fekap_solver_fem
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, analysis_error
   use fekap_model, only: model_type, model_size, dof_rot, predictor_previous, predictor_taylor, &
      & convergence_paper
   use fekap_model_results, only: step_result_type, note_length, has_note
   use fekap_assembly_mesh, only: mesh_type, new_mesh, describe_dof, dof_fixed
   use fekap_assembly_band, only: band_matrix_type, new_band_matrix
   use fekap_element_beam, only: beam_resultants, max_gauss
   use fekap_assembly_assemble, only: assemble_residual, assemble_tangent, assemble_second_derivative, &
      & max_strain, slide_position
   use fekap_contact_slideline, only: slide_geometry, slide_locate, slide_on_element, slide_off_end
   use fekap_solver_stepper, only: stepper_type, clock_seconds, phase_timed
   use fekap_solver_convergence, only: convergence_type, is_converged, extrapolate, hermite_extrapolate, &
      & adams_weights
   implicit none
   private

   public :: fem_stepper_type, new_fem_stepper

   !> Step cuts (halvings) allowed within one step before it is given up.
   integer, parameter :: max_cuts = 8
   !> Element strain above which a converged configuration is not a mechanism
   !> configuration but a self-stressed equilibrium.
   !> It follows the Newton tolerance (a loose paper-style test leaves strains
   !> near the tolerance) but never reaches the strains of a self-stressed
   !> state, which are of order 0.1.
   real(dp), parameter :: min_admissible_strain = 1.0e-8_dp, max_admissible_strain = 1.0e-3_dp
   !> A Newton correction longer than this many model sizes is divergence.
   real(dp), parameter :: divergence_length = 1.0e3_dp
   !> Pivot ratios (see band_pivot_ratio) below which the tangent at a
   !> configuration counts as singular or as near-singular (a warning),
   !> relative to the largest ratio met so far in the run: the ratio itself also
   !> reflects the elements' bending-to-shear stiffness (4 EI / (kGA L^2): 2e-7
   !> for the 474-long lever of Example 5, 1e-12 at EA/EI = 1e12), so only its
   !> drop means a stationary configuration. Below singular_floor the factor is
   !> singular to round-off whatever the reference.
   real(dp), parameter :: singular_drop = 1.0e-10_dp, near_singular_drop = 1.0e-3_dp, &
      & singular_floor = 1.0e-16_dp
   !> Newton's tangent leaves out the geometric stiffness at Gauss points
   !> strained less than this (see solve_step).
   real(dp), parameter :: geometric_strain = 3.0e-3_dp
   !> Contraction of the last Newton correction against the one before, and the
   !> least quadratic-convergence constant times the model size, for the
   !> estimated stop (converged_by_estimate).
   real(dp), parameter :: estimate_contraction = 0.1_dp, least_quadratic_constant = 10.0_dp
   !> The estimated stop asks the next correction to be this share of the length
   !> tolerance (what a verifying iteration would have left).
   real(dp), parameter :: estimate_margin = 0.1_dp
   !> Iterations in a row with the residual below its floor after which
   !> Newton has stalled at round-off.
   integer, parameter :: stall_iterations = 3
   !> Configurations kept for the extrapolating predictor (see predict):
   !> Hermite extrapolation through up to hermite_points positions and
   !> velocities (degree 7, error of order h**8), Adams-Bashforth through the
   !> newest position and `history` velocities, or Lagrange extrapolation
   !> through up to lagrange_points positions (quadratic) where velocities are
   !> not known. On Example 1 at dt = 0.025 the Hermite degree took Newton
   !> from 85 iterations (degree 5) to 66 (degree 7); 63 at degree 9, 60 at 11.
   integer, parameter :: history = 5, hermite_points = 4, lagrange_points = 3
   !> The Adams-Bashforth predictor is taken when its error, estimated by
   !> the difference between its predictions through the newest history - 1
   !> and history velocities, is at most predictor_margin times the length
   !> tolerance; a step whose first Newton correction is that small is
   !> accepted at its predictor (see solve_step).
   real(dp), parameter :: predictor_margin = 1.0e-3_dp
   !> Assembly-mode (branch) jump check: a step is rejected when some rotation
   !> over the step exceeds this many times what the rates at either end of
   !> the step, or the drive increment, can explain (see branch_jump).
   real(dp), parameter :: jump_ratio = 2.0_dp
   !> Relative angles within this many pi of a multiple of pi at either end
   !> of a step do not count as crossing it (links that start or end collinear).
   real(dp), parameter :: hinge_margin = 1.0e-9_dp
   !> Least share of a collinear crossing that the response at the new
   !> configuration must explain in the crossing sense.
   real(dp), parameter :: hinge_response = 1.0e-3_dp
   !> Step-doubling verification (see verify_step): a step in which a hinged
   !> pair crosses collinear turning by more than verify_turn radians is solved
   !> again as two half steps (themselves verified, at most max_verify_depth
   !> halvings deep) and rejected when the results differ by more than
   !> verify_agreement model sizes (or the admissible strain, if larger).
   real(dp), parameter :: verify_turn = 0.1_dp, verify_agreement = 1.0e-6_dp
   !> A crossing step needs no verification when Newton moved every rotation
   !> less than this share of the crossing turn away from the Hermite predictor.
   real(dp), parameter :: verify_predicted = 1.0e-3_dp
   integer, parameter :: max_verify_depth = 10

   !> The accepted state of a stepper that a step changes: what step-doubling
   !> verification restores to solve the same step again in two halves.
   type :: saved_state_type
      real(dp), allocatable :: q(:), v(:), a(:), hist(:, :), thist(:), hist_velocity(:, :), jump_response(:, :)
      integer, allocatable :: seg_accepted(:)
      logical, allocatable :: has_hist_velocity(:)
      real(dp) :: t = 0, reference_pivot = 0
      integer :: nhist = 0, newest = history
      logical :: has_velocity = .false., has_acceleration = .false., has_jump_response = .false.
      character(len=note_length) :: note = ''
      !> The step that follows: the hinged pair that crossed collinear
      !> (link, link, node) and its largest turn, for the messages.
      integer :: crossing(3) = 0
      real(dp) :: turn = 0
   end type saved_state_type

   type, extends(stepper_type) :: fem_stepper_type
      type(model_type) :: model
      type(mesh_type) :: mesh
      type(convergence_type) :: conv
      type(band_matrix_type) :: kff
      !> Free-driven block of the tangent, (nfree, ndriven).
      real(dp), allocatable :: kfd(:, :)
      !> Accepted configuration, velocity and acceleration over all dofs, at time t.
      real(dp), allocatable :: q(:), v(:), a(:)
      real(dp) :: t = 0
      !> Whether v (and a) belong to the accepted configuration.
      logical :: has_velocity = .false., has_acceleration = .false.
      !> Whether kff holds the factor of the tangent at (within tolerance of) q,
      !> and whether factoring the tangent at q failed (a singular configuration).
      logical :: factor_current = .false., accepted_singular = .false.
      !> Quadratic-convergence constant M of Newton (c(k+1) = M c(k)**2) measured
      !> in the last step that showed it, for the estimated stop.
      real(dp) :: newton_constant = 0
      !> Last accepted configurations and their times, for the predictor: a
      !> ring of `history` columns, the newest in column `newest`, the k-th
      !> newest in history_column(self, k); nhist of them filled.
      real(dp), allocatable :: hist(:, :), thist(:)
      integer :: nhist = 0, newest = history
      !> Their velocities, from the linear response to the drives that the
      !> branch-jump check computes whatever rates the run asks for (so that
      !> positions do not depend on them), and whether they are known.
      real(dp), allocatable :: hist_velocity(:, :)
      logical, allocatable :: has_hist_velocity(:)
      !> The last predictor, and whether it was the Hermite or Adams
      !> extrapolation of the history (a smooth continuation of the last
      !> configurations and their velocities).
      real(dp), allocatable :: q_predicted(:)
      logical :: smooth_prediction = .false.
      !> Pivot ratio of the factor behind the last drive response.
      real(dp) :: response_pivot = 0
      !> Drive laws' values at the start time: drives move from the initial configuration.
      real(dp), allocatable :: law0(:)
      !> Length weight of each dof for the correction test: 1 for translations,
      !> the model size for rotations.
      real(dp), allocatable :: dof_length(:)
      real(dp) :: size = 1
      !> Whether the model has external loads (a flexible, stressed analysis).
      logical :: loaded = .false.
      !> Work arrays, allocated once (nothing is allocated in the step loop):
      !> over the dofs, and (ndriven, 4) over the drives (the laws' values,
      !> rates and second rates at a time, and an increment).
      real(dp), allocatable :: r(:), rhs(:, :), qt(:), work(:), drive_work(:, :)
      !> Step cuts in the last advance, for the listing.
      integer :: last_cuts = 0
      !> Element strain (and gap per model size) above which a converged
      !> configuration is rejected: min(1e-3, max(1e-8, 100 tol)).
      real(dp) :: admissible_strain = min_admissible_strain
      !> Largest pivot ratio of a tangent at an accepted configuration so far
      !> (the reference for singular and near-singular configurations).
      real(dp) :: reference_pivot = 0
      !> Remark on the accepted configuration for the listing (empty if none).
      character(len=note_length) :: note = ''
      !> Master segment of each slideline: during the step, and at the accepted configuration.
      integer, allocatable :: seg(:), seg_accepted(:)
      !> Linear response of every dof to unit changes of the drives, (ndof,
      !> ndriven), at the accepted configuration (kept by the branch-jump
      !> check, whatever rates the run computes) and at the new one; and
      !> whether the first is known.
      real(dp), allocatable :: jump_response(:, :), jump_response_new(:, :)
      logical :: has_jump_response = .false.
      !> Length of the shortest link, the unit of translation drives in the jump check.
      real(dp) :: shortest_link = 1
      !> (4, npairs): link ends hinged to each other (link, end, link, end), for the
      !> jump check's collinear crossings.
      integer, allocatable :: hinge_pairs(:, :)
      !> Whether the step just accepted awaits step-doubling verification, and
      !> the number of halvings of the step being solved (0: a step of the caller's).
      logical :: verify_pending = .false.
      integer :: verify_depth = 0
      !> Whether a verification could not be completed (see advance_to).
      logical :: verify_failed = .false.
      !> The accepted state before the step at each verification depth.
      type(saved_state_type) :: before(0:max_verify_depth)
      !> Pivot ratio of the factor in kff, once computed (see factor_pivot).
      real(dp) :: pivot = 0
      logical :: pivot_known = .false.
      !> The largest element strain at the configuration of the last tangent
      !> assembly, and its element.
      real(dp) :: assembled_strain = 0
      integer :: assembled_element = 0
      !> (2, max_gauss, nelem): cos and sin of the elements' section angles at
      !> the configuration of the last tangent assembly, which is the accepted
      !> one whenever kff holds its factor (factor_current): the second
      !> derivative of the rates reuses them.
      real(dp), allocatable :: section(:, :, :)
      !> Whether the predictor extrapolated: guard_extrapolation then checks it
      !> with the strains of the step's first assembly.
      logical :: guard_pending = .false.
      !> Steps advanced so far, and whether the phases of this one are timed.
      integer :: advances = 0
      logical :: timing = .true.
   contains
      procedure :: start => fem_start
      procedure :: advance => fem_advance
      procedure :: plan_text => fem_plan_text
   end type fem_stepper_type

contains

   !> Build the mesh, the equation numbering and all storage for a validated model.
   subroutine new_fem_stepper(self, model)
      use fekap_model, only: solver_dense
      type(fem_stepper_type), intent(out) :: self
      type(model_type), intent(in) :: model
      integer :: i, e
      real(dp) :: f, df, ddf, force_scale, shortest
      self%model = model
      call new_mesh(self%mesh, model)
      associate (n => self%mesh%ndof, nf => self%mesh%nfree, nd => self%mesh%ndriven)
         call new_band_matrix(self%kff, nf, self%mesh%kd, dense=model%analysis%solver == solver_dense, &
            & top=self%mesh%envelope)
         allocate (self%kfd(nf, nd), self%rhs(nf, 1), self%law0(nd), self%drive_work(nd, 4))
         allocate (self%q(n), self%v(n), self%a(n), self%r(n), self%qt(n), self%work(n), source=0.0_dp)
         allocate (self%hist(n, history), self%thist(history), self%hist_velocity(n, history), source=0.0_dp)
         allocate (self%has_hist_velocity(history), source=.false.)
         allocate (self%q_predicted(n), source=0.0_dp)
         allocate (self%jump_response(n, nd), self%jump_response_new(n, nd), source=0.0_dp)
         allocate (self%section(2, max_gauss, size(self%mesh%elements)), source=0.0_dp)
      end associate
      do i = 1, self%mesh%ndriven
         call model%drives(i)%law%eval(model%analysis%t_start, f, df, ddf)
         self%law0(i) = f
      end do
      allocate (self%seg(size(self%mesh%slides)), self%seg_accepted(size(self%mesh%slides)), source=1)
      self%size = model_size(model)
      self%dof_length = merge(self%size, 1.0_dp, self%mesh%dof_kind == dof_rot)
      self%loaded = any(abs(self%mesh%f_ext) > 0)
      self%conv%mode = model%analysis%convergence
      self%conv%tol = model%analysis%tol
      self%conv%length = model%analysis%length_tol*self%size
      self%admissible_strain = min(max_admissible_strain, max(min_admissible_strain, 100*model%analysis%tol))
      self%shortest_link = huge(1.0_dp)
      do i = 1, size(model%links)
         self%shortest_link = min(self%shortest_link, norm2(model%nodes(model%links(i)%node(2))%x - &
            & model%nodes(model%links(i)%node(1))%x))
      end do
      call find_hinge_pairs(self)
      ! Residual floor: a strain of 1e-13 in the stiffest element, or the
      ! round-off of a strain computed from coordinates of the model's size
      ! (eps size / L: 4e-12 in the 10,000-cell scissor lift) if larger.
      ! The Euclidean norm of round-off grows like the square root of the
      ! number of unknowns.
      force_scale = 0
      shortest = huge(1.0_dp)
      do e = 1, size(self%mesh%elements)
         associate (el => self%mesh%elements(e))
            force_scale = max(force_scale, el%c(1), el%c(2), el%c(3)/el%length**2)
            shortest = min(shortest, el%length)
         end associate
      end do
      self%conv%floor = max(1.0e-13_dp, epsilon(1.0_dp)*self%size/shortest)*force_scale* &
         & sqrt(real(max(1, self%mesh%nfree), dp))
   end subroutine new_fem_stepper

   !> The mesh for the listing's plan: its size, band and slideline penalties.
   function fem_plan_text(self) result(text)
      class(fem_stepper_type), intent(in) :: self
      character(:), allocatable :: text
      character(len=160) :: line
      integer :: i
      write (line, '(a,i0,a,i0,a,i0,a,i0,a,i0)') 'mesh: ', size(self%mesh%elements), ' elements, ', &
         & self%mesh%ndof, ' dofs, ', self%mesh%nfree, ' equations, ', self%mesh%ndriven, &
         & ' driven; half-bandwidth ', self%mesh%kd
      text = trim(line)
      do i = 1, size(self%mesh%slides)
         write (line, '(a,es12.5,a,es12.5)') 'slideline '//self%model%slidelines(i)%name//': penalty ', &
            & self%mesh%slides(i)%kp, ', rotational tie ', self%mesh%slides(i)%kr
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
      real(dp) :: clock, pivot
      clock = clock_seconds()
      self%timing = .true.
      self%t = self%model%analysis%t_start
      self%q = self%mesh%q0
      call initial_segments(self, error)
      if (allocated(error)) return
      self%nhist = 0
      self%factor_current = .false.
      self%has_jump_response = .false.
      result%iterations = 0
      call assemble_force(self, self%q, self%t)
      result%residual = residual_norm(self)
      if (self%loaded .and. result%residual > self%conv%floor) then
         ! Loads at t_start /= 0: find the loaded configuration first.
         call solve_step(self, self%t, result%iterations, result%residual, error)
         if (allocated(error)) return
      else
         call accept(self, self%t, self%q)
      end if
      if (.not. self%loaded) then
         ! The response at the start: the branch-jump check's reference and the
         ! first velocity of the predictor's history.
         call refactor_at_accepted(self, info)
         self%has_jump_response = info == 0
         if (info == 0) then
            call factor_pivot(self, pivot)
            call note_response_pivot(self, pivot)
            call drive_response(self, self%jump_response)
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
      character(len=200) :: note
      character(:), allocatable :: cut_reason, last_reason
      real(dp) :: clock
      self%advances = self%advances + 1
      ! The phases are timed on a sample of the steps (and at the start); the
      ! summary scales them to the run (see phase_seconds).
      self%timing = phase_timed(self%advances)
      if (self%timing) clock = clock_seconds()
      call advance_to(self, t, 0, result%iterations, result%residual, self%last_cuts, cut_reason, last_reason, error)
      if (allocated(error)) return
      result%cuts = self%last_cuts
      call solve_rates(self)
      if (allocated(cut_reason)) then
         ! The listing says why the step was cut (the first and the last rejection).
         write (note, '(a,i0,a)') 'step cut ', self%last_cuts, ' time(s); first rejection:'
         if (allocated(last_reason)) cut_reason = cut_reason//'; last rejection: '//last_reason
         if (has_note(self%note)) then
            self%note = trim(note)//' '//cut_reason//'; '//trim(self%note)
         else
            self%note = trim(note)//' '//cut_reason
         end if
      end if
      call fill_result(self, result)
      if (self%timing) self%counts%seconds_sampled = self%counts%seconds_sampled + (clock_seconds() - clock)
   end subroutine fem_advance

   !> Advance the accepted state to time t: try the whole interval, halve the
   !> step after a failure (at most max_cuts times), double it again after a
   !> success. A step that branch_jump finds suspect is verified by two half
   !> steps (verify_step, which calls this again one level deeper); a step
   !> they contradict counts as cut and is replaced by them. The first and last
   !> reasons for a cut are kept for the listing.
   recursive subroutine advance_to(self, t, depth, iterations, residual, cuts, cut_reason, last_reason, error)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      !> Verification depth: 0 for a step of the run, k for a step halved k times.
      integer, intent(in) :: depth
      integer, intent(out) :: iterations, cuts
      !> Residual of the last accepted step.
      real(dp), intent(inout) :: residual
      character(:), allocatable, intent(inout) :: cut_reason, last_reason
      type(error_type), allocatable, intent(out) :: error
      type(error_type), allocatable :: step_error
      character(:), allocatable :: rejection
      real(dp) :: h, h_full, t_try, step_residual
      integer :: it
      character(len=80) :: note
      h_full = t - self%t
      h = h_full
      cuts = 0
      iterations = 0
      do while (self%t < t)
         t_try = min(self%t + h, t)
         if (t - t_try < 1.0e-12_dp*abs(h_full)) t_try = t
         self%verify_depth = depth
         call solve_step(self, t_try, it, step_residual, step_error)
         iterations = iterations + it
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
            cuts = cuts + 1
            call keep_reason(rejection)
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
            cuts = cuts + 1
            if (cuts > max_cuts) then
               write (note, '(a,i0,a)') ' (after ', max_cuts, ' step cuts; try a smaller time step or another predictor)'
               call analysis_error(error, step_error%message//trim(note))
               return
            end if
            call keep_reason(step_error%message)
            deallocate (step_error)
            h = h/2
            cycle
         end if
         residual = step_residual
         if (self%t < t) then
            ! An intermediate point of a cut step: its rates feed the Taylor predictor only.
            if (self%model%analysis%predictor == predictor_taylor) call solve_rates(self)
            h = min(2*h, h_full)
         end if
      end do
   contains
      !> Keep the first and the last reason for a cut.
      subroutine keep_reason(reason)
         character(*), intent(in) :: reason
         if (allocated(cut_reason)) then
            last_reason = reason
         else
            cut_reason = reason
         end if
      end subroutine keep_reason
   end subroutine advance_to

   !> Predict and solve P(q) = 0 at time t; accept the configuration if it is
   !> admissible. Leaves the accepted state untouched on failure.
   subroutine solve_step(self, t, iterations, residual, error)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      integer, intent(out) :: iterations
      real(dp), intent(out) :: residual
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: r0, scale, correction, previous, strain, kg_above, stalled_correction, pivot
      integer :: i, info, element, pass, at_floor
      logical :: moved, by_estimate, at_predictor
      character(len=300) :: msg
      associate (mesh => self%mesh, qt => self%qt, eqd => self%mesh%eq_dof)
         self%seg = self%seg_accepted
         call predict(self, t, qt)
         ! Scale of the residual: what the drive (and load) increment alone
         ! produces from the last configuration, to first order -K_fd dq_d +
         ! dlambda f, with the free-driven block of the last tangent (at the
         ! accepted configuration within tolerance). It does not depend on the predictor.
         scale = 0
         if (self%conv%mode /= convergence_paper .and. self%model%analysis%predictor /= predictor_previous) then
            call drive_increment_residual(self, t, qt, scale)
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
         ! iteration (4.45 -> 3.2 iterations per step on Example 1 at dt =
         ! 0.025). Far from it (large strains) the full tangent is the more robust.
         kg_above = merge(0.0_dp, geometric_strain, self%loaded)
         ! Newton; then, if a slave has slid past its master segment, move it on
         ! to the neighbouring segment and iterate again from there; then, if
         ! the iteration stopped on its estimate, check it (see below).
         verification: do
            by_estimate = .false.
            relocations: do pass = 0, size(mesh%slides)*8
               at_predictor = .false.
               do i = 0, self%model%analysis%max_iter
                  call assemble(self, qt, t, kg_above)
                  ! The predictor's guard, once per step: it needs the strains of this first assembly.
                  if (self%guard_pending) then
                     self%guard_pending = .false.
                     if (guard_extrapolation(self, t, qt)) call assemble(self, qt, t, kg_above)
                  end if
                  residual = residual_norm(self)
                  if (i == 0) then
                     r0 = residual
                     if (self%model%analysis%predictor == predictor_previous) scale = r0
                  end if
                  if (self%conv%mode == convergence_paper) then
                     if (is_converged(self%conv, residual, r0, scale, 0.0_dp)) exit
                  end if
                  if (i == self%model%analysis%max_iter) then
                     write (msg, '(a,es12.5,a,i0,a,es9.2)') 't = ', t, ': Newton did not converge in ', i, &
                        & ' iterations (residual ', residual
                     call analysis_error(error, trim(msg)//')')
                     return
                  end if
                  call factor(self, info)
                  if (info > 0 .and. kg_above > 0) then
                     ! The material tangent is singular at a stationary configuration;
                     ! the geometric stiffness of the iterate's stresses may still
                     ! carry Newton there (full Newton from here on in this step).
                     kg_above = 0
                     call assemble(self, qt, t, kg_above)
                     residual = residual_norm(self)
                     call factor(self, info)
                  end if
                  if (info > 0) then
                     write (msg, '(a,es12.5,a)') 't = ', t, ': singular tangent stiffness at '
                     call analysis_error(error, trim(msg)//' '//describe_dof(mesh, self%model, eqd(info)))
                     return
                  end if
                  call newton_correction(self, correction)
                  if (correction > divergence_length*self%size) then
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
                  ! need no assembly and factorisation of their own. On Example 1
                  ! at dt = 1e-4, three steps in four end at their predictor. Not
                  ! near a stationary configuration: the residual there hardly
                  ! sees an error along the near-singular direction (the double
                  ! crank at dt = 2e-4 kept a predictor past collinear at t =
                  ! 0.75, which the branch-jump check then rejected).
                  if (i == 0 .and. .not. self%loaded .and. self%conv%mode /= convergence_paper) then
                     at_predictor = correction <= predictor_margin*self%conv%length .and. &
                        & self%assembled_strain < kg_above .and. is_converged(self%conv, residual, r0, scale, correction)
                     if (at_predictor) then
                        call factor_pivot(self, pivot)
                        at_predictor = pivot >= near_singular_drop*self%reference_pivot
                     end if
                     if (at_predictor) exit
                  end if
                  call apply_correction(self, qt, iterations)
                  if (self%conv%mode /= convergence_paper) then
                     if (is_converged(self%conv, residual, r0, scale, correction)) exit
                     by_estimate = .not. self%loaded
                     if (by_estimate) by_estimate = converged_by_estimate(self, residual, r0, scale, correction, previous)
                     if (by_estimate) exit
                     ! Round-off: a residual at its floor for stall_iterations
                     ! iterations gives corrections that are noise (the tangent's
                     ! sensitivity times the round-off), so the length test cannot
                     ! be met; the last correction is the accuracy left, reported
                     ! in the listing.
                     if (residual <= self%conv%floor) then
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
               call relocate(self, t, qt, moved, error)
               if (allocated(error)) return
               if (.not. moved) exit relocations
            end do relocations
            if (self%loaded .or. at_predictor) exit verification
            ! The material tangent at the new configuration: the branch-jump
            ! check's response (and from it the predictor's velocity) and, once
            ! accepted, the rates' tangent. The last Newton factor, one correction
            ! away, would give rates off by that correction times the ratio of
            ! axial to bending stiffness (EA L^2 / EI: measured 7e-11 in the
            ! accelerations of Example 1 at dt = 1e-3, 3e-6 at EA/EI = 1e8).
            call assemble(self, qt, t, huge(1.0_dp))
            ! The residual reported for the step is the one at the accepted configuration.
            residual = residual_norm(self)
            call factor(self, info)
            if (.not. by_estimate .or. info /= 0) exit verification
            ! A stop on the estimate is checked with this factor (one back
            ! substitution): the correction it gives must pass the estimate's own
            ! margin, or it is applied as one more Newton iteration and Newton
            ! goes on. (Measured: with a slideline penalty 10 times the default
            ! the estimate after one correction missed by 1e-7.)
            call newton_correction(self, correction)
            if (correction <= estimate_margin*self%conv%length) exit verification
            call apply_correction(self, qt, iterations)
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
            strain = self%assembled_strain
            element = self%assembled_element
            if (strain > self%admissible_strain) then
               write (msg, '(a,es12.5,a,es9.2,a)') 't = ', t, &
                  & ': Newton converged to a self-stressed configuration (strain ', strain, ' in link '
               call analysis_error(error, trim(msg)//' '//self%model%links(mesh%elink(element))%name// &
                  & '), not a mechanism configuration')
               return
            end if
            call check_gaps(self, t, qt, error)
            if (allocated(error)) return
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
            self%note = trim(msg)
         end if
         ! The velocity for the predictor's history comes from the branch-jump
         ! check's response (the same whatever rates the run computes, so
         ! positions do not depend on them).
         if (.not. self%loaded) call record_velocity(self)
      end associate
   end subroutine solve_step

   !> Error-oriented stop of Newton without a verifying iteration (Deuflhard,
   !> Newton Methods for Nonlinear Problems, 2004, sec. 2.1): while Newton
   !> converges quadratically, the correction that would follow the last one,
   !> c, is about M c**2, with M measured from the last two corrections
   !> (M = c / c_previous**2), or after the first correction taken from the
   !> last step and never below least_quadratic_constant / model size. The
   !> step has converged when that next correction is below estimate_margin
   !> times the length tolerance and the residual it leaves, residual * next /
   !> c, passes the residual test. Linear convergence (a contraction above
   !> estimate_contraction, as at singular configurations) is never stopped
   !> this way.
   logical function converged_by_estimate(self, residual, r0, scale, correction, previous) result(done)
      type(fem_stepper_type), intent(inout) :: self
      !> Residual norm from which the last correction was solved, at the predictor, and the scale.
      real(dp), intent(in) :: residual, r0, scale
      !> The last correction and the one before it (0 if none), in lengths.
      real(dp), intent(in) :: correction, previous
      real(dp) :: m, next
      done = .false.
      if (.not. correction > 0) return
      m = least_quadratic_constant/self%size
      if (previous > 0) then
         if (correction > estimate_contraction*previous) return
         ! Corrections near round-off measure nothing.
         if (correction > 1.0e3_dp*epsilon(1.0_dp)*self%size) self%newton_constant = correction/previous**2
         m = max(m, correction/previous**2)
      else
         m = max(m, self%newton_constant)
      end if
      next = m*correction**2
      if (next > estimate_contraction*correction) return
      done = is_converged(self%conv, residual*next/correction, r0, scale, next/estimate_margin)
   end function converged_by_estimate

   !> Norm of -K_fd (q_d(t) - q_d) + (t - t_q) f_ext over the free dofs, with
   !> the driven dofs at t taken from the predictor qt (set_driven's values).
   subroutine drive_increment_residual(self, t, qt, scale)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t, qt(:)
      real(dp), intent(out) :: scale
      associate (dqd => self%drive_work(:, 4), dd => self%mesh%driven_dof)
         dqd = qt(dd) - self%q(dd)
         call drive_load_rhs(self, dqd, merge(t - self%t, 0.0_dp, self%loaded))
      end associate
      scale = sqrt(sum(self%rhs(:, 1)**2))
   end subroutine drive_increment_residual

   !> rhs(:, 1) = -K_fd x + lambda f_ext over the free equations: the
   !> right-hand side of a drive (and load) change x (lambda), by columns of
   !> the free-driven block.
   subroutine drive_load_rhs(self, x, lambda)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: x(:), lambda
      integer :: j, k
      associate (rhs => self%rhs(:, 1), eqd => self%mesh%eq_dof)
         if (lambda /= 0) then
            do k = 1, self%mesh%nfree
               rhs(k) = lambda*self%mesh%f_ext(eqd(k))
            end do
         else
            rhs = 0
         end if
         do j = 1, self%mesh%ndriven
            rhs = rhs - x(j)*self%kfd(:, j)
         end do
      end associate
   end subroutine drive_load_rhs

   !> Initial guess at time t: the paper's last configuration, extrapolation
   !> of the last ones, or a Taylor series from the last rates.
   !> Extrapolation: where the velocities of the last configurations are
   !> known, Hermite through their positions and velocities, or, when its
   !> estimated error is below predictor_margin times the length tolerance,
   !> Adams-Bashforth through the newest position and the velocities; where
   !> they are not, Lagrange through the positions. Hermite is of the higher
   !> order, Adams-Bashforth the less sensitive to round-off: at dt = 1e-4 on
   !> Example 1 the first Newton corrections from Hermite are 0.1 to 10 times
   !> the length tolerance (its weights amplify the round-off of the
   !> positions), from Adams-Bashforth 1e-5 to 1e-2 times.
   !> Without history (the first step) extrapolation and Taylor start from the
   !> tangent predictor, the linear response of the last configuration to the
   !> drive increment: rotating a driven link end alone would strain its
   !> element so much that Newton may leave the assembly branch.
   subroutine predict(self, t, qt)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      real(dp), intent(out) :: qt(:)
      real(dp) :: h
      integer :: i, n, nl, columns(history)
      h = t - self%t
      nl = min(self%nhist, lagrange_points)
      ! The history's columns, newest first.
      do i = 1, self%nhist
         columns(i) = history_column(self, i)
      end do
      self%smooth_prediction = .false.
      self%guard_pending = .false.
      select case (self%model%analysis%predictor)
      case (predictor_previous)
         qt = self%q
      case (predictor_taylor)
         if (self%has_acceleration) then
            qt = self%q + h*self%v + h**2/2*self%a
         else if (self%nhist > 1) then
            call extrapolate(self%hist, self%thist, columns(1:nl), t, qt)
         else
            call tangent_predictor(self, t, qt)
         end if
      case default
         n = 0
         ! The newest configurations whose velocities are known, at least two.
         do while (n < self%nhist)
            if (.not. self%has_hist_velocity(columns(n + 1))) exit
            n = n + 1
         end do
         if (n > 1) then
            if (.not. adams_prediction(self, t, columns(1:n), qt)) then
               call hermite_extrapolate(self%hist, self%hist_velocity, self%thist, columns(1:min(n, hermite_points)), &
                  & t, qt)
            end if
            self%smooth_prediction = .true.
            self%guard_pending = .true.
         else if (self%nhist > 1) then
            call extrapolate(self%hist, self%thist, columns(1:nl), t, qt)
            self%guard_pending = .true.
         else
            call tangent_predictor(self, t, qt)
         end if
      end select
      do i = 1, self%mesh%ndof
         if (self%mesh%status(i) == dof_fixed) qt(i) = self%mesh%q0(i)
      end do
      call set_driven(self, t, qt)
      self%q_predicted = qt
   end subroutine predict

   !> The Adams-Bashforth prediction at t through the `history` newest
   !> velocities into qt (see adams_weights), if all of them are known
   !> (columns) and its error, estimated as its distance from the prediction
   !> through one velocity fewer (lengths, rotations times the model size),
   !> is at most predictor_margin times the length tolerance.
   logical function adams_prediction(self, t, columns, qt) result(taken)
      type(fem_stepper_type), intent(in) :: self
      real(dp), intent(in) :: t
      integer, intent(in) :: columns(:)
      real(dp), intent(inout) :: qt(:)
      real(dp) :: beta(history), drop(history), estimate, difference
      integer :: i, k
      taken = .false.
      if (size(columns) < history) return
      call adams_weights(self%thist, columns, t, beta, drop)
      estimate = 0
      do i = 1, self%mesh%ndof
         qt(i) = self%hist(i, columns(1))
         difference = 0
         do k = 1, history
            qt(i) = qt(i) + beta(k)*self%hist_velocity(i, columns(k))
            difference = difference + drop(k)*self%hist_velocity(i, columns(k))
         end do
         estimate = max(estimate, abs(difference)*self%dof_length(i))
      end do
      taken = estimate <= predictor_margin*self%conv%length
   end function adams_prediction

   !> Whether the step to qt was predicted: the Hermite or Adams extrapolation
   !> of the last configurations and velocities (kept by guard_extrapolation) lies
   !> within verify_predicted * turn of qt in every rotation. The step then
   !> continues the resolved path; landing on the mirror branch would need an
   !> extrapolation error of twice the closest approach to collinear.
   logical function predicted_step(self, qt, turn) result(predicted)
      type(fem_stepper_type), intent(in) :: self
      real(dp), intent(in) :: qt(:), turn
      integer :: i
      predicted = self%smooth_prediction
      if (.not. predicted) return
      do i = 1, self%mesh%ndof
         if (self%mesh%dof_kind(i) /= dof_rot) cycle
         if (abs(qt(i) - self%q_predicted(i)) > verify_predicted*turn) then
            predicted = .false.
            return
         end if
      end do
   end function predicted_step

   !> Extrapolating positions over a large rotation (a quarter turn per step)
   !> distorts the links badly, and Newton from there may find another
   !> assembly branch. Keep the extrapolation qt (just assembled, so its
   !> strain is known) only if it strains the elements less than the last
   !> configuration with the new drive values does; else replace it by that
   !> (and return true).
   logical function guard_extrapolation(self, t, qt) result(replaced)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      real(dp), intent(inout) :: qt(:)
      real(dp) :: strain_previous
      integer :: element
      replaced = .false.
      if (self%assembled_strain < 1.0e-2_dp) return
      self%work = self%q
      call set_driven(self, t, self%work)
      call max_strain(self%mesh, self%work, strain_previous, element)
      if (strain_previous < self%assembled_strain) then
         qt = self%work
         self%q_predicted = qt
         self%smooth_prediction = .false.
         replaced = .true.
      end if
   end function guard_extrapolation

   !> qt = q + dq with K_ff dq_f = -K_fd dq_d + (t - t_q) f_ext: the tangent at
   !> the accepted configuration applied to the drive and load increments.
   subroutine tangent_predictor(self, t, qt)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      real(dp), intent(out) :: qt(:)
      integer :: info
      qt = self%q
      call set_driven(self, t, qt)
      ! At a singular configuration there is no tangent response: start from the last configuration.
      call refactor_at_accepted(self, info)
      if (info > 0) return
      associate (eqd => self%mesh%eq_dof, dd => self%mesh%driven_dof)
         self%rhs(:, 1) = -matmul(self%kfd, qt(dd) - self%q(dd))
         if (self%loaded) self%rhs(:, 1) = self%rhs(:, 1) + (t - self%t)*self%mesh%f_ext(eqd)
         call self%kff%solve(self%rhs)
         qt(eqd) = qt(eqd) + self%rhs(:, 1)
      end associate
   end subroutine tangent_predictor

   !> Make kff the factor of the tangent at the accepted configuration, unless
   !> it is already; info > 0 names the equation where it is singular. For a
   !> kinematic analysis this is the material tangent (46): the last Newton
   !> iterate's tangent will not do, because its residual stresses (strains of
   !> 1e-12) make a geometric stiffness comparable to the bending stiffness
   !> EI/L^3 of slender links (1e-8 on Example 5), which spoils accelerations.
   !> A loaded model is stressed by design and uses the full tangent.
   subroutine refactor_at_accepted(self, info)
      type(fem_stepper_type), intent(inout) :: self
      integer, intent(out) :: info
      info = 0
      if (self%factor_current) return
      call assemble(self, self%q, self%t, merge(0.0_dp, huge(1.0_dp), self%loaded))
      call factor(self, info)
      self%factor_current = info == 0
      self%accepted_singular = info /= 0
   end subroutine refactor_at_accepted

   !> Driven dofs at time t: the initial value plus the law's change since t_start.
   subroutine set_driven(self, t, q)
      type(fem_stepper_type), intent(in) :: self
      real(dp), intent(in) :: t
      real(dp), intent(inout) :: q(:)
      real(dp) :: f, df, ddf
      integer :: i, dof
      do i = 1, self%mesh%ndriven
         call self%model%drives(i)%law%eval(t, f, df, ddf)
         dof = self%mesh%driven_dof(i)
         q(dof) = self%mesh%q0(dof) + (f - self%law0(i))
      end do
   end subroutine set_driven

   !> The master segment each slave starts on: the one it projects into with
   !> the smallest gap.
   subroutine initial_segments(self, error)
      type(fem_stepper_type), intent(inout) :: self
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: xs(2), x1(2), x2(2), g, alpha, s1, best
      integer :: i, k, dofs(6)
      do i = 1, size(self%mesh%slides)
         best = huge(1.0_dp)
         self%seg(i) = 0
         do k = 1, size(self%mesh%slides(i)%seg, 2)
            call slide_position(self%mesh, self%mesh%slides(i), k, self%q, xs, x1, x2, dofs)
            call slide_geometry(xs, x1, x2, g, alpha, s1)
            if (alpha >= -1.0e-9_dp .and. alpha <= 1 + 1.0e-9_dp .and. abs(g) < best) then
               best = abs(g)
               self%seg(i) = k
            end if
         end do
         if (self%seg(i) == 0 .or. best > 1.0e-9_dp*self%size) then
            call analysis_error(error, 'slideline '//self%model%slidelines(i)%name//': the slave node '// &
               & self%model%nodes(self%mesh%slides(i)%slave)%name//' is not on its master line')
            return
         end if
      end do
      self%seg_accepted = self%seg
   end subroutine initial_segments

   !> After convergence: move each slave whose coordinate alpha left [0, 1]
   !> on to the neighbouring master segment (`moved`); past the end of a
   !> slideline the step fails with a message naming slave and slideline.
   subroutine relocate(self, t, q, moved, error)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t, q(:)
      logical, intent(out) :: moved
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: xs(2), x1(2), x2(2), g, alpha, s1
      integer :: i, next, status, dofs(6)
      character(len=120) :: msg
      moved = .false.
      do i = 1, size(self%mesh%slides)
         call slide_position(self%mesh, self%mesh%slides(i), self%seg(i), q, xs, x1, x2, dofs)
         call slide_geometry(xs, x1, x2, g, alpha, s1)
         call slide_locate(alpha, self%seg(i), size(self%mesh%slides(i)%seg, 2), next, status)
         if (status == slide_off_end) then
            write (msg, '(a,es12.5,a,f8.4,a)') 't = ', t, ': the slave left the slideline past its end (alpha = ', &
               & alpha, ') '
            call analysis_error(error, trim(msg)//': slave node '//self%model%nodes(self%mesh%slides(i)%slave)%name// &
               & ', slideline '//self%model%slidelines(i)%name//'; lengthen the master line or shorten the run')
            return
         end if
         if (status /= slide_on_element) then
            self%seg(i) = next
            moved = .true.
         end if
      end do
   end subroutine relocate

   !> A converged mechanism configuration has every slave on its master line.
   subroutine check_gaps(self, t, q, error)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t, q(:)
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: xs(2), x1(2), x2(2), g, alpha, s1
      integer :: i, dofs(6)
      character(len=120) :: msg
      do i = 1, size(self%mesh%slides)
         call slide_position(self%mesh, self%mesh%slides(i), self%seg(i), q, xs, x1, x2, dofs)
         call slide_geometry(xs, x1, x2, g, alpha, s1)
         if (abs(g) > self%admissible_strain*self%size) then
            write (msg, '(a,es12.5,a,es9.2,a)') 't = ', t, ': Newton converged with a gap of ', g, ' at slideline '
            call analysis_error(error, trim(msg)//' '//self%model%slidelines(i)%name//', not a mechanism configuration')
            return
         end if
      end do
   end subroutine check_gaps

   !> Assembly-mode (branch) jump check. A converged, unstrained configuration
   !> may still lie on another assembly branch than the last one: Newton from a
   !> poor predictor can cross over. What the drive increment dd of the step
   !> explains is its linear response, dq = R dd with R = -K_ff^-1 K_fd the
   !> response to unit drive changes, at either end of the step: R at the new
   !> configuration comes from the factor of its material tangent (one back
   !> substitution per drive; the same factor then serves the rates), R at the
   !> last one is kept from the last step. Two tests:
   !> * magnitude: every rotation unknown changes by |d| <= jump_ratio * B with
   !>   B = max(|dq_n|, |dq|, drive increment) (rotation drives in radians,
   !>   translation drives in lengths of the shortest link);
   !> * orientation (hinge_flip): two hinged links that pass through
   !>   collinear within the step must do so in the sense of the response.
   !> Rotations and responses to the drive increment are scale-free.
   subroutine branch_jump(self, t, qt, factored, error)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t, qt(:)
      !> Whether kff holds the factor of the material tangent at qt.
      logical, intent(in) :: factored
      type(error_type), allocatable, intent(out) :: error
      real(dp), allocatable :: swap(:, :)
      real(dp) :: floor, bound, ratio, worst, turn, pivot
      integer :: i, j, worst_dof, flip_link(2), flip_node, crossing(3)
      logical :: has_response
      character(len=200) :: msg
      associate (mesh => self%mesh, eqd => self%mesh%eq_dof, dq_new => self%work, dq_old => self%r, &
         & resp => self%jump_response_new, dd => self%drive_work(:, 4))
         ! The drive increment over the step (set_driven put it on the driven dofs).
         floor = 0
         do j = 1, mesh%ndriven
            dd(j) = qt(mesh%driven_dof(j)) - self%q(mesh%driven_dof(j))
            if (mesh%dof_kind(mesh%driven_dof(j)) == dof_rot) then
               floor = max(floor, abs(dd(j)))
            else
               floor = max(floor, abs(dd(j))/self%shortest_link)
            end if
         end do
         ! Response at the new configuration (unless its tangent is singular).
         pivot = 0
         if (factored) call factor_pivot(self, pivot)
         has_response = pivot >= singular_floor
         if (has_response) then
            call drive_response(self, resp)
         else
            resp = 0
         end if
         call note_response_pivot(self, merge(pivot, 0.0_dp, has_response))
         call apply_response(resp, dd, dq_new)
         if (self%has_jump_response) then
            call apply_response(self%jump_response, dd, dq_old)
         else
            dq_old = 0
         end if
         worst = 0
         worst_dof = 0
         do i = 1, mesh%ndof
            if (mesh%dof_kind(i) /= dof_rot) cycle
            bound = max(floor, abs(dq_new(i)), abs(dq_old(i)))
            if (bound > 0) then
               ratio = abs(qt(i) - self%q(i))/bound
            else
               ratio = merge(0.0_dp, huge(1.0_dp), abs(qt(i) - self%q(i)) <= 0)
            end if
            if (ratio > worst) then
               worst = ratio
               worst_dof = i
            end if
         end do
         call hinge_flip(self, qt, dq_old, dq_new, flip_link, flip_node, turn, crossing)
         if (worst > jump_ratio) then
            write (msg, '(a,es12.5,a,f9.4,a,es9.2,a)') 't = ', t, ': assembly-mode jump rejected (rotation ', &
               & qt(worst_dof) - self%q(worst_dof), ' rad over the step, ', worst, &
               & ' times what the drive increment explains) at'
            call analysis_error(error, trim(msg)//' '//describe_dof(mesh, self%model, worst_dof))
            return
         end if
         if (flip_link(1) > 0) then
            write (msg, '(a,es12.5,a)') 't = ', t, ': assembly-mode jump rejected (links'
            call analysis_error(error, trim(msg)//' '//self%model%links(flip_link(1))%name//' and '// &
               & self%model%links(flip_link(2))%name//' at node '//self%model%nodes(flip_node)%name// &
               & ' passed through collinear against the drive increment''s sense)')
            return
         end if
         ! Endpoint data cannot tell a step that crosses collinear from one that
         ! jumps over a near-toggle onto the mirror branch (by symmetry, the
         ! responses at both ends may agree with a crossing): unless the crossing
         ! pair turns by less than verify_turn, have it confirmed by two half steps.
         if (turn > verify_turn .and. .not. predicted_step(self, qt, turn)) then
            if (self%verify_depth >= max_verify_depth) then
               write (msg, '(a,es12.5,a,f7.4,a,i0,a)') 't = ', t, ': assembly-mode jump rejected (links '// &
                  & self%model%links(crossing(1))%name//' and '//self%model%links(crossing(2))%name// &
                  & ' crossed collinear turning ', turn, ' rad in a step halved ', max_verify_depth, ' times)'
               call analysis_error(error, trim(msg))
               self%verify_failed = .true.
               return
            end if
            call save_state(self, self%before(self%verify_depth))
            self%before(self%verify_depth)%crossing = crossing
            self%before(self%verify_depth)%turn = turn
            self%verify_pending = .true.
         end if
         self%has_jump_response = has_response
      end associate
      ! The new response becomes the accepted one (a swap of the two arrays, no copy).
      call move_alloc(self%jump_response, swap)
      call move_alloc(self%jump_response_new, self%jump_response)
      call move_alloc(swap, self%jump_response_new)
   end subroutine branch_jump

   !> Step-doubling verification of a step to time t that branch_jump found
   !> suspect (a hinged pair crossed collinear turning by more than
   !> verify_turn): the step is accepted, the state before it is in
   !> self%before(depth). The same interval is solved again from that state as
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
      character(:), allocatable :: first_reason, last_reason, pair
      real(dp), allocatable :: q_whole(:)
      real(dp) :: t_end(2), distance, d
      integer :: i, half, it, cuts, worst_dof
      character(len=200) :: msg
      q_whole = self%q
      call restore_state(self, self%before(depth))
      associate (c => self%before(depth)%crossing)
         pair = 'links '//self%model%links(c(1))%name//' and '//self%model%links(c(2))%name//' at node '// &
            & self%model%nodes(c(3))%name
      end associate
      t_end = [self%t + (t - self%t)/2, t]
      iterations = 0
      do half = 1, 2
         call advance_to(self, t_end(half), depth + 1, it, residual, cuts, first_reason, last_reason, half_error)
         iterations = iterations + it
         if (allocated(half_error)) exit
         ! The midpoint's rates feed the Taylor predictor, as at a cut step's intermediate points.
         if (half == 1 .and. self%model%analysis%predictor == predictor_taylor) call solve_rates(self)
      end do
      if (allocated(half_error)) then
         call restore_state(self, self%before(depth))
         self%verify_failed = .true.
         if (depth > 0) then
            call move_alloc(half_error, error)
         else
            write (msg, '(a,es12.5,a,f7.4,a)') 't = ', t, ': possible assembly-mode jump rejected ('//pair// &
               & ' crossed collinear turning ', self%before(depth)%turn, ' rad; two half steps could not confirm it: '
            call analysis_error(error, trim(msg)//' '//half_error%message//')')
         end if
         return
      end if
      ! Distance in model sizes (rotations times the model size).
      distance = 0
      worst_dof = 1
      do i = 1, self%mesh%ndof
         d = abs(q_whole(i) - self%q(i))*self%dof_length(i)/self%size
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

   !> Copy the accepted state of the stepper into state.
   subroutine save_state(self, state)
      type(fem_stepper_type), intent(in) :: self
      type(saved_state_type), intent(inout) :: state
      state%q = self%q
      state%v = self%v
      state%a = self%a
      state%hist = self%hist
      state%hist_velocity = self%hist_velocity
      state%has_hist_velocity = self%has_hist_velocity
      state%thist = self%thist
      state%jump_response = self%jump_response
      state%seg_accepted = self%seg_accepted
      state%t = self%t
      state%reference_pivot = self%reference_pivot
      state%nhist = self%nhist
      state%newest = self%newest
      state%has_velocity = self%has_velocity
      state%has_acceleration = self%has_acceleration
      state%has_jump_response = self%has_jump_response
      state%note = self%note
   end subroutine save_state

   !> Make state the accepted state again; the tangent (and its free-driven
   !> block, which scales the convergence test) is refactored there.
   subroutine restore_state(self, state)
      type(fem_stepper_type), intent(inout) :: self
      type(saved_state_type), intent(in) :: state
      integer :: info
      self%q = state%q
      self%v = state%v
      self%a = state%a
      self%hist = state%hist
      self%hist_velocity = state%hist_velocity
      self%has_hist_velocity = state%has_hist_velocity
      self%thist = state%thist
      self%jump_response = state%jump_response
      self%seg_accepted = state%seg_accepted
      self%seg = state%seg_accepted
      self%t = state%t
      self%reference_pivot = state%reference_pivot
      self%nhist = state%nhist
      self%newest = state%newest
      self%has_velocity = state%has_velocity
      self%has_acceleration = state%has_acceleration
      self%has_jump_response = state%has_jump_response
      self%note = state%note
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
      self%reference_pivot = max(self%reference_pivot, ratio)
   end subroutine note_response_pivot

   !> The velocity of the newest configuration of the predictor's history:
   !> the drive response times the drive rates, when the response is known
   !> and not near a stationary configuration.
   subroutine record_velocity(self)
      type(fem_stepper_type), intent(inout) :: self
      self%has_hist_velocity(self%newest) = self%has_jump_response .and. &
         & self%response_pivot >= near_singular_drop*self%reference_pivot
      if (.not. self%has_hist_velocity(self%newest)) return
      associate (law => self%drive_work(:, 1), rate => self%drive_work(:, 2), rate2 => self%drive_work(:, 3))
         call self%model%drives%law%eval(self%t, law, rate, rate2)
         call apply_response(self%jump_response, rate, self%hist_velocity(:, self%newest))
      end associate
   end subroutine record_velocity

   !> y = resp x: the dofs' change for the drives' change x, through a drive
   !> response resp (ndof, ndriven).
   pure subroutine apply_response(resp, x, y)
      real(dp), intent(in) :: resp(:, :), x(:)
      real(dp), intent(out) :: y(:)
      integer :: j
      if (size(x) == 0) then
         y = 0
         return
      end if
      y = x(1)*resp(:, 1)
      do j = 2, size(x)
         y = y + x(j)*resp(:, j)
      end do
   end subroutine apply_response

   !> Linear response of every dof to unit changes of the drives, (ndof,
   !> ndriven): R_f = -K_ff^-1 K_fd with the current factor, 1 on the drive's
   !> own dof; the other driven and the fixed dofs keep their zeros (resp is
   !> one of the stepper's response arrays, zero there from the start).
   subroutine drive_response(self, resp)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), intent(inout) :: resp(:, :)
      integer :: j, k
      real(dp) :: clock
      do j = 1, self%mesh%ndriven
         self%rhs(:, 1) = -self%kfd(:, j)
         clock = phase_start(self)
         call self%kff%solve(self%rhs)
         call phase_end(self, clock, self%counts%seconds_solves)
         do k = 1, self%mesh%nfree
            resp(self%mesh%eq_dof(k), j) = self%rhs(k, 1)
         end do
         resp(self%mesh%driven_dof(j), j) = 1
      end do
   end subroutine drive_response

   !> Orientation part of the branch-jump check. Two links hinged at a node
   !> have a relative angle psi; in a continuous motion psi crosses k pi (the
   !> links collinear) in the sense in which the drive increment moves it. A
   !> jump to the mirror assembly mode near a flattened configuration (a
   !> fold) crosses against the linear response at the start or at the end of
   !> the step. Returns the first such pair of links (flip_link(1) = 0 if
   !> none) and their node. A zero response (not known) does not object.
   !> Also returns the largest turn |psi_1 - psi_0| of a pair that crossed
   !> collinear in the sense of the responses (0 if none did), and that pair
   !> (link, link, node).
   subroutine hinge_flip(self, qt, dq_old, dq_new, flip_link, flip_node, turn, crossing)
      type(fem_stepper_type), intent(in) :: self
      real(dp), intent(in) :: qt(:), dq_old(:), dq_new(:)
      integer, intent(out) :: flip_link(2), flip_node
      real(dp), intent(out) :: turn
      integer, intent(out) :: crossing(3)
      integer :: k, l1, l2, e1, e2, r1, r2
      real(dp) :: psi0, psi1, lo, hi, sense, pi
      pi = acos(-1.0_dp)
      flip_link = 0
      flip_node = 0
      turn = 0
      crossing = 0
      associate (mesh => self%mesh, links => self%model%links)
         do k = 1, size(self%hinge_pairs, 2)
            l1 = self%hinge_pairs(1, k)
            e1 = self%hinge_pairs(2, k)
            l2 = self%hinge_pairs(3, k)
            e2 = self%hinge_pairs(4, k)
            r1 = mesh%link_rot(e1, l1)
            r2 = mesh%link_rot(e2, l2)
            psi0 = mesh%link_angle0(l1) - mesh%link_angle0(l2) + self%q(r1) - self%q(r2)
            psi1 = mesh%link_angle0(l1) - mesh%link_angle0(l2) + qt(r1) - qt(r2)
            lo = min(psi0, psi1)/pi
            hi = max(psi0, psi1)/pi
            ! A multiple of pi strictly inside (lo, hi): the links passed through collinear.
            if (floor(hi - hinge_margin) < ceiling(lo + hinge_margin)) cycle
            sense = sign(1.0_dp, psi1 - psi0)
            ! The response at the new configuration must carry psi through in the crossing
            ! sense (a response of zero there is the closest approach of a near-toggle, not a
            ! crossing); at the last one it must not oppose it (unknown on the first step).
            if (sense*(dq_old(r1) - dq_old(r2)) < 0 .or. &
               & sense*(dq_new(r1) - dq_new(r2)) <= hinge_response*abs(psi1 - psi0)) then
               flip_link = [l1, l2]
               flip_node = links(l1)%node(e1)
               return
            end if
            if (abs(psi1 - psi0) > turn) then
               turn = abs(psi1 - psi0)
               crossing = [l1, l2, links(l1)%node(e1)]
            end if
         end do
      end associate
   end subroutine hinge_flip

   !> The pairs of link ends that meet at a node with rotations of their own
   !> (hinged, not welded), found once through the ends at each node.
   subroutine find_hinge_pairs(self)
      type(fem_stepper_type), intent(inout) :: self
      integer, allocatable :: count(:), first(:), ends(:, :)
      integer :: nnode, l, e, node, i, j, npair
      nnode = size(self%model%nodes)
      allocate (count(nnode), source=0)
      do l = 1, size(self%model%links)
         count(self%model%links(l)%node) = count(self%model%links(l)%node) + 1
      end do
      allocate (first(nnode + 1))
      first(1) = 1
      do node = 1, nnode
         first(node + 1) = first(node) + count(node)
      end do
      ! ends(:, first(node):first(node+1)-1): (link, end) of every link end at node.
      allocate (ends(2, first(nnode + 1) - 1))
      count = 0
      do l = 1, size(self%model%links)
         do e = 1, 2
            node = self%model%links(l)%node(e)
            ends(:, first(node) + count(node)) = [l, e]
            count(node) = count(node) + 1
         end do
      end do
      npair = 0
      do node = 1, nnode
         do i = first(node), first(node + 1) - 1
            do j = i + 1, first(node + 1) - 1
               if (.not. welded(i, j)) npair = npair + 1
            end do
         end do
      end do
      allocate (self%hinge_pairs(4, npair))
      npair = 0
      do node = 1, nnode
         do i = first(node), first(node + 1) - 1
            do j = i + 1, first(node + 1) - 1
               if (welded(i, j)) cycle
               npair = npair + 1
               self%hinge_pairs(:, npair) = [ends(:, i), ends(:, j)]
            end do
         end do
      end do
   contains
      !> Whether the link ends i and j of `ends` share their rotation.
      logical function welded(i_, j_)
         integer, intent(in) :: i_, j_
         welded = self%mesh%link_rot(ends(2, i_), ends(1, i_)) == self%mesh%link_rot(ends(2, j_), ends(1, j_))
      end function welded
   end subroutine find_hinge_pairs

   !> Make q at time t the accepted configuration and push it on the history
   !> (over the oldest column of the ring).
   subroutine accept(self, t, q)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t, q(:)
      self%newest = modulo(self%newest, history) + 1
      self%hist(:, self%newest) = q
      self%thist(self%newest) = t
      self%has_hist_velocity(self%newest) = .false.
      self%nhist = min(self%nhist + 1, history)
      self%q = q
      self%t = t
      self%seg_accepted = self%seg
      if (has_note(self%note)) self%note = ''
      self%has_velocity = .false.
      self%has_acceleration = .false.
      self%counts%steps = self%counts%steps + 1
   end subroutine accept

   !> The column of the history's k-th newest configuration.
   pure integer function history_column(self, k) result(column)
      type(fem_stepper_type), intent(in) :: self
      integer, intent(in) :: k
      column = modulo(self%newest - k, history) + 1
   end function history_column

   !> Residual and tangent at q (geometric stiffness where strained above
   !> geometric_above, see beam_residual) into r, kff and kfd, and the largest
   !> element strain at q, timed and counted.
   subroutine assemble(self, q, t, geometric_above)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: q(:), t, geometric_above
      real(dp) :: clock
      clock = phase_start(self)
      call assemble_tangent(self%mesh, q, t, self%seg, self%r, self%kff, self%kfd, geometric_above, &
         & self%assembled_strain, self%assembled_element, self%section)
      call phase_end(self, clock, self%counts%seconds_assembly)
      self%counts%tangent_assemblies = self%counts%tangent_assemblies + 1
      self%counts%slideline_evaluations = self%counts%slideline_evaluations + size(self%mesh%slides)
   end subroutine assemble

   !> The residual alone at q into r, timed and counted.
   subroutine assemble_force(self, q, t)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: q(:), t
      real(dp) :: clock
      clock = phase_start(self)
      call assemble_residual(self%mesh, q, t, self%seg, self%r)
      call phase_end(self, clock, self%counts%seconds_assembly)
      self%counts%residual_assemblies = self%counts%residual_assemblies + 1
      self%counts%slideline_evaluations = self%counts%slideline_evaluations + size(self%mesh%slides)
   end subroutine assemble_force

   !> The Newton correction for the residual that residual_norm gathered into
   !> rhs, with the current factor, into rhs, and its length (rotations
   !> weighted by the model size).
   subroutine newton_correction(self, correction)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), intent(out) :: correction
      real(dp) :: clock
      integer :: k
      clock = phase_start(self)
      call self%kff%solve(self%rhs)
      call phase_end(self, clock, self%counts%seconds_solves)
      correction = 0
      do k = 1, self%mesh%nfree
         correction = max(correction, abs(self%rhs(k, 1))*self%dof_length(self%mesh%eq_dof(k)))
      end do
   end subroutine newton_correction

   !> Add the correction in rhs to q: one Newton iteration more.
   subroutine apply_correction(self, q, iterations)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), intent(inout) :: q(:)
      integer, intent(inout) :: iterations
      integer :: k
      do k = 1, self%mesh%nfree
         q(self%mesh%eq_dof(k)) = q(self%mesh%eq_dof(k)) + self%rhs(k, 1)
      end do
      iterations = iterations + 1
      self%counts%iterations = self%counts%iterations + 1
   end subroutine apply_correction

   !> Factor the assembled tangent, counting Cholesky and LU fallbacks.
   subroutine factor(self, info)
      type(fem_stepper_type), intent(inout) :: self
      integer, intent(out) :: info
      real(dp) :: clock
      clock = phase_start(self)
      call self%kff%factor(info)
      call phase_end(self, clock, self%counts%seconds_factorisation)
      self%pivot_known = .false.
      if (self%kff%is_lu) then
         self%counts%lu_factorisations = self%counts%lu_factorisations + 1
      else
         self%counts%cholesky_factorisations = self%counts%cholesky_factorisations + 1
      end if
   end subroutine factor

   !> The pivot ratio of the factor in kff (band_pivot_ratio), computed once
   !> per factorisation: the branch-jump check, the drive response and the
   !> rates all ask for it.
   subroutine factor_pivot(self, ratio)
      type(fem_stepper_type), intent(inout) :: self
      real(dp), intent(out) :: ratio
      if (.not. self%pivot_known) then
         self%pivot = self%kff%pivot_ratio()
         self%pivot_known = .true.
      end if
      ratio = self%pivot
   end subroutine factor_pivot

   !> Velocities K v_f = -K_fd v_d + lambda' f (47) and accelerations
   !> K a_f = -K_fd a_d - d2P[v, v] + lambda'' f (48)-(53), as asked for, with
   !> the tangent at the accepted configuration (the material tangent there,
   !> since the geometric part vanishes with the stresses; the load factor is
   !> lambda = t, so lambda' = 1, lambda'' = 0).
   subroutine solve_rates(self)
      type(fem_stepper_type), intent(inout) :: self
      real(dp) :: ratio, clock
      integer :: i, k, info
      character(len=160) :: note
      character(:), allocatable :: consequence
      ! The pivot ratio of the tangent at the configuration: a stationary one is
      ! noted also when only positions are computed (the tangent is factored
      ! for the branch-jump check anyway, so at no cost).
      if (self%model%analysis%velocities) call refactor_at_accepted(self, info)
      if (self%accepted_singular) then
         ratio = 0
      else if (self%factor_current) then
         call factor_pivot(self, ratio)
      else
         return
      end if
      self%counts%min_pivot_ratio = min(self%counts%min_pivot_ratio, ratio)
      self%reference_pivot = max(self%reference_pivot, ratio)
      if (ratio < singular_drop*self%reference_pivot .or. ratio < singular_floor) then
         consequence = ''
         if (self%model%analysis%velocities) consequence = ': velocities and accelerations are left out of this step'
         write (note, '(a,es12.5,a)') 't = ', self%t, ': singular configuration (the tangent has no inverse)'
         self%note = trim(note)//consequence
         return
      else if (ratio < near_singular_drop*self%reference_pivot) then
         consequence = ')'
         if (self%model%analysis%velocities) consequence = '): velocities and accelerations are ill-conditioned'
         write (note, '(a,es12.5,a,es9.2)') 't = ', self%t, ': near a stationary configuration (pivot ratio ', ratio
         self%note = trim(note)//consequence
      end if
      if (.not. self%model%analysis%velocities) return
      associate (mesh => self%mesh, eqd => self%mesh%eq_dof, f => self%drive_work(:, 1), &
         & vd => self%drive_work(:, 2), ad => self%drive_work(:, 3))
         call self%model%drives%law%eval(self%t, f, vd, ad)
         if (self%has_hist_velocity(self%newest)) then
            ! (47) is R vd with the drive response R of this factor: record_velocity
            ! made it already, for the predictor.
            self%v = self%hist_velocity(:, self%newest)
         else if (self%has_jump_response .and. .not. self%loaded) then
            call apply_response(self%jump_response, vd, self%v)
         else
            self%v = 0
            do i = 1, mesh%ndriven
               self%v(mesh%driven_dof(i)) = vd(i)
            end do
            call drive_load_rhs(self, vd, merge(1.0_dp, 0.0_dp, self%loaded))
            clock = phase_start(self)
            call self%kff%solve(self%rhs)
            call phase_end(self, clock, self%counts%seconds_solves)
            do k = 1, mesh%nfree
               self%v(eqd(k)) = self%rhs(k, 1)
            end do
         end if
         self%counts%velocity_solves = self%counts%velocity_solves + 1
         self%has_velocity = .true.
         if (.not. self%model%analysis%accelerations) return
         clock = phase_start(self)
         ! kff holds the factor of the tangent at q (factor_current), so the
         ! last tangent assembly, whose section angles are kept, was at q.
         call assemble_second_derivative(mesh, self%q, self%v, self%seg, self%work, self%section)
         call phase_end(self, clock, self%counts%seconds_assembly)
         self%counts%slideline_evaluations = self%counts%slideline_evaluations + size(mesh%slides)
         self%a = 0
         do i = 1, mesh%ndriven
            self%a(mesh%driven_dof(i)) = ad(i)
         end do
         call drive_load_rhs(self, ad, 0.0_dp)
         do k = 1, mesh%nfree
            self%rhs(k, 1) = self%rhs(k, 1) - self%work(eqd(k))
         end do
         clock = phase_start(self)
         call self%kff%solve(self%rhs)
         call phase_end(self, clock, self%counts%seconds_solves)
         do k = 1, mesh%nfree
            self%a(eqd(k)) = self%rhs(k, 1)
         end do
         self%counts%acceleration_solves = self%counts%acceleration_solves + 1
         self%has_acceleration = .true.
      end associate
   end subroutine solve_rates

   !> Node positions, velocities, accelerations and link angles of the accepted state.
   subroutine fill_result(self, result)
      type(fem_stepper_type), intent(in) :: self
      type(step_result_type), intent(inout) :: result
      integer :: i, k, dof
      result%t = self%t
      if (has_note(self%note) .or. has_note(result%note)) result%note = self%note
      result%has_velocity = self%has_velocity
      result%has_acceleration = self%has_acceleration
      do i = 1, size(self%model%nodes)
         do k = 1, 2
            dof = self%mesh%tdof(k, i)
            result%pos(k, i) = self%q(dof)
            result%vel(k, i) = self%v(dof)
            result%acc(k, i) = self%a(dof)
         end do
      end do
      do i = 1, size(self%model%links)
         dof = self%mesh%link_rot(1, i)
         result%angle(i) = self%mesh%link_angle0(i) + self%q(dof)
         result%omega(i) = self%v(dof)
         result%alpha(i) = self%a(dof)
      end do
      if (self%model%output%vtk) call fill_fields(self, result)
   end subroutine fill_result

   !> The mesh-level fields of the result, for VTK output: every point, every
   !> element as a line cell with its link and stress resultants.
   subroutine fill_fields(self, result)
      type(fem_stepper_type), intent(in) :: self
      type(step_result_type), intent(inout) :: result
      integer :: ip, e, k
      real(dp) :: xe(6)
      associate (mesh => self%mesh)
         if (.not. allocated(result%mesh_pos)) then
            allocate (result%mesh_pos(2, mesh%npoint), result%mesh_vel(2, mesh%npoint), &
               & result%mesh_acc(2, mesh%npoint), result%cell_force(3, size(mesh%elements)))
            allocate (result%cells(2, size(mesh%elements)), result%cell_link(size(mesh%elements)))
            ! The cells do not change from step to step.
            do e = 1, size(mesh%elements)
               result%cells(:, e) = mesh%dof_point(mesh%edof([1, 4], e))
               result%cell_link(e) = mesh%elink(e)
            end do
         end if
         do ip = 1, mesh%npoint
            result%mesh_pos(:, ip) = self%q(mesh%tdof(:, ip))
            result%mesh_vel(:, ip) = self%v(mesh%tdof(:, ip))
            result%mesh_acc(:, ip) = self%a(mesh%tdof(:, ip))
         end do
         do e = 1, size(mesh%elements)
            do k = 1, 6
               xe(k) = self%q(mesh%edof(k, e))
            end do
            result%cell_force(:, e) = beam_resultants(mesh%elements(e), xe)
         end do
      end associate
   end subroutine fill_fields

   !> The clock at the start of a phase, if this step's phases are timed (else 0).
   real(dp) function phase_start(self) result(clock)
      type(fem_stepper_type), intent(in) :: self
      clock = 0
      if (self%timing) clock = clock_seconds()
   end function phase_start

   !> Add the time since `clock` (from phase_start) to a phase's seconds.
   subroutine phase_end(self, clock, seconds)
      type(fem_stepper_type), intent(in) :: self
      real(dp), intent(in) :: clock
      real(dp), intent(inout) :: seconds
      if (self%timing) seconds = seconds + (clock_seconds() - clock)
   end subroutine phase_end

   !> The assembled residual over the free equations, negated, into rhs (the
   !> right-hand side of a Newton correction), and its Euclidean norm, scaled
   !> by its largest entry so that the squares cannot overflow.
   real(dp) function residual_norm(self) result(norm)
      type(fem_stepper_type), intent(inout) :: self
      real(dp) :: biggest, scale
      integer :: k
      associate (r => self%rhs(:, 1))
         do k = 1, self%mesh%nfree
            r(k) = -self%r(self%mesh%eq_dof(k))
         end do
         biggest = 0
         do k = 1, self%mesh%nfree
            biggest = max(biggest, abs(r(k)))
         end do
         norm = 0
         if (.not. biggest > 0) return
         scale = 1/biggest
         do k = 1, self%mesh%nfree
            norm = norm + (r(k)*scale)**2
         end do
         norm = biggest*sqrt(norm)
      end associate
   end function residual_norm

end module fekap_solver_fem
