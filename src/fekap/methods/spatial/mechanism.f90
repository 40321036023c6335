!> A spatial mechanism as FEKAP's finite element method sees it: links meshed
!> with SE(3) beams and co-rotational trusses, joints as double nodes, no
!> multipliers. A node is a point (its translations) and, for beams, a frame
!> (its rotation); the two nodes of a joint share their point:
!>
!>   spherical   the second node gets a frame of its own (3 rotation dofs);
!>   revolute    its frame is the first node's turned by an angle dof about
!>               an axis fixed in that frame, R_B = R_A exp(theta n^);
!>   universal   two angles about two perpendicular axes,
!>               R_B = R_A exp(alpha n1^) exp(beta n2^);
!>   prismatic   (to the ground) a point on a line, x = x0 + s t, one dof;
!>   slide       a point on a line carried by a moving frame (a prismatic or
!>               cylindrical joint between links): the paper's penalty
!>               slideline with the stroke s as a dof (fekap_spatial_slideline);
!>               the slider's rotation is set by the frame tree (the line's
!>               frame for a prismatic joint, a revolute child about the
!>               line for a cylindrical one).
!>
!> These are the eliminated ("relative-angle dof") joints of the study
!> shared/studies/spatial-se3 (its item 5): as accurate as penalty joints,
!> with fewer dofs, a lower condition number and no penalty factor to choose.
!> Frames are created parent first, so one pass in order gives every frame.
!> Every node frame is I in the reference configuration; a free frame's
!> rotation is a matrix updated multiplicatively, angles and translations are
!> additive.
module fekap_spatial_mechanism
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, input_error
   use fekap_model_drive_law, only: law_type
   use fekap_element_se3_beam, only: se3_beam_type, new_se3_beam, truss_type, new_truss
   implicit none
   private

   public :: spatial_mechanism_type, add_point, add_frame, add_node, add_beam, add_truss, add_drive
   public :: add_spherical, add_revolute, add_universal, add_slide, add_slide_segment, slide_on_segment, &
      & passes_a_segment_end

   !> Kinds of point: fixed (no dof), free (3 translations), on a ground line (1).
   integer, parameter, public :: point_fixed = 0, point_free = 1, point_line = 2
   !> Kinds of frame: fixed (R = I), free (3 body rotations), revolute (1 angle
   !> about an axis of its parent), universal (2 angles).
   integer, parameter, public :: frame_fixed = 0, frame_free = 1, frame_revolute = 2, frame_universal = 3

   !> Relative tolerance on the perpendicularity of a universal joint's axes.
   real(dp), parameter :: perpendicular_tolerance = 1.0e-9_dp

   type, public :: spatial_point_type
      integer :: kind = point_fixed
      !> First dof (0: none).
      integer :: dof = 0
      real(dp) :: x0(3) = 0
      !> Unit direction of a line point.
      real(dp) :: axis(3) = 0
   end type spatial_point_type

   type, public :: spatial_frame_type
      integer :: kind = frame_fixed
      !> The frame it turns relative to (0: the ground, R = I).
      integer :: parent = 0
      integer :: dof = 0
      !> Unit axes, in the parent's body axes (revolute: axis; universal: both).
      real(dp) :: axis(3) = 0, axis2(3) = 0
   end type spatial_frame_type

   !> A point and a frame (0: translations only, the end of a truss).
   type, public :: spatial_node_type
      integer :: point = 0, frame = 0
   end type spatial_node_type

   type, public :: spatial_beam_type
      type(se3_beam_type) :: element
      integer :: nodes(2) = 0
   end type spatial_beam_type

   type, public :: spatial_truss_type
      type(truss_type) :: element
      integer :: points(2) = 0
   end type spatial_truss_type

   !> A slider point on a line carried by a moving frame: the line is
   !> x_A + R_A (offset + s axis) (point A, frame A), its stroke s a dof;
   !> the penalty kp on the gap g = x_B - x_A - R_A (offset + s axis) keeps
   !> point B on it (fekap_spatial_slideline).
   type, public :: spatial_slide_type
      !> The line's point and frame, the slider's point.
      integer :: point_a = 0, frame_a = 0, point_b = 0
      integer :: dof = 0
      !> In frame A's body axes: the line's place at s = 0 (from point A) and unit direction.
      real(dp) :: offset(3) = 0, axis(3) = 0
      real(dp) :: kp = 0
      !> A line of several segments (a planar slideline on a chain of links
      !> hinged together, whose line bends where they meet): segment k is
      !> carried by point seg_point(k) and frame seg_frame(k), at
      !> seg_offset(:, k) + s seg_axis(:, k) in that frame's body axes, and
      !> holds the strokes from seg_start(k) (segment 1: all below segment
      !> 2's start; the last: all beyond its own). The stroke is the arc
      !> length along the line, so that it is continuous where the slider
      !> passes from one segment to the next (slide_on_segment). Not
      !> allocated: one line, the fields above.
      integer, allocatable :: seg_point(:), seg_frame(:)
      real(dp), allocatable :: seg_offset(:, :), seg_axis(:, :), seg_start(:)
   end type spatial_slide_type

   type, public :: spatial_drive_type
      integer :: dof = 0
      type(law_type) :: law
   end type spatial_drive_type

   type :: spatial_mechanism_type
      type(spatial_point_type), allocatable :: points(:)
      type(spatial_frame_type), allocatable :: frames(:)
      type(spatial_node_type), allocatable :: nodes(:)
      type(spatial_beam_type), allocatable :: beams(:)
      type(spatial_truss_type), allocatable :: trusses(:)
      type(spatial_drive_type), allocatable :: drives(:)
      type(spatial_slide_type), allocatable :: slides(:)
      integer :: ndof = 0
      !> Whether a dof is a length (scaled by `length` in convergence tests).
      logical, allocatable :: is_length(:)
      !> Characteristic length: the longest element.
      real(dp) :: length = 0
   end type spatial_mechanism_type

contains

   !> New dofs: n more, lengths or not; first is the first new one.
   subroutine new_dofs(m, n, lengths, first)
      type(spatial_mechanism_type), intent(inout) :: m
      integer, intent(in) :: n
      logical, intent(in) :: lengths
      integer, intent(out) :: first
      if (.not. allocated(m%is_length)) allocate (m%is_length(0))
      first = m%ndof + 1
      m%ndof = m%ndof + n
      m%is_length = [m%is_length, spread(lengths, 1, n)]
   end subroutine new_dofs

   !> A point at x0: fixed, free, or on the ground line x0 + s t (kind point_line, axis t).
   subroutine add_point(m, kind, x0, id, axis, error)
      type(spatial_mechanism_type), intent(inout) :: m
      integer, intent(in) :: kind
      real(dp), intent(in) :: x0(3)
      integer, intent(out) :: id
      real(dp), intent(in), optional :: axis(3)
      type(error_type), allocatable, intent(out) :: error
      type(spatial_point_type) :: p
      if (.not. allocated(m%points)) allocate (m%points(0))
      p%kind = kind
      p%x0 = x0
      select case (kind)
      case (point_free)
         call new_dofs(m, 3, .true., p%dof)
      case (point_line)
         call unit_axis(axis, p%axis, error)
         if (allocated(error)) return
         call new_dofs(m, 1, .true., p%dof)
      case (point_fixed)
      case default
         call input_error(error, 'unknown kind of point')
         return
      end select
      m%points = [m%points, p]
      id = size(m%points)
   end subroutine add_point

   !> The unit vector along a (present, non-zero) axis.
   pure subroutine unit_axis(axis, unit, error)
      real(dp), intent(in), optional :: axis(3)
      real(dp), intent(out) :: unit(3)
      type(error_type), allocatable, intent(out) :: error
      unit = 0
      if (.not. present(axis)) then
         call input_error(error, 'a joint axis is missing: give its three components')
         return
      end if
      if (.not. norm2(axis) > 0) then
         call input_error(error, 'a joint axis is zero: give a direction')
         return
      end if
      unit = axis/norm2(axis)
   end subroutine unit_axis

   !> A frame of the given kind turning relative to parent (0: ground) about
   !> axis (and axis2, universal only: perpendicular to axis).
   subroutine add_frame(m, kind, id, parent, axis, axis2, error)
      type(spatial_mechanism_type), intent(inout) :: m
      integer, intent(in) :: kind
      integer, intent(out) :: id
      integer, intent(in), optional :: parent
      real(dp), intent(in), optional :: axis(3), axis2(3)
      type(error_type), allocatable, intent(out) :: error
      type(spatial_frame_type) :: f
      if (.not. allocated(m%frames)) allocate (m%frames(0))
      f%kind = kind
      if (present(parent)) f%parent = parent
      if (f%parent < 0 .or. f%parent > size(m%frames)) then
         call input_error(error, 'a joint names a frame that does not exist')
         return
      end if
      select case (kind)
      case (frame_free)
         call new_dofs(m, 3, .false., f%dof)
      case (frame_revolute)
         call unit_axis(axis, f%axis, error)
         if (allocated(error)) return
         call new_dofs(m, 1, .false., f%dof)
      case (frame_universal)
         call unit_axis(axis, f%axis, error)
         if (allocated(error)) return
         call unit_axis(axis2, f%axis2, error)
         if (allocated(error)) return
         if (abs(dot_product(f%axis, f%axis2)) > perpendicular_tolerance) then
            call input_error(error, 'the two axes of a universal joint are not perpendicular: '// &
               & 'give axes whose dot product is 0')
            return
         end if
         call new_dofs(m, 2, .false., f%dof)
      case (frame_fixed)
      case default
         call input_error(error, 'unknown kind of frame')
         return
      end select
      m%frames = [m%frames, f]
      id = size(m%frames)
   end subroutine add_frame

   !> A node: a point and a frame (0: none).
   subroutine add_node(m, point, frame, id)
      type(spatial_mechanism_type), intent(inout) :: m
      integer, intent(in) :: point, frame
      integer, intent(out) :: id
      if (.not. allocated(m%nodes)) allocate (m%nodes(0))
      m%nodes = [m%nodes, spatial_node_type(point, frame)]
      id = size(m%nodes)
   end subroutine add_node

   !> The second node of a spherical joint at node a's point: a free frame.
   subroutine add_spherical(m, a, id, error)
      type(spatial_mechanism_type), intent(inout) :: m
      integer, intent(in) :: a
      integer, intent(out) :: id
      type(error_type), allocatable, intent(out) :: error
      integer :: f
      call add_frame(m, frame_free, f, error=error)
      if (allocated(error)) return
      call add_node(m, m%nodes(a)%point, f, id)
   end subroutine add_spherical

   !> The second node of a revolute joint at node a, about axis (a's body axes).
   subroutine add_revolute(m, a, axis, id, error)
      type(spatial_mechanism_type), intent(inout) :: m
      integer, intent(in) :: a
      real(dp), intent(in) :: axis(3)
      integer, intent(out) :: id
      type(error_type), allocatable, intent(out) :: error
      integer :: f
      call add_frame(m, frame_revolute, f, m%nodes(a)%frame, axis, error=error)
      if (allocated(error)) return
      call add_node(m, m%nodes(a)%point, f, id)
   end subroutine add_revolute

   !> The second node of a universal joint at node a, about axis then axis2.
   subroutine add_universal(m, a, axis, axis2, id, error)
      type(spatial_mechanism_type), intent(inout) :: m
      integer, intent(in) :: a
      real(dp), intent(in) :: axis(3), axis2(3)
      integer, intent(out) :: id
      type(error_type), allocatable, intent(out) :: error
      integer :: f
      call add_frame(m, frame_universal, f, m%nodes(a)%frame, axis, axis2, error)
      if (allocated(error)) return
      call add_node(m, m%nodes(a)%point, f, id)
   end subroutine add_universal

   !> A beam between nodes n1 and n2 (both with frames); section
   !> (EA, GA2, GA3, GJ, EI2, EI3), orientation vector as CBAR's. Its
   !> strains are weighed by the element's balanced k (new_se3_beam): the
   !> kinematics does not depend on the stiffnesses, only its Newton and
   !> round-off on their spread.
   subroutine add_beam(m, n1, n2, section, orientation, error)
      type(spatial_mechanism_type), intent(inout) :: m
      integer, intent(in) :: n1, n2
      real(dp), intent(in) :: section(6), orientation(3)
      type(error_type), allocatable, intent(out) :: error
      type(spatial_beam_type) :: b
      real(dp) :: eye(3, 3)
      integer :: i
      if (.not. allocated(m%beams)) allocate (m%beams(0))
      if (m%nodes(n1)%frame == 0 .or. m%nodes(n2)%frame == 0) then
         call input_error(error, 'a beam needs nodes with rotations (a truss does not)')
         return
      end if
      eye = 0
      do i = 1, 3
         eye(i, i) = 1
      end do
      call new_se3_beam(b%element, m%points(m%nodes(n1)%point)%x0, eye, m%points(m%nodes(n2)%point)%x0, eye, &
         & section, orientation, error, balanced=.true.)
      if (allocated(error)) return
      b%nodes = [n1, n2]
      m%beams = [m%beams, b]
      m%length = max(m%length, b%element%length)
   end subroutine add_beam

   !> A truss between points p1 and p2, axial stiffness ea.
   subroutine add_truss(m, p1, p2, ea, error)
      type(spatial_mechanism_type), intent(inout) :: m
      integer, intent(in) :: p1, p2
      real(dp), intent(in) :: ea
      type(error_type), allocatable, intent(out) :: error
      type(spatial_truss_type) :: t
      if (.not. allocated(m%trusses)) allocate (m%trusses(0))
      call new_truss(t%element, m%points(p1)%x0, m%points(p2)%x0, ea, error)
      if (allocated(error)) return
      t%points = [p1, p2]
      m%trusses = [m%trusses, t]
      m%length = max(m%length, t%element%length)
   end subroutine add_truss

   !> A slide of point b along the line through point a's place plus offset
   !> (global axes at the reference configuration, where every frame is I),
   !> direction axis, carried by frame fa (0: the ground); penalty kp > 0.
   !> Its stroke dof is id's `dof`.
   subroutine add_slide(m, a, fa, b, offset, axis, kp, id, error)
      type(spatial_mechanism_type), intent(inout) :: m
      integer, intent(in) :: a, fa, b
      real(dp), intent(in) :: offset(3), axis(3), kp
      integer, intent(out) :: id
      type(error_type), allocatable, intent(out) :: error
      type(spatial_slide_type) :: sl
      integer :: nf, np
      if (.not. allocated(m%slides)) allocate (m%slides(0))
      nf = 0
      if (allocated(m%frames)) nf = size(m%frames)
      np = 0
      if (allocated(m%points)) np = size(m%points)
      if (fa < 0 .or. fa > nf .or. a < 1 .or. a > np .or. b < 1 .or. b > np) then
         call input_error(error, 'a slide names a point or frame that does not exist')
         return
      end if
      if (.not. kp > 0) then
         call input_error(error, 'a slide needs a positive penalty')
         return
      end if
      call unit_axis(axis, sl%axis, error)
      if (allocated(error)) return
      sl%point_a = a
      sl%frame_a = fa
      sl%point_b = b
      sl%offset = offset
      sl%kp = kp
      call new_dofs(m, 1, .true., sl%dof)
      m%slides = [m%slides, sl]
      id = size(m%slides)
   end subroutine add_slide

   !> A further segment of slide id's line, from stroke `start` on (greater
   !> than the last segment's start): carried by point a and frame fa (0:
   !> the ground), the line's place at s = 0 from a's place `offset` and its
   !> direction `axis` (global axes at the reference configuration). The
   !> slide's own line (add_slide) is its first segment.
   subroutine add_slide_segment(m, id, a, fa, offset, axis, start, error)
      type(spatial_mechanism_type), intent(inout) :: m
      integer, intent(in) :: id, a, fa
      real(dp), intent(in) :: offset(3), axis(3), start
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: unit(3)
      integer :: ns, np, nf
      ns = 0
      if (allocated(m%slides)) ns = size(m%slides)
      np = 0
      if (allocated(m%points)) np = size(m%points)
      nf = 0
      if (allocated(m%frames)) nf = size(m%frames)
      if (id < 1 .or. id > ns .or. a < 1 .or. a > np .or. fa < 0 .or. fa > nf) then
         call input_error(error, 'a slide segment names a slide, point or frame that does not exist')
         return
      end if
      call unit_axis(axis, unit, error)
      if (allocated(error)) return
      associate (sl => m%slides(id))
         if (.not. allocated(sl%seg_point)) then
            sl%seg_point = [sl%point_a]
            sl%seg_frame = [sl%frame_a]
            sl%seg_offset = reshape(sl%offset, [3, 1])
            sl%seg_axis = reshape(sl%axis, [3, 1])
            sl%seg_start = [-huge(1.0_dp)]
         end if
         if (.not. start > sl%seg_start(size(sl%seg_start))) then
            call input_error(error, 'the segments of a slide''s line must begin at increasing strokes')
            return
         end if
         sl%seg_point = [sl%seg_point, a]
         sl%seg_frame = [sl%seg_frame, fa]
         sl%seg_offset = reshape([sl%seg_offset, offset], [3, size(sl%seg_point)])
         sl%seg_axis = reshape([sl%seg_axis, unit], [3, size(sl%seg_point)])
         sl%seg_start = [sl%seg_start, start]
      end associate
   end subroutine add_slide_segment

   !> The slide sl on the segment of its line that holds stroke s: point_a,
   !> frame_a, offset and axis those of the segment (sl itself for a line of
   !> one segment). The choice is a function of the stroke alone, so that
   !> Newton's residual and tangent at an iterate use the segment the slider
   !> is on there; where the slider passes a segment's end, the gap is
   !> continuous (the segments meet there at a stress-free configuration)
   !> and its Jacobian turns with the line.
   pure function slide_on_segment(sl, s) result(on)
      type(spatial_slide_type), intent(in) :: sl
      real(dp), intent(in) :: s
      type(spatial_slide_type) :: on
      integer :: k
      if (.not. allocated(sl%seg_point)) then
         on = sl
         return
      end if
      k = segment_of(sl, s)
      on%point_a = sl%seg_point(k)
      on%frame_a = sl%seg_frame(k)
      on%point_b = sl%point_b
      on%dof = sl%dof
      on%offset = sl%seg_offset(:, k)
      on%axis = sl%seg_axis(:, k)
      on%kp = sl%kp
   end function slide_on_segment

   !> The segment of slide sl's line that holds stroke s (1 for a line of one).
   pure integer function segment_of(sl, s) result(k)
      type(spatial_slide_type), intent(in) :: sl
      real(dp), intent(in) :: s
      k = 1
      if (.not. allocated(sl%seg_start)) return
      k = size(sl%seg_start)
      do while (k > 1)
         if (s >= sl%seg_start(k)) exit
         k = k - 1
      end do
   end function segment_of

   !> Whether some slide of m is on another segment of its line at the dofs
   !> q + dq than at q (lines of one segment never are): the slider's path
   !> has a corner between, where its rates jump.
   pure logical function passes_a_segment_end(m, q, dq) result(passes)
      type(spatial_mechanism_type), intent(in) :: m
      real(dp), intent(in) :: q(:), dq(:)
      integer :: i
      passes = .false.
      if (.not. allocated(m%slides)) return
      do i = 1, size(m%slides)
         associate (sl => m%slides(i))
            if (.not. allocated(sl%seg_start)) cycle
            if (segment_of(sl, q(sl%dof)) /= segment_of(sl, q(sl%dof) + dq(sl%dof))) passes = .true.
         end associate
      end do
   end function passes_a_segment_end

   !> Prescribe dof by a time law (a revolute frame's angle: its frame%dof;
   !> a line point's stroke: its point%dof).
   subroutine add_drive(m, dof, law, error)
      type(spatial_mechanism_type), intent(inout) :: m
      integer, intent(in) :: dof
      type(law_type), intent(in) :: law
      type(error_type), allocatable, intent(out) :: error
      if (.not. allocated(m%drives)) allocate (m%drives(0))
      if (dof < 1 .or. dof > m%ndof) then
         call input_error(error, 'a drive names a dof that does not exist')
         return
      end if
      if (any(m%drives%dof == dof)) then
         call input_error(error, 'a dof is driven twice: drive it once')
         return
      end if
      m%drives = [m%drives, spatial_drive_type(dof, law)]
   end subroutine add_drive

end module fekap_spatial_mechanism
