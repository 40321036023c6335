!> The finite element mesh derived from the model: points, degrees of
!> freedom with double nodes at hinges, elements, supports and drives, and
!> equation numbers in reverse Cuthill-McKee order for a small bandwidth.
!>
!> The graph side of the numbering (the free dofs' adjacency and its
!> Cuthill-McKee order) is fekap_assembly_ordering's.
!>
!> The slidelines in mesh terms are fekap_assembly_slides'.
!>
!> Points 1..size(model%nodes) are the model's nodes in order; a link meshed
!> with several elements adds its interior points after them. Every point has
!> two translational dofs, shared by all element ends there (a hinge). Every
!> link end has its own rotation dof ("double noding", the paper after (54));
!> a weld merges the rotation dofs of its links at its node; inside a link
!> consecutive elements share the rotation of their common point.
module fekap_assembly_mesh
   use fekap_kinds, only: dp
   use fekap_model, only: model_type, dof_x, dof_y, dof_rot
   use fekap_element_beam, only: beam_type, new_beam
   use fekap_assembly_slides, only: slide_type, new_slides
   use fekap_union_find, only: find_root, join, flatten
   use fekap_model, only: load_type, effects_statics, effects_dynamics
   use fekap_model_effects, only: planned_effects, has_masses
   use fekap_element_inertia, only: beam_gravity_force
   use fekap_assembly_loads, only: load_set_type
   use fekap_assembly_ordering, only: group_adjacency, cuthill_mckee
   implicit none
   private

   public :: mesh_type, slide_type, new_mesh, describe_dof, point_masses

   !> Status of a degree of freedom.
   integer, parameter, public :: dof_free = 0, dof_fixed = 1, dof_driven = 2

   type :: mesh_type
      integer :: npoint = 0
      integer :: ndof = 0
      !> Number of free dofs (equations) and of driven dofs.
      integer :: nfree = 0
      integer :: ndriven = 0
      !> Half-bandwidth of the free-free tangent in equation order.
      integer :: kd = 0
      !> (nfree): envelope of the free-free tangent, the least equation that
      !> column j couples to (j - kd <= envelope(j) <= j); see new_band_matrix.
      integer, allocatable :: envelope(:)
      !> (2, npoint): initial coordinates of each point.
      real(dp), allocatable :: x0(:, :)
      !> (2, npoint): x and y dof of each point.
      integer, allocatable :: tdof(:, :)
      !> (2, nlink): rotation dof at the first and second end of each link.
      integer, allocatable :: link_rot(:, :)
      !> Initial direction angle of each link.
      real(dp), allocatable :: link_angle0(:)
      !> The links whose angle is read off their chord (first to last node):
      !> those that can bend, of more than one element or in a statics or
      !> dynamics run; not allocated when there are none. Another link's
      !> chord is its first end's rotation (an unstrained element's), which
      !> costs no atan2 a step.
      integer, allocatable :: chord_links(:)
      type(beam_type), allocatable :: elements(:)
      !> (6, nelem): global dofs of each element, (x1, y1, theta1, x2, y2, theta2).
      integer, allocatable :: edof(:, :)
      !> Link of each element.
      integer, allocatable :: elink(:)
      !> (ndof): dof_free, dof_fixed or dof_driven.
      integer, allocatable :: status(:)
      !> (ndof): equation number of a free dof, 0 otherwise.
      integer, allocatable :: eq(:)
      !> (nfree): dof of each equation.
      integer, allocatable :: eq_dof(:)
      !> (ndriven): dof of each drive, in model%drives order.
      integer, allocatable :: driven_dof(:)
      !> (ndof): the drive of a driven dof (its column in the free-driven block), 0 otherwise.
      integer, allocatable :: drive_col(:)
      !> (ndof): what each dof is: the point (or 0) and kind (dof_x, dof_y, dof_rot).
      integer, allocatable :: dof_point(:), dof_kind(:)
      !> (ndof): configuration at the start: coordinates for translations, 0 for rotations.
      real(dp), allocatable :: q0(:)
      !> (ndof): external nodal loads at unit load factor (the LOADs without
      !> a law of their own).
      real(dp), allocatable :: f_ext(:)
      !> The loads at any time t: f_ext times t, the loads with laws, and in
      !> statics the weights (fekap_assembly_loads).
      type(load_set_type) :: loads
      type(slide_type), allocatable :: slides(:)
      !> (2, entries): where the entries of each element's tangent go, as
      !> lists of (k, position), k = i + 6 (j - 1) the entry of the 6 x 6
      !> tangent and position its place in the band storage (kd + 1, nfree) or
      !> in the free-driven block (nfree, ndriven), both counted in memory
      !> order: element e's from scatter_start(e), first scatter_count(1, e)
      !> entries into the band, then scatter_count(2, e) into the free-driven
      !> block. Entries on fixed dofs and in the band's lower triangle are not
      !> listed (an element on free dofs has 21 of its 36: the lists one after
      !> another, not 36 places an element).
      integer, allocatable :: scatter_map(:, :)
      !> (nelem + 1): where each element's list starts in scatter_map (the
      !> last: one past the end).
      integer, allocatable :: scatter_start(:)
      !> (2, nelem): the lengths of the band and free-driven lists of scatter_map.
      integer, allocatable :: scatter_count(:, :)
   end type mesh_type

contains

   !> Build the mesh of a validated model.
   subroutine new_mesh(self, model)
      type(mesh_type), intent(out) :: self
      type(model_type), intent(in) :: model
      integer :: nnode, nlink, l, k, m, ip, np, e, nelem, nrot, i, j, end_
      integer, allocatable :: parent(:), link_rot_tmp(:, :), interior_rot(:), first_interior(:)
      integer, allocatable :: rot_index(:), ends(:)
      real(dp) :: xa(2), xb(2)

      nnode = size(model%nodes)
      nlink = size(model%links)

      ! Points: model nodes, then interior points of multi-element links.
      np = nnode + sum(model%links%nelem - 1)
      self%npoint = np
      allocate (self%x0(2, np), first_interior(nlink))
      do ip = 1, nnode
         self%x0(:, ip) = model%nodes(ip)%x
      end do
      ip = nnode
      do l = 1, nlink
         first_interior(l) = ip + 1
         xa = model%nodes(model%links(l)%node(1))%x
         xb = model%nodes(model%links(l)%node(2))%x
         m = model%links(l)%nelem
         do k = 1, m - 1
            ip = ip + 1
            self%x0(:, ip) = xa + (xb - xa)*real(k, dp)/m
         end do
      end do

      ! Rotation unknowns before welding: two link ends per link, then interior
      ! points; welds merge link ends (union-find on the link-end ids).
      nrot = 2*nlink + (np - nnode)
      allocate (parent(nrot))
      parent = [(i, i=1, nrot)]
      allocate (link_rot_tmp(2, nlink))
      do l = 1, nlink
         link_rot_tmp(:, l) = [2*l - 1, 2*l]
      end do
      if (allocated(model%welds)) then
         do i = 1, size(model%welds)
            allocate (ends(size(model%welds(i)%links)))
            do j = 1, size(ends)
               l = model%welds(i)%links(j)
               end_ = merge(1, 2, model%links(l)%node(1) == model%welds(i)%node)
               ends(j) = link_rot_tmp(end_, l)
            end do
            do j = 2, size(ends)
               call join(parent, ends(1), ends(j))
            end do
            deallocate (ends)
         end do
      end if

      ! Number the dofs: x, y of every point, then one rotation per distinct root.
      self%ndof = 2*np
      allocate (self%tdof(2, np))
      do ip = 1, np
         self%tdof(:, ip) = [2*ip - 1, 2*ip]
      end do
      allocate (rot_index(nrot), source=0)
      call flatten(parent)
      do i = 1, nrot
         j = find_root(parent, i)
         if (rot_index(j) == 0) then
            self%ndof = self%ndof + 1
            rot_index(j) = self%ndof
         end if
         rot_index(i) = rot_index(j)
      end do
      allocate (self%link_rot(2, nlink), interior_rot(np))
      interior_rot = 0
      do l = 1, nlink
         self%link_rot(:, l) = rot_index(link_rot_tmp(:, l))
      end do
      do ip = nnode + 1, np
         interior_rot(ip) = rot_index(2*nlink + ip - nnode)
      end do

      allocate (self%dof_point(self%ndof), self%dof_kind(self%ndof), source=0)
      do ip = 1, np
         self%dof_point(self%tdof(:, ip)) = ip
         self%dof_kind(self%tdof(:, ip)) = [dof_x, dof_y]
      end do
      do l = 1, nlink
         do end_ = 1, 2
            self%dof_point(self%link_rot(end_, l)) = model%links(l)%node(end_)
            self%dof_kind(self%link_rot(end_, l)) = dof_rot
         end do
      end do
      do ip = nnode + 1, np
         self%dof_point(interior_rot(ip)) = ip
         self%dof_kind(interior_rot(ip)) = dof_rot
      end do

      ! Elements.
      nelem = sum(model%links%nelem)
      allocate (self%elements(nelem), self%edof(6, nelem), self%elink(nelem), self%link_angle0(nlink))
      if (any(planned_effects(model) == [effects_statics, effects_dynamics])) then
         self%chord_links = [(l, l=1, nlink)]
      else if (any(model%links%nelem > 1)) then
         self%chord_links = pack([(l, l=1, nlink)], model%links%nelem > 1)
      end if
      e = 0
      do l = 1, nlink
         m = model%links(l)%nelem
         xa = model%nodes(model%links(l)%node(1))%x
         xb = model%nodes(model%links(l)%node(2))%x
         self%link_angle0(l) = atan2(xb(2) - xa(2), xb(1) - xa(1))
         do k = 1, m
            e = e + 1
            self%elink(e) = l
            call new_beam(self%elements(e), xa + (xb - xa)*real(k - 1, dp)/m, xa + (xb - xa)*real(k, dp)/m, &
               & section_stiffness(model, model%links(l)%section), model%analysis%gauss_points)
            self%edof(1:3, e) = [self%tdof(:, link_point(k - 1)), link_rotation(k - 1)]
            self%edof(4:6, e) = [self%tdof(:, link_point(k)), link_rotation(k)]
         end do
      end do

      call set_status(self, model)
      call new_slides(self%slides, model, first_interior, self%x0, self%elements, self%edof, self%tdof, self%link_rot)
      call number_equations(self)
      call build_scatter_map(self)

      allocate (self%q0(self%ndof), source=0.0_dp)
      do ip = 1, np
         self%q0(self%tdof(:, ip)) = self%x0(:, ip)
      end do
      allocate (self%f_ext(self%ndof), source=0.0_dp)
      if (allocated(model%loads)) then
         do i = 1, size(model%loads)
            associate (load => model%loads(i))
               if (load%timed) cycle
               self%f_ext(self%tdof(:, load%node)) = self%f_ext(self%tdof(:, load%node)) + load%force
               if (load%link > 0 .and. load%moment /= 0) then
                  j = end_dof(self, model, load%link, load%node)
                  self%f_ext(j) = self%f_ext(j) + load%moment
               end if
            end associate
         end do
      end if
      call new_load_set(self, model)

   contains

      !> Point k (0..m) along link l.
      integer function link_point(k_) result(p)
         integer, intent(in) :: k_
         if (k_ == 0) then
            p = model%links(l)%node(1)
         else if (k_ == m) then
            p = model%links(l)%node(2)
         else
            p = first_interior(l) + k_ - 1
         end if
      end function link_point

      !> Rotation dof at point k (0..m) along link l.
      integer function link_rotation(k_) result(r)
         integer, intent(in) :: k_
         if (k_ == 0) then
            r = self%link_rot(1, l)
         else if (k_ == m) then
            r = self%link_rot(2, l)
         else
            r = interior_rot(first_interior(l) + k_ - 1)
         end if
      end function link_rotation

   end subroutine new_mesh

   !> Section stiffnesses (EA, kGA, EI) of section index isec.
   pure function section_stiffness(model, isec) result(c)
      type(model_type), intent(in) :: model
      integer, intent(in) :: isec
      real(dp) :: c(3)
      c = [model%sections(isec)%ea, model%sections(isec)%kga, model%sections(isec)%ei]
   end function section_stiffness

   !> The loads over the dofs as functions of time: the loads without a law
   !> (f_ext, times the load factor t), each load with a law, and in statics
   !> the weights of the masses (a dead load).
   subroutine new_load_set(self, model)
      type(mesh_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      integer :: i, column, j, e
      call self%loads%add_column(self%ndof, load_type(), column)
      self%loads%f(:, column) = self%f_ext
      if (allocated(model%loads)) then
         do i = 1, size(model%loads)
            associate (load => model%loads(i))
               if (.not. load%timed) cycle
               call self%loads%add_column(self%ndof, load, column)
               self%loads%f(self%tdof(:, load%node), column) = load%force
               if (load%link > 0 .and. load%moment /= 0) then
                  j = end_dof(self, model, load%link, load%node)
                  self%loads%f(j, column) = load%moment
               end if
            end associate
         end do
      end if
      if (planned_effects(model) /= effects_statics .or. .not. has_masses(model) .or. all(model%gravity == 0)) return
      call self%loads%add_dead_column(self%ndof, column)
      do e = 1, size(self%elements)
         associate (f => self%loads%f(:, column), el => self%elements(e))
            f(self%edof(:, e)) = f(self%edof(:, e)) + beam_gravity_force(el%length, &
               & model%sections(model%links(self%elink(e))%section)%rho_a, model%gravity)
         end associate
      end do
      if (allocated(model%masses)) then
         do i = 1, size(model%masses)
            associate (f => self%loads%f(:, column), m => model%masses(i))
               f(self%tdof(:, m%node)) = f(self%tdof(:, m%node)) + m%mass*model%gravity
            end associate
         end do
      end if
   end subroutine new_load_set

   !> The MASSes block over the dofs: each point mass on its node's two
   !> translations, its rotary inertia on the rotation of its link's end there.
   pure function point_masses(self, model) result(mass)
      type(mesh_type), intent(in) :: self
      type(model_type), intent(in) :: model
      real(dp) :: mass(self%ndof)
      integer :: i, dof
      mass = 0
      if (.not. allocated(model%masses)) return
      do i = 1, size(model%masses)
         associate (m => model%masses(i))
            mass(self%tdof(:, m%node)) = mass(self%tdof(:, m%node)) + m%mass
            if (m%link > 0) then
               dof = end_dof(self, model, m%link, m%node)
               mass(dof) = mass(dof) + m%inertia
            end if
         end associate
      end do
   end function point_masses

   !> The rotation dof of link l at its end on node.
   pure integer function end_dof(self, model, l, node) result(dof)
      type(mesh_type), intent(in) :: self
      type(model_type), intent(in) :: model
      integer, intent(in) :: l, node
      dof = self%link_rot(merge(1, 2, model%links(l)%node(1) == node), l)
   end function end_dof

   !> Mark supported and driven dofs.
   subroutine set_status(self, model)
      type(mesh_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      integer :: i
      allocate (self%status(self%ndof), source=dof_free)
      if (allocated(model%supports)) then
         do i = 1, size(model%supports)
            associate (s => model%supports(i))
               if (s%fix(dof_x)) self%status(self%tdof(1, s%node)) = dof_fixed
               if (s%fix(dof_y)) self%status(self%tdof(2, s%node)) = dof_fixed
               if (s%fix(dof_rot)) self%status(end_dof(self, model, s%link, s%node)) = dof_fixed
            end associate
         end do
      end if
      self%ndriven = 0
      if (allocated(model%drives)) self%ndriven = size(model%drives)
      allocate (self%driven_dof(self%ndriven))
      do i = 1, self%ndriven
         associate (d => model%drives(i))
            if (d%dof == dof_rot) then
               self%driven_dof(i) = end_dof(self, model, d%link, d%node)
            else
               self%driven_dof(i) = self%tdof(d%dof, d%node)
            end if
         end associate
         self%status(self%driven_dof(i)) = dof_driven
      end do
      allocate (self%drive_col(self%ndof), source=0)
      do i = 1, self%ndriven
         self%drive_col(self%driven_dof(i)) = i
      end do
   end subroutine set_status

   !> Equation numbers of the free dofs in reverse Cuthill-McKee order, and the
   !> half-bandwidth and envelope that result.
   subroutine number_equations(self)
      type(mesh_type), intent(inout) :: self
      integer, allocatable :: free_index(:), deg(:), adj_start(:), adj(:), order(:), level(:)
      integer, allocatable :: group_start(:), group_dof(:)
      integer :: nf, e, i, k

      allocate (free_index(self%ndof), source=0)
      nf = 0
      do i = 1, self%ndof
         if (self%status(i) == dof_free) then
            nf = nf + 1
            free_index(i) = nf
         end if
      end do
      self%nfree = nf

      ! Coupling groups: each element's dofs, and each slideline's slave with
      ! all its master points (the slave may reach any master segment).
      call coupling_groups(self, group_start, group_dof)
      ! Adjacency (CSR) of the free dofs: two dofs are adjacent when a group couples them.
      call group_adjacency(group_start, group_dof, free_index, nf, adj_start, adj, deg)
      allocate (order(nf), level(nf))
      call cuthill_mckee(adj_start, adj, deg, order)

      allocate (self%eq(self%ndof), source=0)
      allocate (self%eq_dof(nf))
      ! Reverse: the free dof ordered k-th gets equation nf + 1 - k.
      do k = 1, nf
         level(order(k)) = nf + 1 - k
      end do
      do i = 1, self%ndof
         if (free_index(i) == 0) cycle
         self%eq(i) = level(free_index(i))
         self%eq_dof(self%eq(i)) = i
      end do

      self%kd = 0
      self%envelope = [(k, k = 1, nf)]
      do e = 1, size(group_start) - 1
         associate (g => group_dof(group_start(e):group_start(e + 1) - 1))
            associate (eqs => pack(self%eq(g), self%eq(g) > 0))
               if (size(eqs) > 1) then
                  self%kd = max(self%kd, maxval(eqs) - minval(eqs))
                  do k = 1, size(eqs)
                     self%envelope(eqs(k)) = min(self%envelope(eqs(k)), minval(eqs))
                  end do
               end if
            end associate
         end associate
      end do

   end subroutine number_equations

   !> Destinations of every element tangent entry (see mesh_type%scatter_map),
   !> so that assembly adds without looking up equation numbers or skipping
   !> entries that go nowhere: the lists' lengths, then the lists.
   pure subroutine build_scatter_map(self)
      type(mesh_type), intent(inout) :: self
      integer :: e, nb, nd, band(2, 36), driven(2, 36), at
      allocate (self%scatter_count(2, size(self%elements)), self%scatter_start(size(self%elements) + 1))
      at = 1
      do e = 1, size(self%elements)
         call element_destinations(self, e, band, nb, driven, nd)
         self%scatter_start(e) = at
         self%scatter_count(:, e) = [nb, nd]
         at = at + nb + nd
      end do
      self%scatter_start(size(self%elements) + 1) = at
      allocate (self%scatter_map(2, at - 1))
      do e = 1, size(self%elements)
         call element_destinations(self, e, band, nb, driven, nd)
         at = self%scatter_start(e)
         self%scatter_map(:, at:at + nb - 1) = band(:, 1:nb)
         self%scatter_map(:, at + nb:at + nb + nd - 1) = driven(:, 1:nd)
      end do
   end subroutine build_scatter_map

   !> Element e's entries into the band (nb) and into the free-driven block
   !> (nd), as build_scatter_map lists them.
   pure subroutine element_destinations(self, e, band, nb, driven, nd)
      type(mesh_type), intent(in) :: self
      integer, intent(in) :: e
      integer, intent(out) :: band(2, 36), nb, driven(2, 36), nd
      integer :: i, j, ei, ej, dj
      nb = 0
      nd = 0
      do j = 1, 6
         dj = self%edof(j, e)
         ej = self%eq(dj)
         do i = 1, 6
            ei = self%eq(self%edof(i, e))
            if (ei == 0) cycle
            if (ej > 0) then
               if (ei <= ej) then
                  nb = nb + 1
                  ! A(ei, ej) at (kd + 1 + ei - ej, ej) of the band storage.
                  band(:, nb) = [i + 6*(j - 1), self%kd + 1 + ei - ej + (self%kd + 1)*(ej - 1)]
               end if
            else if (self%drive_col(dj) > 0) then
               nd = nd + 1
               driven(:, nd) = [i + 6*(j - 1), ei + self%nfree*(self%drive_col(dj) - 1)]
            end if
         end do
      end do
   end subroutine element_destinations

   !> Dof groups that the tangent couples: every element, and every slideline
   !> (slave translations and tie rotation with every master point's translations).
   pure subroutine coupling_groups(self, group_start, group_dof)
      type(mesh_type), intent(in) :: self
      integer, allocatable, intent(out) :: group_start(:), group_dof(:)
      integer :: e, i, k, ng, nel, total
      nel = size(self%edof, 2)
      ng = nel + size(self%slides)
      ! Sizes first, then fill: no array grows inside the loops.
      total = 6*nel
      do i = 1, size(self%slides)
         associate (sl => self%slides(i))
            total = total + 2 + merge(1, 0, sl%slave_rot > 0)
            if (.not. sl%ground) total = total + 2*(size(sl%seg, 2) + 1)
         end associate
      end do
      allocate (group_start(ng + 1), group_dof(total))
      group_start(1) = 1
      k = 0
      do e = 1, nel
         group_dof(k + 1:k + 6) = self%edof(:, e)
         k = k + 6
         group_start(e + 1) = k + 1
      end do
      do i = 1, size(self%slides)
         associate (sl => self%slides(i))
            group_dof(k + 1:k + 2) = self%tdof(:, sl%slave)
            k = k + 2
            if (sl%slave_rot > 0) then
               group_dof(k + 1) = sl%slave_rot
               k = k + 1
            end if
            if (.not. sl%ground) then
               do e = 1, size(sl%seg, 2)
                  group_dof(k + 1:k + 2) = self%tdof(:, sl%seg(1, e))
                  k = k + 2
               end do
               group_dof(k + 1:k + 2) = self%tdof(:, sl%seg(2, size(sl%seg, 2)))
               k = k + 2
            end if
         end associate
         group_start(nel + i + 1) = k + 1
      end do
   end subroutine coupling_groups

   !> A readable name of a dof, for messages: "x of node C", "rotation of link AB at node A".
   function describe_dof(self, model, dof) result(text)
      type(mesh_type), intent(in) :: self
      type(model_type), intent(in) :: model
      integer, intent(in) :: dof
      character(:), allocatable :: text
      integer :: ip, l
      character(len=16) :: num
      ip = self%dof_point(dof)
      if (ip <= size(model%nodes)) then
         text = 'node '//model%nodes(ip)%name
      else
         write (num, '(i0)') ip
         text = 'interior point '//trim(num)
      end if
      select case (self%dof_kind(dof))
      case (dof_x)
         text = 'x of '//text
      case (dof_y)
         text = 'y of '//text
      case default
         text = 'rotation at '//text
         do l = 1, size(model%links)
            if (any(self%link_rot(:, l) == dof)) then
               text = text//' (link '//model%links(l)%name//')'
               exit
            end if
         end do
      end select
   end function describe_dof

end module fekap_assembly_mesh
