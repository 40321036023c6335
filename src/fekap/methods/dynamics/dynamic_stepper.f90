!> Flexible dynamics on the FEM's mesh: the equations of motion
!> (fekap_dynamics_dynamic_system) integrated by generalized-alpha
!> (fekap_dynamics_generalized_alpha), each step solved by Newton on the band
!> iteration matrix K + c1 C + c2 M, or by the energy-momentum integrator
!> (fekap_dynamics_energy_momentum: its step's equations and band LU), cut in halves when it fails and grown
!> back (fekap_stepping_step_control). Drives prescribe their dofs' motion
!> (value, rate and second rate of their laws); what the drives and supports
!> apply is the residual on their dofs (reactions.csv, as kinetostatics'
!> rows). The start: the drives' kinematic velocities when they move the
!> whole mechanism (else rest), and the consistent accelerations of
!> M a0 = g(0) - P(q0) - C v0. Each step also gives the energies, the work of
!> loads and drives and the momenta (energy.csv).
!>
!> The stepper's data and the parts of its work live in the modules
!> fekap_dynamics_dynamic_data (state, iterate), fekap_dynamics_stepper_start
!> (the start), fekap_dynamics_alpha_step and fekap_dynamics_em_step (the
!> integrators' Newton solves), fekap_dynamics_step_contract (their
!> convergence contract) and fekap_dynamics_step_result (an accepted step's
!> rows, reactions and energies).
module fekap_dynamics_dynamic_stepper
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, analysis_error
   use fekap_model, only: model_type, integrator_energy_momentum
   use fekap_model_results, only: step_result_type, has_note
   use fekap_assembly_mesh, only: dof_driven, describe_dof
   use fekap_assembly_tracking, only: relocate
   use fekap_stepping_stepper, only: clock_seconds, phase_timed
   use fekap_fem_setup, only: new_fem_base, mesh_plan_line
   use fekap_stepping_step_control, only: step_cuts_type, advance_by_cuts, dynamics_advice, try_accepted, try_failed, &
      & try_ended
   use fekap_stepping_stepper, only: stepper_type
   use fekap_dynamics_generalized_alpha, only: alpha_coefficients_type, new_alpha_coefficients
   use fekap_dynamics_dynamic_system, only: new_dynamic_system, kinetic_energy, strain_energy, has_damping, &
      & has_slide_damping, damping_work, penalty_energy
   use fekap_dynamics_energy_momentum, only: new_em_system, em_dissipation, massless_dofs
   use fekap_reactions_kinetostatics, only: new_kinetostatics
   use fekap_strings, only: es_text
   use fekap_stepping_newton, only: newton_report_type, stop_at_floor
   use fekap_dynamics_dynamic_data, only: dynamic_data_type, dynamic_state_type, energy_names, energy_count
   use fekap_dynamics_stepper_start, only: start_dynamics
   use fekap_dynamics_alpha_step, only: alpha_newton
   use fekap_dynamics_em_step, only: em_newton
   use fekap_dynamics_step_result, only: fill_result, keep_step_start
   use fekap_dynamics_local_error, only: step_local_error, adapted_step, least_step
   use fekap_stepping_interrupt, only: interrupt_signal
   implicit none
   private

   public :: dynamic_stepper_type, new_dynamic_stepper, dynamic_state_type, energy_names, energy_count

   !> A step that creates more energy than this fraction of the kinetic and
   !> strain energy (or of the step's work) is rejected and cut.
   real(dp), parameter :: max_created = 0.05_dp


   !> The dynamics stepper: its data (dynamic_data_type) with the start and
   !> the advance of the stepper_type interface.
   type, extends(dynamic_data_type) :: dynamic_stepper_type
   contains
      procedure :: start => dynamic_start
      procedure :: advance => dynamic_advance
      procedure :: plan_text => dynamic_plan_text
   end type dynamic_stepper_type

contains

   !> The mesh and storage for a validated model with masses.
   subroutine new_dynamic_stepper(self, model)
      type(dynamic_stepper_type), intent(out) :: self
      type(model_type), intent(in) :: model
      integer :: n
      call new_fem_base(self, model, dense=.false.)
      call new_dynamic_system(self%dynamics, model, self%mesh)
      call new_kinetostatics(self%rows, model, self%mesh)
      ! Corrections near round-off measure no Newton constant.
      self%reuse%least = 1.0e3_dp*epsilon(1.0_dp)*self%model_length
      self%damped = has_damping(self%dynamics)
      self%slide_damped = has_slide_damping(self%dynamics)
      if (model%analysis%integrator == integrator_energy_momentum) then
         call new_em_system(self%em, self%mesh)
         self%massless = massless_dofs(self%dynamics, self%mesh)
      end if
      n = self%mesh%ndof
      allocate (self%state%q(n), self%state%v(n), self%state%acc(n), self%state%a(n), self%state%g(n), &
         & self%state%r(n), source=0.0_dp)
      allocate (self%qt(n), self%vt(n), self%acct(n), self%at(n), self%gt(n), self%zt(n), self%dzt(n), source=0.0_dp)
      allocate (self%state%seg(size(self%mesh%slides)), source=1)
   end subroutine new_dynamic_stepper

   !> The mesh and the integrator for the listing's plan.
   function dynamic_plan_text(self) result(text)
      class(dynamic_stepper_type), intent(in) :: self
      character(:), allocatable :: text
      character(len=200) :: line
      type(alpha_coefficients_type) :: c
      c = new_alpha_coefficients(self%model%analysis%rho_inf, self%model%analysis%dt)
      text = mesh_plan_line(self)
      if (self%model%analysis%integrator == integrator_energy_momentum) then
         write (line, '(a,f6.4,a,f7.4,a)') 'integrator: energy-momentum (midpoint rule, discrete gradient), rho_inf ', &
            & c%rho_inf, ' (strain dissipation chi ', em_dissipation(c%rho_inf), ')'
      else
         write (line, '(a,f6.4,a,f7.4,a,f7.4,a,f7.4,a,f7.4,a)') 'integrator: generalized-alpha (Chung-Hulbert), rho_inf ', &
            & c%rho_inf, ' (alpha_m ', c%am, ', alpha_f ', c%af, ', beta ', c%beta, ', gamma ', c%gamma, ')'
      end if
      text = text//new_line('a')//'  '//trim(line)
      if (self%model%analysis%adaptive) text = text//new_line('a')//'  steps: adaptive, each step''s local error '// &
         & 'estimate at most '//trim(adjustl(es_text(self%model%analysis%adaptive_tol, 10, 3)))// &
         & ' (rows at the output instants)'
      if (len_trim(self%start_velocity) > 0) text = text//new_line('a')//'  start: '//trim(self%start_velocity)
      if (len_trim(self%start_state) > 0) text = text//new_line('a')//'  start state: '//trim(self%start_state)
   end function dynamic_plan_text

   !> The start: velocities, consistent accelerations, energies (start_dynamics).
   subroutine dynamic_start(self, result, error)
      class(dynamic_stepper_type), intent(inout) :: self
      type(step_result_type), intent(inout) :: result
      type(error_type), allocatable, intent(out) :: error
      call start_dynamics(self, result, error)
   end subroutine dynamic_start

   !> Advance to time t under step control (the kinematics' loop,
   !> advance_by_cuts: a failed step is cut, and grows back), or by adaptive
   !> steps (adaptive_advance) when the deck asks for them.
   subroutine dynamic_advance(self, t, result, error)
      class(dynamic_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      type(step_result_type), intent(inout) :: result
      type(error_type), allocatable, intent(out) :: error
      type(step_cuts_type) :: cuts
      real(dp) :: clock
      self%advances = self%advances + 1
      self%system%timing = phase_timed(self%advances)
      clock = 0
      if (self%system%timing) clock = clock_seconds()
      self%try_residual = 0
      self%try_floor = 0
      self%advance_estimate = 0
      if (self%model%analysis%adaptive) then
         call adaptive_advance(self, t, result%iterations, result%cuts, error)
      else
         call advance_by_cuts(self, dynamic_try, no_between, self%state%t, t, 0, dynamics_advice, cuts, &
            & result%iterations, error)
         result%cuts = cuts%cuts
      end if
      if (.not. allocated(error)) then
         result%residual = self%try_residual
         call fill_result(self, result)
         ! The result lives through the run: a note of an earlier step must not stay.
         if (has_note(result%note)) result%note = ''
         if (allocated(cuts%first)) result%note = cuts%note()
      end if
      ! A failed step's phases were timed too: its time is sampled with them
      ! (else the summary scales them to many times the run's).
      if (self%system%timing) self%counts%seconds_sampled = self%counts%seconds_sampled + (clock_seconds() - clock)
   end subroutine dynamic_advance

   !> A try of one step to time t (for advance_by_cuts): failed when Newton
   !> fails (advance_by_cuts ends the advance instead of cutting when a
   !> signal stopped it).
   recursive subroutine dynamic_try(stepper, t, depth, iterations, outcome, reason)
      class(stepper_type), intent(inout) :: stepper
      real(dp), intent(in) :: t
      integer, intent(in) :: depth
      integer, intent(out) :: iterations, outcome
      type(error_type), allocatable, intent(out) :: reason
      outcome = try_ended
      iterations = 0
      ! No verification by half steps here: every try is at depth 0.
      if (depth /= 0) return
      select type (self => stepper)
      class is (dynamic_stepper_type)
         call solve_step(self, t, huge(1.0_dp), iterations, self%try_residual, reason)
         outcome = merge(try_failed, try_accepted, allocated(reason))
      end select
   end subroutine dynamic_try

   !> Adaptive steps to time t (`time T0 T1 DT adaptive TOL`): each step's
   !> local error estimate (fekap_dynamics_local_error) must stay at or below
   !> TOL. A step above it is rejected and tried again shorter, by the
   !> controller (adapted_step); a step whose Newton solve fails, at half
   !> its length. An accepted step sets the next one's length by the same
   !> controller. The steps land on t exactly (a step that would end less
   !> than its own length before t is cut to half the rest). A step that
   !> must be shorter than least_step (T1 - T0) ends the run with an error
   !> naming the time and the estimate. `rejected`: the steps tried again.
   subroutine adaptive_advance(self, t, iterations, rejected, error)
      type(dynamic_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      integer, intent(out) :: iterations, rejected
      type(error_type), allocatable, intent(out) :: error
      type(error_type), allocatable :: reason
      real(dp) :: h, h_min, rest, tol, t_new
      integer :: its
      character(len=400) :: msg
      logical :: clipped
      tol = self%model%analysis%adaptive_tol
      h_min = least_step*(self%model%analysis%t_end - self%model%analysis%t_start)
      iterations = 0
      rejected = 0
      ! The first step: the output interval (the controller shortens it at once if need be).
      if (self%h_next <= 0) self%h_next = t - self%state%t
      do while (self%state%t < t)
         rest = t - self%state%t
         h = self%h_next
         clipped = h >= rest
         if (clipped) then
            h = rest
            t_new = t
         else
            if (2*h > rest) h = 0.5_dp*rest
            t_new = self%state%t + h
         end if
         call solve_step(self, t_new, tol, its, self%try_residual, reason)
         iterations = iterations + its
         if (.not. allocated(reason) .and. self%try_estimate <= tol) then
            ! Accepted: a step shortened to land on t does not shorten the next.
            if (clipped) then
               self%h_next = max(self%h_next, adapted_step(h, self%try_estimate, tol))
            else
               self%h_next = adapted_step(h, self%try_estimate, tol)
            end if
            cycle
         end if
         if (allocated(reason) .and. interrupt_signal() /= 0) then
            call move_alloc(reason, error)
            return
         end if
         rejected = rejected + 1
         self%counts%rejected_steps = self%counts%rejected_steps + 1
         if (allocated(reason)) then
            self%h_next = 0.5_dp*h
         else
            self%h_next = adapted_step(h, self%try_estimate, tol)
         end if
         if (self%h_next < h_min) then
            if (allocated(reason)) then
               write (msg, '(a,a,a,a,a)') 't = ', trim(adjustl(es_text(self%state%t, 12, 5))), &
                  & ': the adaptive step cannot be shortened below the least step ', &
                  & trim(adjustl(es_text(h_min, 10, 3))), ' (1e-12 (T1 - T0)): '//reason%message
            else
               write (msg, '(a,a,a,a,a,a,a,a,a)') 't = ', trim(adjustl(es_text(self%state%t, 12, 5))), &
                  & ': the adaptive step cannot meet the tolerance ', trim(adjustl(es_text(tol, 10, 3))), &
                  & ': the local error estimate is ', trim(adjustl(es_text(self%try_estimate, 10, 3))), &
                  & ' at a step of ', trim(adjustl(es_text(h, 10, 3))), &
                  & ', and a shorter step would be below the least step (1e-12 (T1 - T0))'
            end if
            call analysis_error(error, trim(msg))
            return
         end if
      end do
   end subroutine adaptive_advance

   !> Between the steps of a cut advance: nothing (the accepted state is all
   !> the next step needs).
   subroutine no_between(stepper, t)
      class(stepper_type), intent(inout) :: stepper
      real(dp), intent(in) :: t
   end subroutine no_between

   !> One step from the accepted state to t_new (generalized-alpha or the
   !> energy-momentum integrator) with its local error estimate (try_estimate);
   !> the state is left untouched on failure, and when the estimate is above
   !> `limit` (the adaptive tolerance; huge: every converged step is accepted).
   subroutine solve_step(self, t_new, limit, iterations, residual, error)
      type(dynamic_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t_new, limit
      integer, intent(out) :: iterations
      real(dp), intent(out) :: residual
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: work_loads, work_drives, dissipated, kinetic, strain, penalty, energy, created
      real(dp) :: z(self%mesh%ndof)
      integer :: d
      integer :: seg(size(self%state%seg))
      logical :: moved, em
      character(len=300) :: msg
      type(newton_report_type) :: report
      em = self%model%analysis%integrator == integrator_energy_momentum
      associate (state => self%state, mesh => self%mesh, system => self%system, dyn => self%dynamics)
         if (em) then
            call em_newton(self, t_new, report, error)
         else
            call alpha_newton(self, t_new, report, error)
         end if
         iterations = report%iterations
         residual = report%last_residual
         if (allocated(error)) return
         if (.not. all(abs(self%qt) <= huge(1.0_dp))) then
            call analysis_error(error, 'the configuration is not finite')
            return
         end if
         call step_local_error(self, t_new - state%t)
         if (self%try_estimate > limit) return
         ! Work over the step: the trapezoidal rule of the forces on the
         ! displacement (exact for the trapezoidal integrator of a linear system);
         ! energy-momentum: on its increments z (Cayley's psi on rotations).
         if (em) then
            z = self%zt
         else
            z = self%qt - state%q
         end if
         work_loads = 0
         work_drives = 0
         do d = 1, mesh%ndof
            associate (dq => z(d))
               work_loads = work_loads + 0.5_dp*(state%g(d) + self%gt(d) - 2*dyn%weight(d))*dq
               ! Energy-momentum: the residual is the step's reaction.
               if (mesh%status(d) == dof_driven .and. em) then
                  work_drives = work_drives + system%r(d)*dq
               else if (mesh%status(d) == dof_driven) then
                  work_drives = work_drives + 0.5_dp*(state%r(d) + system%r(d))*dq
               end if
            end associate
         end do
         dissipated = 0
         if (self%damped .and. em) then
            ! Energy-momentum: the damping acts on the step's mean rate z/h (exactly this work).
            dissipated = damping_work(dyn, mesh, state%q, z/(t_new - state%t), self%qt, z/(t_new - state%t), state%seg, &
               & t_new - state%t, z)
         else if (self%damped .or. self%slide_damped) then
            dissipated = damping_work(dyn, mesh, state%q, state%v, self%qt, self%vt, state%seg, t_new - state%t)
         end if
         kinetic = kinetic_energy(dyn, mesh, self%vt)
         strain = strain_energy(mesh, self%qt)
         ! The springs of the step's own segments (those its forces used).
         penalty = penalty_energy(mesh, self%qt, state%seg)
         energy = kinetic + strain + penalty - dot_product(dyn%weight, self%qt)
         ! The integrator dissipates (rho_inf < 1) or keeps (1) energy: a step
         ! that creates much of it has jumped to another solution of its
         ! nonlinear equations (stiff modes of a large motion); a shorter one does not.
         created = energy - state%energy - work_loads - work_drives + dissipated
         if (created > max_created*max(kinetic + strain, state%kinetic + state%strain, abs(work_loads + work_drives))) &
            & then
            write (msg, '(a,a,a,a,a)') 'the step creates energy (', es_text(created, 12, 4), ' against ', &
               & es_text(kinetic + strain, 12, 4), ' kinetic and strain): a jump to another solution of its equations'
            call analysis_error(error, trim(msg))
            return
         end if
         seg = state%seg
         call relocate(mesh, self%model, t_new, self%qt, seg, moved, error)
         if (allocated(error)) return
         if (em) call keep_step_start(self, t_new - state%t)
         state%seg = seg
         if (em) self%h_prev = t_new - state%t
         state%work_loads = state%work_loads + work_loads
         state%work_drives = state%work_drives + work_drives
         state%dissipated = state%dissipated + dissipated
         state%kinetic = kinetic
         state%strain = strain
         state%penalty = penalty
         state%energy = energy
         state%t = t_new
         state%q = self%qt
         state%v = self%vt
         state%acc = self%acct
         state%a = self%at
         state%g = self%gt
         state%r = system%r
         self%counts%steps = self%counts%steps + 1
         if (report%stopped == stop_at_floor) then
            self%counts%floor_steps = self%counts%floor_steps + 1
            self%try_floor = self%try_floor + 1
         end if
         self%advance_estimate = max(self%advance_estimate, self%try_estimate)
         if (self%try_estimate > self%counts%largest_estimate) then
            self%counts%largest_estimate = self%try_estimate
            self%counts%largest_estimate_t = t_new
            self%counts%largest_estimate_where = ''
            if (self%try_estimate_dof > 0) self%counts%largest_estimate_where = &
               & describe_dof(mesh, self%model, self%try_estimate_dof)
         end if
      end associate
   end subroutine solve_step

end module fekap_dynamics_dynamic_stepper
