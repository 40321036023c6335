!> The spatial mechanism of a spatial deck's model: joints as double nodes
!> turned into shared points and a tree of frames (fekap_spatial_mechanism).
!> The nodes joined by joints share one point (fixed by a joint to the
!> ground, on a ground line by a prismatic or cylindrical one, else free);
!> welded nodes share one frame; each revolute or universal joint makes one
!> frame the child of the other, the tree grown outwards from the ground
!> (breadth first), so a joint written "backwards" is turned round and its
!> angle counted with a sign. A joint's angle (stroke) is the second node's
!> rotation about (motion along) the axis relative to the first node's, zero
!> at the deck's configuration; a drive prescribes its change since the
!> start time, law(t) - law(t_start). A prismatic or cylindrical joint
!> between two nodes is a slide (fekap_spatial_slideline): its second node's
!> point stays on the line through that node's start place along the axis,
!> carried by the first node's frame; the second node's frame is the
!> first's (prismatic) or its revolute child about the axis (cylindrical).
!> A prismatic joint along a line of segments (joint%segments, made by
!> `--spatial` for a planar slider on a chain of links) is a slide whose
!> line is carried segment by segment, its stroke the arc length along it,
!> and holds no rotation.
!>
!> The module is over 600 lines with one concept: the joints' double nodes
!> made into the mechanism's points, frames and slides, with their checks;
!> the drives and reported joints follow the frames it makes.
module fekap_spatial_build
   use fekap_kinds, only: dp
   use fekap_vectors, only: cross
   use fekap_error, only: error_type, input_error
   use fekap_union_find, only: find_root, join
   use fekap_model, only: model_type, loc_file
   use fekap_model_drive_law, only: law_type, law_rate, law_harmonic, law_polynomial, law_table, &
      & law_constant, law_linear
   use fekap_model_spatial, only: spatial_joint_type, reported_joints, joint_spherical, joint_revolute, joint_universal, &
      & joint_prismatic, joint_cylindrical, joint_weld
   use fekap_spatial_mechanism, only: spatial_mechanism_type, add_point, add_frame, add_node, add_beam, &
      & add_truss, add_drive, add_slide, add_slide_segment, point_fixed, point_free, point_line, frame_fixed, &
      & frame_free, frame_revolute, &
      & frame_universal
   implicit none
   private

   public :: spatial_map_type, build_spatial_mechanism, shifted_law

   !> Where the model's entities are in the mechanism.
   type :: spatial_map_type
      !> The mechanism's point and frame (0: none) of each model node.
      integer, allocatable :: node_point(:), node_frame(:)
      !> Reported joints (revolute: angle; prismatic: stroke): model joint,
      !> mechanism dof and the sign of the joint's motion in it.
      integer, allocatable :: report_joint(:), report_dof(:)
      real(dp), allocatable :: report_sign(:)
   end type spatial_map_type

contains

   !> Build m from the model's spatial data (read and checked by the deck).
   subroutine build_spatial_mechanism(model, m, map, error)
      type(model_type), intent(in) :: model
      type(spatial_mechanism_type), intent(out) :: m
      type(spatial_map_type), intent(out) :: map
      type(error_type), allocatable, intent(out) :: error
      integer :: nn, nj, i, k, c, o, p, head, tail
      integer, allocatable :: point_set(:), frame_set(:), ground_joint(:), class_point(:), class_frame(:)
      integer, allocatable :: angle_dof(:), stroke_dof(:), queue(:), mech_node(:)
      real(dp), allocatable :: angle_sign(:), stroke_sign(:)
      logical, allocatable :: has_frame(:), used(:), report_stroke(:)
      logical :: carried
      real(dp) :: d(3), v(3), sign, kp
      type(law_type) :: law
      nn = size(model%nodes)
      nj = size(model%spatial%joints)
      allocate (angle_dof(nj), stroke_dof(nj), source=0)
      allocate (angle_sign(nj), stroke_sign(nj), source=1.0_dp)
      associate (joints => model%spatial%joints)
         ! Points: the nodes of a joint share one.
         point_set = [(i, i=1, nn)]
         do k = 1, nj
            if (is_slide(joints(k))) cycle
            if (joints(k)%node(2) > 0) call join(point_set, joints(k)%node(1), joints(k)%node(2))
         end do
         allocate (ground_joint(nn), class_point(nn), source=0)
         do k = 1, nj
            if (joints(k)%node(2) > 0) cycle
            c = find_root(point_set, joints(k)%node(1))
            if (ground_joint(c) > 0) then
               if (grounds_point(joints(ground_joint(c))) .neqv. grounds_point(joints(k))) then
                  call joint_error(joints(k), 'joint '//joints(k)%name//' and joint '// &
                     & joints(ground_joint(c))%name//' hold one point to the ground in two ways', &
                     & 'one point is fixed or slides on one line of the ground: keep one of them', error)
                  return
               end if
               if (.not. grounds_point(joints(k)) .and. &
                  & norm2(cross(joints(k)%axis, joints(ground_joint(c))%axis)) > 1.0e-9_dp) then
                  call joint_error(joints(k), 'joints '//joints(k)%name//' and '//joints(ground_joint(c))%name// &
                     & ' slide one point along two lines', 'give them one axis, or keep one of them', error)
                  return
               end if
            end if
            ground_joint(c) = k
         end do
         do i = 1, nn
            if (find_root(point_set, i) /= i) cycle
            if (ground_joint(i) == 0) then
               call add_point(m, point_free, position(i), class_point(i), error=error)
            else if (grounds_point(joints(ground_joint(i)))) then
               call add_point(m, point_fixed, position(i), class_point(i), error=error)
            else
               call add_point(m, point_line, position(i), class_point(i), joints(ground_joint(i))%axis, error)
               stroke_dof(ground_joint(i)) = m%points(class_point(i))%dof
               if (.not. joints(ground_joint(i))%ground_first) stroke_sign(ground_joint(i)) = -1
            end if
            if (allocated(error)) return
         end do
         ! A prismatic joint named a second time on one line shares the first's stroke.
         do k = 1, nj
            if (joints(k)%node(2) == 0 .and. .not. grounds_point(joints(k)) .and. stroke_dof(k) == 0) then
               p = class_point(find_root(point_set, joints(k)%node(1)))
               stroke_dof(k) = m%points(p)%dof
               if (.not. joints(k)%ground_first) stroke_sign(k) = -1
            end if
         end do
         allocate (map%node_point(nn))
         do i = 1, nn
            map%node_point(i) = class_point(find_root(point_set, i))
         end do

         ! Frames: on the nodes of beams and of the joints that hold rotations.
         allocate (has_frame(nn), source=.false.)
         do k = 1, size(model%links)
            if (.not. model%spatial%truss(k)) has_frame(model%links(k)%node) = .true.
         end do
         do k = 1, nj
            if (joints(k)%kind /= joint_spherical) has_frame(pack(joints(k)%node, joints(k)%node > 0)) = .true.
         end do
         frame_set = [(i, i=1, nn)]
         do k = 1, nj
            if (any(joints(k)%kind == [joint_weld, joint_prismatic]) .and. joints(k)%node(2) > 0 .and. &
               & .not. allocated(joints(k)%segments)) then
               call join(frame_set, joints(k)%node(1), joints(k)%node(2))
            end if
         end do
         do i = 1, nn
            if (has_frame(i)) has_frame(find_root(frame_set, i)) = .true.
         end do
         call check_free_spin(model, frame_set, error)
         if (allocated(error)) return
         call check_free_bodies(model, frame_set, error)
         if (allocated(error)) return
         allocate (class_frame(nn), source=0)
         allocate (queue(nn), source=0)
         allocate (used(nj), source=.false.)
         head = 1
         tail = 0
         ! Frames held by the ground first.
         do k = 1, nj
            if (joints(k)%node(2) > 0 .or. joints(k)%kind == joint_spherical) cycle
            c = find_root(frame_set, joints(k)%node(1))
            used(k) = .true.
            if (class_frame(c) > 0) then
               call joint_error(joints(k), 'joint '//joints(k)%name//' holds the rotation of node '// &
                  & model%nodes(joints(k)%node(1))%name//' to the ground a second time', &
                  & 'one joint to the ground sets a node''s rotation: keep one', error)
               return
            end if
            select case (joints(k)%kind)
            case (joint_weld, joint_prismatic)
               call add_frame(m, frame_fixed, class_frame(c), 0, error=error)
            case (joint_revolute, joint_cylindrical)
               call add_frame(m, frame_revolute, class_frame(c), 0, joints(k)%axis, error=error)
               angle_dof(k) = m%frames(class_frame(c))%dof
               if (.not. joints(k)%ground_first) angle_sign(k) = -1
            case (joint_universal)
               if (joints(k)%ground_first) then
                  call add_frame(m, frame_universal, class_frame(c), 0, joints(k)%axis, joints(k)%axis2, error)
               else
                  call add_frame(m, frame_universal, class_frame(c), 0, joints(k)%axis2, joints(k)%axis, error)
               end if
            case default                                 ! spherical: skipped above
            end select
            if (allocated(error)) return
            tail = tail + 1
            queue(tail) = c
         end do
         do
            ! Grow the tree from the frames placed so far through revolute and universal joints.
            do while (head <= tail)
               c = queue(head)
               head = head + 1
               do k = 1, nj
                  if (all(joints(k)%kind /= [joint_revolute, joint_universal, joint_cylindrical]) .or. &
                     & joints(k)%node(2) == 0) cycle
                  if (used(k)) cycle
                  if (find_root(frame_set, joints(k)%node(1)) == c) then
                     o = find_root(frame_set, joints(k)%node(2))
                     sign = 1
                  else if (find_root(frame_set, joints(k)%node(2)) == c) then
                     o = find_root(frame_set, joints(k)%node(1))
                     sign = -1
                  else
                     cycle
                  end if
                  used(k) = .true.
                  if (o == c .or. class_frame(o) > 0) then
                     call joint_error(joints(k), 'joint '//joints(k)%name//' closes a loop of joints that '// &
                        & 'set rotations (revolute, universal, weld) between frames already related', &
                        & 'a loop of links needs elastic links between its joints: make one of these joints '// &
                        & 'spherical, or remove it', error)
                     return
                  end if
                  if (any(joints(k)%kind == [joint_revolute, joint_cylindrical])) then
                     call add_frame(m, frame_revolute, class_frame(o), class_frame(c), joints(k)%axis, error=error)
                     angle_dof(k) = m%frames(class_frame(o))%dof
                     angle_sign(k) = sign
                  else if (sign > 0) then
                     call add_frame(m, frame_universal, class_frame(o), class_frame(c), joints(k)%axis, &
                        & joints(k)%axis2, error)
                  else
                     call add_frame(m, frame_universal, class_frame(o), class_frame(c), joints(k)%axis2, &
                        & joints(k)%axis, error)
                  end if
                  if (allocated(error)) return
                  tail = tail + 1
                  queue(tail) = o
               end do
            end do
            ! A part not held by the ground: its first frame turns freely.
            c = 0
            do i = 1, nn
               if (find_root(frame_set, i) == i .and. has_frame(i) .and. class_frame(i) == 0) then
                  c = i
                  exit
               end if
            end do
            if (c == 0) exit
            call add_frame(m, frame_free, class_frame(c), error=error)
            if (allocated(error)) return
            tail = tail + 1
            queue(tail) = c
         end do

         allocate (mech_node(nn))
         do i = 1, nn
            call add_node(m, map%node_point(i), class_frame(find_root(frame_set, i)), mech_node(i))
         end do
         map%node_frame = m%nodes(mech_node)%frame
         do k = 1, size(model%links)
            associate (link => model%links(k), sec => model%spatial%sections(model%links(k)%section))
               if (model%spatial%truss(k)) then
                  call add_truss(m, map%node_point(link%node(1)), map%node_point(link%node(2)), sec%c(1), error)
               else
                  d = position(link%node(2)) - position(link%node(1))
                  v = sec%orientation
                  if (all(v == 0)) then
                     ! A symmetric section (the deck checks): the global axis most across the link.
                     v = 0
                     v(minloc(abs(d), 1)) = 1
                  end if
                  call add_beam(m, mech_node(link%node(1)), mech_node(link%node(2)), sec%c, v, error)
               end if
            end associate
            if (allocated(error)) then
               error%message = model%links(k)%name//': '//error%message
               return
            end if
         end do

         ! The slides, with a penalty of the links' largest axial stiffness per
         ! length (as the planar default_penalty: no new scale in the tangent).
         kp = 0
         if (allocated(m%beams)) then
            do i = 1, size(m%beams)
               kp = max(kp, m%beams(i)%element%section(1)/m%beams(i)%element%length)
            end do
         end if
         if (allocated(m%trusses)) then
            do i = 1, size(m%trusses)
               kp = max(kp, m%trusses(i)%element%ea/m%trusses(i)%element%length)
            end do
         end if
         if (.not. kp > 0) kp = 1
         do k = 1, nj
            if (.not. is_slide(joints(k))) cycle
            carried = .false.
            do i = 1, size(model%links)
               if (model%spatial%truss(i)) cycle
               if (find_root(frame_set, model%links(i)%node(1)) == find_root(frame_set, joints(k)%node(1)) .or. &
                  & find_root(frame_set, model%links(i)%node(2)) == find_root(frame_set, joints(k)%node(1))) then
                  carried = .true.
               end if
            end do
            if (.not. carried) then
               call joint_error(joints(k), 'the first node of joint '//joints(k)%name//' is on no beam link, '// &
                  & 'so nothing carries the line its second node slides along', &
                  & 'write first a node of the link that carries the line (a beam, not a truss)', error)
               return
            end if
            associate (a => joints(k)%node(1), b => joints(k)%node(2))
               if (allocated(joints(k)%segments)) then
                  call add_line_slide(joints(k), i, error)
               else
                  call add_slide(m, map%node_point(a), class_frame(find_root(frame_set, a)), map%node_point(b), &
                     & position(b) - position(a), joints(k)%axis, kp, i, error)
               end if
               if (allocated(error)) then
                  error%message = joints(k)%name//': '//error%message
                  return
               end if
               stroke_dof(k) = m%slides(i)%dof
            end associate
         end do

         do k = 1, size(model%spatial%drives)
            associate (drive => model%spatial%drives(k))
               if (drive%stroke) then
                  law = shifted_law(drive%law, model%analysis%t_start, stroke_sign(drive%joint))
                  call add_drive(m, stroke_dof(drive%joint), law, error)
               else
                  law = shifted_law(drive%law, model%analysis%t_start, angle_sign(drive%joint))
                  call add_drive(m, angle_dof(drive%joint), law, error)
               end if
            end associate
            if (allocated(error)) return
         end do

         call reported_joints(model%spatial, map%report_joint, report_stroke)
         allocate (map%report_dof(size(map%report_joint)), map%report_sign(size(map%report_joint)))
         do i = 1, size(map%report_joint)
            k = map%report_joint(i)
            if (.not. report_stroke(i)) then
               map%report_dof(i) = angle_dof(k)
               map%report_sign(i) = angle_sign(k)
            else
               map%report_dof(i) = stroke_dof(k)
               map%report_sign(i) = stroke_sign(k)
            end if
         end do
      end associate

   contains

      pure function position(node) result(x)
         integer, intent(in) :: node
         real(dp) :: x(3)
         x = [model%nodes(node)%x, model%spatial%z(node)]
      end function position

      !> The slide of a joint along a line of segments (joint%segments): its
      !> stroke the arc length along the line from the second node's start
      !> place (on the segment it projects into with the smallest distance,
      !> as the planar slideline's initial_segments), each segment carried by
      !> its first node's point and frame, from the stroke where it begins.
      subroutine add_line_slide(joint, id, error)
         type(spatial_joint_type), intent(in) :: joint
         integer, intent(out) :: id
         type(error_type), allocatable, intent(out) :: error
         real(dp) :: dir(3, size(joint%segments, 2)), start(size(joint%segments, 2)), seg_len(size(joint%segments, 2))
         real(dp) :: arc, along, gap, best, s0
         integer :: j, on
         associate (seg => joint%segments, b => joint%node(2))
            arc = 0
            do j = 1, size(seg, 2)
               dir(:, j) = position(seg(2, j)) - position(seg(1, j))
               seg_len(j) = norm2(dir(:, j))
               if (.not. seg_len(j) > 0) then
                  call joint_error(joint, 'a segment of the line of joint '//joint%name//' has no length', &
                     & 'give each segment two nodes at different places', error)
                  return
               end if
               dir(:, j) = dir(:, j)/seg_len(j)
               start(j) = arc
               arc = arc + seg_len(j)
            end do
            on = 0
            best = huge(1.0_dp)
            s0 = 0
            do j = 1, size(seg, 2)
               along = dot_product(position(b) - position(seg(1, j)), dir(:, j))
               gap = norm2(position(b) - position(seg(1, j)) - along*dir(:, j))
               if (along >= -1.0e-9_dp*seg_len(j) .and. along <= (1 + 1.0e-9_dp)*seg_len(j) .and. gap < best) then
                  best = gap
                  on = j
                  s0 = start(j) + along
               end if
            end do
            if (on == 0) then
               call joint_error(joint, 'node '//model%nodes(b)%name//' of joint '//joint%name// &
                  & ' is on none of the segments of its line', 'place it on the line', error)
               return
            end if
            call add_slide(m, map%node_point(seg(1, 1)), class_frame(find_root(frame_set, seg(1, 1))), &
               & map%node_point(b), (s0 - start(1))*dir(:, 1), dir(:, 1), kp, id, error)
            if (allocated(error)) return
            do j = 2, size(seg, 2)
               call add_slide_segment(m, id, map%node_point(seg(1, j)), class_frame(find_root(frame_set, seg(1, j))), &
                  & (s0 - start(j))*dir(:, j), dir(:, j), start(j) - s0, error)
               if (allocated(error)) return
            end do
         end associate
      end subroutine add_line_slide

   end subroutine build_spatial_mechanism

   !> A beam whose two end rotations nothing else holds (no other beam, no
   !> joint but a spherical one) turns freely about its own axis: its
   !> strains do not change, so the tangent has a zero pivot that round-off
   !> hides (a beam between two spherical joints). An input error at its
   !> LINKs line: a truss is the element for it (docs/spatial.md). Only the
   !> single beam is caught: links welded into a straight chain between two
   !> spherical joints spin too, and stop later at a singular tangent.
   subroutine check_free_spin(model, frame_set, error)
      type(model_type), intent(in) :: model
      integer, intent(in) :: frame_set(:)
      type(error_type), allocatable, intent(out) :: error
      integer :: holders(size(frame_set)), k, i
      character(len=24) :: where_
      holders = 0
      do k = 1, size(model%links)
         if (model%spatial%truss(k)) cycle
         do i = 1, 2
            associate (c => find_root(frame_set, model%links(k)%node(i)))
               holders(c) = holders(c) + 1
            end associate
         end do
      end do
      do k = 1, size(model%spatial%joints)
         associate (joint => model%spatial%joints(k))
            ! A slide along a line of segments holds no rotation (its slider's is free).
            if (joint%kind == joint_spherical .or. allocated(joint%segments)) cycle
            do i = 1, 2
               if (joint%node(i) == 0) cycle
               associate (c => find_root(frame_set, joint%node(i)))
                  holders(c) = holders(c) + 1
               end associate
            end do
         end associate
      end do
      do k = 1, size(model%links)
         associate (link => model%links(k))
            if (model%spatial%truss(k)) cycle
            if (holders(find_root(frame_set, link%node(1))) > 1 .or. &
               & holders(find_root(frame_set, link%node(2))) > 1) cycle
            write (where_, '(i0,a,i0)') link%loc%line, ':', link%loc%col
            call input_error(error, loc_file(model, link%loc)//':'//trim(where_)//': error: link '//link%name// &
               & ' turns freely about its own axis: nothing but the link holds the rotation of either end '// &
               & '(a beam between two spherical joints); write `truss` after its section, or hold one '// &
               & 'end''s rotation with a revolute, universal or weld joint')
            return
         end associate
      end do
   end subroutine check_free_spin

   !> Bodies whose rotation nothing holds but their points: the frames
   !> joined by beams (and welds) make a body; one no revolute, universal,
   !> prismatic, cylindrical or weld joint holds turns freely about the line
   !> through its points that meet the rest (spherical joints, trusses,
   !> slides, the ground) when those points are on one line (two spherical
   !> joints: links welded into a chain between them). Its tangent has a zero
   !> pivot that round-off hides (LU finds none), so it is an input error at
   !> the body's first LINKs line (check_free_spin catches the single beam
   !> first, with its own message).
   subroutine check_free_bodies(model, frame_set, error)
      type(model_type), intent(in) :: model
      integer, intent(in) :: frame_set(:)
      type(error_type), allocatable, intent(out) :: error
      integer :: body(size(frame_set)), nn, k, i, b, first, count
      logical :: held(size(frame_set)), meets(size(frame_set)), beam_node(size(frame_set))
      real(dp) :: places(3, size(frame_set)), size_
      character(len=24) :: where_
      character(:), allocatable :: names
      nn = size(frame_set)
      ! Bodies: frame classes joined by beams.
      body = [(find_root(frame_set, i), i=1, nn)]
      beam_node = .false.
      do k = 1, size(model%links)
         if (model%spatial%truss(k)) cycle
         call join(body, model%links(k)%node(1), model%links(k)%node(2))
         beam_node(model%links(k)%node) = .true.
      end do
      ! Held: a joint other than spherical (a weld between two nodes only if
      ! it joins two bodies). Meets: a node of a joint other than such a
      ! weld, or a truss's end.
      held = .false.
      meets = .false.
      do k = 1, size(model%spatial%joints)
         associate (joint => model%spatial%joints(k))
            if (joint%kind == joint_weld .and. joint%node(2) > 0) then
               if (find_root(body, joint%node(1)) == find_root(body, joint%node(2))) cycle
            end if
            do i = 1, 2
               if (joint%node(i) == 0) cycle
               meets(joint%node(i)) = .true.
               if (joint%kind /= joint_spherical .and. .not. allocated(joint%segments)) then
                  held(find_root(body, joint%node(i))) = .true.
               end if
            end do
         end associate
      end do
      do k = 1, size(model%links)
         if (model%spatial%truss(k)) meets(model%links(k)%node) = .true.
      end do
      size_ = 1
      do i = 1, nn
         size_ = max(size_, norm2(place(i)))
      end do
      do b = 1, nn
         if (find_root(body, b) /= b .or. held(b)) cycle
         if (.not. any([(beam_node(i) .and. find_root(body, i) == b, i=1, nn)])) cycle
         count = 0
         do i = 1, nn
            if (meets(i) .and. find_root(body, i) == b) then
               count = count + 1
               places(:, count) = place(i)
            end if
         end do
         if (.not. collinear(places(:, 1:count), 1.0e-9_dp*size_)) cycle
         first = 0
         names = ''
         do k = 1, size(model%links)
            if (model%spatial%truss(k) .or. find_root(body, model%links(k)%node(1)) /= b) cycle
            if (first == 0) then
               first = k
               names = model%links(k)%name
            else
               names = names//', '//model%links(k)%name
            end if
         end do
         associate (link => model%links(first))
            write (where_, '(i0,a,i0)') link%loc%line, ':', link%loc%col
            call input_error(error, loc_file(model, link%loc)//':'//trim(where_)//': error: links '//names// &
               & ' turn together freely about the line through the points where they meet the rest of the '// &
               & 'mechanism (no joint but spherical ones holds their rotation); hold one of their nodes'' '// &
               & 'rotation with a revolute, universal or weld joint, or, for a straight chain, make it one truss')
         end associate
         return
      end do
   contains
      pure function place(node) result(x)
         integer, intent(in) :: node
         real(dp) :: x(3)
         x = [model%nodes(node)%x, model%spatial%z(node)]
      end function place
   end subroutine check_free_bodies

   !> Whether the points p(:, i) lie on one line, within tol.
   pure logical function collinear(p, tol)
      real(dp), intent(in) :: p(:, :), tol
      real(dp) :: far, u(3)
      integer :: i, ifar
      collinear = .true.
      if (size(p, 2) < 2) return
      far = 0
      ifar = 1
      do i = 2, size(p, 2)
         if (norm2(p(:, i) - p(:, 1)) > far) then
            far = norm2(p(:, i) - p(:, 1))
            ifar = i
         end if
      end do
      if (far < tol) return
      u = (p(:, ifar) - p(:, 1))/far
      do i = 2, size(p, 2)
         if (norm2(cross(p(:, i) - p(:, 1), u)) > tol) then
            collinear = .false.
            return
         end if
      end do
   end function collinear

   !> Whether a joint slides a node along a line carried by another's frame.
   pure logical function is_slide(joint)
      type(spatial_joint_type), intent(in) :: joint
      is_slide = any(joint%kind == [joint_prismatic, joint_cylindrical]) .and. joint%node(2) > 0
   end function is_slide

   !> Whether a joint to the ground fixes its point (not a line to slide on).
   pure logical function grounds_point(joint)
      type(spatial_joint_type), intent(in) :: joint
      grounds_point = all(joint%kind /= [joint_prismatic, joint_cylindrical])
   end function grounds_point

   !> An input error at the joint's deck line.
   subroutine joint_error(joint, message, advice, error)
      type(spatial_joint_type), intent(in) :: joint
      character(*), intent(in) :: message, advice
      type(error_type), allocatable, intent(out) :: error
      character(len=24) :: where_
      write (where_, '(i0,a,i0)') joint%line, ':', joint%col
      call input_error(error, joint%file//':'//trim(where_)//': error: '//message//'; '//advice)
   end subroutine joint_error

   !> sign*(law(t) - law(t0)): the change of a joint's angle or stroke since
   !> the start, as the mechanism's dof counts it.
   pure function shifted_law(law, t0, sign) result(shifted)
      type(law_type), intent(in) :: law
      real(dp), intent(in) :: t0, sign
      type(law_type) :: shifted
      real(dp) :: f0, df, ddf
      call law%eval(t0, f0, df, ddf)
      shifted = law
      select case (law%kind)
      case (law_rate)
         shifted%c = sign*[law%c(1), law%c(2) - f0]
      case (law_harmonic)
         shifted%c = [sign*(law%c(1) - f0), sign*law%c(2), law%c(3), law%c(4)]
      case (law_polynomial, law_constant)
         shifted%c = sign*law%c
         shifted%c(1) = sign*(law%c(1) - f0)
      case (law_table)
         shifted%tv = sign*(law%tv - f0)
         shifted%tm = sign*law%tm
      case (law_linear)
         shifted%tv = sign*(law%tv - f0)
      case default                                       ! no law: nothing to shift
      end select
   end function shifted_law

end module fekap_spatial_build
