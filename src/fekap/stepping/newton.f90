!> The one Newton driver: a method states its equations as a system
!> (newton_system_type: assemble the residual and, when asked, the iteration
!> matrix; factor it; solve a correction with the factor and apply it) and
!> newton_solve iterates it under a convergence contract
!> (newton_contract_type) and a factor reuse policy (reuse_policy_type),
!> returning what happened as a report (newton_report_type). The driver knows
!> no mesh and no method.
!>
!> The contract (docs/theory.md, "Convergence"), test_at_iterate: an
!> iterate has converged when its residual is at most tolerance times the
!> forces in play (force_scale) and the correction that led to it is at most
!> the length tolerance. A residual that cannot reach the tolerance because
!> of round-off is accepted below the floor, with the same length test, and
!> reported as such (stop_at_floor). At least one correction is made. The
!> kinematics' tests are the other two modes (test_solved_from,
!> test_relative_first).
module fekap_stepping_newton
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, analysis_error
   use fekap_strings, only: int_text, short_real_text
   use fekap_stepping_interrupt, only: interrupt_error
   implicit none
   private

   public :: newton_system_type, newton_contract_type, newton_report_type, newton_solve
   public :: reuse_policy_type, always_refactor_type, kept_factor_type, admissible_strain

   !> Why newton_solve stopped (newton_report_type's stopped).
   integer, parameter, public :: stop_converged = 1, stop_at_floor = 2, stop_spent = 3, stop_diverged = 4, &
      & stop_not_finite = 5, stop_singular = 6, stop_interrupted = 7

   !> When the contract is tested (newton_contract_type's test):
   !> test_at_iterate: the residual at the iterate and the correction that led
   !> to it (see above); test_solved_from: the kinematics' default test, after
   !> each correction, on the residual it was solved from and its length (or
   !> the first iterate's residual at the floor, no correction);
   !> test_relative_first: the paper's test, the residual at the iterate below
   !> tolerance times the first residual (or the floor), no length test.
   integer, parameter, public :: test_at_iterate = 1, test_solved_from = 2, test_relative_first = 3

   !> The convergence contract of one solve.
   type :: newton_contract_type
      !> Residual tolerance, relative to force_scale.
      real(dp) :: tolerance = 1.0e-10_dp
      !> Absolute length tolerance on the last correction (the method's
      !> length tolerance times its model size).
      real(dp) :: length = 1.0e-12_dp
      !> Corrections allowed before the solve gives up.
      integer :: max_iterations = 25
      !> The size of the forces in play (the method's choice, e.g. the largest
      !> norm of the inertia, weights, loads and reactions of the step).
      real(dp) :: force_scale = 0
      !> The residual round-off cannot go below: a last resort, see stop_at_floor.
      real(dp) :: floor = 0
      !> A correction longer than this is divergence.
      real(dp) :: divergence = huge(1.0_dp)
      !> test_at_iterate, test_solved_from or test_relative_first.
      integer :: test = test_at_iterate
      !> The force scale is the first iterate's residual, not force_scale (the
      !> FEM's `previous` predictor: the residual of the drive increment alone
      !> is the residual at the last configuration, known at the first assembly).
      logical :: scale_by_first = .false.
      !> test_solved_from: whether a first iterate whose residual is at the
      !> floor is accepted without a correction (the FEM corrects it once).
      logical :: accept_start_at_floor = .true.
   end type newton_contract_type

   !> What a solve did.
   type :: newton_report_type
      !> Corrections made; factorisations of the iteration matrix.
      integer :: iterations = 0, factorisations = 0
      !> Residual norm at the first iterate and at the last one assembled.
      real(dp) :: first_residual = 0, last_residual = 0
      !> Length of the last correction (0 before the first).
      real(dp) :: last_correction = 0
      !> One of stop_converged, ..., stop_interrupted (0: not stopped yet).
      integer :: stopped = 0
      !> stop_singular: the factorisation's info (the singular equation).
      integer :: info = 0
   contains
      !> Whether the solve converged (at the tolerance or at the floor).
      procedure :: converged => report_converged
   end type newton_report_type

   !> A method's equations for Newton. The system keeps its own iterate.
   type, abstract :: newton_system_type
   contains
      !> The residual at the current iterate and its norm; with `matrix` the
      !> iteration matrix as well (for the factor that follows).
      procedure(assemble_interface), deferred :: assemble
      !> Factor the iteration matrix last assembled; info /= 0: singular.
      procedure(factor_interface), deferred :: factor
      !> Solve the correction for the residual last assembled with the
      !> current factor, apply it to the iterate, and return its length (an
      !> error: no correction, the solve stops with it).
      procedure(correct_interface), deferred :: correct
      !> After a correction that the contract did not stop at, a method's
      !> own stop (stop_converged or stop_at_floor; 0: go on), as the FEM's
      !> on an estimate of the next correction. None by default.
      procedure :: stop_test => system_stop_test
   end type newton_system_type

   abstract interface
      subroutine assemble_interface(self, matrix, norm)
         import :: newton_system_type, dp
         implicit none
         class(newton_system_type), intent(inout) :: self
         logical, intent(in) :: matrix
         real(dp), intent(out) :: norm
      end subroutine assemble_interface

      subroutine factor_interface(self, info)
         import :: newton_system_type
         implicit none
         class(newton_system_type), intent(inout) :: self
         integer, intent(out) :: info
      end subroutine factor_interface

      subroutine correct_interface(self, length, error)
         import :: newton_system_type, dp, error_type
         implicit none
         class(newton_system_type), intent(inout) :: self
         real(dp), intent(out) :: length
         type(error_type), allocatable, intent(out) :: error
      end subroutine correct_interface
   end interface

   !> When a factor of the iteration matrix is kept for a further correction
   !> (modified Newton) and when a correction made with it tells convergence.
   type, abstract :: reuse_policy_type
   contains
      !> A solve begins (no factor yet).
      procedure(policy_begin_interface), deferred :: begin
      !> Whether the next correction may use the factor in hand.
      procedure(policy_keep_interface), deferred :: keep
      !> A fresh factor was made.
      procedure(policy_begin_interface), deferred :: factored
      !> A correction of this length was made (with the kept factor if
      !> `kept`); returns whether its length bounds the error left.
      procedure(policy_observe_interface), deferred :: observe
   end type reuse_policy_type

   abstract interface
      subroutine policy_begin_interface(self)
         import :: reuse_policy_type
         implicit none
         class(reuse_policy_type), intent(inout) :: self
      end subroutine policy_begin_interface

      logical function policy_keep_interface(self)
         import :: reuse_policy_type
         implicit none
         class(reuse_policy_type), intent(in) :: self
      end function policy_keep_interface

      logical function policy_observe_interface(self, kept, correction)
         import :: reuse_policy_type, dp
         implicit none
         class(reuse_policy_type), intent(inout) :: self
         logical, intent(in) :: kept
         real(dp), intent(in) :: correction
      end function policy_observe_interface
   end interface

   !> Full Newton: every correction with a fresh factor.
   type, extends(reuse_policy_type) :: always_refactor_type
   contains
      procedure :: begin => refactor_begin
      procedure :: keep => refactor_keep
      procedure :: factored => refactor_begin
      procedure :: observe => refactor_observe
   end type always_refactor_type

   !> A factor kept while Newton's quadratic constant kappa (measured on
   !> full iterations, delta_k <= kappa delta_k-1^2) bounds the modified
   !> iteration's contraction, 2 kappa times the distance moved since the
   !> factor, by `contraction`. A correction then leaves at most that share
   !> of itself as error, and the convergence test is full Newton's; a kept
   !> factor that contracted less than its bound raises kappa to what it
   !> showed (the factor is renewed sooner) and its correction tells nothing,
   !> unless it is at round-off (below least). kappa lives from solve to solve
   !> (the steps of a run).
   type, extends(reuse_policy_type) :: kept_factor_type
      !> The contraction a kept factor must be bound to; 0: never kept.
      real(dp) :: contraction = 1.0e-3_dp
      !> Newton's quadratic constant as last measured (1 / length); 0: unknown.
      real(dp) :: kappa = 0
      !> Corrections below this measure nothing (round-off).
      real(dp) :: least = 0
      !> Within a solve: whether a factor exists, the distance moved since
      !> it, the last correction, and whether that correction was full.
      logical :: has_factor = .false., full_before = .false.
      real(dp) :: moved = 0, previous = 0
   contains
      procedure :: begin => kept_begin
      procedure :: keep => kept_keep
      procedure :: factored => kept_factored
      procedure :: observe => kept_observe
   end type kept_factor_type


   !> Element strain above which a converged configuration is not a mechanism
   !> configuration but a self-stressed equilibrium (admissible_strain).
   !> It follows the Newton tolerance (a loose paper-style test leaves strains
   !> near the tolerance) but never reaches the strains of a self-stressed
   !> state, which are of order 0.1.
   real(dp), parameter :: min_admissible_strain = 1.0e-8_dp, max_admissible_strain = 1.0e-3_dp

contains

   !> The largest element strain of a mechanism configuration under the
   !> Newton tolerance tol (the planar FEM's and the spatial stepper's check
   !> for a self-stressed equilibrium).
   pure real(dp) function admissible_strain(tol)
      real(dp), intent(in) :: tol
      admissible_strain = min(max_admissible_strain, max(min_admissible_strain, 100*tol))
   end function admissible_strain

   !> Newton on `system` from its current iterate until the contract holds.
   !> Each iterate's residual is assembled alone when the factor in hand is
   !> kept or the last correction already passed the length test (the
   !> iterate has then likely converged and needs no matrix); else with the
   !> iteration matrix, which is factored. error is allocated for every stop
   !> other than convergence, with a message naming the stop (a method may
   !> replace it with its own words, from report%stopped).
   subroutine newton_solve(system, contract, policy, report, error)
      class(newton_system_type), intent(inout) :: system
      type(newton_contract_type), intent(in) :: contract
      class(reuse_policy_type), intent(inout) :: policy
      type(newton_report_type), intent(out) :: report
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: r, correction
      logical :: kept, probed, trusted
      integer :: info
      call policy%begin()
      trusted = .false.
      do
         ! A signal ends the solve here (a slow solve would delay the stop).
         call interrupt_error(error)
         if (allocated(error)) then
            report%stopped = stop_interrupted
            return
         end if
         kept = report%iterations > 0 .and. policy%keep()
         probed = kept .or. (contract%test == test_at_iterate .and. report%iterations > 0 .and. trusted .and. &
            & report%last_correction <= contract%length)
         if (probed) then
            call system%assemble(.false., r)
            call test_iterate(r)
            if (report%stopped /= 0) exit
         end if
         if (.not. kept) then
            call system%assemble(.true., r)
            ! A probed iterate's residual was tested already (the same numbers).
            if (.not. probed) then
               call test_iterate(r)
               if (report%stopped /= 0) exit
            end if
            call system%factor(info)
            if (info /= 0) then
               report%stopped = stop_singular
               report%info = info
               exit
            end if
            report%factorisations = report%factorisations + 1
            call policy%factored()
         end if
         call system%correct(correction, error)
         if (allocated(error)) then
            ! The system's own words (a singular solve named by its dof).
            report%stopped = stop_singular
            return
         end if
         report%iterations = report%iterations + 1
         report%last_correction = correction
         trusted = policy%observe(kept, correction)
         if (correction > contract%divergence) then
            report%stopped = stop_diverged
            exit
         end if
         if (contract%test == test_solved_from .and. trusted .and. correction <= contract%length) then
            report%stopped = accepted(contract, r, scale_of(contract, report))
            if (report%stopped /= 0) exit
         end if
         report%stopped = system%stop_test(report)
         if (report%stopped /= 0) exit
      end do
      if (.not. report%converged()) call analysis_error(error, stop_text(report))
   contains
      !> The tests of an iterate's residual r, in the contract's order.
      subroutine test_iterate(r)
         real(dp), intent(in) :: r
         if (report%iterations == 0) report%first_residual = r
         report%last_residual = r
         select case (contract%test)
         case (test_relative_first)
            if (r < contract%tolerance*report%first_residual .or. r <= contract%floor) then
               report%stopped = stop_converged
               return
            end if
         case (test_solved_from)
            ! An iterate that starts converged (at round-off): no correction.
            if (report%iterations == 0 .and. r <= contract%floor .and. contract%accept_start_at_floor) then
               report%stopped = stop_converged
               return
            end if
         case default
            if (.not. r <= huge(1.0_dp)) then
               report%stopped = stop_not_finite
               return
            end if
            if (report%iterations > 0 .and. trusted .and. report%last_correction <= contract%length) then
               report%stopped = accepted(contract, r, scale_of(contract, report))
               if (report%stopped /= 0) return
            end if
         end select
         if (report%iterations >= contract%max_iterations) report%stopped = stop_spent
      end subroutine test_iterate
   end subroutine newton_solve

   !> The residual test of an iterate whose correction passed the length
   !> test: converged below the tolerance of the forces in play, else at the
   !> round-off floor as the last resort, else not (0).
   pure integer function accepted(contract, r, scale) result(stopped)
      type(newton_contract_type), intent(in) :: contract
      !> The residual, and the force scale (scale_of).
      real(dp), intent(in) :: r, scale
      stopped = 0
      if (r <= contract%tolerance*scale) then
         stopped = stop_converged
      else if (r <= contract%floor) then
         stopped = stop_at_floor
      end if
   end function accepted

   !> The contract's force scale in a solve (see scale_by_first).
   pure real(dp) function scale_of(contract, report) result(scale)
      type(newton_contract_type), intent(in) :: contract
      type(newton_report_type), intent(in) :: report
      if (contract%scale_by_first) then
         scale = report%first_residual
      else
         scale = contract%force_scale
      end if
   end function scale_of

   !> No stop of the method's own.
   integer function system_stop_test(self, report) result(stopped)
      class(newton_system_type), intent(inout) :: self
      type(newton_report_type), intent(in) :: report
      stopped = 0
   end function system_stop_test

   !> Whether the solve converged (at the tolerance, or at the round-off floor).
   pure logical function report_converged(self)
      class(newton_report_type), intent(in) :: self
      report_converged = self%stopped == stop_converged .or. self%stopped == stop_at_floor
   end function report_converged

   !> The message of a solve that did not converge.
   function stop_text(report) result(text)
      type(newton_report_type), intent(in) :: report
      character(:), allocatable :: text
      select case (report%stopped)
      case (stop_spent)
         text = 'Newton did not converge in '//int_text(report%iterations)//' iterations (residual '// &
            & short_real_text(report%last_residual)//', first '//short_real_text(report%first_residual)//')'
      case (stop_diverged)
         text = 'Newton diverged at iteration '//int_text(report%iterations)//' (correction '// &
            & short_real_text(report%last_correction)//')'
      case (stop_not_finite)
         text = 'the residual is not finite at Newton iteration '//int_text(report%iterations)
      case (stop_singular)
         text = 'the iteration matrix is singular at equation '//int_text(report%info)
      case default
         text = 'Newton stopped'
      end select
   end function stop_text

   subroutine refactor_begin(self)
      class(always_refactor_type), intent(inout) :: self
   end subroutine refactor_begin

   logical function refactor_keep(self) result(keep)
      class(always_refactor_type), intent(in) :: self
      keep = .false.
   end function refactor_keep

   logical function refactor_observe(self, kept, correction) result(trusted)
      class(always_refactor_type), intent(inout) :: self
      logical, intent(in) :: kept
      real(dp), intent(in) :: correction
      trusted = .true.
   end function refactor_observe

   subroutine kept_begin(self)
      class(kept_factor_type), intent(inout) :: self
      self%has_factor = .false.
      self%full_before = .false.
      self%moved = 0
      self%previous = 0
   end subroutine kept_begin

   logical function kept_keep(self) result(keep)
      class(kept_factor_type), intent(in) :: self
      keep = self%has_factor .and. self%kappa > 0 .and. 2*self%kappa*self%moved <= self%contraction
   end function kept_keep

   subroutine kept_factored(self)
      class(kept_factor_type), intent(inout) :: self
      self%has_factor = .true.
      self%moved = 0
   end subroutine kept_factored

   !> kappa = delta_k / delta_k-1^2 from a full iteration that follows a
   !> full one (the latest measure counts); a kept factor's correction
   !> tells convergence only when it contracted as bounded (else the error
   !> left may be near the correction itself).
   logical function kept_observe(self, kept, correction) result(trusted)
      class(kept_factor_type), intent(inout) :: self
      logical, intent(in) :: kept
      real(dp), intent(in) :: correction
      if (self%previous > self%least .and. correction > self%least) then
         if (.not. kept .and. self%full_before) then
            self%kappa = correction/self%previous**2
         else if (kept .and. correction > self%contraction*self%previous) then
            self%kappa = max(self%kappa, correction/(2*self%previous*self%moved))
         end if
      end if
      ! A correction at round-off (below least) is trusted: the iterate is as
      ! converged as the arithmetic allows, and a kept factor would otherwise
      ! be stuck there (such corrections raise no kappa).
      trusted = .not. kept .or. correction <= self%contraction*self%previous .or. correction <= self%least
      self%previous = correction
      self%full_before = .not. kept
      self%moved = self%moved + correction
   end function kept_observe

end module fekap_stepping_newton
