!> Before the first step: is every motion of the mechanism held by its
!> supports, drives and links? A kinematic, kinetostatic or static FEM run
!> finds each configuration as the stress-free (or loaded) solution of the
!> finite element equations; a part that can move without straining an
!> element (a four-bar without SUPPorts, a second four-bar that nothing
!> drives) has no determined configuration, and its tangent is singular at
!> every configuration, not only at a change point.
!>
!> The test counts, for each connected part of the mesh (the free dofs
!> joined by elements and sliding joints), Grubler's way: its free dofs less
!> the equations that can hold them, each element at most 3 (a rigid plane
!> body: at most as many as the element's free dofs) and each sliding joint 1
!> (a prismatic joint 2). The equations' rank is at most their count, so a
!> part with more free dofs than equations moves at every configuration:
!> that is free motion, for any geometry, and the run is refused with the
!> part's nodes and links named. The count is linear in the mesh's size and
!> needs no factorisation (a factor's pivots cannot tell a long flexible
!> chain from a free one). It cannot see a free motion that only a special
!> geometry allows (an undriven parallelogram with a redundant bar): there a
!> singular configuration is met and the run's notes say so.
module fekap_fem_determinacy
   use fekap_error, only: error_type, input_error
   use fekap_model, only: model_type, joint_prismatic
   use fekap_assembly_mesh, only: mesh_type, dof_free
   use fekap_union_find, only: find_root, join
   implicit none
   private

   public :: check_determined

   !> Most nodes and links named in the message.
   integer, parameter :: max_named = 12

contains

   !> An input error naming the nodes and links of every part of the mesh
   !> that can move freely (see the module's header).
   subroutine check_determined(mesh, model, error)
      type(mesh_type), intent(in) :: mesh
      type(model_type), intent(in) :: model
      type(error_type), allocatable, intent(out) :: error
      integer, allocatable :: parent(:), balance(:)
      logical, allocatable :: free_part(:), named_node(:), named_link(:)
      integer :: dof, e, k, first, nfree_e, i, root, excess, nslide
      character(:), allocatable :: node_text, link_text
      character(len=12) :: num

      nslide = 0
      if (allocated(model%slidelines)) nslide = size(model%slidelines)
      allocate (parent(mesh%ndof), balance(mesh%ndof), source=0)
      parent = [(dof, dof=1, mesh%ndof)]
      ! Parts: free dofs joined by the elements and the sliding joints.
      do e = 1, size(mesh%elements)
         first = 0
         do k = 1, 6
            dof = mesh%edof(k, e)
            if (mesh%status(dof) /= dof_free) cycle
            if (first == 0) then
               first = dof
            else
               call join(parent, first, dof)
            end if
         end do
      end do
      do i = 1, nslide
         first = slide_dof(mesh, model, i)
         if (first == 0) cycle
         call each_slide_dof(i, first)
      end do

      ! The balance of each part, at its root: free dofs less equations.
      do dof = 1, mesh%ndof
         if (mesh%status(dof) == dof_free) balance(find_root(parent, dof)) = balance(find_root(parent, dof)) + 1
      end do
      do e = 1, size(mesh%elements)
         nfree_e = count(mesh%status(mesh%edof(:, e)) == dof_free)
         if (nfree_e == 0) cycle
         root = find_root(parent, first_free(e))
         balance(root) = balance(root) - min(3, nfree_e)
      end do
      do i = 1, nslide
         first = slide_dof(mesh, model, i)
         if (first == 0) cycle
         root = find_root(parent, first)
         balance(root) = balance(root) - merge(2, 1, model%slidelines(i)%kind == joint_prismatic)
      end do

      allocate (free_part(mesh%ndof), source=.false.)
      do dof = 1, mesh%ndof
         if (parent(dof) == dof .and. mesh%status(dof) == dof_free) free_part(dof) = balance(dof) > 0
      end do
      if (.not. any(free_part)) return

      ! The nodes and links of the free parts.
      allocate (named_node(size(model%nodes)), named_link(size(model%links)), source=.false.)
      do i = 1, size(model%nodes)
         do k = 1, 2
            dof = mesh%tdof(k, i)
            if (mesh%status(dof) == dof_free) then
               if (free_part(find_root(parent, dof))) named_node(i) = .true.
            end if
         end do
      end do
      do e = 1, size(mesh%elements)
         if (count(mesh%status(mesh%edof(:, e)) == dof_free) == 0) cycle
         if (free_part(find_root(parent, first_free(e)))) named_link(mesh%elink(e)) = .true.
      end do
      excess = 0
      do dof = 1, mesh%ndof
         if (free_part(dof)) excess = excess + balance(dof)
      end do
      node_text = listed_names(named_node, 'node')
      link_text = listed_names(named_link, 'link')
      write (num, '(i0)') excess
      call input_error(error, model%file//': the mechanism is not determined by its supports, drives and '// &
         & 'links: a part of it can move freely, at every configuration (at least '//trim(num)// &
         & ' degree'//trim(merge('s', ' ', excess > 1))//' of freedom that no SUPPorts, DRIVes or '// &
         & 'links hold): '//join_texts(node_text, link_text)//'; support or drive the part that moves, '// &
         & 'or remove it')

   contains

      !> Join the dofs of sliding joint i (the slave node, a prismatic
      !> joint's slave rotation, the master links' free dofs) to `first`.
      subroutine each_slide_dof(i, first)
         integer, intent(in) :: i, first
         integer :: j, e, k, dof
         associate (s => model%slidelines(i))
            do k = 1, 2
               dof = mesh%tdof(k, s%slave)
               if (mesh%status(dof) == dof_free) call join(parent, first, dof)
            end do
            if (s%kind == joint_prismatic .and. s%slave_link > 0) then
               do k = 1, 2
                  dof = mesh%link_rot(k, s%slave_link)
                  if (mesh%status(dof) == dof_free) call join(parent, first, dof)
               end do
            end if
            if (.not. allocated(s%master_links)) return
            do j = 1, size(s%master_links)
               do e = 1, size(mesh%elements)
                  if (mesh%elink(e) /= s%master_links(j)) cycle
                  do k = 1, 6
                     dof = mesh%edof(k, e)
                     if (mesh%status(dof) == dof_free) call join(parent, first, dof)
                  end do
               end do
            end do
         end associate
      end subroutine each_slide_dof

      !> The first free dof of element e (it has one).
      integer function first_free(e)
         integer, intent(in) :: e
         integer :: k
         first_free = 0
         do k = 1, 6
            if (mesh%status(mesh%edof(k, e)) == dof_free) then
               first_free = mesh%edof(k, e)
               return
            end if
         end do
      end function first_free

      !> 'nodes A, B, C' of the marked entries (the first max_named, and how many more).
      function listed_names(marked, what) result(text)
         logical, intent(in) :: marked(:)
         character(*), intent(in) :: what
         character(:), allocatable :: text
         integer :: i, n, total
         character(len=12) :: more
         text = ''
         total = count(marked)
         if (total == 0) return
         n = 0
         do i = 1, size(marked)
            if (.not. marked(i)) cycle
            n = n + 1
            if (n > max_named) exit
            if (n > 1) text = text//', '
            if (what == 'node') then
               text = text//model%nodes(i)%name
            else
               text = text//model%links(i)%name
            end if
         end do
         if (total > max_named) then
            write (more, '(i0)') total - max_named
            text = text//' and '//trim(more)//' more'
         end if
         text = what//trim(merge('s', ' ', total > 1))//' '//text
      end function listed_names
   end subroutine check_determined

   !> 'A; B', 'A' or 'B' of two texts ('' left out).
   pure function join_texts(a, b) result(text)
      character(*), intent(in) :: a, b
      character(:), allocatable :: text
      if (len(a) > 0 .and. len(b) > 0) then
         text = a//'; '//b
      else
         text = a//b
      end if
   end function join_texts

   !> A free dof of sliding joint i's slave node, prismatic rotation or
   !> master links, 0 when it has none (everything it touches is held).
   integer function slide_dof(mesh, model, i) result(dof)
      type(mesh_type), intent(in) :: mesh
      type(model_type), intent(in) :: model
      integer, intent(in) :: i
      integer :: k, j, e
      associate (s => model%slidelines(i))
         do k = 1, 2
            dof = mesh%tdof(k, s%slave)
            if (mesh%status(dof) == dof_free) return
         end do
         if (s%kind == joint_prismatic .and. s%slave_link > 0) then
            do k = 1, 2
               dof = mesh%link_rot(k, s%slave_link)
               if (mesh%status(dof) == dof_free) return
            end do
         end if
         if (allocated(s%master_links)) then
            do j = 1, size(s%master_links)
               do e = 1, size(mesh%elements)
                  if (mesh%elink(e) /= s%master_links(j)) cycle
                  do k = 1, 6
                     dof = mesh%edof(k, e)
                     if (mesh%status(dof) == dof_free) return
                  end do
               end do
            end do
         end if
      end associate
      dof = 0
   end function slide_dof

end module fekap_fem_determinacy
