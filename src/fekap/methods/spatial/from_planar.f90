!> A planar kinematics model turned into the spatial model of the same
!> mechanism in the plane z = 0, for `fekap --spatial PLANAR.deck` (the model
!> a spatial deck would give, run by fekap_spatial_build and the spatial
!> stepper; docs/deck-format.md, "Planar decks in 3D"):
!>
!>   node           a node at z = 0; where links meet, one node per rigid
!>                  group of links there (a link, or links welded by WELDs),
!>                  the first keeping the node's name, the others named
!>                  NODE.LINK (LINK the group's first link);
!>   hinge          a revolute joint about +z from the first group's node
!>                  to each other group's (named NODE.LINK);
!>   pin support    a revolute joint about +z from the ground to each group
!>                  (a weld for the group `rot LINK` clamps);
!>   roller, ground-guide SLIDeline
!>                  a slider block NODE.roller (NODE.SLIDELINE) on a prismatic
!>                  joint to the ground along the free line, and a revolute
!>                  joint about +z from it to each group (a weld for the
!>                  clamped group, or a prismatic slideline's slave link);
!>   slider on a moving link (SLIDelines `on LINK`)
!>                  a slider block NODE.SLIDELINE on a prismatic joint to
!>                  the link's first node (a slide along the line through
!>                  the slave's place in the link's direction, carried by
!>                  that node's rotation: fekap_spatial_slideline), and a
!>                  revolute joint about +z from it to each group (a weld
!>                  for a prismatic slideline's slave link);
!>   slider on a line of several links (SLIDelines `on L1 L2 ...`, pin)
!>                  a prismatic joint NODE.SLIDELINE from the line's first
!>                  node to the slave along the links' elements in order,
!>                  each segment carried by its first node's point and
!>                  rotation (the links are hinged, so the line bends where
!>                  they meet): the slide on the segment that holds its
!>                  stroke, the arc length along the line
!>                  (fekap_spatial_mechanism's slide_on_segment), as the
!>                  planar slideline moves its slave on to the next master
!>                  element; the slave's groups hinged as at any node. A
!>                  prismatic one is refused (its planar tie turns the slave
!>                  link at once where the slave passes a hinge);
!>   meshed link    its elements as links LINK, LINK#2, ... between the
!>                  interior nodes LINK#1, ... (welded, as links sharing a
!>                  node are in a spatial model);
!>   section        EA, GA2 = GA3 = kGA, GJ = EI2 = EI3 = EI, axis 2 along +z;
!>   rotation drive the revolute joint that holds the link's end to the
!>                  ground or to a slider block, by the same law;
!>   x or y drive   the stroke of the node's slider block, by the law over
!>                  the line's direction cosine.
!>
!> The out-of-plane motion is held by the elastic links: revolute joints
!> about parallel axes make a planar loop redundant in 3D (a four-bar has
!> three redundant constraints), which the method takes without special
!> settings (Eischen, Sun & Marler's links are elastic; docs/spatial.md).
!> Kinematics only.
module fekap_spatial_from_planar
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, input_error
   use fekap_strings, only: same_name, int_text
   use fekap_model, only: model_type, node_type, link_type, source_loc_type, loc_file, weld_type, support_type, &
      & drive_type, slideline_type, method_fem, dof_x, dof_y, dof_rot, effects_kinematics, &
      & slide_prismatic => joint_prismatic
   use fekap_model_effects, only: effects_plan_type, plan_effects, effects_name
   use fekap_model_spatial, only: spatial_joint_type, spatial_drive_type, spatial_section_type, joint_revolute, &
      & joint_prismatic, joint_weld
   use fekap_spatial_build, only: shifted_law
   implicit none
   private

   public :: spatial_from_planar

   !> The joints' axis: every planar hinge turns about +z.
   real(dp), parameter :: z_axis(3) = [0.0_dp, 0.0_dp, 1.0_dp]

contains

   !> Turn the planar kinematics model into its spatial model (a spatial
   !> model is left as it is). The planar nodes keep their indices (tracked
   !> points), the links their indices and names (a meshed link's first
   !> element keeps them); the joints and drives are those of the header.
   subroutine spatial_from_planar(model, error)
      type(model_type), intent(inout) :: model
      type(error_type), allocatable, intent(out) :: error
      type(effects_plan_type) :: plan
      type(node_type), allocatable :: nodes(:)
      type(link_type), allocatable :: links(:)
      type(spatial_joint_type), allocatable :: joints(:)
      type(spatial_drive_type), allocatable :: drives(:)
      !> Per original link and end: its element at that end, and the joint
      !> that holds that end's group to the ground or a slider block (0: none).
      integer, allocatable :: elem_end(:, :), end_joint(:, :)
      !> Per original node: its slider block's prismatic joint (0: none).
      integer, allocatable :: block_joint(:)
      integer :: nn, nl, k, n, j, e, g, ng, nd, blk, ground_link, slide
      !> Slider blocks on moving links: the block node and its slideline.
      integer, allocatable :: moving_block(:), moving_slide(:)
      !> Sliders on a line of several links: the slave node and its slideline.
      integer, allocatable :: line_slave(:), line_slide(:)
      !> Per original link: the index before its further elements (LINK#2, ...).
      integer, allocatable :: elem_base(:)
      integer, allocatable :: at_link(:), at_end(:), group(:), group_node(:)
      real(dp) :: axis(3), factor
      character(:), allocatable :: what

      if (model%analysis%spatial) return
      if (model%analysis%method /= method_fem) then
         call input_error(error, model%file//': --spatial runs with the finite element method only: '// &
            & 'leave out --method and the ANALysis method line')
         return
      end if
      plan = plan_effects(model)
      if (plan%effects /= effects_kinematics) then
         call input_error(error, model%file//': --spatial runs kinematics only, and this deck''s analysis is '// &
            & effects_name(plan%effects)//' ('//plan%why//'): spatial kinetostatics, statics and dynamics '// &
            & 'are not there yet; run it without --spatial')
         return
      end if

      nn = size(model%nodes)
      nl = size(model%links)
      nodes = model%nodes
      links = model%links
      allocate (joints(0), drives(0), moving_block(0), moving_slide(0), line_slave(0), line_slide(0))

      ! Meshed links: one link per element, welded at the interior nodes LINK#k.
      allocate (elem_end(nl, 2), end_joint(nl, 2), elem_base(nl), source=0)
      do k = 1, nl
         elem_end(k, :) = k
         elem_base(k) = size(links)
         associate (link => model%links(k))
            if (link%nelem <= 1) cycle
            links(k)%nelem = 1
            do e = 1, link%nelem - 1
               call add_node(link%name//'#'//int_text(e), &
                  & model%nodes(link%node(1))%x + real(e, dp)/link%nelem*(model%nodes(link%node(2))%x - &
                  & model%nodes(link%node(1))%x), link%loc)
               if (allocated(error)) return
               if (e == 1) then
                  links(k)%node(2) = size(nodes)
               else
                  links = [links, link_type(link%name//'#'//int_text(e), [size(nodes) - 1, size(nodes)], &
                     & link%section, 1, link%loc)]
               end if
            end do
            links = [links, link_type(link%name//'#'//int_text(link%nelem), [size(nodes), link%node(2)], &
               & link%section, 1, link%loc)]
            elem_end(k, 2) = size(links)
         end associate
      end do

      ! Each node: its rigid groups of links, and what holds them.
      allocate (block_joint(nn), source=0)
      do n = 1, nn
         at_link = [integer ::]
         at_end = [integer ::]
         do k = 1, nl
            do e = 1, 2
               if (model%links(k)%node(e) == n) then
                  at_link = [at_link, k]
                  at_end = [at_end, e]
               end if
            end do
         end do
         ! Groups: the links of a weld at n are one, each other link its own.
         group = [(0, j=1, size(at_link))]
         ng = 0
         do j = 1, size(at_link)
            if (group(j) > 0) cycle
            ng = ng + 1
            group(j) = ng
            do k = 1, size(model%welds)
               if (model%welds(k)%node /= n .or. .not. any(model%welds(k)%links == at_link(j))) cycle
               where (member(at_link, model%welds(k)%links)) group = ng
            end do
         end do
         ! The first group keeps the node; the others get a node of their own.
         group_node = [(0, g=1, ng)]
         do g = 1, ng
            if (g == 1) then
               group_node(g) = n
            else
               call add_node(model%nodes(n)%name//'.'//model%links(first_link(g))%name, model%nodes(n)%x, &
                  & model%nodes(n)%loc)
               if (allocated(error)) return
               group_node(g) = size(nodes)
            end if
         end do
         do j = 1, size(at_link)
            links(elem_end(at_link(j), at_end(j)))%node(at_end(j)) = group_node(group(j))
         end do

         ! What holds the node: a support, a slideline, or nothing (hinges).
         k = 0
         do j = 1, size(model%supports)
            if (model%supports(j)%node == n) k = j
         end do
         slide = 0
         do j = 1, size(model%slidelines)
            if (model%slidelines(j)%slave == n) slide = j
         end do
         if (slide > 0) then
            associate (s => model%slidelines(slide))
               if (.not. s%ground .and. size(s%master_links) > 1 .and. s%kind == slide_prismatic) then
                  call loc_error(s%loc, '--spatial takes a prismatic slider on one moving link only: slideline '// &
                     & s%name//' ties the angle of link '//model%links(s%slave_link)%name//' to a line of '// &
                     & 'several links, and the planar tie turns that link at once, as node '// &
                     & model%nodes(n)%name//' passes from one link to the next, by the change of the angle '// &
                     & 'between them since the start', 'make it a pin slider (leave out prismatic) or run this '// &
                     & 'deck without --spatial')
                  return
               end if
               if (k > 0) then
                  call loc_error(s%loc, '--spatial: node '//model%nodes(n)%name//' is both supported and '// &
                     & 'on the guide of slideline '//s%name, 'keep one of them')
                  return
               end if
            end associate
         end if
         ground_link = 0
         if (k > 0) then
            associate (sup => model%supports(k))
               if (sup%fix(dof_rot)) ground_link = sup%link
               if (sup%fix(dof_x) .and. sup%fix(dof_y)) then
                  do g = 1, ng
                     if (ground_link > 0 .and. any(at_link == ground_link .and. group == g)) then
                        call add_joint(joint_weld, 0, group_node(g), sup%loc)
                     else
                        call add_joint(joint_revolute, 0, group_node(g), sup%loc, z_axis)
                        call hold_group(g, size(joints))
                     end if
                  end do
                  cycle
               else if (.not. (sup%fix(dof_x) .or. sup%fix(dof_y))) then
                  call loc_error(sup%loc, '--spatial does not take a support of a rotation alone (rot without x '// &
                     & 'and y) at node '//model%nodes(n)%name, 'run this deck without --spatial')
                  return
               end if
               ! A roller: a block sliding along the free coordinate.
               axis = merge([0.0_dp, 1.0_dp, 0.0_dp], [1.0_dp, 0.0_dp, 0.0_dp], sup%fix(dof_x))
               call add_block(model%nodes(n)%name//'.roller', axis, sup%loc, ground_link)
               if (allocated(error)) return
            end associate
         else if (slide > 0) then
            associate (s => model%slidelines(slide))
               if (s%kind == slide_prismatic) ground_link = s%slave_link
               if (s%ground) then
                  axis = [s%guide(:, 2) - s%guide(:, 1), 0.0_dp]
                  call add_block(model%nodes(n)%name//'.'//s%name, axis, s%loc, ground_link)
               else if (size(s%master_links) > 1) then
                  ! A pin on a line of several links: the node's groups hinged
                  ! as at any node, its point on the line (added below).
                  do g = 2, ng
                     call add_joint(joint_revolute, group_node(1), group_node(g), model%nodes(n)%loc, z_axis)
                  end do
                  line_slave = [line_slave, n]
                  line_slide = [line_slide, slide]
               else
                  call add_moving_block(model%nodes(n)%name//'.'//s%name, s%loc, ground_link)
                  moving_slide = [moving_slide, slide]
               end if
               if (allocated(error)) return
            end associate
         else
            do g = 2, ng
               call add_joint(joint_revolute, group_node(1), group_node(g), model%nodes(n)%loc, z_axis)
            end do
         end if
      end do

      ! The slides of the blocks on moving links, now that the master links'
      ! end nodes are known: along the link, carried by its first node.
      do j = 1, size(moving_block)
         k = model%slidelines(moving_slide(j))%master_links(1)
         axis = [model%nodes(model%links(k)%node(2))%x - model%nodes(model%links(k)%node(1))%x, 0.0_dp]
         call add_joint(joint_prismatic, links(elem_end(k, 1))%node(1), moving_block(j), &
            & model%slidelines(moving_slide(j))%loc, axis)
      end do

      ! The slides on lines of several links: a prismatic joint from the
      ! first segment's first node to the slave, along the line's segments
      ! (the links' elements in order along it, each from its end nearer
      ! the line's start), carried each by its first node.
      do j = 1, size(line_slave)
         call add_line_joint(line_slave(j), model%slidelines(line_slide(j)))
      end do

      ! Drives: a link's rotation is its end's revolute joint to the ground
      ! (or to a slider block); a node's x or y the stroke of its block.
      do k = 1, size(model%drives)
         associate (d => model%drives(k))
            if (d%dof == dof_rot) then
               e = merge(1, 2, model%links(d%link)%node(1) == d%node)
               if (end_joint(d%link, e) == 0) then
                  call loc_error(d%loc, '--spatial drives the rotation of a link only at a node held to the '// &
                     & 'ground (a pin, a roller or a ground guide), where it is the angle of a revolute joint '// &
                     & 'about +z: link '//model%links(d%link)%name//' is hinged to moving links at node '// &
                     & model%nodes(d%node)%name, 'run this deck without --spatial')
                  return
               end if
               drives = [drives, spatial_drive_type(end_joint(d%link, e), .false., d%law)]
            else
               what = trim(merge('x', 'y', d%dof == dof_x))
               blk = block_joint(d%node)
               factor = 0
               if (blk > 0) factor = joints(blk)%axis(d%dof)/norm2(joints(blk)%axis)
               if (abs(factor) < 1.0e-9_dp) then
                  call loc_error(d%loc, '--spatial drives the '//what//' of a node only on a roller or a ground '// &
                     & 'guide that moves it in '//what//', as the stroke of a prismatic joint: node '// &
                     & model%nodes(d%node)%name//' is not on one', 'run this deck without --spatial')
                  return
               end if
               ! The stroke s moves the node by s times the line's unit direction.
               drives = [drives, spatial_drive_type(blk, .true., &
                  & shifted_law(d%law, model%analysis%t_start, 1/factor))]
            end if
         end associate
      end do

      call move_alloc(nodes, model%nodes)
      call move_alloc(links, model%links)
      model%spatial%z = spread(0.0_dp, 1, size(model%nodes))
      model%spatial%truss = spread(.false., 1, size(model%links))
      if (allocated(model%spatial%sections)) deallocate (model%spatial%sections)
      allocate (model%spatial%sections(size(model%sections)))
      do k = 1, size(model%sections)
         ! In-plane: EA, shear kGA along axis 3 (in the plane), bending EI
         ! about axis 2 = +z. Out of the plane the same sizes (kGA along z, EI
         ! about axis 3, torsion GJ = EI): the motion is stress free, and
         ! stiffnesses of one size keep the tangent's condition (docs/spatial.md).
         associate (s => model%sections(k))
            model%spatial%sections(k) = spatial_section_type([s%ea, s%kga, s%kga, s%ei, s%ei, s%ei], &
               & [(.true., j=1, 6)], z_axis)
         end associate
      end do
      call move_alloc(joints, model%spatial%joints)
      call move_alloc(drives, model%spatial%drives)
      model%welds = model%welds(1:0)
      model%supports = model%supports(1:0)
      model%drives = model%drives(1:0)
      model%slidelines = model%slidelines(1:0)
      model%analysis%spatial = .true.

   contains

      !> The first link of group g.
      integer function first_link(g)
         integer, intent(in) :: g
         first_link = at_link(findloc(group, g, 1))
      end function first_link

      !> The ends of group g are held by joint j (to the ground or a block).
      subroutine hold_group(g, j)
         integer, intent(in) :: g, j
         integer :: i
         do i = 1, size(at_link)
            if (group(i) == g) end_joint(at_link(i), at_end(i)) = j
         end do
      end subroutine hold_group

      !> A new node at (x, 0), its name not one of the deck's.
      subroutine add_node(name, x, loc)
         character(*), intent(in) :: name
         real(dp), intent(in) :: x(2)
         type(source_loc_type), intent(in) :: loc
         integer :: i
         do i = 1, size(nodes)
            if (same_name(nodes(i)%name, name)) then
               call loc_error(nodes(i)%loc, '--spatial names a node of its spatial model '//name// &
                  & ', which is a name of the deck''s', 'rename that node')
               return
            end if
         end do
         nodes = [nodes, node_type(name, x, loc)]
      end subroutine add_node

      !> A joint of the kind between nodes a and b (a = 0: the ground first), told at loc.
      subroutine add_joint(kind, a, b, loc, axis)
         integer, intent(in) :: kind, a, b
         type(source_loc_type), intent(in) :: loc
         real(dp), intent(in), optional :: axis(3)
         type(spatial_joint_type) :: joint
         joint%kind = kind
         if (a == 0) then
            joint%node = [b, 0]
            joint%ground_first = .true.
         else
            joint%node = [a, b]
         end if
         joint%name = nodes(b)%name
         if (present(axis)) joint%axis = axis
         joint%file = loc_file(model, loc)
         joint%line = loc%line
         joint%col = loc%col
         joints = [joints, joint]
      end subroutine add_joint

      !> A slider block at node n on a prismatic joint to the ground along
      !> axis, and a joint from it to each group: a weld for the group of
      !> link `welded` (0: none), else a revolute about +z.
      subroutine add_block(name, axis, loc, welded)
         character(*), intent(in) :: name
         real(dp), intent(in) :: axis(3)
         type(source_loc_type), intent(in) :: loc
         integer, intent(in) :: welded
         integer :: b, gg
         call add_node(name, model%nodes(n)%x, loc)
         if (allocated(error)) return
         b = size(nodes)
         call add_joint(joint_prismatic, 0, b, loc, axis)
         block_joint(n) = size(joints)
         do gg = 1, ng
            if (welded > 0 .and. any(at_link == welded .and. group == gg)) then
               call add_joint(joint_weld, b, group_node(gg), loc)
            else
               call add_joint(joint_revolute, b, group_node(gg), loc, z_axis)
               call hold_group(gg, size(joints))
            end if
         end do
      end subroutine add_block

      !> A slider block at node n on a moving link (its slide added after the
      !> nodes), and a joint from it to each group: a weld for the group of
      !> link `welded` (0: none), else a revolute about +z. Its revolute
      !> joints turn relative to the link, so they hold no rotation drive.
      subroutine add_moving_block(name, loc, welded)
         character(*), intent(in) :: name
         type(source_loc_type), intent(in) :: loc
         integer, intent(in) :: welded
         integer :: b, gg
         call add_node(name, model%nodes(n)%x, loc)
         if (allocated(error)) return
         b = size(nodes)
         moving_block = [moving_block, b]
         do gg = 1, ng
            if (welded > 0 .and. any(at_link == welded .and. group == gg)) then
               call add_joint(joint_weld, b, group_node(gg), loc)
            else
               call add_joint(joint_revolute, b, group_node(gg), loc, z_axis)
            end if
         end do
      end subroutine add_moving_block

      !> The prismatic joint of slideline s's slave (node `slave`, which keeps
      !> its name) along the segments of its master links, named
      !> SLAVE.SLIDELINE. The links are listed in order along the line
      !> (consecutive ones share a node, the deck checks); each is taken from
      !> its end at the previous one (the first: from its end away from the
      !> second), its elements in that order.
      subroutine add_line_joint(slave, s)
         integer, intent(in) :: slave
         type(slideline_type), intent(in) :: s
         integer, allocatable :: segs(:, :), elems(:)
         integer :: i, l, last, m, le
         logical :: reversed
         allocate (segs(2, 0))
         last = 0
         do i = 1, size(s%master_links)
            l = s%master_links(i)
            if (i == 1) then
               reversed = any(model%links(s%master_links(2))%node == model%links(l)%node(1))
            else
               reversed = model%links(l)%node(2) == last
            end if
            m = model%links(l)%nelem
            elems = [l, (elem_base(l) + le, le=1, m - 1)]
            if (reversed) then
               elems = elems(m:1:-1)
               last = model%links(l)%node(1)
            else
               last = model%links(l)%node(2)
            end if
            do le = 1, m
               associate (link => links(elems(le)))
                  if (reversed) then
                     segs = reshape([segs, link%node(2), link%node(1)], [2, size(segs, 2) + 1])
                  else
                     segs = reshape([segs, link%node], [2, size(segs, 2) + 1])
                  end if
               end associate
            end do
         end do
         call add_joint(joint_prismatic, segs(1, 1), slave, s%loc, &
            & [nodes(segs(2, 1))%x - nodes(segs(1, 1))%x, 0.0_dp])
         joints(size(joints))%name = model%nodes(slave)%name//'.'//s%name
         call move_alloc(segs, joints(size(joints))%segments)
      end subroutine add_line_joint

      !> An input error at loc.
      subroutine loc_error(loc, message, advice)
         type(source_loc_type), intent(in) :: loc
         character(*), intent(in) :: message, advice
         call input_error(error, loc_file(model, loc)//':'//int_text(loc%line)//':'//int_text(loc%col)//': error: '// &
            & message//'; '//advice)
      end subroutine loc_error

   end subroutine spatial_from_planar

   !> Whether each of list is in set.
   pure function member(list, set) result(is)
      integer, intent(in) :: list(:), set(:)
      logical :: is(size(list))
      integer :: i
      do i = 1, size(list)
         is(i) = any(set == list(i))
      end do
   end function member

end module fekap_spatial_from_planar
