!> The spatial kinematics' Newton iteration as a system of the one Newton
!> driver (fekap_stepping_newton's newton_solve, full Newton:
!> always_refactor_type), used by the deck's stepper
!> (fekap_spatial_stepper's solve) and by the library's spatial_newton alike.
!> spatial_newton_type keeps the iterate (a state of the mechanism at time
!> t, the drives set) and works on the stepper's band tangent
!> (fekap_spatial_tangent):
!> - assemble: the residual and the material tangent at the iterate
!>   (exact at the stress-free solution, where the geometric part vanishes);
!>   every assembly after a correction counts as an iteration (the
!>   correction needed another assembly after it);
!> - factor: the band factor; the condition estimate where the stepper
!>   watches the tangents, and at the first factor the change-point test of
!>   the predictor (near singular against the run's best: the solve stops,
!>   `found`);
!> - correct: the correction (lengths relative to the mechanism's length,
!>   angles in radians), applied to the iterate, unless it grew after the
!>   second (the solve stops: stop_test); an accepted one is applied too and
!>   the iterate it was solved from, whose factored tangent is that of the
!>   solution to round-off, is kept for the rates (`at`, with its
!>   configuration `c`);
!> - stop_test: the spatial method's own stops beside the contract's length:
!>   a correction at the round-off of the dofs' values, and for a run with
!>   rates a second correction below the length tolerance (see
!>   spatial_contract).
!> The contract is the planar FEM's kinematics contract (fekap_fem_convergence's
!> newton_contract: after each correction, the residual it was solved from
!> and its length), with a force scale of the mechanism's own (spatial_force_scale).
module fekap_spatial_newton
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, analysis_error
   use fekap_model, only: analysis_type, convergence_default
   use fekap_model_work, only: work_counts_type
   use fekap_stepping_newton, only: newton_system_type, newton_contract_type, newton_report_type, newton_solve, &
      & always_refactor_type, stop_converged, stop_at_floor, stop_diverged, stop_spent, stop_singular, &
      & stop_interrupted
   use fekap_stepping_change_point, only: change_verdict, change_regular
   use fekap_fem_convergence, only: convergence_type, newton_contract
   use fekap_spatial_mechanism, only: spatial_mechanism_type
   use fekap_spatial_tangent, only: spatial_tangent_type
   use fekap_spatial_change_point, only: shortest_element
   use fekap_spatial_kinematics, only: spatial_state_type, spatial_configuration_type, configure, assemble_spatial, &
      & set_drives, update_state, new_spatial_state, tangent_for, singular
   implicit none
   private

   public :: spatial_newton_type, spatial_contract, spatial_force_scale, spatial_newton, spatial_report_type

   !> factor's info when the change-point test found the predictor's tangent
   !> near singular (the solve stops; `found` says why).
   integer, parameter, public :: info_change_point = -1

   !> The last correction (relative to the mechanism's length) below which
   !> the iterate's tangent gives the rates: the rates at an iterate differ
   !> from those at the solution by about d(rates)/dq times the correction
   !> (an acceleration omega^2 times it), so a correction at the length
   !> tolerance's 1e-12 would cost the accelerations two digits. A run with
   !> rates asks its contract for this length; a correction that the length
   !> tolerance accepts above it is applied and the next, whatever its size
   !> below the tolerance, ends the solve (stop_test).
   real(dp), parameter, public :: rate_tol = 1.0e-14_dp
   !> A correction within this many units in the last place of the largest
   !> dof value (relative, as the corrections) is round-off, whatever the
   !> length tolerance and rate_tol say: a revolute angle driven 1,000 turns
   !> is 6,283 rad, whose last place (9e-13) the other dofs' corrections
   !> inherit, and another iteration cannot reduce it.
   real(dp), parameter :: roundoff_places = 4

   !> The outcome of the library's spatial_newton.
   type :: spatial_report_type
      !> Corrections made (the last one included).
      integer :: iterations = 0
      !> The last correction, lengths divided by the mechanism's length.
      real(dp) :: correction = 0
      logical :: converged = .false.
   end type spatial_report_type

   !> One Newton solve of the spatial kinematics at time t.
   type, extends(newton_system_type) :: spatial_newton_type
      type(spatial_mechanism_type), pointer :: m => null()
      !> The band tangent assembled and factored at each iterate.
      type(spatial_tangent_type), pointer :: kt => null()
      !> Where the work is counted (assemblies, factorisations, iterations).
      type(work_counts_type), pointer :: counts => null()
      !> The iterate (the drives set at t).
      type(spatial_state_type) :: s
      real(dp) :: t = 0
      !> The iterate whose factored tangent ended the solve, and its
      !> configuration (the last assembled): the rates' tangent.
      type(spatial_state_type) :: at
      type(spatial_configuration_type) :: c
      !> Each dof's unit in the corrections: 1 / the mechanism's length for
      !> lengths, 1 for angles.
      real(dp), allocatable :: scale(:)
      !> The residual of the last assembly and its norm on the free dofs.
      real(dp), allocatable :: res(:)
      real(dp) :: residual = 0
      !> The contract's length test and residual test, for stop_test's own stops.
      real(dp) :: length = 0, tolerance = 0, force_scale = 0, floor = 0
      !> The deck's length tolerance (rate runs: contract length rate_tol).
      real(dp) :: tol = 0
      !> Whether the rates are taken at the solution (the second correction
      !> below tol ends the solve).
      logical :: refine_rates = .false.
      !> Check the predictor's tangent for a change point; keep the least
      !> condition estimate of the iterates' tangents (least_rcond).
      logical :: detect = .false., watch = .false.
      !> The run's best reciprocal condition number (change_verdict's reference).
      real(dp) :: reference_rcond = 0
      !> Results: the change point found at the predictor, its tangent's
      !> condition, the least condition of a watched solve.
      logical :: found = .false.
      real(dp) :: predictor_rcond = 0, least_rcond = 0
      !> Corrections solved (tries), iterations counted (corrections followed
      !> by an assembly), the last correction and the one before.
      integer :: tries = 0, iterations = 0
      real(dp) :: correction = 0, last = 0
      !> A correction below tol was met (refining), the last correction
      !> passed the length tests (length_ok; at round-off: at_roundoff), or
      !> grew (not applied; the solve stops).
      logical :: refining = .false., length_ok = .false., at_roundoff = .false., grew = .false.
   contains
      procedure :: begin => spatial_begin
      procedure :: assemble => spatial_assemble
      procedure :: factor => spatial_factor
      procedure :: correct => spatial_correct
      procedure :: stop_test => spatial_stop_test
      procedure :: why => spatial_why
   end type spatial_newton_type

contains

   !> The spatial method's contract: the planar FEM's kinematics contract
   !> (newton_contract, its `default` test: after each correction, the residual
   !> it was solved from at most `tolerance` times force_scale or at the
   !> residual floor, and the correction's length at most the length
   !> tolerance tol) on the spatial units: corrections relative to the
   !> mechanism's length (model size 1), force_scale spatial_force_scale's.
   !> A run with rates asks rate_tol of the length (stop_test ends its solve
   !> at a second correction below tol as well). The paper's test (the
   !> residual alone, relative to the first) is not the spatial method's: its
   !> rates need the factor at the iterate the last correction was solved from.
   !> max_corrections counts the last correction too.
   pure function spatial_contract(tolerance, tol, max_corrections, force_scale, floor, refine_rates) result(contract)
      real(dp), intent(in) :: tolerance, tol, force_scale, floor
      integer, intent(in) :: max_corrections
      logical, intent(in) :: refine_rates
      type(newton_contract_type) :: contract
      type(convergence_type) :: conv
      conv%mode = convergence_default
      conv%tol = tolerance
      conv%length = tol
      if (refine_rates) conv%length = min(tol, rate_tol)
      conv%residual_floor = floor
      contract = newton_contract(conv, force_scale, max_corrections, 1.0_dp)
      ! Every solve factors its first iterate: the rates and the drive
      ! response come from the factor at the solution.
      contract%accept_start_at_floor = .false.
   end function spatial_contract

   !> The mechanism's force scale and residual floor, from its tangent kt
   !> assembled at the reference configuration: force_scale the largest
   !> residual a unit correction of one free dof makes (its diagonal term
   !> times its unit: the mechanism's length for lengths, 1 rad for angles),
   !> so that the contract's `tolerance` times it is the residual of a
   !> relative correction `tolerance` in the stiffest dof, whatever the
   !> step; the floor, as the planar FEM's residual_floor, a relative
   !> correction of 1e-13 (or the round-off of a strain, eps times the
   !> mechanism's length over its shortest element) there, times the square
   !> root of the number of unknowns.
   subroutine spatial_force_scale(m, kt, shortest, force_scale, floor)
      type(spatial_mechanism_type), intent(in) :: m
      type(spatial_tangent_type), intent(inout) :: kt
      real(dp), intent(in) :: shortest
      real(dp), intent(out) :: force_scale, floor
      type(spatial_configuration_type) :: c
      real(dp) :: res(m%ndof)
      integer :: i, dof
      call configure(m, new_spatial_state(m), c)
      call assemble_spatial(m, c, res, sparse=kt)
      force_scale = 0
      do i = 1, kt%nfree
         dof = kt%fdof(i)
         force_scale = max(force_scale, abs(kt%kff%a(kt%kff%kd + 1, kt%equation(dof)))* &
            & merge(m%length, 1.0_dp, m%is_length(dof)))
      end do
      floor = max(1.0e-13_dp, epsilon(1.0_dp)*m%length/shortest)*force_scale*sqrt(real(max(1, kt%nfree), dp))
   end subroutine spatial_force_scale

   !> A solve at time t from state s (its drives set here) under `contract`
   !> (spatial_contract's, of the length tolerance tol and refine_rates):
   !> the mechanism, its tangent's storage and where to count the work.
   subroutine spatial_begin(self, m, kt, counts, s, t, contract, tol, refine_rates)
      class(spatial_newton_type), intent(inout) :: self
      type(spatial_mechanism_type), target, intent(in) :: m
      type(spatial_tangent_type), target, intent(inout) :: kt
      type(work_counts_type), target, intent(inout) :: counts
      type(spatial_state_type), intent(in) :: s
      real(dp), intent(in) :: t, tol
      type(newton_contract_type), intent(in) :: contract
      logical, intent(in) :: refine_rates
      real(dp) :: vd(m%ndof), ad(m%ndof)
      self%m => m
      self%kt => kt
      self%counts => counts
      self%s = s
      self%t = t
      self%tol = tol
      self%refine_rates = refine_rates
      self%length = contract%length
      self%tolerance = contract%tolerance
      self%force_scale = contract%force_scale
      self%floor = contract%floor
      call set_drives(m, t, self%s, vd, ad)
      self%scale = merge(1/m%length, 1.0_dp, m%is_length)
      if (.not. allocated(self%res)) allocate (self%res(m%ndof))
      self%tries = 0
      self%iterations = 0
      self%correction = 0
      self%last = huge(1.0_dp)
      self%refining = .false.
      self%length_ok = .false.
      self%at_roundoff = .false.
      self%grew = .false.
      self%found = .false.
      self%residual = 0
   end subroutine spatial_begin

   !> The residual and the material tangent at the iterate (the contract
   !> tests after a correction, and full Newton factors each iterate).
   subroutine spatial_assemble(self, matrix, norm)
      class(spatial_newton_type), intent(inout) :: self
      logical, intent(in) :: matrix
      real(dp), intent(out) :: norm
      if (self%tries > 0) then
         self%iterations = self%iterations + 1
         self%counts%iterations = self%counts%iterations + 1
      end if
      call configure(self%m, self%s, self%c)
      call assemble_spatial(self%m, self%c, self%res, sparse=self%kt)
      self%counts%tangent_assemblies = self%counts%tangent_assemblies + 1
      self%residual = norm2(self%res(self%kt%fdof))
      norm = self%residual
   end subroutine spatial_assemble

   !> The band factor of the tangent; the condition estimates the stepper
   !> watches; at the first factor the change-point test of the predictor
   !> (a failed factor counts as a condition of 0). info: the singular dof,
   !> or info_change_point.
   subroutine spatial_factor(self, info)
      class(spatial_newton_type), intent(inout) :: self
      integer, intent(out) :: info
      real(dp) :: rcond
      call self%kt%factor(info)
      if (self%kt%is_lu()) then
         self%counts%lu_factorisations = self%counts%lu_factorisations + 1
      else
         self%counts%cholesky_factorisations = self%counts%cholesky_factorisations + 1
      end if
      rcond = 0
      if ((self%watch .or. (self%tries == 0 .and. self%detect)) .and. info == 0) call self%kt%rcond(rcond)
      if (self%watch) then
         if (self%tries == 0) self%least_rcond = huge(1.0_dp)
         self%least_rcond = min(self%least_rcond, rcond)
      end if
      if (self%tries == 0 .and. self%detect) then
         self%predictor_rcond = rcond
         if (change_verdict(self%predictor_rcond, self%reference_rcond) /= change_regular) then
            self%found = .true.
            info = info_change_point
         end if
      end if
   end subroutine spatial_factor

   !> The correction from the last residual with the factor, its length
   !> (relative, the largest over the dofs), applied to the iterate unless
   !> it grew: after the second correction, one above the length tests and
   !> longer than the one before, while no correction has met tol yet.
   subroutine spatial_correct(self, length, error)
      class(spatial_newton_type), intent(inout) :: self
      real(dp), intent(out) :: length
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: dq(self%m%ndof), roundoff
      real(dp), allocatable :: rhs(:)
      rhs = -self%res(self%kt%fdof)
      call self%kt%solve(rhs)
      dq = 0
      dq(self%kt%fdof) = rhs
      self%correction = maxval(abs(dq*self%scale))
      length = self%correction
      self%tries = self%tries + 1
      if (.not. self%correction < huge(1.0_dp)) then
         call analysis_error(error, 'the correction is not a finite number')
         return
      end if
      ! The dofs are coupled: the round-off of the largest value (at least
      ! a rotation of 1 rad or the mechanism's length) bounds every
      ! correction that another iteration could make (see roundoff_places).
      roundoff = roundoff_places*maxval(spacing(max(abs(self%s%q), 1/self%scale))*self%scale)
      self%at_roundoff = self%correction < roundoff
      self%length_ok = self%correction <= self%length .or. (self%correction < max(self%tol, roundoff) .and. &
         & (self%correction < max(rate_tol, roundoff) .or. self%refining .or. .not. self%refine_rates))
      if (self%length_ok) then
         ! Converged at the iterate it was solved from, the solution to
         ! round-off: its factored tangent gives the rates.
         self%at = self%s
      else
         ! Converged, but the rates want the next iterate (once: round-off may keep it above rate_tol).
         if (self%correction < max(self%tol, roundoff)) self%refining = .true.
         self%grew = self%tries >= 3 .and. self%correction > self%last .and. .not. self%refining
         if (self%grew) return
         self%last = self%correction
      end if
      call update_state(self%m, self%s, dq)
   end subroutine spatial_correct

   !> The spatial method's stops beside the contract's: a correction that
   !> grew (stop_diverged); one that passed the length tests above the
   !> contract's length (round-off, or the second below tol of a run with
   !> rates) ends the solve if the residual it was solved from passes the
   !> contract's residual test, or at round-off whatever it is (stop_at_floor).
   integer function spatial_stop_test(self, report) result(stopped)
      class(spatial_newton_type), intent(inout) :: self
      type(newton_report_type), intent(in) :: report
      stopped = 0
      if (self%grew) then
         stopped = stop_diverged
      else if (self%length_ok) then
         if (self%residual <= self%tolerance*self%force_scale) then
            stopped = stop_converged
         else if (self%residual <= self%floor .or. self%at_roundoff) then
            stopped = stop_at_floor
         end if
      end if
   end function spatial_stop_test

   !> Why a solve that did not converge stopped (report and error from
   !> newton_solve; limit: the iterations the caller allowed).
   function spatial_why(self, report, error, limit) result(why)
      class(spatial_newton_type), intent(in) :: self
      type(newton_report_type), intent(in) :: report
      type(error_type), intent(in) :: error
      integer, intent(in) :: limit
      character(:), allocatable :: why
      character(len=200) :: text
      select case (report%stopped)
      case (stop_spent)
         write (text, '(a,i0,a)') 'no convergence in ', limit, ' iterations'
      case (stop_diverged)
         if (self%grew) then
            write (text, '(a,i0)') 'the correction grew at iteration ', self%tries
         else
            write (text, '(a,es9.2,a)') 'the correction diverged (', self%correction, ' mechanism lengths)'
         end if
      case (stop_singular)
         if (self%found) then
            text = 'a change point at the predictor'
         else if (report%info > 0) then
            write (text, '(a,i0)') 'singular tangent at dof ', report%info
         else
            text = error%message
         end if
      case default
         text = error%message
      end select
      why = trim(text)
   end function spatial_why

   !> Newton-Raphson on the free dofs at time t (drives set first) from s
   !> until the correction is below tol (lengths relative to the
   !> mechanism's length), the residual it was solved from below the
   !> analysis' default tolerance of the mechanism's force scale: the
   !> stepper's solve (spatial_newton_type, spatial_contract) without rates,
   !> change points or step cuts. At most max_iterations corrections.
   subroutine spatial_newton(m, t, s, tol, max_iterations, report, error)
      type(spatial_mechanism_type), target, intent(in) :: m
      real(dp), intent(in) :: t, tol
      type(spatial_state_type), intent(inout) :: s
      integer, intent(in) :: max_iterations
      type(spatial_report_type), intent(out) :: report
      type(error_type), allocatable, intent(out) :: error
      type(spatial_tangent_type), target :: kt
      type(work_counts_type), target :: counts
      type(spatial_newton_type) :: system
      type(newton_contract_type) :: contract
      type(always_refactor_type) :: full
      type(newton_report_type) :: solved
      type(analysis_type) :: defaults
      real(dp) :: force_scale, floor
      character(:), allocatable :: why
      call tangent_for(m, kt)
      call spatial_force_scale(m, kt, shortest_element(m), force_scale, floor)
      contract = spatial_contract(defaults%tol, tol, max_iterations, force_scale, floor, .false.)
      call system%begin(m, kt, counts, s, t, contract, tol, .false.)
      call newton_solve(system, contract, full, solved, error)
      s = system%s
      report%iterations = solved%iterations
      report%correction = system%correction
      report%converged = solved%converged()
      if (.not. allocated(error)) return
      select case (solved%stopped)
      case (stop_singular)
         if (solved%info > 0) then
            deallocate (error)
            call singular(error, solved%info, t)
         end if
      case (stop_interrupted)
         ! The interrupt keeps its message.
      case default
         why = system%why(solved, error, max_iterations)
         deallocate (error)
         call analysis_error(error, 'Newton did not converge in the spatial kinematics ('//why//'): a dead point '// &
            & 'or a configuration that does not assemble; drive another joint or take smaller steps')
      end select
   end subroutine spatial_newton

end module fekap_spatial_newton
