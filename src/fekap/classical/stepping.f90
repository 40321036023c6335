!> What both constraint-equation methods share around their Newton solves:
!> the history of converged configurations behind the predictors, the values
!> of drives relative to the initial configuration, the convergence settings
!> taken from the analysis, and the texts of their messages.
module fekap_classical_stepping
   use fekap_kinds, only: dp
   use fekap_model, only: analysis_type, predictor_previous, predictor_extrapolate, predictor_taylor
   use fekap_model_drive_law, only: law_type
   use fekap_solver_convergence, only: convergence_type, extrapolate
   implicit none
   private

   public :: history_type, new_history, drive_value, new_step_convergence, real_text, no_convergence_text

   !> The last (up to three) converged configurations, newest first, and the
   !> rates of the newest one when they were computed.
   type :: history_type
      !> Number of stored configurations (0 to 3).
      integer :: count = 0
      !> (ncoord, 3): configurations; column 1 is the newest.
      real(dp), allocatable :: q(:, :)
      !> Their times.
      real(dp) :: t(3) = 0
      !> Whether qd and qdd hold the rates of configuration 1.
      logical :: has_rates = .false.
      real(dp), allocatable :: qd(:), qdd(:)
   contains
      !> Store a newly converged configuration (its rates are unknown until set_rates).
      procedure :: push => history_push
      !> Record the velocities and accelerations of the newest configuration.
      procedure :: set_rates => history_set_rates
      !> The predictor's guess at a new time.
      procedure :: predict => history_predict
   end type history_type

contains

   !> An empty history for ncoord coordinates.
   pure subroutine new_history(self, ncoord)
      type(history_type), intent(out) :: self
      integer, intent(in) :: ncoord
      allocate (self%q(ncoord, 3), source=0.0_dp)
      allocate (self%qd(ncoord), self%qdd(ncoord), source=0.0_dp)
   end subroutine new_history

   pure subroutine history_push(self, q, t)
      class(history_type), intent(inout) :: self
      real(dp), intent(in) :: q(:), t
      self%q(:, 3) = self%q(:, 2)
      self%q(:, 2) = self%q(:, 1)
      self%q(:, 1) = q
      self%t(3) = self%t(2)
      self%t(2) = self%t(1)
      self%t(1) = t
      self%count = min(3, self%count + 1)
      self%has_rates = .false.
   end subroutine history_push

   pure subroutine history_set_rates(self, qd, qdd)
      class(history_type), intent(inout) :: self
      real(dp), intent(in) :: qd(:), qdd(:)
      self%qd = qd
      self%qdd = qdd
      self%has_rates = .true.
   end subroutine history_set_rates

   !> Predictor at time t: predictor_previous takes the last converged
   !> configuration (the paper's (10)); predictor_extrapolate the Lagrange
   !> extrapolation through the last (up to) three; predictor_taylor
   !> q + dt q' + dt**2/2 q'' from the last rates, or extrapolation when
   !> velocities and accelerations were not both computed.
   pure subroutine history_predict(self, kind, t, q)
      class(history_type), intent(in) :: self
      !> predictor_previous, predictor_extrapolate or predictor_taylor.
      integer, intent(in) :: kind
      real(dp), intent(in) :: t
      real(dp), intent(out) :: q(:)
      real(dp) :: h
      integer :: k
      k = max(1, self%count)
      select case (kind)
      case (predictor_previous)
         q = self%q(:, 1)
      case (predictor_taylor)
         if (self%has_rates) then
            h = t - self%t(1)
            q = self%q(:, 1) + h*self%qd + h**2/2*self%qdd
         else
            call extrapolate(self%q(:, 1:k), self%t(1:k), t, q)
         end if
      case default
         call extrapolate(self%q(:, 1:k), self%t(1:k), t, q)
      end select
   end subroutine history_predict

   !> Value and rates at time t of a driven quantity that starts at `initial`
   !> at t_start: initial + law(t) - law(t_start). For an absolute law that
   !> starts consistently this is law(t) itself.
   elemental subroutine drive_value(law, initial, t_start, t, f, df, ddf)
      type(law_type), intent(in) :: law
      real(dp), intent(in) :: initial, t_start, t
      real(dp), intent(out) :: f, df, ddf
      real(dp) :: f0, df0, ddf0
      call law%eval(t_start, f0, df0, ddf0)
      call law%eval(t, f, df, ddf)
      f = initial + (f - f0)
   end subroutine drive_value

   !> Convergence settings of a step from the analysis: mode and tolerance
   !> as given, the length tolerance scaled by the model size, and an absolute
   !> residual floor at rounding level (a step that starts converged).
   pure function new_step_convergence(analysis, size_) result(conv)
      type(analysis_type), intent(in) :: analysis
      !> model_size(model).
      real(dp), intent(in) :: size_
      type(convergence_type) :: conv
      conv%mode = analysis%convergence
      conv%tol = analysis%tol
      conv%length = analysis%length_tol*size_
      conv%floor = 1.0e-14_dp*size_
   end function new_step_convergence

   !> The message of a step that hit max_iter.
   pure function no_convergence_text(step, t, iterations, residual) result(text)
      integer, intent(in) :: step, iterations
      real(dp), intent(in) :: t, residual
      character(:), allocatable :: text
      character(len=16) :: buf
      write (buf, '(i0)') step
      text = 'step '//trim(buf)//' at t = '//real_text(t)
      write (buf, '(i0)') iterations
      text = text//' did not converge in '//trim(buf)//' iterations (residual '//real_text(residual)//')'
   end function no_convergence_text

   !> A short text for a real: fixed notation without trailing zeros for
   !> moderate magnitudes, otherwise scientific with four digits.
   pure function real_text(x) result(text)
      real(dp), intent(in) :: x
      character(:), allocatable :: text
      character(len=32) :: buf
      integer :: k
      if (abs(x) < tiny(x)) then
         text = '0'
         return
      end if
      if (abs(x) >= 1.0e-3_dp .and. abs(x) < 1.0e6_dp) then
         write (buf, '(f0.6)') x
         text = trim(buf)
         k = len(text)
         do while (text(k:k) == '0')
            k = k - 1
         end do
         if (text(k:k) == '.') k = k - 1
         text = text(1:k)
         if (text(1:1) == '.') text = '0'//text
         if (text(1:2) == '-.') text = '-0'//text(2:)
      else
         write (buf, '(es11.4)') x
         text = trim(adjustl(buf))
      end if
   end function real_text

end module fekap_classical_stepping
