!> Change points in the FEM stepper (the pure tests are
!> fekap_fem_change_point's): the test of a step's predictor, and the
!> row of an output time that the stepper stepped over (fekap_fem's
!> step_over solves the next output time from the last regular state as one
!> double step): positions by Hermite interpolation through the two regular
!> states, corrected onto the mechanism; the row never enters the
!> predictor's history. Also the next output time of the run's uniform steps.
module fekap_fem_fill
   use fekap_kinds, only: dp
   use fekap_assembly_mesh, only: dof_fixed
   use fekap_fem_setup, only: set_driven
   use fekap_fem_linear_system, only: system_rcond
   use fekap_stepping_predictor, only: predictor_margin
   use fekap_fem_rates, only: solve_velocities, solve_accelerations
   use fekap_assembly_strain_rate, only: strain_rate_rcond_bounds
   use fekap_stepping_change_point, only: uniform_next_time => next_output_time
   use fekap_fem_change_point, only: hermite_fill, correct_fill, fill_order, &
      & rates_drop, fill_shift, estimate_needed
   use fekap_fem_state, only: fem_state_type, fem_core_type
   use fekap_fem_factor, only: fill_tangent, root_rcond, factor_root
   use fekap_fem_predict, only: drive_laws_at
   implicit none
   private

   public :: check_predictor, interpolate_fill, finish_fill, filled_state, next_output_time

contains

   !> The change-point test of a step's predictor (a run's step, at its first
   !> try), with the factor Newton's first iteration just made there (B_f's if
   !> root_solved, else K's unless info > 0): its condition estimate against
   !> the run's best, recorded in the change-point record (record_predictor).
   !> B_f's estimate is left out where its bounds from the last estimate
   !> decide as the estimate would (estimate_needed; docs/hard-cases.md,
   !> "When the estimate is made"): the lower bound stands for it, which
   !> the branch check then trusts and which leaves the run's best as it is.
   subroutine check_predictor(self, root_solved, info)
      class(fem_core_type), intent(inout) :: self
      logical, intent(in) :: root_solved
      integer, intent(in) :: info
      real(dp) :: rcond, high
      integer :: root_info
      rcond = 0
      if (root_solved) then
         call strain_rate_rcond_bounds(self%root, rcond, high)
         if (estimate_needed(rcond, high, self%state%reference_rcond)) then
            call root_rcond(self, rcond)
            self%counts%condition_estimates = self%counts%condition_estimates + 1
         end if
      else if (self%root_form) then
         ! Newton's first step took K's (a predictor strained beyond kg_above):
         ! the estimate is still B_f's, the scale of the run's best. K's own
         ! is off B_f's squared by the spread of the weights W (1e6 times
         ! larger on a four-bar of 3,500 elements a link, where it became the
         ! run's best and every later estimate looked near singular against
         ! it: the responses untrusted, the rocker's dead point rejected as a
         ! flip). The stress-free B_f at the predictor is factored, as the
         ! rates' factor is (factor_root; a B_f singular there stays so:
         ! rcond 0, a change point, as K's estimate of 0 made it).
         call factor_root(self, self%qt, self%seg, root_info, self%system%section)
         if (root_info == 0) then
            call root_rcond(self, rcond)
            self%counts%condition_estimates = self%counts%condition_estimates + 1
         end if
      else if (info == 0) then
         call system_rcond(self%system, rcond, self%counts)
      end if
      call self%change%record_predictor(rcond, self%state%reference_rcond)
   end subroutine check_predictor

   !> The row at time t of a change point stepped over (see fekap_fem's
   !> step_over), from the regular states on both sides (before_change and
   !> ahead): positions by Hermite interpolation (quintic with both sides'
   !> velocities and accelerations, cubic with velocities; order), corrected
   !> onto the mechanism (correct_fill: its iterations and residual), the
   !> condition estimate of the tangent there and whether it is singular
   !> against the run's best.
   subroutine interpolate_fill(self, t, q_fill, iterations, residual, order, rcond_fill, singular)
      class(fem_core_type), intent(inout) :: self
      real(dp), intent(in) :: t
      real(dp), allocatable, intent(out) :: q_fill(:)
      integer, intent(out) :: iterations, order
      real(dp), intent(out) :: residual, rcond_fill
      logical, intent(out) :: singular
      real(dp), allocatable :: v0(:), a0(:), v1(:), a1(:)
      real(dp) :: correction
      integer :: i
      logical :: has_v0, has_a0, has_v1, has_a1
      ! The rates of the two sides: the solved ones, else the predictor's history velocities.
      associate (bf => self%change%before, n => self%change%ahead, q => self%qt)
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
            & iterations, correction, residual, self%counts)
         call fill_tangent(self, q, t, rcond_fill)
         q_fill = q
         singular = rcond_fill < rates_drop*bf%reference_rcond
      end associate
   end subroutine interpolate_fill

   !> A fill near, not on, a change point whose row could not be solved as a
   !> step: finished by plain Newton (correct_fill without the shift), with
   !> the tangent's condition estimate there for the rates.
   subroutine finish_fill(self, t, q_fill, iterations, residual, rcond_fill)
      class(fem_core_type), intent(inout) :: self
      real(dp), intent(in) :: t
      real(dp), contiguous, intent(inout) :: q_fill(:)
      integer, intent(inout) :: iterations
      real(dp), intent(out) :: residual, rcond_fill
      real(dp) :: correction
      integer :: its
      call correct_fill(self%system, self%mesh, q_fill, t, self%seg, self%dof_length, &
         & predictor_margin*self%conv%length, 0.0_dp, its, correction, residual, self%counts)
      iterations = iterations + its
      call fill_tangent(self, q_fill, t, rcond_fill)
   end subroutine finish_fill

   !> Make the filled row at t the stepper's state, for output only (the state
   !> ahead is the next advance's): its note, and its rates where the tangent
   !> is regular enough (not singular; ill-conditioned, as the note says). At a
   !> bifurcation the rates are fixed only by the second-order (bifurcation)
   !> equations, which this does not solve (docs/hard-cases.md): left out.
   subroutine filled_state(self, t, q_fill, order, rcond, rcond_fill, residual, singular)
      class(fem_core_type), intent(inout) :: self
      real(dp), intent(in) :: t
      real(dp), contiguous, intent(in) :: q_fill(:)
      integer, intent(in) :: order
      !> Condition estimates at the predictor and at the filled configuration.
      real(dp), intent(in) :: rcond, rcond_fill, residual
      logical, intent(in) :: singular
      character(:), allocatable :: what
      character(len=360) :: text
      associate (bf => self%change%before, n => self%change%ahead)
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
            call drive_laws_at(self, t)
            call solve_velocities(self%system, self%mesh, self%law_rate, self%state%v, self%counts)
            self%state%has_velocity = .true.
            if (self%model%analysis%accelerations) then
               call solve_accelerations(self%system, self%mesh, q_fill, self%state%v, self%seg, self%law_rate2, &
                  & self%state%a, self%work, self%counts)
               self%state%has_acceleration = .true.
            end if
         end if
      end associate
   end subroutine filled_state

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
      class(fem_core_type), intent(in) :: self
      real(dp), intent(in) :: t
      associate (an => self%model%analysis)
         t_next = uniform_next_time(an%t_start, an%t_end, an%dt, self%state%t, t)
      end associate
   end function next_output_time

end module fekap_fem_fill
