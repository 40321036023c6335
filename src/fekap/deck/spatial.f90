!> Reading a spatial deck's geometry and motion (ANALysis `type kinematics
!> spatial`): SECTions with the 3D stiffnesses, NODEs `name x y z`, LINKs
!> (beams, or trusses), JOINts (two coincident nodes, or a node and the
!> ground, with their axes) and DRIVes of joint angles and strokes. Every
!> problem is reported at its deck:line:col with what to do: a zero axis,
!> universal axes that are not perpendicular, a joint's nodes not at one
!> place, a missing node.
module fekap_deck_spatial
   use fekap_kinds, only: dp
   use fekap_vectors, only: cross
   use fekap_model, only: model_type, section_type, node_type, link_type, source_loc_type, loc_file
   use fekap_model_spatial, only: spatial_section_type, spatial_joint_type, spatial_drive_type, joint_names, &
      & joint_spherical, joint_revolute, joint_universal, joint_prismatic, joint_cylindrical, joint_weld
   use fekap_deck_card, only: is_word_of
   use fekap_strings, only: lower, same_name, word_index, short_real_text
   use fekap_deck_name_index, only: new_name_index
   use fekap_deck_context, only: context_type
   use fekap_deck_geometry, only: lookup_node, max_coordinate, too_many
   use fekap_deck_motion, only: read_law
   implicit none
   private

   public :: read_spatial_sections, read_spatial_nodes, read_spatial_links, read_joints, read_spatial_drives
   public :: spatial_size

   !> Range of the section stiffnesses (as the planar sections').
   real(dp), parameter :: min_property = 1.0e-100_dp, max_property = 1.0e100_dp
   !> Relative tolerance of a universal joint's axes being perpendicular (the
   !> library's, fekap_spatial_mechanism) and of an orientation vector being
   !> along its link (then it gives no section axes).
   real(dp), parameter :: perpendicular_tol = 1.0e-9_dp, parallel_tol = 1.0e-6_dp
   !> Links shorter than this times the model size have zero length.
   real(dp), parameter :: zero_length = 1.0e-12_dp
   !> Numbers of axis components each joint kind takes (joint_names' order).
   integer, parameter :: axis_fields(6) = [0, 3, 6, 3, 3, 0]

contains

   !> Diagonal of the nodes' bounding box in 3D (1 without extent).
   pure real(dp) function spatial_size(model) result(size_)
      type(model_type), intent(in) :: model
      real(dp) :: lo(3), hi(3), p(3)
      integer :: i
      size_ = 1
      if (.not. allocated(model%nodes) .or. .not. allocated(model%spatial%z)) return
      if (size(model%nodes) == 0) return
      lo = [model%nodes(1)%x, model%spatial%z(1)]
      hi = lo
      do i = 2, size(model%nodes)
         p = [model%nodes(i)%x, model%spatial%z(i)]
         lo = min(lo, p)
         hi = max(hi, p)
      end do
      size_ = norm2(hi - lo)
      if (size_ <= 0) size_ = 1
   end function spatial_size

   !> A node's position.
   pure function position(model, node) result(x)
      type(model_type), intent(in) :: model
      integer, intent(in) :: node
      real(dp) :: x(3)
      x = [model%nodes(node)%x, model%spatial%z(node)]
   end function position

   !> SECTions: `name EA= GA2= GA3= GJ= EI2= EI3= [vx= vy= vz=]` (a truss's
   !> section may give EA= alone); v is the orientation vector.
   subroutine read_spatial_sections(ctx, model, lines)
      type(context_type), intent(inout) :: ctx
      type(model_type), intent(inout) :: model
      integer, intent(in) :: lines(:)
      character(*), parameter :: keys(9) = [character(len=3) :: 'ea', 'ga2', 'ga3', 'gj', 'ei2', 'ei3', &
         & 'vx', 'vy', 'vz']
      character(*), parameter :: allowed = 'EA= GA2= GA3= GJ= EI2= EI3= vx= vy= vz= (no blanks around =)'
      integer :: i, k, iline, eq, key, n
      real(dp) :: v
      logical :: ok
      character(:), allocatable :: field
      allocate (model%sections(size(lines)), model%spatial%sections(size(lines)))
      n = 0
      do i = 1, size(lines)
         iline = lines(i)
         if (.not. ctx%name_field(iline, 1, 'section')) cycle
         if (.not. ctx%require(iline, 'name EA=... [GA2=... GA3=... GJ=... EI2=... EI3=... vx= vy= vz=]', &
            & 'a spatial SECTions line')) cycle
         n = n + 1
         model%sections(n) = section_type()
         model%sections(n)%name = ctx%field(iline, 1)
         model%sections(n)%loc = ctx%loc(iline, 1)
         model%spatial%sections(n) = spatial_section_type()
         associate (s => model%spatial%sections(n))
            do k = 2, ctx%nfields(iline)
               field = ctx%field(iline, k)
               eq = index(field, '=')
               key = 0
               if (eq > 1) key = findloc(keys, lower(field(:eq - 1)), 1)
               if (key == 0) then
                  call ctx%error(iline, k, "expected PROPERTY=VALUE of a spatial section, not '"//field//"'", &
                     & label='properties: '//allowed)
                  cycle
               end if
               call ctx%real_field(iline, k, v, ok, text=field(eq + 1:))
               if (.not. ok) cycle
               if (key <= 6) then
                  if (s%given(key)) then
                     call ctx%error(iline, k, "property '"//field(:eq - 1)//"' given twice on this line")
                  else if (v < min_property .or. v > max_property) then
                     call ctx%error(iline, k, 'section stiffness '//field(:eq - 1)//' out of range', &
                        & label='stiffnesses are positive, between 1e-100 and 1e100')
                  else
                     s%c(key) = v
                     s%given(key) = .true.
                  end if
               else if (abs(v) > max_coordinate) then
                  call ctx%error(iline, k, 'orientation component too large', label='at most 1e100 in magnitude')
               else
                  s%orientation(key - 6) = v
               end if
            end do
            if (.not. s%given(1)) call ctx%error(iline, 1, 'section '//ctx%field(iline, 1)//' has no EA=', &
               & label='every spatial section gives EA= (a beam''s also GA2= GA3= GJ= EI2= EI3=)')
            model%sections(n)%ea = s%c(1)
            model%sections(n)%kga = s%c(2)
            model%sections(n)%ei = s%c(6)
         end associate
      end do
      model%sections = model%sections(:n)
      model%spatial%sections = model%spatial%sections(:n)
   end subroutine read_spatial_sections

   !> NODEs: `name x y z`.
   subroutine read_spatial_nodes(ctx, model, lines)
      type(context_type), intent(inout) :: ctx
      type(model_type), intent(inout) :: model
      integer, intent(in) :: lines(:)
      real(dp) :: x(3)
      integer :: n, i, iline, j
      logical :: ok
      allocate (model%nodes(size(lines)), model%spatial%z(size(lines)))
      call new_name_index(ctx%nodes, size(lines))
      call new_name_index(ctx%dropped_nodes, size(lines))
      n = 0
      do i = 1, size(lines)
         iline = lines(i)
         if (.not. ctx%name_field(iline, 1, 'node')) cycle
         ok = ctx%require(iline, 'name x y z', 'a NODEs line of a spatial deck')
         if (ok) ok = .not. too_many(ctx, iline, 4, 'name x y z', 'a NODEs line of a spatial deck')
         if (.not. ok) then
            call ctx%dropped_nodes%insert(ctx%field(iline, 1), 1, j)
            cycle
         end if
         n = n + 1
         model%nodes(n) = node_type()
         model%nodes(n)%name = ctx%field(iline, 1)
         model%nodes(n)%loc = ctx%loc(iline, 1)
         x = 0
         do j = 1, 3
            call ctx%real_field(iline, j + 1, x(j), ok)
            if (ok .and. abs(x(j)) > max_coordinate) then
               call ctx%error(iline, j + 1, 'coordinate too large', label='at most 1e100 in magnitude')
               x(j) = 0
            end if
         end do
         model%nodes(n)%x = x(1:2)
         model%spatial%z(n) = x(3)
         call ctx%nodes%insert(model%nodes(n)%name, n, j)
         if (j > 0) then
            call ctx%error_at(model%nodes(n)%loc, "duplicate node name '"//model%nodes(n)%name//"'", &
               & label='each node needs its own name', note_loc=model%nodes(j)%loc, note='first defined here')
            n = n - 1
         end if
      end do
      model%nodes = model%nodes(:n)
      model%spatial%z = model%spatial%z(:n)
   end subroutine read_spatial_nodes

   !> LINKs: `name first-node second-node section [truss]`: an SE(3) beam
   !> (the default), or a co-rotational truss (two-force member, no rotations).
   subroutine read_spatial_links(ctx, model, lines)
      type(context_type), intent(inout) :: ctx
      type(model_type), intent(inout) :: model
      integer, intent(in) :: lines(:)
      character(*), parameter :: form = 'name first-node second-node section [truss]'
      integer :: n, i, iline, j, k, sec
      logical :: ok
      real(dp) :: d(3), v(3)
      allocate (model%links(size(lines)), model%spatial%truss(size(lines)))
      call new_name_index(ctx%links, size(lines))
      call new_name_index(ctx%dropped_links, size(lines))
      n = 0
      do i = 1, size(lines)
         iline = lines(i)
         if (.not. ctx%name_field(iline, 1, 'link')) cycle
         ok = ctx%require(iline, form, 'a LINKs line of a spatial deck')
         if (ok) ok = .not. too_many(ctx, iline, 5, form, 'a LINKs line of a spatial deck')
         if (.not. ok) then
            call ctx%dropped_links%insert(ctx%field(iline, 1), 1, j)
            cycle
         end if
         n = n + 1
         model%links(n) = link_type()
         model%links(n)%name = ctx%field(iline, 1)
         model%links(n)%loc = ctx%loc(iline, 1)
         model%spatial%truss(n) = .false.
         if (ctx%nfields(iline) == 5) then
            if (is_word_of(lower(ctx%field(iline, 5)), 'truss', 4)) then
               model%spatial%truss(n) = .true.
            else
               call ctx%error(iline, 5, "unknown link kind '"//ctx%field(iline, 5)//"'", &
                  & label='leave it out for a beam, or write truss (a two-force member between spherical joints)')
            end if
         end if
         do k = 1, 2
            model%links(n)%node(k) = lookup_node(ctx, iline, k + 1)
         end do
         sec = 0
         do j = 1, size(model%sections)
            if (same_name(model%sections(j)%name, ctx%field(iline, 4))) sec = j
         end do
         model%links(n)%section = sec
         if (sec == 0) call ctx%error(iline, 4, "undefined section '"//ctx%field(iline, 4)//"'", &
            & label='define it in SECTions')
         if (any(model%links(n)%node == 0)) then
            call ctx%dropped_links%insert(model%links(n)%name, 1, j)
            n = n - 1
            cycle
         end if
         d = position(model, model%links(n)%node(2)) - position(model, model%links(n)%node(1))
         if (model%links(n)%node(1) == model%links(n)%node(2)) then
            call ctx%error(iline, 3, 'link '//model%links(n)%name//' joins node '//ctx%field(iline, 2)// &
               & ' to itself', label='a link joins two different nodes')
         else if (norm2(d) < zero_length*spatial_size(model)) then
            call ctx%error(iline, 1, 'zero-length link '//model%links(n)%name//': nodes '//ctx%field(iline, 2)// &
               & ' and '//ctx%field(iline, 3)//' are at the same place', label='move one of the nodes (see NODEs)')
         else if (sec > 0 .and. .not. model%spatial%truss(n)) then
            associate (s => model%spatial%sections(sec))
               if (.not. all(s%given)) then
                  call ctx%error(iline, 4, 'section '//ctx%field(iline, 4)//' lacks stiffnesses a beam needs', &
                     & label='give EA= GA2= GA3= GJ= EI2= EI3= in SECTions, or make the link a truss')
               else if (all(s%orientation == 0)) then
                  if (s%c(2) /= s%c(3) .or. s%c(5) /= s%c(6)) then
                     call ctx%error(iline, 4, 'section '//ctx%field(iline, 4)//' is not symmetric and has no '// &
                        & 'orientation vector', label='give vx= vy= vz= in SECTions: the direction of its axis 2')
                  end if
               else
                  v = s%orientation
                  if (norm2(cross(v, d)) <= parallel_tol*norm2(v)*norm2(d)) then
                     call ctx%error(iline, 4, 'the orientation vector of section '//ctx%field(iline, 4)// &
                        & ' lies along link '//model%links(n)%name, label='give a vx= vy= vz= across the link')
                  end if
               end if
            end associate
         end if
         call ctx%links%insert(model%links(n)%name, n, j)
         if (j > 0) then
            call ctx%error_at(model%links(n)%loc, "duplicate link name '"//model%links(n)%name//"'", &
               & label='each link needs its own name', note_loc=model%links(j)%loc, note='first defined here')
            n = n - 1
         end if
      end do
      model%links = model%links(:n)
      model%spatial%truss = model%spatial%truss(:n)
   end subroutine read_spatial_links

   !> JOINts: `name kind first-node second-node|ground [axis components]`:
   !> spherical, weld (no axis); revolute, prismatic, cylindrical (one axis:
   !> 3 numbers); universal (two perpendicular axes: 6 numbers). The nodes
   !> must be at one place (within the length tolerance of the model size).
   subroutine read_joints(ctx, model, lines)
      type(context_type), intent(inout) :: ctx
      type(model_type), intent(inout) :: model
      integer, intent(in) :: lines(:)
      character(*), parameter :: form = 'name kind first-node second-node|ground [axis x y z [axis2 x y z]]'
      type(spatial_joint_type) :: j
      integer :: n, i, k, iline, nax, first
      real(dp) :: ax(6), gap, tol
      logical :: ok, fine
      character(len=40) :: count_text
      type(source_loc_type) :: loc
      allocate (model%spatial%joints(size(lines)))
      tol = model%analysis%length_tol*spatial_size(model)
      n = 0
      do i = 1, size(lines)
         iline = lines(i)
         if (.not. ctx%name_field(iline, 1, 'joint')) cycle
         if (.not. ctx%require(iline, form, 'a JOINts line')) cycle
         j = spatial_joint_type()
         j%name = ctx%field(iline, 1)
         loc = ctx%loc(iline, 1)
         j%file = loc_file(model, loc)
         j%line = loc%line
         j%col = loc%col
         j%kind = word_index(ctx%field(iline, 2), joint_names)
         if (j%kind == 0) then
            call ctx%error(iline, 2, "unknown joint kind '"//ctx%field(iline, 2)//"'", label='kinds: '//joint_names)
            cycle
         end if
         do k = 1, n
            if (same_name(model%spatial%joints(k)%name, j%name)) then
               call ctx%error(iline, 1, "duplicate joint name '"//j%name//"'", label='each joint needs its own name')
               exit
            end if
         end do
         nax = axis_fields(j%kind)
         write (count_text, '(i0)') nax
         if (ctx%nfields(iline) /= 4 + nax) then
            first = min(ctx%nfields(iline), 4 + nax) + 1
            if (ctx%nfields(iline) > 4 + nax) then
               call ctx%error(iline, first, "unexpected field '"//ctx%field(iline, first)//"'", &
                  & label='a '//ctx%field(iline, 2)//' joint takes '//trim(count_text)//' axis components')
            else
               call ctx%error(iline, first, 'missing axis component', label='a '//ctx%field(iline, 2)// &
                  & ' joint takes '//trim(count_text)//' axis components after its nodes, e.g. 0 0 1')
            end if
            cycle
         end if
         ok = .true.
         do k = 1, 2
            if (same_name(ctx%field(iline, k + 2), 'ground')) then
               j%node(k) = 0
            else
               j%node(k) = lookup_node(ctx, iline, k + 2)
               ok = ok .and. j%node(k) > 0
            end if
         end do
         if (.not. ok) cycle
         if (all(j%node == 0)) then
            call ctx%error(iline, 4, 'joint '//j%name//' joins the ground to itself', &
               & label='name a node for one of its ends')
            cycle
         end if
         if (j%node(1) == 0) then
            ! The ground written first: kept as node(2) = 0, with the order noted.
            j%node = [j%node(2), 0]
            j%ground_first = .true.
         end if
         if (j%node(1) == j%node(2)) then
            call ctx%error(iline, 4, 'joint '//j%name//' joins node '//ctx%field(iline, 3)//' to itself', &
               & label='a joint joins two coincident nodes of different links, or a node and the ground')
            cycle
         end if
         if (j%node(2) > 0) then
            gap = norm2(position(model, j%node(1)) - position(model, j%node(2)))
            if (gap > tol) then
               call ctx%error(iline, 4, 'the nodes of joint '//j%name//' are not at one place: '// &
                  & ctx%field(iline, 3)//' and '//ctx%field(iline, 4)//' are '//short_real_text(gap)//' apart', &
                  & label='a joint''s nodes must coincide (within the length tolerance '// &
                  & short_real_text(model%analysis%length_tol)//' of the model size): give them the same coordinates')
               cycle
            end if
         end if
         ax = 0
         fine = .true.
         do k = 1, nax
            call ctx%real_field(iline, 4 + k, ax(k), ok)
            fine = fine .and. ok
         end do
         if (.not. fine) cycle
         do k = 1, nax/3
            if (.not. norm2(ax(3*k - 2:3*k)) > 0) then
               call ctx%error(iline, 3*k + 2, 'the axis of joint '//j%name//' is zero', &
                  & label='give the axis direction (any length), e.g. 0 0 1')
               fine = .false.
            end if
         end do
         if (.not. fine) cycle
         if (nax >= 3) j%axis = ax(1:3)/norm2(ax(1:3))
         if (nax == 6) then
            j%axis2 = ax(4:6)/norm2(ax(4:6))
            if (abs(dot_product(j%axis, j%axis2)) > perpendicular_tol) then
               call ctx%error(iline, 8, 'the two axes of universal joint '//j%name//' are not perpendicular '// &
                  & '(their angle is '//short_real_text(acos(max(-1.0_dp, min(1.0_dp, &
                  & dot_product(j%axis, j%axis2))))*180/acos(-1.0_dp))//' deg)', &
                  & label='give a second axis whose dot product with the first is 0')
               cycle
            end if
         end if
         n = n + 1
         model%spatial%joints(n) = j
      end do
      model%spatial%joints = model%spatial%joints(:n)
   end subroutine read_joints

   !> DRIVes: `rotation JOINT law` (a revolute or cylindrical joint's angle)
   !> or `stroke JOINT law` (a prismatic or cylindrical joint's stroke): the
   !> joint moves by law(t) - law(t_start) from the deck's configuration.
   subroutine read_spatial_drives(ctx, model, lines)
      type(context_type), intent(inout) :: ctx
      type(model_type), intent(inout) :: model
      integer, intent(in) :: lines(:)
      character(*), parameter :: form = 'rotation JOINT law ... | stroke JOINT law ...'
      type(spatial_drive_type) :: d
      integer :: n, i, k, iline, what
      logical :: ok
      allocate (model%spatial%drives(size(lines)))
      n = 0
      do i = 1, size(lines)
         iline = lines(i)
         if (.not. ctx%require(iline, 'what joint law', 'a DRIVes line of a spatial deck')) cycle
         what = word_index(ctx%field(iline, 1), 'rotation stroke')
         if (what == 0) then
            call ctx%error(iline, 1, "unknown drive '"//ctx%field(iline, 1)//"' of a spatial deck", &
               & label='drives: '//form)
            cycle
         end if
         d = spatial_drive_type()
         do k = 1, size(model%spatial%joints)
            if (same_name(model%spatial%joints(k)%name, ctx%field(iline, 2))) d%joint = k
         end do
         if (d%joint == 0) then
            call ctx%error(iline, 2, "undefined joint '"//ctx%field(iline, 2)//"'", label='define it in JOINts')
            cycle
         end if
         associate (kind => model%spatial%joints(d%joint)%kind)
            if (what == 1 .and. all(kind /= [joint_revolute, joint_cylindrical])) then
               call ctx%error(iline, 2, 'joint '//ctx%field(iline, 2)//' has no angle to drive', &
                  & label='a rotation drives a revolute or cylindrical joint')
               cycle
            else if (what == 2 .and. all(kind /= [joint_prismatic, joint_cylindrical])) then
               call ctx%error(iline, 2, 'joint '//ctx%field(iline, 2)//' has no stroke to drive', &
                  & label='a stroke drives a prismatic or cylindrical joint')
               cycle
            end if
         end associate
         d%stroke = what == 2
         if (any(model%spatial%drives(:n)%joint == d%joint .and. &
            & (model%spatial%drives(:n)%stroke .eqv. d%stroke))) then
            call ctx%error(iline, 2, 'joint '//ctx%field(iline, 2)//' is driven twice', label='drive it once')
            cycle
         end if
         call read_law(ctx, iline, 3, d%law, ok)
         if (.not. ok) cycle
         n = n + 1
         model%spatial%drives(n) = d
      end do
      model%spatial%drives = model%spatial%drives(:n)
   end subroutine read_spatial_drives

end module fekap_deck_spatial
