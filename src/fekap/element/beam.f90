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

   public :: beam_type, new_beam, beam_residual, beam_second_derivative, beam_max_strain

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
   !> `geometric = .false.` leaves out kg (the material tangent of (46)).
   pure subroutine beam_residual(self, xe, p, k, geometric)
      type(beam_type), intent(in) :: self
      real(dp), intent(in) :: xe(6)
      real(dp), intent(out) :: p(6)
      real(dp), intent(out), optional :: k(6, 6)
      logical, intent(in), optional :: geometric
      real(dp) :: bw(3, 6), gam(3), grad(3, 2), hess(3, 3, 2), b(6, 3), sig(3), xi, w, wl, g(3, 3), gb(3, 6)
      integer :: ig, i, j
      logical :: with_kg
      with_kg = .true.
      if (present(geometric)) with_kg = geometric
      p = 0
      if (present(k)) k = 0
      do ig = 1, self%ngauss
         call gauss_point(self%ngauss, ig, xi, w)
         wl = w*self%length/2
         call point_state(self, xe, xi, bw, gam, grad, hess)
         sig = self%c*gam                                   ! (30)
         b(:, 1) = matmul(grad(:, 1), bw)                   ! dGamma1/dd
         b(:, 2) = matmul(grad(:, 2), bw)                   ! dGamma2/dd
         b(:, 3) = [0.0_dp, 0.0_dp, -1/self%length, 0.0_dp, 0.0_dp, 1/self%length]
         p = p + wl*matmul(b, sig)                          ! (38)
         if (present(k)) then
            do j = 1, 6                                     ! km, (43) first integral
               do i = 1, 6
                  k(i, j) = k(i, j) + wl*(self%c(1)*b(i, 1)*b(j, 1) + self%c(2)*b(i, 2)*b(j, 2) &
                     & + self%c(3)*b(i, 3)*b(j, 3))
               end do
            end do
            if (with_kg) then                               ! kg = Bw^T G Bw, (43)-(44)
               g = sig(1)*hess(:, :, 1) + sig(2)*hess(:, :, 2)
               gb = matmul(g, bw)
               do j = 1, 6
                  do i = 1, 6
                     k(i, j) = k(i, j) + wl*(bw(1, i)*gb(1, j) + bw(2, i)*gb(2, j) + bw(3, i)*gb(3, j))
                  end do
               end do
            end if
         end if
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

end module fekap_element_beam
