!> The constraint-equation methods of the paper, for comparison with the
!> finite element method: orientation angles (four-bar linkages only) and
!> Cartesian coordinates (any planar mechanism of links, welds, supports,
!> drives and slidelines).
module fekap_classical
   use fekap_classical_angles, only: angles_stepper_type, new_angles_stepper
   use fekap_classical_cartesian, only: cartesian_stepper_type, new_cartesian_stepper
   implicit none
   private

   public :: angles_stepper_type, new_angles_stepper, cartesian_stepper_type, new_cartesian_stepper

end module fekap_classical
