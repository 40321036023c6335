!> The Newton convergence test shared by every method, so that iteration
!> counts are comparable, and the FEM's stop on an estimate of the next
!> correction.
module fekap_fem_convergence
   use fekap_kinds, only: dp
   use fekap_model, only: convergence_paper, convergence_default
   use fekap_assembly_mesh, only: mesh_type
   use fekap_stepping_newton, only: newton_contract_type, test_relative_first, test_solved_from
   implicit none
   private

   public :: convergence_type, is_converged, converged_by_estimate, residual_floor, newton_contract

   !> A Newton correction longer than this many model sizes is divergence (every method).
   real(dp), parameter, public :: divergence_length = 1.0e3_dp

   !> Contraction of the last Newton correction against the one before, and the
   !> least quadratic-convergence constant times the model size, for the
   !> estimated stop (converged_by_estimate).
   real(dp), parameter :: estimate_contraction = 0.1_dp, least_quadratic_constant = 10.0_dp
   !> The estimated stop asks the next correction to be this share of the length
   !> tolerance (what a verifying iteration would have left).
   real(dp), parameter, public :: estimate_margin = 0.1_dp

   !> Settings of the test; see docs/theory.md, "Convergence".
   type :: convergence_type
      !> convergence_paper or convergence_default.
      integer :: mode = convergence_default
      !> Residual ratio tolerance.
      real(dp) :: tol = 1.0e-10_dp
      !> Absolute length tolerance on the last correction (length_tol * model size).
      real(dp) :: length = 1.0e-12_dp
      !> Absolute residual floor, below which a step counts as converged
      !> whatever its scale (a step that starts converged).
      real(dp) :: residual_floor = 0
   end type convergence_type

contains

   !> The contract of stepping/newton.f90's driver under these settings, as
   !> the kinematic methods (the FEM's and the classical ones) hold it: the
   !> test against the increment's residual force_scale (`default`) or the
   !> first residual (`paper`), the tolerance, the length tolerance, the
   !> round-off floor, the deck's iterations and divergence beyond
   !> divergence_length model sizes.
   pure function newton_contract(conv, force_scale, max_iterations, model_length) result(contract)
      type(convergence_type), intent(in) :: conv
      real(dp), intent(in) :: force_scale, model_length
      integer, intent(in) :: max_iterations
      type(newton_contract_type) :: contract
      contract%test = merge(test_relative_first, test_solved_from, conv%mode == convergence_paper)
      contract%tolerance = conv%tol
      contract%force_scale = force_scale
      contract%length = conv%length
      contract%floor = conv%residual_floor
      contract%max_iterations = max_iterations
      contract%divergence = divergence_length*model_length
   end function newton_contract

   !> The least residual norm Newton can be asked for on a mesh (model size
   !> model_length): a strain of 1e-13 in the stiffest element, or the
   !> round-off of a strain computed from coordinates of the model's size
   !> (eps size / L) if larger. The Euclidean norm of round-off grows like the
   !> square root of the number of unknowns.
   pure real(dp) function residual_floor(mesh, model_length) result(floor)
      type(mesh_type), intent(in) :: mesh
      real(dp), intent(in) :: model_length
      real(dp) :: force_scale, shortest
      integer :: e
      force_scale = 0
      shortest = huge(1.0_dp)
      do e = 1, size(mesh%elements)
         associate (el => mesh%elements(e))
            force_scale = max(force_scale, el%ea, el%kga, el%ei/el%length**2)
            shortest = min(shortest, el%length)
         end associate
      end do
      floor = max(1.0e-13_dp, epsilon(1.0_dp)*model_length/shortest)*force_scale*sqrt(real(max(1, mesh%nfree), dp))
   end function residual_floor

   !> The convergence test after a Newton solve.
   !>   paper:   ||P(i)|| / ||P(0)|| < tol (r0 is the residual at the predictor).
   !>   default: ||P(i)|| <= tol * scale, with scale the residual of the drive
   !>            increment alone (independent of the predictor), or ||P(i)|| <= floor;
   !>            and the correction computed from P(i) is below the length tolerance.
   pure logical function is_converged(self, r, r0, reference, correction) result(done)
      type(convergence_type), intent(in) :: self
      !> Residual norm at the current iterate, at the predictor, and the scale.
      real(dp), intent(in) :: r, r0, reference
      !> Max-norm of the translational part of the correction solved from r.
      real(dp), intent(in) :: correction
      if (self%mode == convergence_paper) then
         done = r < self%tol*r0 .or. r <= self%residual_floor
      else
         done = (r <= self%tol*reference .or. r <= self%residual_floor) .and. correction <= self%length
      end if
   end function is_converged

   !> Error-oriented stop of Newton without a verifying iteration (Deuflhard,
   !> Newton Methods for Nonlinear Problems, 2004, sec. 2.1): while Newton
   !> converges quadratically, the correction that would follow the last one,
   !> c, is about M c**2, with M measured from the last two corrections
   !> (M = c / c_previous**2), or after the first correction taken from the
   !> last step (`constant`) and never below least_quadratic_constant / model
   !> size. The step has converged when that next correction is below
   !> estimate_margin times the length tolerance and the residual it leaves,
   !> residual * next / c, passes the residual test. Linear convergence (a
   !> contraction above estimate_contraction, as at singular configurations)
   !> is never stopped this way.
   logical function converged_by_estimate(self, model_length, constant, residual, r0, reference, correction, previous) &
      & result(done)
      type(convergence_type), intent(in) :: self
      !> The model size (model_size).
      real(dp), intent(in) :: model_length
      !> The quadratic-convergence constant M last measured (updated here).
      real(dp), intent(inout) :: constant
      !> Residual norm from which the last correction was solved, at the predictor, and the scale.
      real(dp), intent(in) :: residual, r0, reference
      !> The last correction and the one before it (0 if none), in lengths.
      real(dp), intent(in) :: correction, previous
      real(dp) :: m, next
      done = .false.
      if (.not. correction > 0) return
      m = least_quadratic_constant/model_length
      if (previous > 0) then
         if (correction > estimate_contraction*previous) return
         ! Corrections near round-off measure nothing.
         if (correction > 1.0e3_dp*epsilon(1.0_dp)*model_length) constant = correction/previous**2
         m = max(m, correction/previous**2)
      else
         m = max(m, constant)
      end if
      next = m*correction**2
      if (next > estimate_contraction*correction) return
      done = is_converged(self, residual*next/correction, r0, reference, next/estimate_margin)
   end function converged_by_estimate

end module fekap_fem_convergence
