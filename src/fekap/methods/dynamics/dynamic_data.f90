!> The dynamics stepper's data: the accepted state of a step, the iterate,
!> the integrators' storage and the start's descriptions (dynamic_data_type,
!> which fekap_dynamics_dynamic_stepper's dynamic_stepper_type extends with
!> its start and advance), and the drives' motion and the supports' hold on
!> an iterate.
module fekap_dynamics_dynamic_data
   use fekap_kinds, only: dp
   use fekap_assembly_mesh, only: dof_fixed
   use fekap_fem_setup, only: fem_base_type
   use fekap_stepping_newton, only: kept_factor_type
   use fekap_dynamics_dynamic_system, only: dynamic_system_type
   use fekap_dynamics_energy_momentum, only: em_system_type
   use fekap_reactions_kinetostatics, only: kinetostatics_type
   implicit none
   private

   public :: dynamic_data_type, dynamic_state_type, energy_names, drive_motion, hold_fixed

   !> The columns of energy.csv after step,t (fill_result of fekap_dynamics_step_result).
   character(*), parameter :: energy_names = 'kinetic,strain,penalty,gravity,work_loads,work_drives,dissipated,'// &
      & 'balance,px,py,angular'
   integer, parameter, public :: energy_count = 11

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
   type, abstract, extends(fem_base_type) :: dynamic_data_type
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
      !> The local error estimate of the last step tried (fekap_dynamics_local_error)
      !> and its dof, and the largest of the current advance's accepted steps.
      real(dp) :: try_estimate = 0, advance_estimate = 0
      integer :: try_estimate_dof = 0
      !> Adaptive steps: the length of the next step to try (0: none yet).
      real(dp) :: h_next = 0
      !> Generalized-alpha's kept factor (fekap_stepping_newton's
      !> kept_factor_type; its contraction 0: every iteration factors afresh).
      type(kept_factor_type) :: reuse
      !> How the start's velocities were found, for the plan.
      character(len=120) :: start_velocity = ''
      !> How the start's configuration and accelerations were found (consistent_start), for the plan.
      character(len=200) :: start_state = ''
      integer :: advances = 0
   end type dynamic_data_type

contains

   !> The drives' dofs at time t: value, rate, second rate of their laws.
   subroutine drive_motion(self, t, q, v, acc)
      class(dynamic_data_type), intent(inout) :: self
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

   !> Supported dofs stay put in the iterate.
   subroutine hold_fixed(self)
      class(dynamic_data_type), intent(inout) :: self
      integer :: d
      do d = 1, self%mesh%ndof
         if (self%mesh%status(d) == dof_fixed) then
            self%qt(d) = self%state%q(d)
            self%vt(d) = 0
            self%acct(d) = 0
         end if
      end do
   end subroutine hold_fixed

end module fekap_dynamics_dynamic_data
