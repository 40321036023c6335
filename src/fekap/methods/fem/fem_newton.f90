!> The FEM's Newton iteration of a step as a system of the one Newton driver
!> (fekap_stepping_newton's newton_solve, full Newton: always_refactor_type):
!> fem_newton_type is the step's Newton workspace, owned by this module and
!> passed explicitly. What the FEM adds to the driver's loop lives in its
!> assemble, factor, correct and stop_test:
!> - assemble: the residual and tangent of the iterate (newton_assembly: the
!>   material tangent below kg_above, K or the square-root form's B), with
!>   the predictor's guard at the step's first assembly (guard_extrapolation,
!>   when predict extrapolated);
!> - factor: the square-root form's B_f solve, or K's factor; at the step's
!>   first factor the change-point probe (check_predictor: a near-singular
!>   tangent at the predictor ends the solve, `change%found`); a singular
!>   material tangent switches to the full tangent for the rest of the step;
!> - correct: the correction, applied unless it diverges or the predictor
!>   has converged already (at_predictor: a first correction at round-off);
!> - stop_test: the stop on an estimate of the next correction
!>   (converged_by_estimate) and the stall at the residual's round-off floor.
!> The relocation of slidelines and the check of an estimated stop wrap
!> newton_solve in fekap_fem's solve_step; the step-doubling verification
!> wraps the try of a step.
module fekap_fem_newton
   use fekap_kinds, only: dp
   use fekap_error, only: error_type
   use fekap_model, only: convergence_paper, predictor_previous
   use fekap_stepping_newton, only: newton_system_type, newton_contract_type, newton_report_type, stop_converged, &
      & stop_at_floor
   use fekap_stepping_predictor, only: predictor_margin
   use fekap_fem_convergence, only: is_converged, converged_by_estimate, newton_contract
   use fekap_fem_linear_system, only: assemble_system, factor_system, residual_norm, newton_correction
   use fekap_fem_rates, only: near_singular_drop
   use fekap_fem_state, only: fem_core_type
   use fekap_fem_factor, only: newton_assembly, root_correction, take_correction, accepted_pivot
   use fekap_fem_predict, only: guard_extrapolation
   use fekap_fem_fill, only: check_predictor
   implicit none
   private

   public :: fem_newton_type, fem_contract

   !> Newton's tangent leaves out the geometric stiffness at Gauss points
   !> strained less than this (see begin_step).
   real(dp), parameter :: geometric_strain = 3.0e-3_dp
   !> Iterations in a row with the residual below its floor after which
   !> Newton has stalled at round-off.
   integer, parameter :: stall_iterations = 3

   !> factor's info when the change-point probe found the predictor's tangent
   !> near singular (the solve stops; the stepper's change%found says why).
   integer, parameter, public :: info_change_point = -1

   !> The Newton workspace of one FEM step at time t: the stepper it solves
   !> (its iterate is the stepper's qt), what the step's passes share, and
   !> what one pass (one newton_solve) knows.
   type, extends(newton_system_type) :: fem_newton_type
      class(fem_core_type), pointer :: fem => null()
      real(dp) :: t = 0
      !> Gauss points strained above this get the geometric stiffness (0:
      !> full Newton, after a singular material tangent, for the step).
      real(dp) :: kg_above = 0
      !> The residual scale (the drive and load increment's residual).
      real(dp) :: increment_residual = 0
      !> The step's last residual assembled, its last correction and the one
      !> before (for the estimate), and the correction left at a stall (0: none).
      real(dp) :: residual = 0, correction = 0, previous = 0, stalled_correction = 0
      !> Corrections applied in the step (the step's iterations), and
      !> iterations in a row at the residual's floor.
      integer :: iterations = 0, at_floor = 0
      !> Whether the last pass stopped on the estimate (kept across a
      !> relocation: solve_step checks it after the last pass).
      logical :: by_estimate = .false.
      !> One pass: corrections tried, the residual at its first iterate,
      !> whether it ended at the predictor, whether the square-root form
      !> solved its correction.
      integer :: tries = 0
      real(dp) :: r0 = 0
      logical :: at_predictor = .false., root_solved = .false.
      !> The contract's divergence length (a diverging correction is not applied).
      real(dp) :: divergence = huge(1.0_dp)
      !> The predictor's guard: whether the step's first assembly is still to
      !> check an extrapolated predictor (guard_extrapolation).
      logical :: guard_pending = .false.
   contains
      procedure :: begin_step
      procedure :: begin_pass
      procedure :: assemble => fem_assemble
      procedure :: factor => fem_factor
      procedure :: correct => fem_correct
      procedure :: stop_test => fem_stop_test
   end type fem_newton_type

contains

   !> The FEM's convergence contract (docs/theory.md, "Convergence"): the
   !> deck's tolerance relative to the residual of the drive (and load)
   !> increment (`default`, after each correction, with the deck's length
   !> tolerance times the model size) or to the first residual (`paper`); the
   !> round-off floor; the deck's iterations per pass.
   function fem_contract(fem, increment_residual) result(contract)
      class(fem_core_type), intent(in) :: fem
      real(dp), intent(in) :: increment_residual
      type(newton_contract_type) :: contract
      contract = newton_contract(fem%conv, increment_residual, fem%model%analysis%max_iter, fem%model_length)
      contract%scale_by_first = fem%model%analysis%predictor == predictor_previous
      contract%accept_start_at_floor = .false.
   end function fem_contract

   !> A step of `fem` at time t from its predictor (in fem%qt); `guard`:
   !> the predictor extrapolated (predict's guard).
   subroutine begin_step(self, fem, t, contract, guard)
      class(fem_newton_type), intent(inout) :: self
      class(fem_core_type), target, intent(inout) :: fem
      real(dp), intent(in) :: t
      type(newton_contract_type), intent(in) :: contract
      logical, intent(in) :: guard
      self%fem => fem
      self%t = t
      self%guard_pending = guard
      self%increment_residual = contract%force_scale
      self%divergence = contract%divergence
      self%iterations = 0
      self%r0 = 0
      self%residual = 0
      self%correction = 0
      self%previous = 0
      self%at_floor = 0
      self%stalled_correction = 0
      self%by_estimate = .false.
      ! Newton's tangent leaves out the geometric stiffness where the iterate
      ! is strained less than geometric_strain. At a mechanism configuration
      ! the stresses vanish, so near it the material tangent is the exact
      ! tangent to first order and convergence stays quadratic (Gauss-Newton
      ! on a zero-residual problem), while the geometric stiffness of a
      ! predictor's small spurious strains, which can exceed the bending
      ! stiffness of slender links, no longer bends the path of the
      ! iteration (docs/performance.md has the iteration counts). Far from
      ! it (large strains) the full tangent is the more robust.
      self%kg_above = merge(0.0_dp, geometric_strain, fem%loaded)
   end subroutine begin_step

   !> A pass of Newton (one newton_solve) from the current iterate.
   subroutine begin_pass(self)
      class(fem_newton_type), intent(inout) :: self
      self%tries = 0
      self%at_predictor = .false.
   end subroutine begin_pass

   !> The residual and tangent at the iterate (the FEM always assembles both:
   !> its contract tests after a correction, and full Newton factors each).
   subroutine fem_assemble(self, matrix, norm)
      class(fem_newton_type), intent(inout) :: self
      logical, intent(in) :: matrix
      real(dp), intent(out) :: norm
      associate (fem => self%fem)
         call newton_assembly(fem, fem%qt, self%t, self%kg_above)
         ! The predictor's guard, once per step: it needs the strains of this first assembly.
         if (self%guard_pending) then
            self%guard_pending = .false.
            if (guard_extrapolation(fem, self%t, fem%qt)) call newton_assembly(fem, fem%qt, self%t, self%kg_above)
         end if
         self%residual = residual_norm(fem%system, fem%mesh)
         if (self%tries == 0) then
            self%r0 = self%residual
            if (fem%model%analysis%predictor == predictor_previous) self%increment_residual = self%r0
         end if
      end associate
      norm = self%residual
   end subroutine fem_assemble

   !> The factor of the iteration's tangent (or the square-root form's
   !> correction, which factors B_f); the change-point probe at the step's
   !> first factor; a singular material tangent retried with the full one.
   subroutine fem_factor(self, info)
      class(fem_newton_type), intent(inout) :: self
      integer, intent(out) :: info
      associate (fem => self%fem)
         self%root_solved = .false.
         if (fem%root_form .and. fem%system%assembled_strain < self%kg_above) then
            call root_correction(fem, fem%qt, .false., self%correction, self%root_solved)
            ! B_f singular at the iterate: K's Newton step (its tangent was not assembled).
            if (.not. self%root_solved) then
               call assemble_system(fem%system, fem%mesh, fem%qt, self%t, fem%seg, self%kg_above, fem%counts)
            end if
         end if
         info = 0
         if (.not. self%root_solved) call factor_system(fem%system, info, fem%counts)
         if (self%tries == 0 .and. fem%change%detect) then
            ! A change point at the predictor: Newton does not iterate on a
            ! near-singular tangent (see fekap_fem's step_over).
            call check_predictor(fem, self%root_solved, info)
            if (fem%change%found) then
               info = info_change_point
               return
            end if
         end if
         if (.not. self%root_solved .and. info > 0 .and. self%kg_above > 0) then
            ! The material tangent is singular at a stationary configuration;
            ! the geometric stiffness of the iterate's stresses may still
            ! carry Newton there (full Newton from here on in this step).
            self%kg_above = 0
            call assemble_system(fem%system, fem%mesh, fem%qt, self%t, fem%seg, self%kg_above, fem%counts)
            self%residual = residual_norm(fem%system, fem%mesh)
            call factor_system(fem%system, info, fem%counts)
         end if
      end associate
   end subroutine fem_factor

   !> The correction and its length, applied to the iterate (one iteration of
   !> the step) unless it diverges (newton_solve then stops) or the pass's
   !> first correction finds the predictor converged (at_predictor).
   subroutine fem_correct(self, length, error)
      class(fem_newton_type), intent(inout) :: self
      real(dp), intent(out) :: length
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: pivot
      logical :: first
      associate (fem => self%fem)
         if (.not. self%root_solved) then
            call newton_correction(fem%system, fem%mesh, fem%dof_length, self%correction, fem%counts)
         end if
         length = self%correction
         first = self%tries == 0
         self%tries = self%tries + 1
         if (self%correction > self%divergence) return
         ! Converged where this pass starts (the predictor, or an iterate that
         ! solve_step corrected): a first correction below predictor_margin
         ! times the length tolerance (at round-off with the default tolerance)
         ! leaves it as it is, and the tangent just factored, material only
         ! (every Gauss point strained less than kg_above), is the tangent at
         ! the accepted configuration: the branch-jump check and the rates need
         ! no assembly and factorisation of their own. In the square-root form
         ! that is B_f's factor at the predictor with the strains of the
         ! iterate, round-off away from the stress-free B_f at the corrected
         ! configuration (the rates' refinement, whose residual is the
         ! stress-free strain rates there, takes the difference up; see
         ! solve_step). Not near a stationary
         ! configuration: the residual there hardly sees an error along the
         ! near-singular direction (a predictor kept past collinear is then
         ! rejected by the branch-jump check). The contract's test, the same
         ! as is_converged's, then stops the pass.
         if (first .and. .not. fem%loaded .and. fem%conv%mode /= convergence_paper) then
            self%at_predictor = self%correction <= predictor_margin*fem%prediction%length .and. &
               & fem%system%assembled_strain < self%kg_above .and. &
               & is_converged(fem%conv, self%residual, self%r0, self%increment_residual, self%correction)
            if (self%at_predictor) then
               ! K's factor, or in the square-root form B_f's (0 if K took its correction).
               if (fem%root_form .and. .not. self%root_solved) then
                  pivot = 0
               else
                  pivot = accepted_pivot(fem)
               end if
               self%at_predictor = pivot >= near_singular_drop*fem%state%reference_pivot
            end if
            if (self%at_predictor) then
               ! The square-root form takes its correction all the same (the
               ! positions are Newton's, as if the factor were made again).
               if (self%root_solved) call take_correction(fem, fem%qt, self%iterations)
               return
            end if
         end if
         call take_correction(fem, fem%qt, self%iterations)
      end associate
   end subroutine fem_correct

   !> After a correction the contract did not accept: the stop on an estimate
   !> of the next correction (not loaded), and the stall at round-off: a
   !> residual at its floor for stall_iterations iterations gives corrections
   !> that are noise (the tangent's sensitivity times the round-off), so the
   !> length test cannot be met; the last correction is the accuracy left,
   !> reported in the listing (stalled_correction).
   integer function fem_stop_test(self, report) result(stopped)
      class(fem_newton_type), intent(inout) :: self
      type(newton_report_type), intent(in) :: report
      stopped = 0
      associate (fem => self%fem)
         if (fem%conv%mode /= convergence_paper) then
            self%by_estimate = .not. fem%loaded
            if (self%by_estimate) self%by_estimate = converged_by_estimate(fem%conv, fem%model_length, &
               & fem%newton_constant, self%residual, self%r0, self%increment_residual, self%correction, self%previous)
            if (self%by_estimate) then
               stopped = stop_converged
               return
            end if
            if (self%residual <= fem%conv%residual_floor) then
               self%at_floor = self%at_floor + 1
            else
               self%at_floor = 0
            end if
            if (self%at_floor >= stall_iterations) then
               self%stalled_correction = self%correction
               stopped = stop_at_floor
               return
            end if
         end if
         self%previous = self%correction
      end associate
   end function fem_stop_test

end module fekap_fem_newton
