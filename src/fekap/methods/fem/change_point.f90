!> Change points of the FEM: configurations where the tangent loses rank
!> (every bar of a parallelogram chain horizontal, the double crank's
!> collinear positions). Newton does not iterate there: the stepper detects
!> a near-singular tangent at the predictor by its condition estimate
!> (change_verdict), solves the next output time from the last regular state
!> as one double step, and fills the skipped row for output only from its two
!> regular neighbours (hermite_fill), its positions then corrected in the
!> range of the tangent (correct_fill). The thresholds and the fill are
!> fekap_stepping_change_point's (shared with the spatial stepper). docs/hard-cases.md (Change points)
!> has the measurements behind the thresholds. The stepper's change-point
!> record (change_record_type) is this module's: whether a step checks its
!> predictor, what the check found, and the regular states on either side of
!> a change point stepped over; its procedures are the only ones that assign
!> its fields (Fortran has no read-only components: they are public for
!> reading without a copy; test/app/test_layers.py checks the assignments).
module fekap_fem_change_point
   use fekap_kinds, only: dp
   use fekap_stepping_change_point, only: change_verdict, response_trusted, hermite_fill, fill_order, change_drop, &
      & rates_drop, response_drop, change_regular, change_near_singular, fill_shift, fill_iterations
   use fekap_fem_accepted, only: fem_state_type
   use fekap_model_work, only: work_counts_type
   use fekap_assembly_mesh, only: mesh_type
   use fekap_fem_linear_system, only: linear_system_type, assemble_system, assemble_system_residual, &
      & factor_system, residual_norm, newton_correction, apply_correction
   implicit none
   private

   public :: correct_fill, change_record_type, estimate_needed
   ! The thresholds and the fill shared with the spatial stepper, for this module's users.
   public :: change_verdict, response_trusted, hermite_fill, fill_order, change_drop, rates_drop, response_drop, &
      & change_regular, change_near_singular, fill_shift, fill_iterations

   !> A predictor's condition estimate may be left out only when the bounds
   !> on it (strain_rate_rcond_bounds) keep it at least skip_margin times
   !> change_drop times the run's best (see estimate_needed): a margin for
   !> the estimator's own error at the configuration it was made at (dlacn2
   !> gives a lower bound of ||B^-1|| that is rarely more than a few times
   !> short, squared on the tangent's scale).
   real(dp), parameter, public :: skip_margin = 100
   !> ... and only when the bounds keep it at most reference_slack times
   !> the run's best (the largest estimate so far, the reference of
   !> change_drop, response_drop and rates_drop): where an estimate would
   !> have raised the best by less than that, the reference lags by that
   !> factor at most, well within the estimate's own error (dlacn2's ||B^-1||_1 is a
   !> lower bound, rarely more than a few times short, squared on the
   !> tangent's scale), so the thresholds relative to it move by less than
   !> they are uncertain anyway. Without the slack, every step whose bound
   !> reached above the best was estimated: most steps near the run's best
   !> condition (docs/hard-cases.md, "When the estimate is made").
   real(dp), parameter, public :: reference_slack = 1.1_dp

   !> The FEM stepper's change-point record (see fekap_fem's step_over).
   type :: change_record_type
      !> Whether the step being solved checks its predictor's tangent (a run's
      !> step, at its first try), and whether it found it near singular.
      logical :: detect = .false., found = .false.
      !> The condition estimate of the predictor's tangent, and whether it was
      !> found regular: the estimate then stands for the accepted
      !> configuration's in the branch-jump check (one estimate a step, not two).
      real(dp) :: predictor_rcond = 0
      logical :: predictor_regular = .false.
      !> The regular states on either side of a change point stepped over: the
      !> state before it, and the one solved at the next output time, kept for
      !> the next advance with its iterations, residual, cuts and
      !> configurations accepted at the round-off floor (has_ahead).
      type(fem_state_type) :: before, ahead
      logical :: has_ahead = .false.
      integer :: ahead_iterations = 0, ahead_cuts = 0, ahead_floor = 0
      real(dp) :: ahead_residual = 0
   contains
      !> An advance begins: it checks its predictor if `detect`; nothing found yet.
      procedure :: begin_advance => record_begin_advance
      !> No more checks of a predictor in this advance.
      procedure :: stop_detecting => record_stop_detecting
      !> A step's predictor is not (yet) known regular.
      procedure :: forget_predictor => record_forget_predictor
      !> The check of a predictor's tangent: its condition estimate against the
      !> run's best (change_verdict); found if near singular. Ends the detection.
      procedure :: record_predictor => record_record_predictor
      !> The change point found has been dealt with.
      procedure :: clear_found => record_clear_found
      !> Keep the regular state before a change point.
      procedure :: keep_before => record_keep_before
      !> Keep the state solved beyond a change point for the next advance.
      procedure :: keep_ahead => record_keep_ahead
      !> Whether a state ahead was kept; it is the next advance's once (taken).
      procedure :: take_ahead => record_take_ahead
   end type change_record_type

contains

   pure subroutine record_begin_advance(self, detect)
      class(change_record_type), intent(inout) :: self
      logical, intent(in) :: detect
      self%detect = detect
      self%found = .false.
   end subroutine record_begin_advance

   pure subroutine record_stop_detecting(self)
      class(change_record_type), intent(inout) :: self
      self%detect = .false.
   end subroutine record_stop_detecting

   pure subroutine record_forget_predictor(self)
      class(change_record_type), intent(inout) :: self
      self%predictor_regular = .false.
   end subroutine record_forget_predictor

   pure subroutine record_record_predictor(self, rcond, reference)
      class(change_record_type), intent(inout) :: self
      !> The predictor tangent's reciprocal condition number (0: its factor failed).
      real(dp), intent(in) :: rcond
      !> The run's best so far.
      real(dp), intent(in) :: reference
      self%detect = .false.
      self%predictor_rcond = rcond
      self%predictor_regular = change_verdict(rcond, reference) == change_regular
      if (.not. self%predictor_regular) self%found = .true.
   end subroutine record_record_predictor

   pure subroutine record_clear_found(self)
      class(change_record_type), intent(inout) :: self
      self%found = .false.
   end subroutine record_clear_found

   subroutine record_keep_before(self, state)
      class(change_record_type), intent(inout) :: self
      type(fem_state_type), intent(in) :: state
      self%before = state
   end subroutine record_keep_before

   subroutine record_keep_ahead(self, state, iterations, residual, cuts, floor)
      class(change_record_type), intent(inout) :: self
      type(fem_state_type), intent(in) :: state
      integer, intent(in) :: iterations, cuts, floor
      real(dp), intent(in) :: residual
      self%ahead = state
      self%ahead_iterations = iterations
      self%ahead_residual = residual
      self%ahead_cuts = cuts
      self%ahead_floor = floor
      self%has_ahead = .true.
   end subroutine record_keep_ahead

   pure subroutine record_take_ahead(self, taken)
      class(change_record_type), intent(inout) :: self
      logical, intent(out) :: taken
      taken = self%has_ahead
      self%has_ahead = .false.
   end subroutine record_take_ahead

   !> Whether a predictor's condition estimate must be made, given bounds
   !> low <= rcond <= high on it (strain_rate_rcond_bounds) and the run's
   !> best so far, reference: unless the bounds show it regular by
   !> skip_margin (change_verdict and response_trusted would say regular and
   !> trusted) and no better than reference_slack times the run's best (the
   !> reference would change by less than that), both whatever the estimate
   !> within the bounds.
   pure logical function estimate_needed(low, high, reference) result(needed)
      real(dp), intent(in) :: low, high, reference
      needed = .not. (reference > 0 .and. low >= skip_margin*change_drop*reference .and. &
         & high <= reference_slack*reference)
   end function estimate_needed

   !> Correct the filled positions q at time t (driven and fixed dofs already
   !> set) onto the mechanism's configurations by Newton with the shifted
   !> material tangent K + mu I, mu = shift max diag K (shift = fill_shift on
   !> a singular tangent; 0, plain Newton, where it is regular enough) (at most
   !> fill_iterations corrections, until one is below `length`, each dof
   !> weighted by dof_length). Returns the corrections taken, the last
   !> correction's length and the residual at the corrected q. The system is
   !> left holding the shifted factor (not the tangent at q).
   subroutine correct_fill(system, mesh, q, t, seg, dof_length, length, shift, iterations, correction, residual, &
      & counts)
      type(linear_system_type), intent(inout) :: system
      type(mesh_type), intent(in) :: mesh
      real(dp), contiguous, intent(inout) :: q(:)
      real(dp), intent(in) :: t, length, shift
      integer, intent(in) :: seg(:)
      real(dp), contiguous, intent(in) :: dof_length(:)
      integer, intent(out) :: iterations
      real(dp), intent(out) :: correction, residual
      type(work_counts_type), intent(inout) :: counts
      real(dp) :: mu
      integer :: info
      iterations = 0
      correction = huge(1.0_dp)
      do while (iterations < fill_iterations)
         call assemble_system(system, mesh, q, t, seg, huge(1.0_dp), counts)
         residual = residual_norm(system, mesh)
         associate (diag => system%kff%a(system%kff%kd + 1, :))
            if (size(diag) == 0) exit
            mu = shift*maxval(diag)
            diag = diag + mu
         end associate
         call factor_system(system, info, counts)
         if (info /= 0) exit
         call newton_correction(system, mesh, dof_length, correction, counts)
         call apply_correction(system, mesh, q)
         iterations = iterations + 1
         counts%iterations = counts%iterations + 1
         if (correction <= length) exit
      end do
      call assemble_system_residual(system, mesh, q, t, seg, counts)
      residual = residual_norm(system, mesh)
   end subroutine correct_fill

end module fekap_fem_change_point
