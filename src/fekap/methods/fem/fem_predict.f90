!> The FEM's predictor of a step: the initial guess at a new time (the
!> paper's last configuration, extrapolation of the history, a Taylor series
!> from the last rates, or the tangent predictor), the guard against an
!> extrapolation that strains the links more than the last configuration
!> would, the scale of the step's residual (what the drive and load
!> increments alone produce), and the history's velocity of an accepted
!> configuration from its drive response.
module fekap_fem_predict
   use fekap_kinds, only: dp
   use fekap_model, only: predictor_previous, predictor_taylor
   use fekap_assembly_assemble, only: max_strain
   use fekap_fem_setup, only: set_driven, put_driven_values
   use fekap_fem_linear_system, only: drive_load_rhs, apply_response
   use fekap_stepping_predictor, only: extrapolate_history, taylor_predict, prediction_none, prediction_smooth, &
      & predictor_margin
   use fekap_fem_rates, only: near_singular_drop
   use fekap_fem_state, only: fem_core_type
   use fekap_fem_factor, only: refactor_at_accepted
   implicit none
   private

   public :: predict, guard_extrapolation, drive_increment_residual, record_velocity, drive_laws_at

contains

   !> Initial guess at time t: the paper's last configuration, extrapolation
   !> of the last ones (see extrapolate_history), or a Taylor series from the
   !> last rates. Without history (the first step) extrapolation and Taylor
   !> start from the tangent predictor, the linear response of the last
   !> configuration to the drive increment: rotating a driven link end alone
   !> would strain its element so much that Newton may leave the assembly branch.
   !> `guard`: the predictor extrapolated, and guard_extrapolation is to check
   !> it with the strains of the step's first assembly.
   subroutine predict(self, t, qt, guard)
      class(fem_core_type), intent(inout) :: self
      real(dp), intent(in) :: t
      real(dp), contiguous, intent(inout) :: qt(:)
      logical, intent(out) :: guard
      integer :: i, made
      logical :: smooth
      smooth = .false.
      guard = .false.
      call self%prediction%begin(max(self%conv%length, roundoff_length(self)/predictor_margin))
      associate (state => self%state)
         select case (self%model%analysis%predictor)
         case (predictor_previous)
            qt = state%q
         case (predictor_taylor)
            if (state%has_acceleration) then
               call taylor_predict(state%q, state%v, state%a, t - state%t, qt)
            else
               call extrapolate_history(state%history, t, .false., self%prediction%length, self%dof_length, qt, made)
               if (made == prediction_none) call tangent_predictor(self, t, qt)
            end if
         case default
            call extrapolate_history(state%history, t, .true., self%prediction%length, self%dof_length, qt, made)
            smooth = made == prediction_smooth
            guard = made /= prediction_none
            if (made == prediction_none) call tangent_predictor(self, t, qt)
         end select
      end associate
      do i = 1, size(self%fixed_dofs)
         qt(self%fixed_dofs(i)) = self%mesh%q0(self%fixed_dofs(i))
      end do
      ! The driven dofs as set_driven puts them, from the laws at t, which
      ! the history's velocity and the rates of the step at t then take.
      call drive_laws_at(self, t)
      call put_driven_values(self, self%law_value, qt)
      call self%prediction%record(qt, smooth)
   end subroutine predict

   !> The round-off of the accepted configuration's dofs in lengths: one unit
   !> of round-off (epsilon) of the largest |q| times its dof's length
   !> (rotations times the model size). A predictor can be no closer to the
   !> solution than that, nor a Newton correction from it smaller: rotations
   !> grow without bound over a run's revolutions (4 pi after two), and
   !> predictor_margin times the length tolerance falls below their round-off.
   real(dp) function roundoff_length(self) result(length)
      class(fem_core_type), intent(in) :: self
      integer :: i
      length = 0
      do i = 1, self%mesh%ndof
         length = max(length, abs(self%state%q(i))*self%dof_length(i))
      end do
      length = epsilon(1.0_dp)*length
   end function roundoff_length

   !> Extrapolating positions over a large rotation (a quarter turn per step)
   !> distorts the links badly, and Newton from there may find another
   !> assembly branch. Keep the extrapolation qt (just assembled, so its
   !> strain is known) only if it strains the elements less than the last
   !> configuration with the new drive values does; else replace it by that
   !> (and return true).
   logical function guard_extrapolation(self, t, qt) result(replaced)
      class(fem_core_type), intent(inout) :: self
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
         call self%prediction%replace(qt)
         replaced = .true.
      end if
   end function guard_extrapolation

   !> qt = q + dq with K_ff dq_f = -K_fd dq_d + f(t) - f(t_q): the tangent at
   !> the accepted configuration applied to the drive and load increments.
   subroutine tangent_predictor(self, t, qt)
      class(fem_core_type), intent(inout) :: self
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

   !> Norm of -K_fd (q_d(t) - q_d) + f(t) - f(t_q) over the free dofs, with
   !> the driven dofs at t taken from the predictor qt (set_driven's values).
   subroutine drive_increment_residual(self, t, qt, norm)
      class(fem_core_type), intent(inout) :: self
      real(dp), intent(in) :: t
      real(dp), contiguous, intent(in) :: qt(:)
      real(dp), intent(out) :: norm
      integer :: k
      associate (dqd => self%drive_step, dd => self%mesh%driven_dof)
         dqd = qt(dd) - self%state%q(dd)
         if (self%loaded) then
            call self%mesh%loads%change(self%state%t, t, self%load_work)
            call drive_load_rhs(self%system, self%mesh, dqd, self%load_work)
         else
            call drive_load_rhs(self%system, self%mesh, dqd)
         end if
      end associate
      norm = 0
      do k = 1, self%mesh%nfree
         ! sum's order, from 0 (a loop: the intrinsic on the component's section cost twice as much).
         norm = norm + self%system%rhs(k, 1)**2
      end do
      norm = sqrt(norm)
   end subroutine drive_increment_residual

   !> The velocity of the newest configuration of the predictor's history:
   !> the drive response times the drive rates, when the response is known
   !> and not near a stationary configuration.
   subroutine record_velocity(self)
      class(fem_core_type), intent(inout) :: self
      associate (state => self%state, history => self%state%history)
         history%has_velocity(history%newest) = state%has_jump_response .and. &
            & self%response_pivot >= near_singular_drop*state%reference_pivot
         if (.not. history%has_velocity(history%newest)) return
         call drive_laws_at(self, state%t)
         call apply_response(state%jump_response, self%law_rate, history%velocity(:, history%newest))
      end associate
   end subroutine record_velocity

   !> The drives' values, rates and second rates at time t in law_value,
   !> law_rate and law_rate2, evaluated unless they hold those at t already
   !> (the history's velocity and the rates of a step ask at the same time).
   subroutine drive_laws_at(self, t)
      class(fem_core_type), intent(inout) :: self
      real(dp), intent(in) :: t
      integer :: i
      if (self%laws_known .and. self%laws_t == t) return
      ! Drive by drive (the elemental call on the drives' component array cost three times the laws).
      do i = 1, self%mesh%ndriven
         call self%model%drives(i)%law%eval(t, self%law_value(i), self%law_rate(i), self%law_rate2(i))
      end do
      self%laws_t = t
      self%laws_known = .true.
   end subroutine drive_laws_at

end module fekap_fem_predict
