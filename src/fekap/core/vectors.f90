!> Vectors of 3-space as the spatial element, its deck reader and its
!> mechanism all need them: the cross product.
module fekap_vectors
   use fekap_kinds, only: dp
   implicit none
   private

   public :: cross

contains

   !> a x b.
   pure function cross(a, b) result(c)
      real(dp), intent(in) :: a(3), b(3)
      real(dp) :: c(3)
      c = [a(2)*b(3) - a(3)*b(2), a(3)*b(1) - a(1)*b(3), a(1)*b(2) - a(2)*b(1)]
   end function cross

end module fekap_vectors
