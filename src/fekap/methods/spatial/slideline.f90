!> The spatial slideline: a point B kept on a line carried by a moving frame
!> A by a penalty spring, the paper's sliding joint (Eischen, Sun & Marler,
!> eqs. (55)-(65): a slave node on a master line, energy kp g^2/2) carried to
!> three dimensions. In the plane the gap is the slave's normal distance
!> from the master chord, and the slave's place along the line follows from
!> the positions; here the place along the line is a dof of its own, the
!> stroke s, and the gap is the vector from the line's point at s to B:
!>
!>   g = x_B - x_A - R_A u,   u = o + s a,   energy kp |g|^2/2,
!>
!> o the line's place at s = 0 and a its unit direction, both fixed in frame
!> A's body axes. With s a dof the gap's Jacobian has full rank 3 in
!> (x_B, s), no projection P = I - t t^T enters, the stroke is what a drive
!> prescribes and joints.csv reports, and a meshed master link needs no
!> element switching (the line is the link's, not an element's chord).
!> With body increments dtheta of R_A (R_A <- R_A exp(dtheta^)):
!>
!>   dg = dx_B - dx_A + R_A u^ dtheta - R_A a ds,
!>
!> N = dg/d(x_B, x_A, theta_A, s) = [I, -I, R_A u^, -R_A a]. As for the
!> beams, the force is N^T kp g and the material tangent kp N^T N is exact
!> where the gap is zero (every converged kinematic configuration: the exact
!> motion is stress free). The convective term, g'' along q (+) sigma v with
!> no dof acceleration (points are linear in their dofs; frame A's body
!> angular velocity omega and its rate kappa, fekap_spatial_kinematics'
!> frame_curvature):
!>
!>   c = -R_A (omega x (omega x u) + kappa x u + 2 s' omega x a).
module fekap_spatial_slideline
   use fekap_kinds, only: dp
   use fekap_vectors, only: cross
   use fekap_spatial_mechanism, only: spatial_mechanism_type, spatial_slide_type
   implicit none
   private

   public :: slide_gap, slide_convective, assemble_slides

contains

   !> The skew matrix u^ (u^ w = u x w).
   pure function hat(u) result(h)
      real(dp), intent(in) :: u(3)
      real(dp) :: h(3, 3)
      h = reshape([0.0_dp, u(3), -u(2), -u(3), 0.0_dp, u(1), u(2), -u(1), 0.0_dp], [3, 3])
   end function hat

   !> The gap g of point xb from the line x_A + R_A (offset + s axis) and, if
   !> asked, its Jacobian n over the local dofs (x_B, x_A, theta_A, s) (10).
   pure subroutine slide_gap(xa, ra, xb, s, offset, axis, g, n)
      real(dp), intent(in) :: xa(3), ra(3, 3), xb(3), s, offset(3), axis(3)
      real(dp), intent(out) :: g(3)
      real(dp), intent(out), optional :: n(3, 10)
      real(dp) :: u(3)
      integer :: i
      u = offset + s*axis
      g = xb - xa - matmul(ra, u)
      if (.not. present(n)) return
      n = 0
      do i = 1, 3
         n(i, i) = 1
         n(i, 3 + i) = -1
      end do
      n(:, 7:9) = matmul(ra, hat(u))
      n(:, 10) = -matmul(ra, axis)
   end subroutine slide_gap

   !> The convective term c = g'' - N (0, 0, dtheta'', s'') along
   !> q (+) sigma v: frame A's body angular velocity omega and its rate
   !> kappa, the stroke's rate sd (header).
   pure function slide_convective(ra, s, offset, axis, omega, kappa, sd) result(c)
      real(dp), intent(in) :: ra(3, 3), s, offset(3), axis(3), omega(3), kappa(3), sd
      real(dp) :: c(3)
      real(dp) :: u(3)
      u = offset + s*axis
      c = -matmul(ra, cross(omega, cross(omega, u)) + cross(kappa, u) + 2*sd*cross(omega, axis))
   end function slide_convective

   !> Add the slides' forces sum G^T N^T kp g to residual and, if asked,
   !> their material tangent sum G^T kp N^T N G to tangent and, with the dof
   !> rates v and the frames' curvature kappa, their convective load
   !> sum G^T N^T kp c to conv. x, g, r, w: the configuration's point
   !> positions and their dof derivatives, frame rotations and theirs
   !> (fekap_spatial_kinematics' spatial_configuration_type); s the dofs.
   pure subroutine assemble_slides(m, q, x, g, r, w, residual, tangent, v, kappa, conv)
      type(spatial_mechanism_type), intent(in) :: m
      real(dp), intent(in) :: q(:), x(:, :), g(:, :, :), r(:, :, :), w(:, :, :)
      real(dp), intent(inout) :: residual(:)
      real(dp), intent(inout), optional :: tangent(:, :)
      real(dp), intent(in), optional :: v(:), kappa(:, :)
      real(dp), intent(inout), optional :: conv(:)
      real(dp) :: ra(3, 3), gap(3), n(3, 10), ge(10, m%ndof), ng(3, m%ndof), omega(3), ka(3), c(3)
      integer :: i, k
      if (.not. allocated(m%slides)) return
      do i = 1, size(m%slides)
         associate (sl => m%slides(i))
            ge = 0
            ge(1:3, :) = g(:, :, sl%point_b)
            ge(4:6, :) = g(:, :, sl%point_a)
            ra = 0
            do k = 1, 3
               ra(k, k) = 1
            end do
            omega = 0
            ka = 0
            if (sl%frame_a > 0) then
               ra = r(:, :, sl%frame_a)
               ge(7:9, :) = w(:, :, sl%frame_a)
               if (present(conv)) then
                  omega = matmul(w(:, :, sl%frame_a), v)
                  ka = kappa(:, sl%frame_a)
               end if
            end if
            ge(10, sl%dof) = 1
            call slide_gap(x(:, sl%point_a), ra, x(:, sl%point_b), q(sl%dof), sl%offset, sl%axis, gap, n)
            ng = matmul(n, ge)
            residual = residual + sl%kp*matmul(gap, ng)
            if (present(tangent)) tangent = tangent + sl%kp*matmul(transpose(ng), ng)
            if (present(conv)) then
               c = slide_convective(ra, q(sl%dof), sl%offset, sl%axis, omega, ka, v(sl%dof))
               conv = conv + sl%kp*matmul(c, ng)
            end if
         end associate
      end do
   end subroutine assemble_slides

end module fekap_spatial_slideline
