!> The magnitude rule of the assembly-mode (branch) jump check, shared by
!> the planar FEM (fekap_fem_branch), the constraint-equation methods and the
!> spatial stepper: a converged configuration may lie on another assembly
!> branch than the last one (Newton from a poor predictor can cross over);
!> a rotation over the step that exceeds jump_ratio times what the linear
!> responses to the drive increment at either end of the step, or the
!> increment itself, can explain is a jump (docs/hard-cases.md, section 1).
module fekap_stepping_jump
   use fekap_kinds, only: dp
   implicit none
   private

   public :: jump_bound_ratio

   !> A step is rejected when some rotation over the step exceeds this many
   !> times what the rates at either end of the step, or the drive increment,
   !> can explain (the FEM, the classical methods and the spatial stepper alike).
   real(dp), parameter, public :: jump_ratio = 2.0_dp

contains

   !> The ratio of the change of a coordinate over a step to what explains it:
   !> max(|dq_old|, |dq_new|, floor), the linear responses to the drive
   !> increment at the two ends of the step and the increment itself (huge
   !> for a change that nothing explains).
   elemental real(dp) function jump_bound_ratio(change, dq_old, dq_new, floor_) result(ratio)
      real(dp), intent(in) :: change, dq_old, dq_new, floor_
      real(dp) :: bound
      bound = max(floor_, abs(dq_new), abs(dq_old))
      if (bound > 0) then
         ratio = abs(change)/bound
      else
         ratio = merge(0.0_dp, huge(1.0_dp), abs(change) <= 0)
      end if
   end function jump_bound_ratio

end module fekap_stepping_jump
