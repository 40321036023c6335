!> Disjoint sets over 1..n (union-find): which link ends are welded into one
!> rotation (the mesh) or one rigid body (the classical methods).
module fekap_union_find
   implicit none
   private

   public :: find_root, join, flatten

contains

   !> The representative of i's set; parent(k) = k marks a representative.
   !> A loop, not a recursion: a chain of 100,000 welded links makes a deep tree.
   pure integer function find_root(parent, i) result(root)
      integer, intent(in) :: parent(:), i
      root = i
      do while (parent(root) /= root)
         root = parent(root)
      end do
   end function find_root

   !> Merge the sets of i and j; the smaller index represents the union. The
   !> paths from i and j are pointed straight at it, so that a sequence of
   !> joins takes time about linear in their number.
   pure subroutine join(parent, i, j)
      integer, intent(inout) :: parent(:)
      integer, intent(in) :: i, j
      integer :: ri, rj, root
      ri = find_root(parent, i)
      rj = find_root(parent, j)
      root = min(ri, rj)
      call compress(parent, i, root)
      call compress(parent, j, root)
      parent(max(ri, rj)) = root
   end subroutine join

   !> Point every element straight at its representative: after it,
   !> find_root takes one step. One ascending pass suffices, since a parent
   !> never has a larger index than its child (the smaller index represents).
   pure subroutine flatten(parent)
      integer, intent(inout) :: parent(:)
      integer :: k
      do k = 1, size(parent)
         parent(k) = parent(parent(k))
      end do
   end subroutine flatten

   !> Point every element on the path from i to its root at `root`.
   pure subroutine compress(parent, i, root)
      integer, intent(inout) :: parent(:)
      integer, intent(in) :: i, root
      integer :: k, next
      k = i
      do while (parent(k) /= k)
         next = parent(k)
         parent(k) = root
         k = next
      end do
      parent(k) = root
   end subroutine compress

end module fekap_union_find
