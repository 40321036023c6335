!> Each link's rotation, angular velocity and angular acceleration of a
!> spatial run (links.csv), in global axes, from the mechanism's state and
!> rates at every step.
!>
!> The rotation is a unit quaternion (q0, q1, q2, q3) = (cos(phi/2),
!> sin(phi/2) n) of R, the link's rotation relative to the deck's
!> configuration, its sign kept continuous from step to step (the sign
!> nearer the last step's, q . q_prev >= 0): it turns smoothly through any
!> number of turns, where a rotation vector breaks at |phi| = 2 pi (the
!> study shared/studies/spatial-se3). A step must turn a link by less than
!> pi for the sign to follow it. omega and alpha are global: R' = omega^ R,
!> omega = 2 vec(q' q*), alpha = omega' = 2 vec(q'' q*).
!>
!>   beam   R is its first node's frame (every frame is I at the deck's
!>          configuration): omega = R W v, alpha = R (W a + kappa), W the
!>          frame's body rotation per dof and kappa its convective part
!>          (fekap_spatial_kinematics' configure and frame_curvature).
!>   truss  it has no frame (its spin about its chord is free): R is the
!>          chord's frame carried along without spin (parallel transport),
!>          R e0 = e for the reference chord e0 and the current one e, and
!>          omega = e x e' is normal to the chord, alpha = omega' = e x e''.
!>          R is accumulated over the steps by the smallest rotation from
!>          the last step's chord to this one (exact for a chord that turns
!>          in one plane; otherwise within O(h^2) of the transport, h the
!>          step): unlike a beam's, a truss's rotation is continuous however
!>          the chord tumbles, but it does not return to its start after a
!>          closed path of the chord (it is turned about the chord by the
!>          solid angle the chord swept).
module fekap_spatial_link_motion
   use fekap_kinds, only: dp
   use fekap_vectors, only: cross
   use fekap_element_se3, only: so3_quaternion
   use fekap_model, only: model_type
   use fekap_spatial_mechanism, only: spatial_mechanism_type
   use fekap_spatial_kinematics, only: spatial_state_type, spatial_configuration_type, frame_curvature, point_rate
   implicit none
   private

   public :: link_motion_type, new_link_motion, fill_link_motion

   !> Per model link: its frame (beam) or its end points (truss), and the
   !> last step's quaternion and chord.
   type :: link_motion_type
      integer, allocatable :: frame(:), points(:, :)
      real(dp), allocatable :: q(:, :), chord(:, :)
   end type link_motion_type

contains

   !> The links of the model: a beam by its first node's frame, a truss by
   !> its end points (node_frame, node_point: the mechanism's frame and point
   !> of each model node); every rotation I at the deck's configuration.
   pure subroutine new_link_motion(self, model, m, node_frame, node_point)
      type(link_motion_type), intent(out) :: self
      type(model_type), intent(in) :: model
      type(spatial_mechanism_type), intent(in) :: m
      integer, intent(in) :: node_frame(:), node_point(:)
      integer :: k, n
      n = size(model%links)
      allocate (self%frame(n), self%points(2, n), source=0)
      allocate (self%q(0:3, n), self%chord(3, n), source=0.0_dp)
      self%q(0, :) = 1
      do k = 1, n
         associate (nodes => model%links(k)%node)
            if (model%spatial%truss(k)) then
               self%points(:, k) = node_point(nodes)
               self%chord(:, k) = unit(m%points(self%points(2, k))%x0 - m%points(self%points(1, k))%x0)
            else
               self%frame(k) = node_frame(nodes(1))
            end if
         end associate
      end do
   end subroutine new_link_motion

   !> The links' quaternions (4, links), angular velocities and accelerations
   !> (3, links) at state s (configuration c) with dof rates v and a; the
   !> quaternions and chords kept for the next step.
   pure subroutine fill_link_motion(self, m, s, c, v, a, q, omega, alpha)
      type(link_motion_type), intent(inout) :: self
      type(spatial_mechanism_type), intent(in) :: m
      type(spatial_state_type), intent(in) :: s
      type(spatial_configuration_type), intent(in) :: c
      real(dp), intent(in) :: v(:), a(:)
      real(dp), intent(out) :: q(0:, :), omega(:, :), alpha(:, :)
      real(dp) :: kappa(3, size(c%r, 3)), r(3, 3), d(3), dd(3), ddd(3), e(3), ed(3), length, rate
      integer :: k
      kappa = 0
      if (any(self%frame > 0)) kappa = frame_curvature(m, s, c, v)
      do k = 1, size(self%frame)
         if (self%frame(k) > 0) then
            r = c%r(:, :, self%frame(k))
            q(:, k) = so3_quaternion(r)
            omega(:, k) = matmul(r, matmul(c%w(:, :, self%frame(k)), v))
            alpha(:, k) = matmul(r, matmul(c%w(:, :, self%frame(k)), a) + kappa(:, self%frame(k)))
         else
            associate (p => self%points(:, k))
               d = c%x(:, p(2)) - c%x(:, p(1))
               dd = point_rate(c, p(2), v) - point_rate(c, p(1), v)
               ! Points move linearly in their dofs: their accelerations are G a.
               ddd = point_rate(c, p(2), a) - point_rate(c, p(1), a)
            end associate
            length = norm2(d)
            e = d/length
            rate = dot_product(e, dd)
            ed = (dd - rate*e)/length
            omega(:, k) = cross(e, dd)/length
            ! e'' = (d'' - 2 L' e' - L'' e)/L, and e x e = 0.
            alpha(:, k) = cross(e, ddd - 2*rate*ed)/length
            q(:, k) = quaternion_product(shortest_arc(self%chord(:, k), e), self%q(:, k))
            q(:, k) = q(:, k)/norm2(q(:, k))
            self%chord(:, k) = e
         end if
         if (dot_product(q(:, k), self%q(:, k)) < 0) q(:, k) = -q(:, k)
         self%q(:, k) = q(:, k)
      end do
   end subroutine fill_link_motion

   !> The unit quaternion of the smallest rotation taking unit vector a to
   !> unit vector b (b not opposite to a: a step turns a chord by less than pi).
   pure function shortest_arc(a, b) result(q)
      real(dp), intent(in) :: a(3), b(3)
      real(dp) :: q(0:3)
      ! (1 + a.b, a x b) is 2 cos(phi/2) (cos(phi/2), sin(phi/2) n).
      q(0) = 1 + dot_product(a, b)
      q(1:3) = cross(a, b)
      q = q/norm2(q)
   end function shortest_arc

   !> The Hamilton product p q (the rotation q, then p).
   pure function quaternion_product(p, q) result(pq)
      real(dp), intent(in) :: p(0:3), q(0:3)
      real(dp) :: pq(0:3)
      pq(0) = p(0)*q(0) - dot_product(p(1:3), q(1:3))
      pq(1:3) = p(0)*q(1:3) + q(0)*p(1:3) + cross(p(1:3), q(1:3))
   end function quaternion_product

   pure function unit(x) result(u)
      real(dp), intent(in) :: x(3)
      real(dp) :: u(3)
      u = x/norm2(x)
   end function unit

end module fekap_spatial_link_motion
