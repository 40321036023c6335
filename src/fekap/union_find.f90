!> Disjoint sets over 1..n (union-find): which link ends are welded into one
!> rotation (the mesh) or one rigid body (the classical methods).
module fekap_union_find
   implicit none
   private

   public :: find_root, join

contains

   !> The representative of i's set; parent(k) = k marks a representative.
   pure recursive integer function find_root(parent, i) result(root)
      integer, intent(in) :: parent(:), i
      if (parent(i) == i) then
         root = i
      else
         root = find_root(parent, parent(i))
      end if
   end function find_root

   !> Merge the sets of i and j; the smaller index represents the union.
   pure subroutine join(parent, i, j)
      integer, intent(inout) :: parent(:)
      integer, intent(in) :: i, j
      integer :: ri, rj
      ri = find_root(parent, i)
      rj = find_root(parent, j)
      if (ri /= rj) parent(max(ri, rj)) = min(ri, rj)
   end subroutine join

end module fekap_union_find
