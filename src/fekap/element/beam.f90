!> The 2-node planar Simo-Reissner beam with linear shape functions
!> (Eischen, Sun & Marler, eqs. (27)-(53)).
!>
!> The element works on current nodal positions and rotations
!> xe = (x1, y1, theta1, x2, y2, theta2), theta measured from the initial
!> configuration. An initially inclined element (initial angle phi0) is
!> handled by measuring the cross-section angle as phi = phi0 + theta, which
!> is the paper's coordinate transformation (note after (54)) done once:
!>   Gamma1 = cos(phi) x1' + sin(phi) x2' - 1,  Gamma2 = -sin(phi) x1' + cos(phi) x2',
!>   kappa = theta',
!> i.e. (27) with Delta^T applied to the deformed tangent x' = dx/dS. Rotations
!> are never wrapped, so a rigid motion of any size gives zero strain.
module fekap_element_beam
   use fekap_kinds, only: dp
   implicit none
   private

   public :: beam_type, new_beam, beam_residual, beam_second_derivative, beam_max_strain, beam_resultants

   !> Immutable definition of one element.
   type :: beam_type
      !> Reference length and initial angle (from +x, radians).
      real(dp) :: length = 1
      real(dp) :: angle = 0
      !> EA, kGA, EI: the diagonal of C in (30).
      real(dp) :: c(3) = 1
      !> Gauss points: 1 (reduced, avoids shear locking) or 2 (full).
      integer :: ngauss = 1
   end type beam_type

contains

   !> Element from its initial end points, section stiffnesses and quadrature.
   pure subroutine new_beam(self, x1, x2, c, ngauss)
      type(beam_type), intent(out) :: self
      real(dp), intent(in) :: x1(2), x2(2), c(3)
      integer, intent(in) :: ngauss
      self%length = norm2(x2 - x1)
      self%angle = atan2(x2(2) - x1(2), x2(1) - x1(1))
      self%c = c
      self%ngauss = ngauss
   end subroutine new_beam

   !> Gauss point ig of the rule: natural coordinate and weight.
   pure subroutine gauss_point(ngauss, ig, xi, w)
      integer, intent(in) :: ngauss, ig
      real(dp), intent(out) :: xi, w
      if (ngauss == 1) then
         xi = 0
         w = 2
      else
         xi = merge(-1, 1, ig == 1)/sqrt(3.0_dp)
         w = 1
      end if
   end subroutine gauss_point

   !> Strain state at one Gauss point: the map Bw from element dofs to
   !> w = (x1', x2', phi), strains, and gradients/Hessians of Gamma1, Gamma2 in w.
   pure subroutine point_state(self, xe, xi, bw, gam, grad, hess)
      type(beam_type), intent(in) :: self
      real(dp), intent(in) :: xe(6), xi
      real(dp), intent(out) :: bw(3, 6), gam(3), grad(3, 2), hess(3, 3, 2)
      real(dp) :: n1, n2, a(2), phi, c, s
      n1 = (1 - xi)/2
      n2 = (1 + xi)/2
      bw = 0
      bw(1, 1) = -1/self%length
      bw(1, 4) = 1/self%length
      bw(2, 2) = -1/self%length
      bw(2, 5) = 1/self%length
      bw(3, 3) = n1
      bw(3, 6) = n2
      a = (xe(4:5) - xe(1:2))/self%length
      phi = self%angle + n1*xe(3) + n2*xe(6)
      c = cos(phi)
      s = sin(phi)
      gam(1) = c*a(1) + s*a(2) - 1
      gam(2) = -s*a(1) + c*a(2)
      gam(3) = (xe(6) - xe(3))/self%length
      grad(:, 1) = [c, s, gam(2)]
      grad(:, 2) = [-s, c, -(1 + gam(1))]
      hess = 0
      hess(1, 3, 1) = -s
      hess(2, 3, 1) = c
      hess(3, 1, 1) = -s
      hess(3, 2, 1) = c
      hess(3, 3, 1) = -(1 + gam(1))
      hess(1, 3, 2) = -c
      hess(2, 3, 2) = -s
      hess(3, 1, 2) = -c
      hess(3, 2, 2) = -s
      hess(3, 3, 2) = -gam(2)
   end subroutine point_state

   !> Internal force p (38) and, if asked, the tangent k = km + kg (43)-(44);
   !> kg is left out at Gauss points whose largest strain (|Gamma1|, |Gamma2|,
   !> |kappa| L) is at most `geometric_above` (default 0: kg everywhere; huge:
   !> the material tangent of (46)).
   !> With w = (x1', x2', phi) = Bw xe at a Gauss point, the columns of Bw are
   !> ax (d x1'), ay (d x2') and ph (d phi), so that
   !>   km = EA b1 b1^T + kGA b2 b2^T + EI bk bk^T,  b_m = Bw^T grad Gamma_m,
   !>   kg = Bw^T (P H1 + V H2) Bw = g13 (ax ph^T + ph ax^T) + g23 (ay ph^T + ph ay^T) + g33 ph ph^T
   !> with g13 = -s P - c V, g23 = c P - s V, g33 = -(1 + Gamma1) P - Gamma2 V (the paper's G).
   pure subroutine beam_residual(self, xe, p, k, geometric_above)
      type(beam_type), intent(in) :: self
      real(dp), intent(in) :: xe(6)
      real(dp), intent(out) :: p(6)
      real(dp), intent(out), optional :: k(6, 6)
      real(dp), intent(in), optional :: geometric_above
      real(dp) :: b1(6), b2(6), bk(6), ax(6), ay(6), ph(6), sig(3), a(2)
      real(dp) :: xi, w, wl, n1, n2, phi, c, s, g1, g2, g13, g23, g33, rl
      integer :: ig, i, j
      real(dp) :: kg_strain
      kg_strain = 0
      if (present(geometric_above)) kg_strain = geometric_above
      rl = 1/self%length
      a = (xe(4:5) - xe(1:2))*rl
      ax = [-rl, 0.0_dp, 0.0_dp, rl, 0.0_dp, 0.0_dp]
      ay = [0.0_dp, -rl, 0.0_dp, 0.0_dp, rl, 0.0_dp]
      bk = [0.0_dp, 0.0_dp, -rl, 0.0_dp, 0.0_dp, rl]
      p = 0
      if (present(k)) k = 0
      do ig = 1, self%ngauss
         call gauss_point(self%ngauss, ig, xi, w)
         wl = w*self%length/2
         n1 = (1 - xi)/2
         n2 = (1 + xi)/2
         phi = self%angle + n1*xe(3) + n2*xe(6)
         c = cos(phi)
         s = sin(phi)
         g1 = c*a(1) + s*a(2) - 1                          ! (27)
         g2 = -s*a(1) + c*a(2)
         sig = self%c*[g1, g2, (xe(6) - xe(3))*rl]         ! (30)
         ph = [0.0_dp, 0.0_dp, n1, 0.0_dp, 0.0_dp, n2]
         b1 = c*ax + s*ay + g2*ph                           ! dGamma1/dxe
         b2 = -s*ax + c*ay - (1 + g1)*ph                    ! dGamma2/dxe
         p = p + wl*(sig(1)*b1 + sig(2)*b2 + sig(3)*bk)     ! (38)
         if (.not. present(k)) cycle
         g13 = 0
         g23 = 0
         g33 = 0
         if (max(abs(g1), abs(g2), abs(xe(6) - xe(3))) > kg_strain) then
            g13 = -s*sig(1) - c*sig(2)
            g23 = c*sig(1) - s*sig(2)
            g33 = -(1 + g1)*sig(1) - g2*sig(2)
         end if
         do j = 1, 6                                        ! (43)-(44)
            do i = 1, 6
               k(i, j) = k(i, j) + wl*(self%c(1)*b1(i)*b1(j) + self%c(2)*b2(i)*b2(j) + self%c(3)*bk(i)*bk(j) &
                  & + g13*(ax(i)*ph(j) + ph(i)*ax(j)) + g23*(ay(i)*ph(j) + ph(i)*ay(j)) + g33*ph(i)*ph(j))
            end do
         end do
      end do
   end subroutine beam_residual

   !> Second directional derivative d2p = d^2 p / dd^2 [v, v] of the internal
   !> force: the term (dK/dt) v of the acceleration equations (48)-(53),
   !> exact at any configuration (at a stress-free one it reduces to (49)).
   pure subroutine beam_second_derivative(self, xe, v, d2p)
      type(beam_type), intent(in) :: self
      real(dp), intent(in) :: xe(6), v(6)
      real(dp), intent(out) :: d2p(6)
      real(dp) :: bw(3, 6), gam(3), grad(3, 2), hess(3, 3, 2), bk(6), sig(3), t3(3, 2), vw(3)
      real(dp) :: xi, w, wl, phi, c, s, vp
      integer :: ig, m
      d2p = 0
      do ig = 1, self%ngauss
         call gauss_point(self%ngauss, ig, xi, w)
         wl = w*self%length/2
         call point_state(self, xe, xi, bw, gam, grad, hess)
         sig = self%c*gam
         vw = matmul(bw, v)
         vp = vw(3)
         phi = self%angle + bw(3, 3)*xe(3) + bw(3, 6)*xe(6)
         c = cos(phi)
         s = sin(phi)
         ! Third derivatives of Gamma1, Gamma2 in w contracted twice with vw.
         t3(:, 1) = [-c*vp**2, -s*vp**2, -2*vp*(c*vw(1) + s*vw(2)) - gam(2)*vp**2]
         t3(:, 2) = [s*vp**2, -c*vp**2, 2*vp*(s*vw(1) - c*vw(2)) + (1 + gam(1))*vp**2]
         do m = 1, 2
            bk = matmul(grad(:, m), bw)
            d2p = d2p + wl*(sig(m)*matmul(t3(:, m), bw) &
               & + 2*self%c(m)*dot_product(bk, v)*matmul(matmul(hess(:, :, m), vw), bw) &
               & + self%c(m)*dot_product(vw, matmul(hess(:, :, m), vw))*bk)
         end do
         ! kappa is linear in d: no second derivative.
      end do
   end subroutine beam_second_derivative

   !> Largest strain magnitude at the Gauss points: |Gamma1|, |Gamma2|, |kappa|*length.
   pure real(dp) function beam_max_strain(self, xe) result(strain)
      type(beam_type), intent(in) :: self
      real(dp), intent(in) :: xe(6)
      real(dp) :: bw(3, 6), gam(3), grad(3, 2), hess(3, 3, 2), xi, w
      integer :: ig
      strain = 0
      do ig = 1, self%ngauss
         call gauss_point(self%ngauss, ig, xi, w)
         call point_state(self, xe, xi, bw, gam, grad, hess)
         strain = max(strain, abs(gam(1)), abs(gam(2)), abs(gam(3))*self%length)
      end do
   end function beam_max_strain

   !> Stress resultants (P, V, M) (30) averaged over the Gauss points.
   pure function beam_resultants(self, xe) result(sig)
      type(beam_type), intent(in) :: self
      real(dp), intent(in) :: xe(6)
      real(dp) :: sig(3)
      real(dp) :: bw(3, 6), gam(3), grad(3, 2), hess(3, 3, 2), xi, w
      integer :: ig
      sig = 0
      do ig = 1, self%ngauss
         call gauss_point(self%ngauss, ig, xi, w)
         call point_state(self, xe, xi, bw, gam, grad, hess)
         sig = sig + self%c*gam/self%ngauss
      end do
   end function beam_resultants

end module fekap_element_beam
