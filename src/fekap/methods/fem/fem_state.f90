!> The FEM stepper's data: the accepted state (fem_state_type, of
!> fekap_fem_accepted), the steps awaiting verification (fekap_fem_verification's
!> stack), and the stepper's storage and settings (fem_core_type,
!> allocated once by new_fem_core, with its component records: the factor
!> (fekap_fem_factor_record), the predictor (fekap_fem_prediction) and the
!> change points (fekap_fem_change_point)), with what a step does to them at its
!> end: accept a configuration (push it on the predictor's history) and fill
!> the step's result; and the procedures through which another method
!> (reactions/) uses the FEM. The modules fem_factor, fem_predict,
!> fem_converged, fem_fill and fem_newton act on fem_core_type; fekap_fem
!> composes them.
module fekap_fem_state
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, analysis_error
   use fekap_model, only: model_type, solver_dense, effects_kinematics, effects_kinetostatics
   use fekap_model_effects, only: planned_effects
   use fekap_model_results, only: step_result_type, note_length, has_note
   use fekap_fem_setup, only: fem_base_type, new_fem_base, mesh_plan_line
   use fekap_fem_convergence, only: convergence_type
   use fekap_stepping_predictor, only: new_predictor_history
   use fekap_stepping_newton, only: admissible_strain
   use fekap_fem_branch, only: branch_check_type, new_branch_check
   use fekap_fem_accepted, only: fem_state_type
   use fekap_fem_verification, only: verification_stack_type
   use fekap_fem_factor_record, only: factor_record_type
   use fekap_fem_prediction, only: prediction_type, new_prediction
   use fekap_fem_change_point, only: change_record_type
   use fekap_assembly_strain_rate, only: strain_rate_type, new_strain_rate, strain_rows, solve_material_tangent
   use fekap_assembly_mesh, only: dof_fixed
   use fekap_fem_fields, only: fill_nodes_links, fill_fields
   use fekap_stepping_step_control, only: step_cuts_type, dead_point_advice, limit_load_advice
   use fekap_strings, only: es_text
   use fekap_assembly_loads, only: load_set_type
   implicit none
   private

   public :: fem_state_type, fem_core_type, new_fem_core, accept, fill_result
   public :: note_response_pivot, prepend_cuts_note, model_distance, no_convergence_error

   !> The model, mesh, linear system, drives' start values and scales are
   !> fem_base_type's (new_fem_base), as the dynamics stepper's.
   type, abstract, extends(fem_base_type) :: fem_core_type
      type(convergence_type) :: conv
      type(branch_check_type) :: branch
      type(fem_state_type) :: state
      !> Whether the system holds the factor of the tangent at (within
      !> tolerance of) the accepted configuration, and whether factoring the
      !> tangent there failed (a singular configuration).
      type(factor_record_type) :: factor
      !> Quadratic-convergence constant M of Newton (c(k+1) = M c(k)**2) measured
      !> in the last step that showed it, for the estimated stop.
      real(dp) :: newton_constant = 0
      !> The last predictor, whether it was a smooth (Hermite or Adams)
      !> extrapolation of the history, and its length tolerance.
      type(prediction_type) :: prediction
      !> Pivot ratio of the factor behind the last drive response.
      real(dp) :: response_pivot = 0
      !> Whether the model has external loads (a flexible, stressed analysis).
      logical :: loaded = .false.
      !> Whether the run is kinetostatics, which solves the deflection of its
      !> loads with the factor at the accepted configuration
      !> (solve_at_accepted): never a factor carried there (carry_factor; a
      !> step accepted at its predictor keeps the predictor's, a round-off
      !> correction away).
      logical :: kinetostatic = .false.
      !> Work over the dofs: a change or rate of the loads (mesh%loads).
      real(dp), allocatable :: load_work(:)
      !> Work arrays over the dofs, allocated once (nothing is allocated in the
      !> step loop): the iterate, scratch, and the responses to a step's drive
      !> increment at its two ends.
      real(dp), allocatable :: qt(:), work(:), dq_new(:), dq_old(:)
      !> The drives' increment over a step.
      real(dp), allocatable :: drive_step(:)
      !> The time at which the base's law_value, law_rate and law_rate2 were
      !> evaluated (fekap_fem_predict's drive_laws_at), if laws_known.
      real(dp) :: laws_t = 0
      logical :: laws_known = .false.
      !> The fixed dofs (mesh%status dof_fixed), whose predictor is q0.
      integer, allocatable :: fixed_dofs(:)
      !> Master segment of each slideline during the step.
      integer, allocatable :: seg(:)
      !> The drive response at the new configuration (swapped with the state's).
      real(dp), allocatable :: jump_response_new(:, :)
      !> Step cuts in the last advance, for the listing.
      integer :: last_cuts = 0
      !> Element strain (and gap per model size) above which a converged
      !> configuration is rejected: min(1e-3, max(1e-8, 100 tol)).
      real(dp) :: admissible_strain = 1.0e-8_dp
      !> What a step given up after its cuts means (advance_by_cuts): a dead
      !> point of a drive, or without drives (statics) a limit load.
      character(:), allocatable :: cut_advice
      !> The steps awaiting step-doubling verification, one per halving.
      type(verification_stack_type) :: verification
      !> Steps advanced so far.
      integer :: advances = 0
      !> The strain-rate operator B_f and its factor (see the module header),
      !> and whether the square-root form is used (then the factor record refers
      !> to the factor of the stress-free B_f in root).
      type(strain_rate_type) :: root
      logical :: root_form = .false.
      !> Scratch over the equations for the square-root form's solves.
      real(dp), allocatable :: root_work(:)
      !> Whether the K form's rates of a redundant mechanism are refined
      !> with its strain rates (root%refines, unloaded kinematics or kinetostatics: see
      !> fekap_fem_rates' refine_rates), and its scratch over B's rows.
      logical :: refined_rates = .false.
      real(dp), allocatable :: strain_work(:)
      !> Change points (see step_over): the predictor's check and the regular
      !> states on either side of a change point stepped over.
      type(change_record_type) :: change
   contains
      procedure :: plan_text => fem_plan_text
      !> Take the external loads out of the mesh (kinetostatics: the motion
      !> is the unloaded one, the loads act in the reactions only).
      procedure :: release_loads => core_release_loads
      !> The load columns of the mesh (statics' load steps scale them).
      procedure :: set_loads => core_set_loads
      !> The configuration the start's Newton begins from (statics' load
      !> steps begin each solve from the last equilibrium).
      procedure :: set_start => core_set_start
      !> Whether the system holds the factor of the tangent at the accepted configuration.
      procedure :: holds_accepted_factor => core_holds_accepted_factor
      !> Solve with that factor, in place, right-hand sides over the free equations.
      procedure :: solve_at_accepted => core_solve_at_accepted
   end type fem_core_type

contains

   !> Build the mesh, the equation numbering and all storage for a validated model.
   subroutine new_fem_core(self, model)
      class(fem_core_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      integer :: i
      call new_fem_base(self, model, dense=model%analysis%solver == solver_dense)
      associate (n => self%mesh%ndof, nd => self%mesh%ndriven, state => self%state)
         allocate (self%drive_step(nd), source=0.0_dp)
         allocate (state%q(n), state%v(n), state%a(n), self%qt(n), self%work(n), self%dq_new(n), self%dq_old(n), &
            & source=0.0_dp)
         call new_predictor_history(state%history, n)
         call new_prediction(self%prediction, n)
         allocate (state%jump_response(n, nd), self%jump_response_new(n, nd), source=0.0_dp)
         allocate (self%seg(size(self%mesh%slides)), state%seg(size(self%mesh%slides)), source=1)
      end associate
      self%loaded = self%mesh%loads%is_loaded()
      allocate (self%load_work(self%mesh%ndof), source=0.0_dp)
      self%fixed_dofs = pack([(i, i=1, self%mesh%ndof)], self%mesh%status(1:self%mesh%ndof) == dof_fixed)
      call new_strain_rate(self%root, self%mesh)
      self%kinetostatic = planned_effects(model) == effects_kinetostatics
      allocate (self%root_work(self%mesh%nfree), source=0.0_dp)
      call choose_form(self)
      self%conv%mode = model%analysis%convergence
      self%conv%tol = model%analysis%tol
      self%conv%length = model%analysis%length_tol*self%model_length
      self%admissible_strain = admissible_strain(model%analysis%tol)
      self%cut_advice = dead_point_advice
      if (.not. allocated(model%drives)) then
         self%cut_advice = limit_load_advice
      else if (size(model%drives) == 0) then
         self%cut_advice = limit_load_advice
      end if
      call new_branch_check(self%branch, model, self%mesh)
      self%conv%residual_floor = self%residual_floor
   end subroutine new_fem_core

   subroutine core_release_loads(self, loads)
      class(fem_core_type), intent(inout) :: self
      type(load_set_type), intent(out) :: loads
      loads = self%mesh%loads
      self%mesh%loads%f = 0
      self%loaded = .false.
      call choose_form(self)
   end subroutine core_release_loads

   !> The form of the linear systems: the square-root form where B_f is
   !> square and the motion unstressed (kinematics, and kinetostatics, whose
   !> loads act on its deflection, not on its motion: release_loads); a
   !> redundant mechanism's K-form rates refined with its strain rates
   !> there. Stressed configurations (loads, statics) have no such residual.
   subroutine choose_form(self)
      class(fem_core_type), intent(inout) :: self
      logical :: unstressed
      unstressed = .not. self%loaded .and. (self%kinetostatic .or. planned_effects(self%model) == effects_kinematics)
      self%root_form = self%root%applies .and. unstressed .and. self%model%analysis%solver /= solver_dense
      self%refined_rates = self%root%refines .and. unstressed
      if (self%refined_rates .and. .not. allocated(self%strain_work)) then
         allocate (self%strain_work(strain_rows(self%mesh)), source=0.0_dp)
      end if
   end subroutine choose_form

   subroutine core_set_loads(self, f)
      class(fem_core_type), intent(inout) :: self
      real(dp), intent(in) :: f(:, :)
      self%mesh%loads%f = f
   end subroutine core_set_loads

   subroutine core_set_start(self, q0)
      class(fem_core_type), intent(inout) :: self
      real(dp), intent(in) :: q0(:)
      self%mesh%q0 = q0
   end subroutine core_set_start

   pure logical function core_holds_accepted_factor(self) result(holds)
      class(fem_core_type), intent(in) :: self
      holds = self%factor%is_current()
   end function core_holds_accepted_factor

   !> K_ff x = rhs at the accepted configuration (kinetostatics' deflection,
   !> the only user): in the square-root form through B_f's factor
   !> (solve_material_tangent: the condition of B_f, not of K).
   subroutine core_solve_at_accepted(self, rhs)
      class(fem_core_type), intent(inout) :: self
      real(dp), contiguous, intent(inout) :: rhs(:, :)
      integer :: j
      if (.not. self%root_form) then
         call self%system%kff%solve(rhs)
         return
      end if
      do j = 1, size(rhs, 2)
         call solve_material_tangent(self%root, self%mesh, rhs(:, j))
      end do
   end subroutine core_solve_at_accepted

   !> The mesh for the listing's plan: its size, band and slideline penalties.
   function fem_plan_text(self) result(text)
      class(fem_core_type), intent(in) :: self
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

   !> Make q at time t the accepted configuration and push it on the history.
   subroutine accept(self, t, q)
      class(fem_core_type), intent(inout) :: self
      real(dp), intent(in) :: t
      real(dp), contiguous, intent(in) :: q(:)
      associate (state => self%state)
         call state%history%push(q, t)
         ! Same size (no reallocation on assignment to check).
         state%q(:) = q
         state%t = t
         state%seg(:) = self%seg
         if (has_note(state%note)) state%note = ''
         state%has_velocity = .false.
         state%has_acceleration = .false.
      end associate
      self%counts%steps = self%counts%steps + 1
   end subroutine accept

   !> The result of the accepted state: nodes and links, and the mesh's
   !> fields when VTK output is asked for.
   subroutine fill_result(self, result)
      class(fem_core_type), intent(in) :: self
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

   !> Record the pivot ratio of the factor behind a drive response (0 if
   !> none) in the run's reference: the predictor trusts a response as a
   !> velocity only away from stationary configurations.
   subroutine note_response_pivot(self, ratio)
      class(fem_core_type), intent(inout) :: self
      real(dp), intent(in) :: ratio
      self%response_pivot = ratio
      self%state%reference_pivot = max(self%state%reference_pivot, ratio)
   end subroutine note_response_pivot
   !> Put the note of a cut step (why it was cut: the first and the last
   !> rejection) before the configuration's own note, if it was cut.
   subroutine prepend_cuts_note(note, cuts)
      character(len=note_length), intent(inout) :: note
      type(step_cuts_type), intent(in) :: cuts
      if (.not. allocated(cuts%first)) return
      if (has_note(note)) then
         note = cuts%note()//'; '//trim(note)
      else
         note = cuts%note()
      end if
   end subroutine prepend_cuts_note

   !> The largest distance between two configurations over the dofs, in model
   !> sizes (rotations times the model size), and the dof where it is.
   pure subroutine model_distance(self, qa, qb, distance, worst_dof)
      class(fem_core_type), intent(in) :: self
      real(dp), intent(in) :: qa(:), qb(:)
      real(dp), intent(out) :: distance
      integer, intent(out) :: worst_dof
      real(dp) :: d
      integer :: i
      distance = 0
      worst_dof = 1
      do i = 1, self%mesh%ndof
         d = abs(qa(i) - qb(i))*self%dof_length(i)/self%model_length
         if (d > distance) then
            distance = d
            worst_dof = i
         end if
      end do
   end subroutine model_distance

   !> The error of a step at time t whose Newton iteration did not converge.
   pure subroutine no_convergence_error(t, iterations, residual, error)
      real(dp), intent(in) :: t, residual
      integer, intent(in) :: iterations
      type(error_type), allocatable, intent(out) :: error
      character(len=120) :: msg
      write (msg, '(a,es12.5,a,i0,a,es9.2)') 't = ', t, ': Newton did not converge in ', iterations, &
         & ' iterations (residual ', residual
      call analysis_error(error, trim(msg)//')', t=t)
   end subroutine no_convergence_error

end module fekap_fem_state
