!> The magnitude rule of the assembly-mode (branch) jump check, shared by
!> the planar FEM (fekap_fem_branch), the constraint-equation methods and the
!> spatial stepper: a converged configuration may lie on another assembly
!> branch than the last one (Newton from a poor predictor can cross over);
!> a rotation over the step that exceeds jump_ratio times what the linear
!> responses to the drive increment at either end of the step, or the
!> increment itself, can explain is a jump (docs/hard-cases.md, section 1).
!> Also the orientation rule (collinear_crossing): two links hinged about
!> one axis whose relative angle passes through a multiple of pi (the links
!> collinear) within the step must do so in the sense of the responses; and
!> the thresholds of the step-doubling verification of crossing steps.
module fekap_stepping_jump
   use fekap_kinds, only: dp
   implicit none
   private

   public :: jump_bound_ratio, collinear_crossing

   !> A step is rejected when some rotation over the step exceeds this many
   !> times what the rates at either end of the step, or the drive increment,
   !> can explain (the FEM, the classical methods and the spatial stepper alike).
   real(dp), parameter, public :: jump_ratio = 2.0_dp

   !> Relative angles within this many pi of a multiple of pi at either end
   !> of a step do not count as crossing it (links that start or end collinear).
   real(dp), parameter :: hinge_margin = 1.0e-9_dp
   !> Least share of a collinear crossing that the response at the new
   !> configuration must explain in the crossing sense.
   real(dp), parameter :: hinge_response = 1.0e-3_dp
   !> Step-doubling verification: a step in which a hinged pair crosses
   !> collinear turning by more than verify_turn radians is to be solved again
   !> as two half steps (themselves verified, at most max_verify_depth
   !> halvings deep).
   real(dp), parameter, public :: verify_turn = 0.1_dp
   integer, parameter, public :: max_verify_depth = 10
   !> A crossing step needs no verification when Newton moved every rotation
   !> less than this share of the crossing turn away from a smooth predictor.
   real(dp), parameter, public :: verify_predicted = 1.0e-3_dp

   !> Outcomes of collinear_crossing: the pair does not pass through
   !> collinear; it does, against the responses (a flip to the mirror
   !> assembly mode); it does, in their sense (turning by |psi1 - psi0|).
   integer, parameter, public :: crossing_none = 0, crossing_against = 1, crossing_along = 2

contains

   !> The ratio of the change of a coordinate over a step to what explains it:
   !> max(|dq_old|, |dq_new|, floor, resolution), the linear responses to
   !> the drive increment at the two ends of the step, the increment itself,
   !> and the least rotation the method's Newton resolves (its length
   !> tolerance, relative to the model size: radians). A change within
   !> Newton's resolution is round-off, not a jump: a drive held still
   !> (rate 0) explains nothing, yet its steps move by round-off (huge for a
   !> change that nothing explains, were resolution 0).
   elemental real(dp) function jump_bound_ratio(change, dq_old, dq_new, floor_, resolution) result(ratio)
      real(dp), intent(in) :: change, dq_old, dq_new, floor_, resolution
      real(dp) :: bound
      bound = max(floor_, abs(dq_new), abs(dq_old), resolution)
      if (bound > 0) then
         ratio = abs(change)/bound
      else
         ratio = merge(0.0_dp, huge(1.0_dp), abs(change) <= 0)
      end if
   end function jump_bound_ratio

   !> The orientation rule on a pair of links hinged about one axis whose
   !> relative angle goes from psi0 to psi1 over the step (unwrapped), with
   !> the linear responses of that angle to the drive increment at the last
   !> configuration (dpsi_old, zero where not known) and at the new one
   !> (dpsi_new). In a continuous motion psi crosses k pi (the links
   !> collinear) in the sense in which the drive increment moves it; a jump
   !> to the mirror assembly mode near a flattened configuration (a fold)
   !> crosses against the response at the start or at the end of the step.
   !> The response at the new configuration must carry psi through in the
   !> crossing sense (a response of zero there is the closest approach of a
   !> near-toggle, not a crossing); the one at the last must not oppose it.
   elemental integer function collinear_crossing(psi0, psi1, dpsi_old, dpsi_new) result(outcome)
      real(dp), intent(in) :: psi0, psi1, dpsi_old, dpsi_new
      real(dp) :: lo, hi, sense, pi
      pi = acos(-1.0_dp)
      lo = min(psi0, psi1)/pi
      hi = max(psi0, psi1)/pi
      outcome = crossing_none
      ! A multiple of pi strictly inside (lo, hi): the links passed through collinear.
      if (floor(hi - hinge_margin) < ceiling(lo + hinge_margin)) return
      sense = sign(1.0_dp, psi1 - psi0)
      if (sense*dpsi_old < 0 .or. sense*dpsi_new <= hinge_response*abs(psi1 - psi0)) then
         outcome = crossing_against
      else
         outcome = crossing_along
      end if
   end function collinear_crossing

end module fekap_stepping_jump
