!> Rigid bodies of the Cartesian-coordinate method: a link, or a group of
!> links welded together, is one body with coordinates q = (x, y, phi).
!>
!> Reference point and angle: (x, y) is the mass centre of the body's links
!> treated as uniform bars of equal mass per length (the paper's (13)-(20)
!> take link midpoints); phi is the direction angle node(1)->node(2) of the
!> body's first link (lowest link index), so for a one-link body phi is the
!> link angle of the paper. A point of a body has constant local coordinates
!> s (its initial offset from the reference point rotated back by the initial
!> phi) and is at r = (x, y) + A(phi) s, with A the rotation matrix.
module fekap_classical_bodies
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, input_error
   use fekap_model, only: model_type, model_size
   use fekap_union_find, only: find_root, join, flatten
   implicit none
   private

   public :: body_map_type, new_body_map, rotate, perp

   !> Links grouped into bodies and nodes placed on them.
   type :: body_map_type
      integer :: nbody = 0
      !> Body of each link.
      integer, allocatable :: link_body(:)
      !> First (lowest-index) link of each body.
      integer, allocatable :: first_link(:)
      !> Initial coordinates (x, y, phi) of each body, 3 per body.
      real(dp), allocatable :: q0(:)
      !> Direction angle of each link minus the angle phi of its body (constant).
      real(dp), allocatable :: link_offset(:)
      !> A body carrying each node (0: the node is on no link) and the node's local coordinates in it.
      integer, allocatable :: node_body(:)
      real(dp), allocatable :: node_local(:, :)
      !> Initial node coordinates (2, nnode).
      real(dp), allocatable :: x0(:, :)
   contains
      !> Local coordinates in body b of the point initially at x.
      procedure :: local => body_local
      !> Position, velocity and acceleration of a point of a body.
      procedure :: position => body_position
   end type body_map_type

contains

   !> Group the links of `model` into bodies through the welds (union-find)
   !> and compute reference points, angles and local node coordinates.
   subroutine new_body_map(self, model, error)
      type(body_map_type), intent(out) :: self
      type(model_type), intent(in) :: model
      type(error_type), allocatable, intent(out) :: error
      integer, allocatable :: parent(:)
      real(dp), allocatable :: total(:)
      integer :: nlink, nnode, i, j, b, root
      real(dp) :: v(2), angle, mid(2)

      nlink = 0
      nnode = 0
      if (allocated(model%links)) nlink = size(model%links)
      if (allocated(model%nodes)) nnode = size(model%nodes)
      allocate (self%x0(2, nnode))
      do i = 1, nnode
         self%x0(:, i) = model%nodes(i)%x
      end do
      do i = 1, nlink
         v = self%x0(:, model%links(i)%node(2)) - self%x0(:, model%links(i)%node(1))
         if (norm2(v) <= 1.0e-12_dp*model_size(model)) then
            call input_error(error, 'link '//model%links(i)%name//' has zero length')
            return
         end if
      end do

      ! Union-find over the links, joining the links of each weld.
      allocate (parent(nlink))
      parent = [(i, i=1, nlink)]
      if (allocated(model%welds)) then
         do i = 1, size(model%welds)
            associate (w => model%welds(i)%links)
               do j = 2, size(w)
                  call join(parent, w(1), w(j))
               end do
            end associate
         end do
      end if
      ! Number the bodies in the order of their first links.
      call flatten(parent)
      allocate (self%link_body(nlink), source=0)
      allocate (self%first_link(nlink))
      do i = 1, nlink
         root = find_root(parent, i)
         if (self%link_body(root) == 0) then
            self%nbody = self%nbody + 1
            self%link_body(root) = self%nbody
            self%first_link(self%nbody) = i
         end if
         self%link_body(i) = self%link_body(root)
      end do
      self%first_link = self%first_link(1:self%nbody)

      ! Mass centres (length-weighted link midpoints) and angles.
      allocate (self%q0(3*self%nbody), source=0.0_dp)
      allocate (total(self%nbody), source=0.0_dp)
      allocate (self%link_offset(nlink))
      do i = 1, nlink
         b = self%link_body(i)
         associate (x1 => self%x0(:, model%links(i)%node(1)), x2 => self%x0(:, model%links(i)%node(2)))
            mid = (x1 + x2)/2
            total(b) = total(b) + norm2(x2 - x1)
            self%q0(3*b - 2:3*b - 1) = self%q0(3*b - 2:3*b - 1) + norm2(x2 - x1)*mid
         end associate
      end do
      do b = 1, self%nbody
         self%q0(3*b - 2:3*b - 1) = self%q0(3*b - 2:3*b - 1)/total(b)
         i = self%first_link(b)
         v = self%x0(:, model%links(i)%node(2)) - self%x0(:, model%links(i)%node(1))
         self%q0(3*b) = atan2(v(2), v(1))
      end do
      do i = 1, nlink
         v = self%x0(:, model%links(i)%node(2)) - self%x0(:, model%links(i)%node(1))
         angle = atan2(v(2), v(1))
         self%link_offset(i) = angle - self%q0(3*self%link_body(i))
      end do

      ! Each node on the body of the first link that has an end there.
      allocate (self%node_body(nnode), source=0)
      allocate (self%node_local(2, nnode), source=0.0_dp)
      do i = nlink, 1, -1
         do j = 1, 2
            self%node_body(model%links(i)%node(j)) = self%link_body(i)
         end do
      end do
      do i = 1, nnode
         if (self%node_body(i) > 0) self%node_local(:, i) = self%local(self%node_body(i), self%x0(:, i))
      end do
   end subroutine new_body_map



   !> Local coordinates in body b of the point initially at x: A(-phi0)(x - c0).
   pure function body_local(self, b, x) result(s)
      class(body_map_type), intent(in) :: self
      integer, intent(in) :: b
      real(dp), intent(in) :: x(2)
      real(dp) :: s(2)
      s = rotate(-self%q0(3*b), x - self%q0(3*b - 2:3*b - 1))
   end function body_local

   !> Position r = (x, y) + A(phi) s of the point with local coordinates s on
   !> body b, with its velocity and acceleration from the rates qd, qdd.
   pure subroutine body_position(self, b, s, q, qd, qdd, r, v, a)
      class(body_map_type), intent(in) :: self
      integer, intent(in) :: b
      real(dp), intent(in) :: s(2), q(:), qd(:), qdd(:)
      real(dp), intent(out) :: r(2), v(2), a(2)
      real(dp) :: as(2)
      if (b < 1 .or. b > self%nbody) then
         r = 0
         v = 0
         a = 0
         return
      end if
      as = rotate(q(3*b), s)
      r = q(3*b - 2:3*b - 1) + as
      v = qd(3*b - 2:3*b - 1) + qd(3*b)*perp(as)
      a = qdd(3*b - 2:3*b - 1) + qdd(3*b)*perp(as) - qd(3*b)**2*as
   end subroutine body_position

   !> A(phi) s.
   pure function rotate(phi, s) result(r)
      real(dp), intent(in) :: phi, s(2)
      real(dp) :: r(2)
      r = [cos(phi)*s(1) - sin(phi)*s(2), sin(phi)*s(1) + cos(phi)*s(2)]
   end function rotate

   !> v rotated by +90 degrees: (-v2, v1).
   pure function perp(v) result(w)
      real(dp), intent(in) :: v(2)
      real(dp) :: w(2)
      w = [-v(2), v(1)]
   end function perp

end module fekap_classical_bodies
