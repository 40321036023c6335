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
!>
!> fekap_spatial_kinematics' assemble_spatial adds each slide's G^T N^T kp g,
!> G^T kp N^T N G and G^T N^T kp c over the dofs its gap depends on.
module fekap_spatial_slideline
   use fekap_kinds, only: dp
   use fekap_vectors, only: cross
   implicit none
   private

   public :: slide_gap, slide_convective

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

end module fekap_spatial_slideline
