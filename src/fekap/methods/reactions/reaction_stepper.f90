!> The finite element method with the reactions of a kinetostatic or a
!> static analysis: each step is the FEM's, then the reactions in
!> fekap_model_reactions' rows. The FEM itself is untouched: a kinematics
!> run does not pass here.
!>
!> Kinetostatics: the FEM gives the motion (positions, velocities,
!> accelerations); the loads of the masses and gravity along it, the
!> elastic deflection they cause (solved with the FEM's factor at the
!> accepted configuration, the one its rates used: of the material tangent,
!> or of B_f in the square-root form)
!> and the reactions follow (fekap_reactions_kinetostatics). The external loads
!> (LOADs) act in kinetostatics' loads, not on the motion: the stepper takes
!> them from the FEM's mesh, whose kinematics then runs unloaded.
!>
!> With OUTPut `deflection on` the deflection u of each node is a result of
!> the step (deflection.csv), and the run's largest, over every point of the
!> mesh, a note of its last step.
!>
!> Statics: the FEM solves the loaded equilibrium at each time on its loaded
!> path; the reactions are those of that equilibrium (fekap_reactions_statics).
!> A start whose loads (a dead load, the weights) the FEM's Newton cannot
!> take in one solve from the unloaded configuration is load stepped: the
!> loads times a factor from 0 to 1, cut in halves on failure and grown back
!> (fekap_stepping_step_control), each solve from the last equilibrium; the
!> listing's note of step 0 gives the factors.
module fekap_reactions_reaction_stepper
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, analysis_error, error_analysis
   use fekap_model, only: effects_statics
   use fekap_model_results, only: step_result_type, has_note
   use fekap_model_reactions, only: reaction_count
   use fekap_stepping_stepper, only: stepper_type
   use fekap_fem, only: fem_stepper_type
   use fekap_stepping_step_control, only: step_cuts_type, max_cuts, advance_by_cuts, limit_load_advice, try_accepted, try_failed, &
      & try_ended
   use fekap_strings, only: es_text
   use fekap_assembly_loads, only: load_set_type
   use fekap_reactions_kinetostatics, only: kinetostatics_type, new_kinetostatics, kinetostatic_loads, &
      & kinetostatic_reactions
   use fekap_reactions_statics, only: static_reactions
   implicit none
   private

   public :: reaction_stepper_type, new_reaction_stepper

   !> Statics' load stepping of the start (load_steps): the full loads, the
   !> full load's failure (replayed as the first try) and its iterations, the
   !> steps taken, their factors and the last failure, for the note and the
   !> error; the FEM's result through the tries.
   type :: load_steps_type
      real(dp), allocatable :: full(:, :)
      type(error_type), allocatable :: failure
      logical :: replay = .false.
      integer :: steps = 0, first_iterations = 0
      character(:), allocatable :: factors, last
      type(step_result_type) :: result
   end type load_steps_type

   type, extends(stepper_type) :: reaction_stepper_type
      type(fem_stepper_type) :: fem
      !> Whether the analysis is statics (else kinetostatics).
      logical :: statics = .false.
      !> The masses and the reaction rows.
      type(kinetostatics_type) :: kinetostatics
      !> Work over the dofs: the loads (statics: the residual), the deflection
      !> (statics: zero accelerations), the external loads; over the
      !> equations: the right-hand side.
      real(dp), allocatable :: f(:), u(:), external(:), rhs(:, :)
      !> Kinetostatics: the external loads (LOADs), which the FEM's motion does not see.
      type(load_set_type) :: loads
      !> Kinetostatics with OUTPut deflection: the run's largest deflection
      !> so far, its mesh point, step and time.
      logical :: deflection = .false.
      real(dp) :: largest = -1, largest_t = 0
      integer :: largest_point = 0, largest_step = 0
      !> (npoint): the link of each mesh point (its name in the note).
      integer, allocatable :: point_link(:)
      type(load_steps_type) :: load_steps
   contains
      procedure :: start => reaction_start
      procedure :: advance => reaction_advance
      procedure :: plan_text => reaction_plan_text
   end type reaction_stepper_type

contains

   !> Kinetostatics, or statics if `effects` is effects_statics, on a new FEM
   !> stepper (new_fem_stepper) of the model.
   subroutine new_reaction_stepper(self, fem, effects)
      type(reaction_stepper_type), intent(out) :: self
      type(fem_stepper_type), intent(in) :: fem
      integer, intent(in) :: effects
      self%fem = fem
      self%statics = effects == effects_statics
      if (.not. self%statics) then
         ! The motion is the kinematic one: the loads leave the FEM for the reactions.
         call self%fem%release_loads(self%loads)
      end if
      call new_kinetostatics(self%kinetostatics, fem%model, fem%mesh)
      self%deflection = .not. self%statics .and. fem%model%output%deflection
      if (self%deflection) call map_points(self)
      allocate (self%f(self%fem%mesh%ndof), self%u(self%fem%mesh%ndof), self%external(self%fem%mesh%ndof), &
         & source=0.0_dp)
      allocate (self%rhs(self%fem%mesh%nfree, 1), source=0.0_dp)
   end subroutine new_reaction_stepper

   !> The FEM's plan lines.
   function reaction_plan_text(self) result(text)
      class(reaction_stepper_type), intent(in) :: self
      character(:), allocatable :: text
      text = self%fem%plan_text()
      if (self%deflection) text = text//new_line('a')//'  deflection: the elastic deflection of every node '// &
         & 'in deflection.csv (OUTPut deflection on), the largest in the last step''s note'
   end function reaction_plan_text

   !> The link of each mesh point (a node on several links: one of them).
   subroutine map_points(self)
      type(reaction_stepper_type), intent(inout) :: self
      integer :: e
      associate (mesh => self%fem%mesh)
         allocate (self%point_link(mesh%npoint), source=0)
         do e = 1, size(mesh%elements)
            self%point_link(mesh%dof_point(mesh%edof(1, e))) = mesh%elink(e)
            self%point_link(mesh%dof_point(mesh%edof(4, e))) = mesh%elink(e)
         end do
      end associate
   end subroutine map_points

   subroutine reaction_start(self, result, error)
      class(reaction_stepper_type), intent(inout) :: self
      type(step_result_type), intent(inout) :: result
      type(error_type), allocatable, intent(out) :: error
      call self%fem%start(result, error)
      if (allocated(error) .and. self%statics) then
         if (error%kind == error_analysis) call load_steps(self, result, error)
      end if
      self%counts = self%fem%counts
      if (allocated(error)) return
      call add_reactions(self, result)
   end subroutine reaction_start

   !> Statics' start when Newton could not take the start's loads at once
   !> (`failure`, the FEM's error): the loads times a factor stepped from 0
   !> to 1 by the shared step control (advance_by_cuts over the load factor,
   !> load_try), each solve (the FEM's start) from the last equilibrium; the
   !> note of step 0 lists the factors.
   subroutine load_steps(self, result, error)
      type(reaction_stepper_type), intent(inout) :: self
      type(step_result_type), intent(inout) :: result
      type(error_type), allocatable, intent(inout) :: error
      type(step_cuts_type) :: cuts
      real(dp), allocatable :: q_start(:)
      integer :: iterations
      character(len=12) :: smallest
      associate (steps => self%load_steps)
         call move_alloc(error, steps%failure)
         steps%full = self%fem%mesh%loads%f
         q_start = self%fem%mesh%q0
         steps%replay = .true.
         steps%steps = 0
         steps%factors = ''
         steps%last = steps%failure%message
         steps%result = result
         steps%first_iterations = result%iterations
         call advance_by_cuts(self, load_try, load_between, 0.0_dp, 1.0_dp, 0, limit_load_advice, cuts, iterations, &
            & error)
         call self%fem%set_start(q_start)
         call self%fem%set_loads(steps%full)
         result = steps%result
         if (allocated(error)) then
            if (error%kind == error_analysis) then
               ! The load steps' reason stands alone, with what was reached.
               if (len(steps%factors) == 0) steps%factors = ' none'
               write (smallest, '(i0)') 2**max_cuts
               call analysis_error(error, 'the start''s loads did not converge at once, nor in load steps '// &
                  & 'from 0 to 1 (down to 1/'//trim(smallest)//' of the load; factors reached:'// &
                  & steps%factors//'): '//steps%failure%message//'; last: '//steps%last)
            end if
            return
         end if
         ! The full load's try (the FEM's start before load stepping) counts too.
         result%iterations = steps%first_iterations + iterations
         result%cuts = cuts%cuts
         block
            character(len=80) :: head
            write (head, '(a,i0,a,i0,a)') 'load stepped: ', steps%steps, ' load steps (', cuts%cuts, &
               & ' cuts) from the unloaded configuration, factors'
            result%note = trim(head)//steps%factors//' (the full load at once: '//steps%failure%message//')'
         end block
      end associate
   end subroutine load_steps

   !> A try of statics' load stepping (for advance_by_cuts): the FEM's start
   !> under the loads times `factor`. The full load's try was the FEM's start
   !> itself, and its failure is replayed (the first cut) without solving again.
   recursive subroutine load_try(stepper, factor, depth, iterations, outcome, reason)
      class(stepper_type), intent(inout) :: stepper
      real(dp), intent(in) :: factor
      integer, intent(in) :: depth
      integer, intent(out) :: iterations, outcome
      type(error_type), allocatable, intent(out) :: reason
      iterations = 0
      outcome = try_ended
      select type (self => stepper)
      type is (reaction_stepper_type)
         associate (steps => self%load_steps)
            if (steps%replay) then
               steps%replay = .false.
               reason = steps%failure
               outcome = try_failed
               return
            end if
            call self%fem%set_loads(factor*steps%full)
            call self%fem%start(steps%result, reason)
            iterations = steps%result%iterations
            if (allocated(reason)) then
               if (reason%kind == error_analysis) then
                  steps%last = reason%message
                  outcome = try_failed
               end if
               return
            end if
            ! The next solve starts from this equilibrium (only free dofs move:
            ! the supported and driven ones keep their start values).
            call self%fem%set_start(self%fem%state%q)
            steps%steps = steps%steps + 1
            steps%factors = steps%factors//' '//es_text(factor, 9, 3)
            outcome = try_accepted
         end associate
      end select
   end subroutine load_try

   !> Nothing between load steps.
   subroutine load_between(stepper, factor)
      class(stepper_type), intent(inout) :: stepper
      real(dp), intent(in) :: factor
   end subroutine load_between

   subroutine reaction_advance(self, t, result, error)
      class(reaction_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      type(step_result_type), intent(inout) :: result
      type(error_type), allocatable, intent(out) :: error
      call self%fem%advance(t, result, error)
      self%counts = self%fem%counts
      if (allocated(error)) return
      call add_reactions(self, result)
   end subroutine reaction_advance

   !> The reactions of the accepted step. Kinetostatics needs its
   !> accelerations (the FEM then holds the factor of the tangent there).
   !> Values near the deck's limits could overflow: such a step gets empty
   !> reaction columns, never an Inf or NaN.
   subroutine add_reactions(self, result)
      type(reaction_stepper_type), intent(inout) :: self
      type(step_result_type), intent(inout) :: result
      if (.not. allocated(result%reactions)) allocate (result%reactions(3, reaction_count(self%fem%model)))
      if (self%statics) then
         ! u is zero throughout: the zero accelerations of the elements' own weights.
         call static_reactions(self%kinetostatics, self%fem%mesh, self%fem%state%q, self%fem%state%t, &
            & self%fem%state%seg, self%f, self%u, result%reactions)
      else
         ! The result lives through the run: a step without accelerations has no
         ! reactions and no deflection (not the last step's).
         result%has_deflection = .false.
         result%has_reactions = self%fem%state%has_acceleration .and. self%fem%holds_accepted_factor()
         if (.not. result%has_reactions) then
            if (self%deflection) call note_largest(self, result)
            return
         end if
         call kinetostatic_step(self, result)
      end if
      result%has_reactions = all(abs(result%reactions) <= huge(1.0_dp))
   end subroutine add_reactions

   !> Kinetostatics' loads along the motion, the deflection they cause and the reactions.
   subroutine kinetostatic_step(self, result)
      type(reaction_stepper_type), intent(inout) :: self
      type(step_result_type), intent(inout) :: result
      integer :: k
      associate (mesh => self%fem%mesh)
         call kinetostatic_loads(self%kinetostatics, mesh, self%fem%state%a, self%f)
         if (self%loads%is_loaded()) then
            call self%loads%at(self%fem%state%t, self%external)
            self%f = self%f + self%external
         end if
         do k = 1, mesh%nfree
            self%rhs(k, 1) = self%f(mesh%eq_dof(k))
         end do
         call self%fem%solve_at_accepted(self%rhs)
         self%u = 0
         do k = 1, mesh%nfree
            self%u(mesh%eq_dof(k)) = self%rhs(k, 1)
         end do
         call kinetostatic_reactions(self%kinetostatics, mesh, self%fem%state%q, self%fem%state%seg, &
            & self%fem%state%a, self%f, self%u, result%reactions)
         if (self%deflection) call add_deflection(self, result)
      end associate
   end subroutine kinetostatic_step

   !> The nodes' deflection (u of their translations) as the step's result,
   !> and the run's largest over every mesh point so far.
   subroutine add_deflection(self, result)
      type(reaction_stepper_type), intent(inout) :: self
      type(step_result_type), intent(inout) :: result
      integer :: ip, nnode
      real(dp) :: size_
      associate (mesh => self%fem%mesh, model => self%fem%model)
         nnode = size(model%nodes)
         if (.not. allocated(result%deflection)) allocate (result%deflection(2, nnode))
         do ip = 1, nnode
            result%deflection(:, ip) = self%u(mesh%tdof(:, ip))
         end do
         result%has_deflection = all(abs(result%deflection) <= huge(1.0_dp))
         do ip = 1, mesh%npoint
            size_ = norm2(self%u(mesh%tdof(:, ip)))
            if (size_ > self%largest) then
               self%largest = size_
               self%largest_point = ip
               self%largest_step = result%step
               self%largest_t = self%fem%state%t
            end if
         end do
      end associate
      call note_largest(self, result)
   end subroutine add_deflection

   !> At the last step, the run's largest deflection as a note (whether or not
   !> that step has accelerations).
   subroutine note_largest(self, result)
      type(reaction_stepper_type), intent(in) :: self
      type(step_result_type), intent(inout) :: result
      integer :: ip
      character(len=40) :: step_text
      character(:), allocatable :: where_, text
      associate (model => self%fem%model)
         if (self%fem%state%t < model%analysis%t_end .or. self%largest_point == 0) return
         ip = self%largest_point
         if (ip <= size(model%nodes)) then
            where_ = 'node '//model%nodes(ip)%name
         else
            where_ = 'a point of link '//model%links(self%point_link(ip))%name
         end if
         write (step_text, '(a,i0)') ' at step ', self%largest_step
         text = 'largest elastic deflection '//trim(adjustl(es_text(self%largest, 12, 5)))//' at '//where_// &
            & trim(step_text)//' (t = '//trim(adjustl(es_text(self%largest_t, 12, 5)))//')'
         if (has_note(result%note)) then
            result%note = trim(result%note)//'; '//text
         else
            result%note = text
         end if
      end associate
   end subroutine note_largest

end module fekap_reactions_reaction_stepper
