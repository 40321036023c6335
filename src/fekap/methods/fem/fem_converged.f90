!> What the FEM makes of a converged configuration before and after it is
!> accepted: the check that it is a mechanism configuration, the branch check of the step (fekap_fem_branch) with the drive
!> responses at its two ends, which accepts, rejects or asks for
!> verification by half steps; and the velocities (47) and accelerations
!> (49) of the accepted configuration with the tangent there, with the note
!> on how close to singular it is.
module fekap_fem_converged
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, analysis_error
   use fekap_model, only: predictor_taylor
   use fekap_assembly_tracking, only: check_gaps
   use fekap_fem_linear_system, only: apply_response, phase_start, phase_end
   use fekap_fem_branch, only: drive_increment, branch_verdict, branch_reject, branch_verify, branch_unverifiable
   use fekap_fem_rates, only: pivot_note, solve_velocities, solve_accelerations, singular_floor, root_velocities, &
      & root_accelerations, refine_rates, plain_rates_rcond
   use fekap_assembly_strain_rate, only: rate_geometry_at, strain_rate_rcond_bounds
   use fekap_fem_change_point, only: response_trusted
   use fekap_fem_state, only: fem_core_type, note_response_pivot
   use fekap_fem_predict, only: record_velocity, drive_laws_at
   use fekap_fem_factor, only: refactor_at_accepted, accepted_pivot, accepted_rcond, accepted_response
   implicit none
   private

   public :: branch_jump, solve_rates, check_mechanism, start_response

contains

   !> The branch check of the step to qt (see fekap_fem_branch), with the
   !> drive responses at its two ends: at the new configuration from the
   !> factor of its material tangent (one back substitution per drive; the
   !> same factor then serves the rates), at the last one kept from the last
   !> step. A suspect step is accepted with its state before pushed on the
   !> verification stack at `depth` for verify_step.
   subroutine branch_jump(self, t, qt, factored, depth, verdict, error)
      class(fem_core_type), intent(inout) :: self
      real(dp), intent(in) :: t
      real(dp), contiguous, intent(in) :: qt(:)
      !> Whether the system holds the factor of the material tangent at qt.
      logical, intent(in) :: factored
      !> The halvings of the step (0: a step of the run).
      integer, intent(in) :: depth
      !> fekap_fem_branch's verdict: branch_accept, branch_reject (error),
      !> branch_verify (the step is to be verified), branch_unverifiable (error).
      integer, intent(out) :: verdict
      type(error_type), allocatable, intent(out) :: error
      real(dp), allocatable :: swap(:, :)
      real(dp) :: step_floor, turn, pivot, rcond
      integer :: crossing(3)
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
            if (self%change%predictor_regular) then
               rcond = self%change%predictor_rcond
            else
               call accepted_rcond(self, rcond)
            end if
         end if
         has_response = factored .and. pivot >= singular_floor .and. response_trusted(rcond, state%reference_rcond)
         if (has_response) then
            call accepted_response(self, resp)
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
            & step_floor, self%prediction%smooth, self%prediction%q, self%verification%can_verify(depth), verdict, &
            & error, crossing, turn)
         select case (verdict)
         case (branch_reject)
            return
         case (branch_unverifiable)
            return
         case (branch_verify)
            call self%verification%push(depth, state, crossing, turn)
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

   !> Velocities and accelerations of the accepted configuration, as asked
   !> for (see fekap_fem_rates), with the tangent there (the material
   !> tangent, since the geometric part vanishes with the stresses), and the
   !> note on how close to singular it is.
   subroutine solve_rates(self)
      class(fem_core_type), intent(inout) :: self
      real(dp) :: ratio, low, high, clock
      integer :: info
      logical :: regular, refine, kept
      ! The pivot ratio of the tangent at the configuration: a stationary one is
      ! noted also when only positions are computed (the tangent is factored
      ! for the branch-jump check anyway, so at no cost).
      if (self%model%analysis%velocities) call refactor_at_accepted(self, info)
      if (self%factor%is_singular()) then
         ratio = 0
      else if (self%factor%is_current()) then
         ratio = accepted_pivot(self)
      else
         return
      end if
      associate (state => self%state, history => self%state%history)
         self%counts%min_pivot_ratio = min(self%counts%min_pivot_ratio, ratio)
         state%reference_pivot = max(state%reference_pivot, ratio)
         call pivot_note(state%t, ratio, state%reference_pivot, self%model%analysis%velocities, state%note, regular)
         if (.not. regular .or. .not. self%model%analysis%velocities) return
         call drive_laws_at(self, state%t)
         if (self%root_form) then
            ! The square-root form, refined unless the bounds on B_f's
            ! condition from the last estimate show it well conditioned
            ! (plain_rates_rcond; no bounds, no skip: see fekap_fem_rates).
            ! Always refined under the Taylor predictor, whose positions come
            ! from these rates: a change of their round-off is amplified near
            ! a change point there (docs/theory.md, "Rates at scale"), while
            ! the other predictors take the branch check's drive response, so
            ! that positions never depend on how the rates were solved.
            refine = self%model%analysis%predictor == predictor_taylor
            if (.not. refine) then
               call strain_rate_rcond_bounds(self%root, low, high)
               refine = .not. low >= plain_rates_rcond
            end if
            ! A factor kept from the predictor (fekap_fem's solve_step) keeps
            ! B's geometry there; the refinement's residuals need q's own.
            call self%factor%take_kept_predictor(kept)
            if (kept .and. refine) then
               clock = phase_start(self%system)
               call rate_geometry_at(self%root, self%mesh, state%q, self%seg, self%system%residual_section)
               call phase_end(self%system, clock, self%counts%seconds_assembly)
            end if
            ! The rates' solves with B_f, timed with their refinements' residuals.
            clock = phase_start(self%system)
            if ((.not. refine .or. self%root%carried) .and. history%has_velocity(history%newest)) then
               ! Unrefined, (47) is R v_d with the drive response R of this
               ! factor, the plain solve of the same system: record_velocity
               ! made it already, for the predictor (as in the K form below).
               ! A factor carried to the configuration (fekap_fem_factor's
               ! carry_factor) refined R there once, as root_velocities would
               ! v: R v_d is then the refined velocities.
               state%v(:) = history%velocity(:, history%newest)
            else
               call root_velocities(self%root, self%mesh, self%law_rate, state%v, self%root_work, refine)
            end if
            self%counts%velocity_solves = self%counts%velocity_solves + 1
            state%has_velocity = .true.
            if (self%model%analysis%accelerations) then
               call root_accelerations(self%root, self%mesh, state%v, self%law_rate2, state%a, self%root_work, refine)
               self%counts%acceleration_solves = self%counts%acceleration_solves + 1
               state%has_acceleration = .true.
            end if
            call phase_end(self%system, clock, self%counts%seconds_solves)
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
         if (self%refined_rates) then
            ! B's geometry at q, for the strain rates of a redundant mechanism.
            clock = phase_start(self%system)
            call rate_geometry_at(self%root, self%mesh, state%q, self%seg, self%system%section)
            call phase_end(self%system, clock, self%counts%seconds_assembly)
            call refine_rates(self%root, self%mesh, self%system, state%v, self%strain_work, self%counts)
         end if
         self%counts%velocity_solves = self%counts%velocity_solves + 1
         state%has_velocity = .true.
         if (.not. self%model%analysis%accelerations) return
         ! The system holds the factor of the tangent at q (the factor record), so
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
         if (self%refined_rates) call refine_rates(self%root, self%mesh, self%system, state%a, self%strain_work, &
            & self%counts, state%v)
         self%counts%acceleration_solves = self%counts%acceleration_solves + 1
         state%has_acceleration = .true.
      end associate
   end subroutine solve_rates

   !> Whether the converged configuration qt at time t is a mechanism
   !> configuration, not a self-stressed equilibrium: every element strained
   !> less than the admissible strain (the strains of the material tangent's
   !> assembly at qt, which the system holds) and every slave on its line.
   subroutine check_mechanism(self, t, qt, error)
      class(fem_core_type), intent(inout) :: self
      real(dp), intent(in) :: t
      real(dp), contiguous, intent(in) :: qt(:)
      type(error_type), allocatable, intent(out) :: error
      character(len=300) :: msg
      associate (strain => self%system%assembled_strain, element => self%system%assembled_element)
         if (strain > self%admissible_strain) then
            write (msg, '(a,es12.5,a,es9.2,a)') 't = ', t, &
               & ': Newton converged to a self-stressed configuration (strain ', strain, ' in link '
            call analysis_error(error, trim(msg)//' '//self%model%links(self%mesh%elink(element))%name// &
               & '), not a mechanism configuration', t=t)
            return
         end if
      end associate
      if (size(self%mesh%slides) > 0) then
         call check_gaps(self%mesh, self%model, t, qt, self%seg, self%admissible_strain*self%model_length, error)
      end if
   end subroutine check_mechanism

   !> The drive response at the start (an unloaded model): the branch-jump
   !> check's reference and the first velocity of the predictor's history.
   subroutine start_response(self)
      class(fem_core_type), intent(inout) :: self
      integer :: info
      real(dp) :: rcond
      call refactor_at_accepted(self, info)
      self%state%has_jump_response = info == 0
      if (info == 0) then
         call note_response_pivot(self, accepted_pivot(self))
         call accepted_response(self, self%state%jump_response)
         call accepted_rcond(self, rcond)
         self%state%reference_rcond = rcond
      end if
      call record_velocity(self)
   end subroutine start_response

end module fekap_fem_converged
