!> The graph side of equation numbering: the adjacency of the free dofs
!> that coupling groups make (each element's dofs, a slideline's slave with
!> its master points), in compressed rows, and its Cuthill-McKee order,
!> component by component from a pseudo-peripheral vertex (George-Liu), so
!> that the reverse order gives a small bandwidth (fekap_assembly_mesh).
module fekap_assembly_ordering
   implicit none
   private

   public :: group_adjacency, cuthill_mckee

contains

   !> The adjacency of nf vertices (the free dofs) in compressed rows: two
   !> vertices are adjacent when a group couples them. Group e holds the dofs
   !> group_dof(group_start(e):group_start(e + 1) - 1); free_index maps a dof
   !> to its vertex (0: not free). adj(adj_start(a):adj_start(a + 1) - 1) are
   !> the neighbours of a (one entry per coupling group), deg(a) their number.
   subroutine group_adjacency(group_start, group_dof, free_index, nf, adj_start, adj, deg)
      integer, intent(in) :: group_start(:), group_dof(:), free_index(:), nf
      integer, allocatable, intent(out) :: adj_start(:), adj(:), deg(:)
      integer, allocatable :: fill(:)
      integer :: i
      ! Two passes over the coupled pairs: count each vertex's neighbours, then list them.
      allocate (deg(nf), source=0)
      call couple_pairs(.false.)
      allocate (adj_start(nf + 1))
      adj_start(1) = 1
      do i = 1, nf
         adj_start(i + 1) = adj_start(i) + deg(i)
      end do
      allocate (adj(adj_start(nf + 1) - 1), fill(nf))
      fill = adj_start(1:nf)
      call couple_pairs(.true.)

   contains

      !> Every pair (a, b) of distinct vertices that a group couples: counted
      !> in deg(a), or (record) listed in adj from fill(a) on.
      subroutine couple_pairs(record)
         logical, intent(in) :: record
         integer :: e, ia, ib, a, b
         do e = 1, size(group_start) - 1
            do ia = group_start(e), group_start(e + 1) - 1
               a = free_index(group_dof(ia))
               if (a == 0) cycle
               do ib = group_start(e), group_start(e + 1) - 1
                  b = free_index(group_dof(ib))
                  if (b == 0 .or. b == a) cycle
                  if (record) then
                     adj(fill(a)) = b
                     fill(a) = fill(a) + 1
                  else
                     deg(a) = deg(a) + 1
                  end if
               end do
            end do
         end do
      end subroutine couple_pairs

   end subroutine group_adjacency

   !> Cuthill-McKee order of the graph (adj_start, adj, deg of
   !> group_adjacency): component by component, each from a pseudo-peripheral
   !> vertex, neighbours in order of increasing degree; order(k) is the k-th vertex.
   subroutine cuthill_mckee(adj_start, adj, deg, order)
      integer, intent(in) :: adj_start(:), adj(:), deg(:)
      integer, intent(out) :: order(:)
      ! Allocated, not automatic (here and in peripheral, bfs_levels): a chain
      ! of 10^5 links has 3 10^5 dofs.
      integer, allocatable :: level(:)
      logical, allocatable :: seen(:)
      integer :: nf, n_ordered, start, head, tail, v, w, k
      nf = size(deg)
      allocate (level(nf), source=0)
      allocate (seen(nf), source=.false.)
      n_ordered = 0
      do while (n_ordered < nf)
         start = minloc(deg, dim=1, mask=.not. seen)
         start = peripheral(start)
         head = n_ordered + 1
         tail = n_ordered + 1
         order(tail) = start
         seen(start) = .true.
         do while (head <= tail)
            v = order(head)
            head = head + 1
            ! Neighbours in order of increasing degree.
            do
               w = 0
               do k = adj_start(v), adj_start(v + 1) - 1
                  if (.not. seen(adj(k))) then
                     if (w == 0) then
                        w = adj(k)
                     else if (deg(adj(k)) < deg(w)) then
                        w = adj(k)
                     end if
                  end if
               end do
               if (w == 0) exit
               seen(w) = .true.
               tail = tail + 1
               order(tail) = w
            end do
         end do
         n_ordered = tail
      end do

   contains

      !> A pseudo-peripheral vertex of the component of v0 (George-Liu: repeat the
      !> BFS from a lowest-degree vertex of the last level while its depth grows).
      integer function peripheral(v0) result(r)
         integer, intent(in) :: v0
         integer :: depth, new_depth, pass
         logical, allocatable :: mark(:)
         allocate (mark(nf))
         r = v0
         depth = -1
         do pass = 1, 5
            call bfs_levels(r, mark, new_depth)
            if (new_depth <= depth) exit
            depth = new_depth
            r = minloc(deg, dim=1, mask=mark .and. level == new_depth)
         end do
      end function peripheral

      !> Breadth-first levels from v0 over the vertices not yet ordered: the
      !> vertices reached (mark), their levels and the largest.
      subroutine bfs_levels(v0, mark, depth)
         integer, intent(in) :: v0
         logical, intent(out) :: mark(nf)
         integer, intent(out) :: depth
         integer, allocatable :: queue(:)
         integer :: qh, qt, u, kk
         allocate (queue(nf))
         mark = .false.
         level = 0
         qh = 1
         qt = 1
         queue(1) = v0
         mark(v0) = .true.
         do while (qh <= qt)
            u = queue(qh)
            qh = qh + 1
            do kk = adj_start(u), adj_start(u + 1) - 1
               if (.not. mark(adj(kk)) .and. .not. seen(adj(kk))) then
                  mark(adj(kk)) = .true.
                  level(adj(kk)) = level(u) + 1
                  qt = qt + 1
                  queue(qt) = adj(kk)
               end if
            end do
         end do
         depth = maxval(level, mask=mark)
      end subroutine bfs_levels

   end subroutine cuthill_mckee

end module fekap_assembly_ordering
