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
!> Over 600 lines: the stepper's start, the two integrators' Newton loops and
!> the energy, work and reactions of an accepted step all work on the one
!> stepper state (iterate, accepted state, step control); the equations
!> themselves live in the modules named above.
module fekap_dynamics_dynamic_stepper
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, analysis_error
   use fekap_model, only: model_type, integrator_energy_momentum
   use fekap_model_results, only: step_result_type, has_note
   use fekap_assembly_mesh, only: mesh_type, dof_driven, dof_fixed, dof_free
   use fekap_assembly_tracking, only: relocate, slide_position
   use fekap_assembly_assemble, only: scatter_element
   use fekap_stepping_stepper, only: clock_seconds, phase_timed
   use fekap_fem_setup, only: fem_base_type, new_fem_base, start_configuration, mesh_plan_line
   use fekap_fem_linear_system, only: assemble_system, factor_system, &
      & system_pivot, residual_norm, newton_correction, solve_system
   use fekap_stepping_step_control, only: step_cuts_type, advance_by_cuts, try_accepted, try_failed, try_ended
   use fekap_stepping_stepper, only: stepper_type
   use fekap_stepping_interrupt, only: interrupt_error
   use fekap_fem_fields, only: fill_nodes_links, fill_fields
   use fekap_dynamics_generalized_alpha, only: alpha_coefficients_type, new_alpha_coefficients, alpha_predict, &
      & alpha_update
   use fekap_dynamics_dynamic_system, only: dynamic_system_type, new_dynamic_system, external_forces, &
      & assemble_dynamics, kinetic_energy, strain_energy, momentum, has_damping, times6, &
      & has_slide_damping, damping_work, element_damping_force, slide_damping_force, penalty_energy
   use fekap_dynamics_energy_momentum, only: em_system_type, new_em_system, em_dissipation, assemble_em, factor_em, &
      & solve_em, em_free_velocities, massless_dofs, em_increments
   use fekap_reactions_kinetostatics, only: kinetostatics_type, new_kinetostatics, slider_force
   use fekap_model_reactions, only: reaction_count
   use fekap_strings, only: es_text
   use fekap_fem_convergence, only: divergence_length
   use fekap_stepping_newton, only: newton_system_type, newton_contract_type, newton_report_type, newton_solve, &
      & kept_factor_type, always_refactor_type, stop_spent, stop_not_finite, stop_singular, stop_at_floor
   use fekap_dynamics_consistent_start, only: start_report_type, consistent_start
   implicit none
   private

   public :: dynamic_stepper_type, new_dynamic_stepper, dynamic_state_type, energy_names

   !> The columns of energy.csv after step,t (see dynamic_stepper_type's energy).
   character(*), parameter :: energy_names = 'kinetic,strain,penalty,gravity,work_loads,work_drives,dissipated,'// &
      & 'balance,px,py,angular'
   integer, parameter, public :: energy_count = 11
   !> A step that creates more energy than this fraction of the kinetic and
   !> strain energy (or of the step's work) is rejected and cut.
   real(dp), parameter :: max_created = 0.05_dp

   !> The accepted state: time, configuration, velocity, acceleration, the
   !> integrator's acceleration variable a, the external forces, the residual
   !> (the constrained dofs' reactions), and the accumulated work.
   type :: dynamic_state_type
      real(dp) :: t = 0
      real(dp), allocatable :: q(:), v(:), acc(:), a(:), g(:), r(:)
      integer, allocatable :: seg(:)
      !> Work of the loads, of the drives, and the energy the damping dissipated.
      real(dp) :: work_loads = 0, work_drives = 0, dissipated = 0
      !> Kinetic and strain energy, and their sum with the gravity potential.
      !> (penalty: the slidelines' springs.)
      real(dp) :: kinetic = 0, strain = 0, penalty = 0, energy = 0
   end type dynamic_state_type

   !> The model, mesh, linear system, drives' start values and scales are
   !> the FEM's (fem_base_type, new_fem_base).
   type, extends(fem_base_type) :: dynamic_stepper_type
      type(dynamic_system_type) :: dynamics
      type(kinetostatics_type) :: rows
      type(dynamic_state_type) :: state
      !> The energy-momentum integrator's band LU storage (if it integrates).
      type(em_system_type) :: em
      !> The iterate of a step.
      real(dp), allocatable :: qt(:), vt(:), acct(:), at(:), gt(:)
      !> Energy-momentum: the iterate's increments z and dz/dq1 (em_increments).
      real(dp), allocatable :: zt(:), dzt(:)
      !> Energy of the start (kinetic + strain + gravity), for the balance.
      real(dp) :: energy0 = 0
      !> Velocities at the start over all dofs, if given (tests, benchmarks);
      !> else the drives' kinematic velocities.
      real(dp), allocatable :: v_start(:)
      !> Whether some element is damped (has_damping), and some slideline
      !> (has_slide_damping: generalized-alpha only, see effects.f90's plan).
      logical :: damped = .false., slide_damped = .false.
      !> Energy-momentum: the dofs without mass (their velocities are the
      !> rates of the mean rates, see em_velocities), and the last step's length.
      logical, allocatable :: massless(:)
      real(dp) :: h_prev = 0
      !> Energy-momentum: the start (q0, v0, master segments) and length of
      !> the last accepted step, for its reactions (fill_reactions: the
      !> elements' end forces of the step's own equations); em_h 0 at the start.
      real(dp), allocatable :: em_q0(:), em_v0(:)
      integer, allocatable :: em_seg(:)
      real(dp) :: em_h = 0
      !> The residual of the last step tried (advance_by_cuts' tries), and
      !> the steps of the current advance accepted at the round-off floor.
      real(dp) :: try_residual = 0
      integer :: try_floor = 0
      !> Generalized-alpha's kept factor (fekap_stepping_newton's
      !> kept_factor_type; its contraction 0: every iteration factors afresh).
      type(kept_factor_type) :: reuse
      !> How the start's velocities were found, for the plan.
      character(len=120) :: start_velocity = ''
      !> How the start's configuration and accelerations were found (consistent_start), for the plan.
      character(len=200) :: start_state = ''
      integer :: advances = 0
   contains
      procedure :: start => dynamic_start
      procedure :: advance => dynamic_advance
      procedure :: plan_text => dynamic_plan_text
   end type dynamic_stepper_type

   !> A generalized-alpha step's equations for newton_solve: the stepper
   !> (its iterate, system and counts; associated for one solve) and the
   !> step's coefficients.
   type, extends(newton_system_type) :: alpha_system_type
      type(dynamic_stepper_type), pointer :: s => null()
      type(alpha_coefficients_type) :: c
      real(dp) :: t_new = 0
   contains
      procedure :: assemble => alpha_assemble
      procedure :: factor => alpha_factor
      procedure :: correct => alpha_correct
   end type alpha_system_type

   !> An energy-momentum step's equations for newton_solve: the stepper
   !> (associated for one solve), the step's length and strain dissipation.
   type, extends(newton_system_type) :: em_newton_system_type
      type(dynamic_stepper_type), pointer :: s => null()
      real(dp) :: h = 0, chi = 0
   contains
      procedure :: assemble => em_assemble
      procedure :: factor => em_factor
      procedure :: correct => em_correct
   end type em_newton_system_type

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
      if (len_trim(self%start_velocity) > 0) text = text//new_line('a')//'  start: '//trim(self%start_velocity)
      if (len_trim(self%start_state) > 0) text = text//new_line('a')//'  start state: '//trim(self%start_state)
   end function dynamic_plan_text

   !> The start: velocities, consistent accelerations, energies.
   subroutine dynamic_start(self, result, error)
      class(dynamic_stepper_type), intent(inout) :: self
      type(step_result_type), intent(inout) :: result
      type(error_type), allocatable, intent(out) :: error
      type(start_report_type) :: report
      integer :: info
      associate (state => self%state, mesh => self%mesh)
         ! The drives' start values law0 are new_fem_base's.
         call start_configuration(self, state%t, state%q, state%seg, error)
         if (allocated(error)) return
         call drive_motion(self, state%t, state%q, state%v, state%acc)
         call start_velocities(self, info)
         if (self%model%analysis%start_unstrained) then
            call start_accelerations(self, error)
            self%start_state = 'unstrained, accelerations of M a = -R (ANALysis start unstrained)'
         else
            call external_forces(self%dynamics, mesh, state%t, state%g)
            call consistent_start(self%dynamics, self%system, mesh, state%q, state%v, state%acc, state%t, state%seg, &
               & self%counts, report, error)
            state%r = self%system%r
            call describe_start(self, report)
            if (.not. allocated(error) .and. .not. report%usable) call start_accelerations(self, error)
         end if
         if (allocated(error)) return
         state%a = state%acc
         state%work_loads = 0
         state%work_drives = 0
         state%dissipated = 0
         state%kinetic = kinetic_energy(self%dynamics, mesh, state%v)
         state%strain = strain_energy(mesh, state%q)
         state%penalty = penalty_energy(mesh, state%q, state%seg)
         state%energy = state%kinetic + state%strain + state%penalty - dot_product(self%dynamics%weight, state%q)
         self%energy0 = state%energy
         result%iterations = 0
         result%residual = 0
         call fill_result(self, result)
         ! The plan is written before the start: the listing's note of step 0 says how it went.
         if (.not. self%model%analysis%start_unstrained) then
            result%note = 'start: '//trim(self%start_velocity)//'; '//trim(self%start_state)
         end if
      end associate
   end subroutine dynamic_start

   !> The plan's line on a consistent start.
   subroutine describe_start(self, report)
      type(dynamic_stepper_type), intent(inout) :: self
      type(start_report_type), intent(in) :: report
      character(len=200) :: line
      write (line, '(a,es9.2,a,i0,a,i0,a,i0,a,es9.2,a)') 'consistent (rigid-link accelerations; deflection up to ', &
         & report%deflection, '; ', report%passes, ' passes of ', report%iterations_a, ' + ', report%iterations_delta, &
         & ' iterations; residual ', report%residual, ' of the forces)'
      if (.not. report%converged) line = trim(line)//': the iterations stopped short'
      if (.not. report%usable) then
         write (line, '(a,es9.2,a)') 'unstrained, accelerations of M a = -R: the consistent start left ', &
            & report%residual, ' of the forces unbalanced (links too flexible for its linear deflection)'
      end if
      self%start_state = line
   end subroutine describe_start

   !> Velocities at the start: given (v_start), or those the drives' rates
   !> give a mechanism they move whole (K_ff v_f = -K_fd v_d with the material
   !> tangent at the unstrained start, as the kinematics' (47)), else the
   !> drives' own rates with the rest at rest.
   subroutine start_velocities(self, info)
      type(dynamic_stepper_type), intent(inout) :: self
      integer, intent(out) :: info
      integer :: k, j
      real(dp) :: ratio
      info = 0
      associate (state => self%state, mesh => self%mesh, system => self%system)
         if (.not. allocated(self%v_start) .and. allocated(self%model%start_velocities)) then
            if (size(self%model%start_velocities) > 0) call deck_velocities(self)
         end if
         if (allocated(self%v_start)) then
            state%v = self%v_start
            call drive_motion(self, state%t, self%qt, state%v, self%acct)
            self%start_velocity = 'velocities given (VELOcities), the other links at rest'
            return
         end if
         self%start_velocity = 'at rest'
         if (mesh%ndriven == 0 .or. all(self%law_rate == 0)) return
         call assemble_system(system, mesh, state%q, state%t, state%seg, huge(1.0_dp), self%counts)
         call factor_system(system, info, self%counts)
         ratio = 0
         if (info == 0) call system_pivot(system, ratio)
         if (info /= 0 .or. ratio < 1.0e-12_dp) then
            self%start_velocity = 'the drives'' rates, the rest at rest (the drives do not move the whole mechanism)'
            return
         end if
         system%rhs(:, 1) = 0
         do j = 1, mesh%ndriven
            system%rhs(:, 1) = system%rhs(:, 1) - self%law_rate(j)*system%kfd(:, j)
         end do
         call solve_system(system, self%counts)
         do k = 1, mesh%nfree
            state%v(mesh%eq_dof(k)) = system%rhs(k, 1)
         end do
         self%start_velocity = 'the drives'' kinematic velocities'
      end associate
   end subroutine start_velocities

   !> v_start from the deck's VELOcities: each listed link's rigid motion on
   !> its elements' dofs; the dofs of links not listed at rest, but for their
   !> ends at nodes of listed links.
   subroutine deck_velocities(self)
      type(dynamic_stepper_type), intent(inout) :: self
      integer :: i, e, a, l
      real(dp) :: x1(2)
      allocate (self%v_start(self%mesh%ndof), source=0.0_dp)
      associate (mesh => self%mesh, model => self%model)
         do i = 1, size(model%start_velocities)
            associate (sv => model%start_velocities(i))
               l = sv%link
               x1 = model%nodes(model%links(l)%node(1))%x
               do e = 1, size(mesh%elements)
                  if (mesh%elink(e) /= l) cycle
                  do a = 0, 1
                     self%v_start(mesh%edof(3*a + 1:3*a + 2, e)) = sv%velocity_at(x1, &
                        & mesh%q0(mesh%edof(3*a + 1:3*a + 2, e)))
                     self%v_start(mesh%edof(3*a + 3, e)) = sv%omega
                  end do
               end do
            end associate
         end do
      end associate
   end subroutine deck_velocities

   !> The consistent accelerations at the start: M_ff a_f = -R_f with R at
   !> a_f = 0 (the drives' second rates on theirs). A free dof without mass
   !> (its row of M is zero) keeps a = 0: its equation is static.
   subroutine start_accelerations(self, error)
      type(dynamic_stepper_type), intent(inout) :: self
      type(error_type), allocatable, intent(out) :: error
      integer :: k, e, info
      real(dp) :: mdiag
      associate (state => self%state, mesh => self%mesh, system => self%system, dyn => self%dynamics)
         call external_forces(dyn, mesh, state%t, state%g)
         do k = 1, mesh%nfree
            state%acc(mesh%eq_dof(k)) = 0
         end do
         call assemble_dynamics(dyn, system, mesh, state%q, state%v, state%acc, state%t, state%seg, self%counts)
         state%r = system%r
         call system%kff%zero()
         do e = 1, size(mesh%elements)
            ! M_ff only: no entries into the free-driven block.
            call scatter_element(mesh%scatter_map(:, :, e), mesh%scatter_count(1, e), 0, dyn%me(:, :, e), &
               & system%kff%a, system%kfd)
         end do
         do k = 1, mesh%nfree
            mdiag = system%kff%a(mesh%kd + 1, k) + dyn%point_mass(mesh%eq_dof(k))
            system%kff%a(mesh%kd + 1, k) = mdiag
            system%rhs(k, 1) = -state%r(mesh%eq_dof(k))
            if (mdiag == 0) then
               system%kff%a(mesh%kd + 1, k) = 1
               system%rhs(k, 1) = 0
            end if
         end do
         call factor_system(system, info, self%counts)
         if (info /= 0) then
            call analysis_error(error, 'the mass matrix is singular at the start: consistent accelerations '// &
               & 'cannot be found (give every moving dof a mass)')
            return
         end if
         call solve_system(system, self%counts)
         do k = 1, mesh%nfree
            state%acc(mesh%eq_dof(k)) = system%rhs(k, 1)
         end do
         ! The start's residual with its accelerations: the reactions there.
         call assemble_dynamics(dyn, system, mesh, state%q, state%v, state%acc, state%t, state%seg, self%counts)
         state%r = system%r
      end associate
   end subroutine start_accelerations

   !> The drives' dofs at time t: value, rate, second rate of their laws.
   subroutine drive_motion(self, t, q, v, acc)
      type(dynamic_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      real(dp), intent(inout) :: q(:), v(:), acc(:)
      integer :: i, dof
      if (self%mesh%ndriven == 0) return
      call self%model%drives%law%eval(t, self%law_value, self%law_rate, self%law_rate2)
      do i = 1, self%mesh%ndriven
         dof = self%mesh%driven_dof(i)
         q(dof) = self%mesh%q0(dof) + (self%law_value(i) - self%law0(i))
         v(dof) = self%law_rate(i)
         acc(dof) = self%law_rate2(i)
      end do
   end subroutine drive_motion

   !> Advance to time t under step control (the kinematics' loop,
   !> advance_by_cuts: a failed step is cut, and grows back).
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
      call advance_by_cuts(self, dynamic_try, no_between, self%state%t, t, 0, cuts, result%iterations, error)
      if (allocated(error)) return
      result%residual = self%try_residual
      result%cuts = cuts%cuts
      call fill_result(self, result)
      ! The result lives through the run: a note of an earlier step must not stay.
      if (has_note(result%note)) result%note = ''
      if (allocated(cuts%first)) result%note = cuts%note()
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
         call solve_step(self, t, iterations, self%try_residual, reason)
         outcome = merge(try_failed, try_accepted, allocated(reason))
      end select
   end subroutine dynamic_try

   !> Between the steps of a cut advance: nothing (the accepted state is all
   !> the next step needs).
   subroutine no_between(stepper, t)
      class(stepper_type), intent(inout) :: stepper
      real(dp), intent(in) :: t
   end subroutine no_between

   !> One step from the accepted state to t_new (generalized-alpha or the
   !> energy-momentum integrator); the state is left untouched on failure.
   subroutine solve_step(self, t_new, iterations, residual, error)
      type(dynamic_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t_new
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
      end associate
   end subroutine solve_step

   !> Newton on a step of generalized-alpha from the accepted state to
   !> t_new (fekap_stepping_newton's newton_solve on alpha_system_type,
   !> with the stepper's kept factor): the iterate into qt, vt, acct, at and
   !> the residual (the reactions) into system%r.
   subroutine alpha_newton(self, t_new, report, error)
      type(dynamic_stepper_type), target, intent(inout) :: self
      real(dp), intent(in) :: t_new
      type(newton_report_type), intent(out) :: report
      type(error_type), allocatable, intent(out) :: error
      type(alpha_system_type) :: newton
      associate (state => self%state, mesh => self%mesh, dyn => self%dynamics)
         newton%c = new_alpha_coefficients(self%model%analysis%rho_inf, t_new - state%t)
         newton%t_new = t_new
         newton%s => self
         call alpha_predict(newton%c, state%q, state%v, state%acc, state%a, self%qt, self%vt, self%acct, self%at)
         call hold_fixed(self)
         call drive_motion(self, t_new, self%qt, self%vt, self%acct)
         call external_forces(dyn, mesh, t_new, self%gt)
         call newton_solve(newton, step_contract(self), self%reuse, report, error)
         if (allocated(error)) call newton_failure(report, 'K + c1 C + c2 M', error)
      end associate
   end subroutine alpha_newton

   !> The residual R at generalized-alpha's iterate (with `matrix` the
   !> iteration matrix K + c1 C + c2 M), gathered for a correction, and its norm.
   subroutine alpha_assemble(self, matrix, norm)
      class(alpha_system_type), intent(inout) :: self
      logical, intent(in) :: matrix
      real(dp), intent(out) :: norm
      associate (s => self%s)
         if (matrix) then
            call assemble_dynamics(s%dynamics, s%system, s%mesh, s%qt, s%vt, s%acct, self%t_new, s%state%seg, &
               & s%counts, self%c%c1, self%c%c2)
         else
            call assemble_dynamics(s%dynamics, s%system, s%mesh, s%qt, s%vt, s%acct, self%t_new, s%state%seg, s%counts)
         end if
         norm = residual_norm(s%system, s%mesh)
      end associate
   end subroutine alpha_assemble

   subroutine alpha_factor(self, info)
      class(alpha_system_type), intent(inout) :: self
      integer, intent(out) :: info
      call factor_system(self%s%system, info, self%s%counts)
   end subroutine alpha_factor

   !> The correction of q with the factor in hand, and generalized-alpha's
   !> update of the rates with it.
   subroutine alpha_correct(self, length, error)
      class(alpha_system_type), intent(inout) :: self
      real(dp), intent(out) :: length
      type(error_type), allocatable, intent(out) :: error
      integer :: k, d
      associate (s => self%s)
         call newton_correction(s%system, s%mesh, s%dof_length, length, s%counts)
         do k = 1, s%mesh%nfree
            d = s%mesh%eq_dof(k)
            call alpha_update(self%c, s%system%rhs(k, 1), s%qt(d), s%vt(d), s%acct(d), s%at(d))
         end do
         s%counts%iterations = s%counts%iterations + 1
      end associate
   end subroutine alpha_correct

   !> Newton on a step of the energy-momentum integrator
   !> (fekap_dynamics_energy_momentum) from the accepted state to t_new
   !> (newton_solve on em_system_type, a fresh factor every iteration): the
   !> iterate into qt, vt (v1 = 2 (q1 - q0)/h - v0 on the free dofs) and acct
   !> (the step's mean acceleration (v1 - v0)/h; the drives' second rate on
   !> theirs), the residual (the step's reactions) into system%r. The
   !> predictor is q0 + h v0 + h^2/2 acc0.
   subroutine em_newton(self, t_new, report, error)
      type(dynamic_stepper_type), target, intent(inout) :: self
      real(dp), intent(in) :: t_new
      type(newton_report_type), intent(out) :: report
      type(error_type), allocatable, intent(out) :: error
      type(em_newton_system_type) :: newton
      type(always_refactor_type) :: full
      real(dp) :: h
      associate (state => self%state, mesh => self%mesh, dyn => self%dynamics)
         h = t_new - state%t
         newton%h = h
         newton%chi = em_dissipation(self%model%analysis%rho_inf)
         newton%s => self
         self%qt = state%q + h*state%v + 0.5_dp*h**2*state%acc
         call hold_fixed(self)
         call drive_motion(self, t_new, self%qt, self%vt, self%acct)
         call em_velocities(self, h)
         call external_forces(dyn, mesh, t_new, self%gt)
         call newton_solve(newton, step_contract(self), full, report, error)
         if (allocated(error)) then
            call newton_failure(report, 'dp/dq + C/h + 2 M/h^2', error)
            return
         end if
         self%acct = (self%vt - state%v)/h
         ! The step's mean rates z/h, for the next step's massless dofs.
         self%at = self%zt/h
         call drive_motion(self, t_new, self%qt, self%vt, self%acct)
      end associate
   end subroutine em_newton

   !> The energy-momentum step's residual at the iterate (with `matrix` its
   !> iteration matrix), gathered for a correction, and its norm.
   subroutine em_assemble(self, matrix, norm)
      class(em_newton_system_type), intent(inout) :: self
      logical, intent(in) :: matrix
      real(dp), intent(out) :: norm
      associate (s => self%s)
         call assemble_em(s%em, s%dynamics, s%mesh, s%state%q, s%qt, s%state%v, s%vt, s%state%g, s%gt, s%zt, s%dzt, &
            & self%h, self%chi, s%state%seg, s%system%r, tangent=matrix)
         if (matrix) then
            s%counts%tangent_assemblies = s%counts%tangent_assemblies + 1
         else
            s%counts%residual_assemblies = s%counts%residual_assemblies + 1
         end if
         norm = residual_norm(s%system, s%mesh)
      end associate
   end subroutine em_assemble

   subroutine em_factor(self, info)
      class(em_newton_system_type), intent(inout) :: self
      integer, intent(out) :: info
      call factor_em(self%s%em, info)
   end subroutine em_factor

   !> The correction of q with the factor, and the velocities of the new iterate.
   subroutine em_correct(self, length, error)
      class(em_newton_system_type), intent(inout) :: self
      real(dp), intent(out) :: length
      type(error_type), allocatable, intent(out) :: error
      integer :: info, k, d
      associate (s => self%s)
         length = 0
         call solve_em(s%em, s%system%rhs(:, 1), info)
         if (info /= 0) then
            call singular_matrix(error, 'dp/dq + C/h + 2 M/h^2', info)
            return
         end if
         do k = 1, s%mesh%nfree
            d = s%mesh%eq_dof(k)
            length = max(length, abs(s%system%rhs(k, 1))*s%dof_length(d))
            s%qt(d) = s%qt(d) + s%system%rhs(k, 1)
         end do
         call em_velocities(s, self%h)
         s%counts%iterations = s%counts%iterations + 1
      end associate
   end subroutine em_correct

   !> The iterate's increments zt, dzt (once per iterate: assemble_em, the
   !> step's work and the next step's mean rates use them) and its free dofs'
   !> velocities (em_free_velocities).
   subroutine em_velocities(self, h)
      type(dynamic_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: h
      call em_increments(self%mesh, self%state%q, self%qt, self%zt, self%dzt)
      call em_free_velocities(self%mesh, self%massless, h, self%h_prev, self%state%v, self%state%a, self%zt, self%vt)
   end subroutine em_velocities

   !> Supported dofs stay put in the iterate.
   subroutine hold_fixed(self)
      type(dynamic_stepper_type), intent(inout) :: self
      integer :: d
      do d = 1, self%mesh%ndof
         if (self%mesh%status(d) == dof_fixed) then
            self%qt(d) = self%state%q(d)
            self%vt(d) = 0
            self%acct(d) = 0
         end if
      end do
   end subroutine hold_fixed

   !> Both integrators' convergence contract (fekap_stepping_newton): the
   !> deck's tolerance relative to the forces in play in the step
   !> (step_force_scale), its length tolerance times the model size, its
   !> iterations; the round-off floor of the mesh's stiffness as the last resort.
   !> Divergence is a correction longer than the model sizes of
   !> divergence_length plus the predictor's own move: a first correction may
   !> undo a long extrapolation (a step far longer than a stiff mode's period,
   !> where q0 + h v0 + h^2/2 a0 runs off) without Newton diverging.
   function step_contract(self) result(contract)
      type(dynamic_stepper_type), intent(in) :: self
      type(newton_contract_type) :: contract
      contract%tolerance = self%model%analysis%tol
      contract%length = self%model%analysis%length_tol*self%model_length
      contract%max_iterations = self%model%analysis%max_iter
      contract%force_scale = step_force_scale(self)
      contract%floor = self%residual_floor
      contract%divergence = divergence_length*self%model_length + &
         & maxval(abs(self%qt - self%state%q)*self%dof_length)
   end function step_contract

   !> The forces in play in a step: the largest Euclidean norm (over all
   !> dofs) of the weights and loads at its end (gt), of the inertia M a of
   !> its predicted accelerations (acct), and of the reactions of supports
   !> and drives at its start (the residual on the constrained dofs). The
   !> element forces balance these (or are their reactions); a residual is
   !> small when it is small against them, not against the stiffness.
   function step_force_scale(self) result(scale)
      type(dynamic_stepper_type), intent(in) :: self
      real(dp) :: scale
      real(dp) :: inertia(self%mesh%ndof), ae(6)
      integer :: e, i
      associate (mesh => self%mesh, dyn => self%dynamics)
         inertia = dyn%point_mass*self%acct
         do e = 1, size(mesh%elements)
            do i = 1, 6
               ae(i) = self%acct(mesh%edof(i, e))
            end do
            ae = times6(dyn%me, e, ae)
            do i = 1, 6
               inertia(mesh%edof(i, e)) = inertia(mesh%edof(i, e)) + ae(i)
            end do
         end do
         scale = max(norm2(self%gt), norm2(inertia), norm2(merge(self%state%r, 0.0_dp, mesh%status /= dof_free)))
      end associate
   end function step_force_scale

   !> A Newton solve of a step that did not converge (newton_solve's error):
   !> its message in the integrators' words (the iteration matrix named by `what`).
   subroutine newton_failure(report, what, error)
      type(newton_report_type), intent(in) :: report
      character(*), intent(in) :: what
      type(error_type), allocatable, intent(inout) :: error
      character(len=300) :: msg
      select case (report%stopped)
      case (stop_not_finite)
         deallocate (error)
         call analysis_error(error, 'the residual of the equations of motion is not finite (the step is '// &
            & 'too long for the motion, or the mechanism has a dof without mass and stiffness)')
      case (stop_spent)
         deallocate (error)
         write (msg, '(a,i0,a,a,a,a)') 'Newton did not converge in ', report%iterations, ' iterations (residual ', &
            & es_text(report%last_residual, 12, 5), ', first ', es_text(report%first_residual, 12, 5)//')'
         call analysis_error(error, trim(msg))
      case (stop_singular)
         deallocate (error)
         call singular_matrix(error, what, report%info)
      case default
         ! Divergence and interrupts keep newton_solve's message.
      end select
   end subroutine newton_failure

   !> The iteration matrix (named by `what`) has no factor.
   subroutine singular_matrix(error, what, info)
      type(error_type), allocatable, intent(out) :: error
      character(*), intent(in) :: what
      integer, intent(in) :: info
      character(len=300) :: msg
      write (msg, '(a,a,a,i0,a)') 'the iteration matrix ', what, ' is singular at equation ', info, &
         & ' (a free dof with neither mass nor stiffness)'
      call analysis_error(error, trim(msg))
   end subroutine singular_matrix

   !> The result of the accepted state: nodes and links, reactions, energy;
   !> only its time when the step's rows are not written (at fine steps most
   !> are not, and the reactions and momenta cost a tenth of a step).
   subroutine fill_result(self, result)
      type(dynamic_stepper_type), intent(inout) :: self
      type(step_result_type), intent(inout) :: result
      real(dp) :: p(3)
      associate (state => self%state, mesh => self%mesh, dyn => self%dynamics)
         result%t = state%t
         result%floor = self%try_floor
         result%has_velocity = .true.
         result%has_acceleration = .true.
         if (.not. result%written) return
         call fill_nodes_links(mesh, self%model, state%q, state%v, state%acc, result)
         if (self%model%output%vtk) call fill_fields(mesh, state%q, state%v, state%acc, result)
         if (.not. allocated(result%reactions)) allocate (result%reactions(3, reaction_count(self%model)))
         call fill_reactions(self, result%reactions)
         result%has_reactions = all(abs(result%reactions) <= huge(1.0_dp))
         p = momentum(dyn, mesh, state%q, state%v)
         if (.not. allocated(result%energy)) allocate (result%energy(energy_count))
         result%energy = [state%kinetic, state%strain, state%penalty, &
            & state%energy - state%kinetic - state%strain - state%penalty, state%work_loads, &
            & state%work_drives, state%dissipated, &
            & state%energy - state%work_loads - state%work_drives + state%dissipated - self%energy0, p(1), p(2), p(3)]
         result%has_energy = .true.
      end associate
   end subroutine fill_result

   !> The reactions in kinetostatics' rows: drives and supports the residual
   !> on their dofs; joints the end forces of the link's element there,
   !> P_e + M_e acc_e + C_e v_e - weight_e (each element in equilibrium
   !> under its end forces and its own inertia, damping and weight).
   subroutine fill_reactions(self, reactions)
      type(dynamic_stepper_type), intent(in) :: self
      real(dp), intent(out) :: reactions(:, :)
      integer :: row, e, k, dof
      real(dp) :: pe(6)
      logical :: em_step
      reactions = 0
      ! Energy-momentum's residual (the supports' and drives' rows) is that of
      ! its step's equations: the joints' and sliders' rows too (em_end_forces).
      em_step = self%model%analysis%integrator == integrator_energy_momentum .and. self%em_h > 0
      associate (state => self%state, mesh => self%mesh, dyn => self%dynamics, rows => self%rows)
         do row = 1, size(reactions, 2)
            e = rows%row_element(row)
            if (e > 0) then
               if (em_step) then
                  call em_end_forces(self, e, pe)
               else
                  call end_forces(e, pe)
               end if
               reactions(:, row) = pe(3*rows%row_end(row) - 2:3*rows%row_end(row))
            else if (rows%row_slide(row) > 0 .and. em_step) then
               call em_slider_force(self, rows%row_slide(row), reactions(:, row))
            else if (rows%row_slide(row) > 0) then
               ! A sliding joint: the penalty force on the slave, and its dashpot's.
               call slider_force(mesh, rows%row_slide(row), state%q, state%seg, reactions(:, row))
               if (self%slide_damped) call add_dashpot(rows%row_slide(row), reactions(1:2, row))
            else
               do k = 1, 3
                  dof = rows%row_dof(k, row)
                  if (dof > 0) reactions(k, row) = state%r(dof)
               end do
            end if
         end do
      end associate
   contains
      !> force -= the dashpot's force on the slave's translations (slideline i's).
      subroutine add_dashpot(i, force)
         integer, intent(in) :: i
         real(dp), intent(inout) :: force(2)
         real(dp) :: f(6)
         integer :: dofs(6)
         call slide_damping_force(self%dynamics, self%mesh, i, self%state%q, self%state%v, self%state%seg(i), f, dofs)
         force = force - f(1:2)
      end subroutine add_dashpot
      subroutine end_forces(e, fe)
         integer, intent(in) :: e
         real(dp), intent(out) :: fe(6)
         real(dp) :: xe(6), ae(6), weight(6)
         integer :: i
         do i = 1, 6
            xe(i) = self%state%q(self%mesh%edof(i, e))
            ae(i) = self%state%acc(self%mesh%edof(i, e))
         end do
         call element_force(self%mesh, e, xe, fe)
         ! The element's own weight (point masses belong to the pins).
         weight = element_weight(self%model, self%mesh, e)
         fe = fe + times6(self%dynamics%me, e, ae) - weight
         if (self%damped) fe = fe + element_damping_force(self%dynamics, self%mesh, e, self%state%q, self%state%v)
      end subroutine end_forces
   end subroutine fill_reactions

   !> Energy-momentum: the step's start (q0, v0, master segments: those its
   !> forces used) and length, for its reactions (fill_reactions).
   subroutine keep_step_start(self, h)
      type(dynamic_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: h
      self%em_q0 = self%state%q
      self%em_v0 = self%state%v
      self%em_seg = self%state%seg
      self%em_h = h
   end subroutine keep_step_start

   !> Element e's end forces in the last energy-momentum step's equations
   !> (assemble_em): its discrete gradient p(q0, q1) with the dissipation
   !> chi + 2 beta/h, M_e (v1 - v0)/h, alpha M_e z/h, less its weight; so that
   !> each node's joint rows add up to its support, drive and slider rows
   !> (the step's residual there), as generalized-alpha's do.
   subroutine em_end_forces(self, e, fe)
      use fekap_element_discrete_gradient, only: beam_discrete_gradient, cayley_increment
      use fekap_model, only: dof_rot
      type(dynamic_stepper_type), intent(in) :: self
      integer, intent(in) :: e
      real(dp), intent(out) :: fe(6)
      real(dp) :: x0(6), x1(6), am(6), z(6), chi_e, h, dpsi
      integer :: i, d
      h = self%em_h
      do i = 1, 6
         d = self%mesh%edof(i, e)
         x0(i) = self%em_q0(d)
         x1(i) = self%state%q(d)
         am(i) = (self%state%v(d) - self%em_v0(d))/h
         z(i) = x1(i) - x0(i)
         if (self%mesh%dof_kind(d) == dof_rot) call cayley_increment(x1(i) - x0(i), z(i), dpsi)
      end do
      chi_e = em_dissipation(self%model%analysis%rho_inf) + 2*self%dynamics%beta(e)/h
      call beam_discrete_gradient(self%mesh%elements(e), x0, x1, chi_e, fe)
      fe = fe + times6(self%dynamics%me, e, am) - element_weight(self%model, self%mesh, e)
      if (self%dynamics%alpha(e) /= 0) fe = fe + self%dynamics%alpha(e)*times6(self%dynamics%me, e, z/h)
   end subroutine em_end_forces

   !> Slideline i's force on its slave in the last energy-momentum step's
   !> equations: minus the penalty spring's discrete gradient on the step's
   !> master segment (assemble_em; as slider_force, the force the spring applies).
   subroutine em_slider_force(self, i, force)
      use fekap_contact_slide_gradient, only: slide_discrete_gradient
      type(dynamic_stepper_type), intent(in) :: self
      integer, intent(in) :: i
      real(dp), intent(out) :: force(3)
      real(dp) :: x0(6), x1(6), pe(6)
      integer :: dofs(6)
      call slide_position(self%mesh, self%mesh%slides(i), self%em_seg(i), self%em_q0, x0(1:2), x0(3:4), x0(5:6), dofs)
      call slide_position(self%mesh, self%mesh%slides(i), self%em_seg(i), self%state%q, x1(1:2), x1(3:4), x1(5:6), &
         & dofs)
      call slide_discrete_gradient(x0, x1, self%mesh%slides(i)%kp, pe)
      force = [-pe(1), -pe(2), 0.0_dp]
   end subroutine em_slider_force

   subroutine element_force(mesh, e, xe, pe)
      use fekap_element_beam, only: beam_residual
      type(mesh_type), intent(in) :: mesh
      integer, intent(in) :: e
      real(dp), intent(in) :: xe(6)
      real(dp), intent(out) :: pe(6)
      call beam_residual(mesh%elements(e), xe, pe)
   end subroutine element_force

   pure function element_weight(model, mesh, e) result(w)
      use fekap_element_inertia, only: beam_gravity_force
      type(model_type), intent(in) :: model
      type(mesh_type), intent(in) :: mesh
      integer, intent(in) :: e
      real(dp) :: w(6)
      w = beam_gravity_force(mesh%elements(e)%length, model%sections(model%links(mesh%elink(e))%section)%rho_a, &
         & model%gravity)
   end function element_weight

end module fekap_dynamics_dynamic_stepper
