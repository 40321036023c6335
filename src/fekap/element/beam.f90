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

   public :: beam_type, new_beam, beam_residual, add_beam_residuals, beam_second_derivative, beam_max_strain
   public :: beam_resultants
   public :: beam_strain_energy
   !> The quadrature and the strains at a Gauss point, for the element's
   !> damping (fekap_element_beam_damping).
   public :: gauss_point, point_strain

   !> Most Gauss points of an element (see beam_type%ngauss).
   integer, parameter, public :: max_gauss = 2
   !> What beam_residual keeps of a section (its `section`): the cosine and
   !> sine of its angle, and the angle itself (to tell whether another
   !> evaluation at the same angle can take them; the square-root form's B).
   integer, parameter, public :: section_values = 3

   !> Immutable definition of one element.
   type :: beam_type
      !> Reference length and initial angle (from +x, radians).
      real(dp) :: length = 1
      real(dp) :: angle = 0
      !> Axial, shear and bending stiffness of the section, EA, kGA, EI: the
      !> diagonal of C in (30).
      real(dp) :: ea = 1, kga = 1, ei = 1
      !> Gauss points: 1 (reduced, avoids shear locking) or 2 (full).
      integer :: ngauss = 1
   end type beam_type

contains

   !> Element from its initial end points, section stiffnesses (EA, kGA, EI)
   !> and quadrature.
   pure subroutine new_beam(self, x1, x2, stiffness, ngauss)
      type(beam_type), intent(out) :: self
      real(dp), intent(in) :: x1(2), x2(2), stiffness(3)
      integer, intent(in) :: ngauss
      self%length = norm2(x2 - x1)
      self%angle = atan2(x2(2) - x1(2), x2(1) - x1(1))
      self%ea = stiffness(1)
      self%kga = stiffness(2)
      self%ei = stiffness(3)
      self%ngauss = ngauss
   end subroutine new_beam

   !> Gauss point ig of the rule: natural coordinate and weight.
   pure subroutine gauss_point(ngauss, ig, xi, w)
      integer, intent(in) :: ngauss, ig
      real(dp), intent(out) :: xi, w
      call rule_point(ngauss, ig, xi, w)
   end subroutine gauss_point

   !> gauss_point, private so that this module's kernels inline it (as
   !> gauss_strain: a call of the public one at every element evaluation).
   pure subroutine rule_point(ngauss, ig, xi, w)
      integer, intent(in) :: ngauss, ig
      real(dp), intent(out) :: xi, w
      if (ngauss == 1) then
         xi = 0
         w = 2
      else
         xi = merge(-1, 1, ig == 1)/sqrt(3.0_dp)
         w = 1
      end if
   end subroutine rule_point

   !> Section angle phi, its cosine and sine, and the strains Gamma1, Gamma2
   !> (27) at the Gauss point with shape functions n1, n2; rl = 1/length.
   pure subroutine point_strain(self, xe, n1, n2, rl, c, s, g1, g2)
      type(beam_type), intent(in) :: self
      real(dp), intent(in) :: xe(6), n1, n2, rl
      real(dp), intent(out) :: c, s, g1, g2
      real(dp) :: phi
      call gauss_strain(self, xe, n1, n2, rl, c, s, g1, g2, phi)
   end subroutine point_strain

   !> point_strain with the angle phi, private so that this module's kernels
   !> inline it (the release build's -fPIC keeps public procedures out of line).
   pure subroutine gauss_strain(self, xe, n1, n2, rl, c, s, g1, g2, phi)
      type(beam_type), intent(in) :: self
      real(dp), intent(in) :: xe(6), n1, n2, rl
      real(dp), intent(out) :: c, s, g1, g2, phi
      phi = self%angle + n1*xe(3) + n2*xe(6)
      ! One sincos call: the compiler pairs cos and sin of the same argument.
      c = cos(phi)
      s = sin(phi)
      call section_strain(xe, rl, c, s, g1, g2)
   end subroutine gauss_strain

   !> The strains Gamma1, Gamma2 (27) of a section whose angle has cosine c
   !> and sine s (known from an earlier evaluation at the same xe).
   pure subroutine section_strain(xe, rl, c, s, g1, g2)
      real(dp), intent(in) :: xe(6), rl, c, s
      real(dp), intent(out) :: g1, g2
      real(dp) :: a1, a2
      a1 = (xe(4) - xe(1))*rl
      a2 = (xe(5) - xe(2))*rl
      g1 = c*a1 + s*a2 - 1
      g2 = -s*a1 + c*a2
   end subroutine section_strain

   !> Internal force p (38) and, if asked, the tangent k = km + kg (43)-(44);
   !> kg is left out at Gauss points whose largest strain (|Gamma1|, |Gamma2|,
   !> |kappa| L) is at most `geometric_above` (default 0: kg everywhere; huge:
   !> the material tangent of (46)).
   !> With w = (x1', x2', phi) = Bw xe at a Gauss point, the columns of Bw are
   !> ax (d x1'), ay (d x2') and ph (d phi), so that
   !>   km = EA b1 b1^T + kGA b2 b2^T + EI bk bk^T,  b_m = Bw^T grad Gamma_m,
   !>   kg = Bw^T (P H1 + V H2) Bw = g13 (ax ph^T + ph ax^T) + g23 (ay ph^T + ph ay^T) + g33 ph ph^T
   !> with g13 = -s P - c V, g23 = c P - s V, g33 = -(1 + Gamma1) P - Gamma2 V (the paper's G).
   !> The vectors are sparse: ax, ay and the translational parts of b1, b2 are
   !> -/+ (1/L) times a direction at the two nodes (e1 = (c, s) for b1,
   !> e2 = (-s, c) for b2), ph and the rotational parts of b1, b2 are (n1, n2)
   !> times a number, bk = (1/L) (-1, +1) on the rotations. So k has three
   !> blocks, summed over the Gauss points and spread out at the end:
   !>   translation-translation  -/+ M,  M = w/(2L) (EA e1 e1^T + kGA e2 e2^T),
   !>   translation-rotation     -/+ h n_b,  h = (wl/L) (EA Gamma2 e1 - kGA (1 + Gamma1) e2 + (g13, g23)),
   !>   rotation-rotation        r n_a n_b + wl EI/L^2 (-/+ 1),  r = wl (EA Gamma2^2 + kGA (1 + Gamma1)^2 + g33),
   !> (wl = w L / 2 the Gauss weight times the Jacobian; -/+: minus for unlike nodes).
   pure subroutine beam_residual(self, xe, p, k, geometric_above, strain, section)
      type(beam_type), intent(in) :: self
      real(dp), intent(in) :: xe(6)
      real(dp), intent(out) :: p(6)
      real(dp), intent(out), optional :: k(6, 6)
      real(dp), intent(in), optional :: geometric_above
      !> The largest strain, as beam_max_strain (a by-product of the Gauss points).
      real(dp), intent(out), optional :: strain
      !> cos and sin of the section angle and the angle at each Gauss point,
      !> for beam_second_derivative at the same xe (see section_values).
      real(dp), intent(out), optional :: section(section_values, max_gauss)
      real(dp) :: xi, w, wl, n1, n2, c, s, g1, g2, kap, sp, sv, sm, rl, phi
      real(dp) :: g13, g23, g33, kg_strain, ea, ga, ca, cb, m11, m12, m22, hx, hy, r
      real(dp) :: th(2, 2), rr(3), ei
      integer :: ig
      if (.not. present(k) .and. self%ngauss == 1) then
         call one_point_residual(self, xe, p, strain, section)
         return
      end if
      kg_strain = 0
      if (present(geometric_above)) kg_strain = geometric_above
      rl = 1/self%length
      kap = (xe(6) - xe(3))*rl
      ea = self%ea
      ga = self%kga
      p = 0
      m11 = 0
      m12 = 0
      m22 = 0
      th = 0
      rr = 0
      ei = 0
      ! |kappa| L = |theta2 - theta1|, the same along the element.
      if (present(strain)) strain = abs(xe(6) - xe(3))
      do ig = 1, self%ngauss
         call rule_point(self%ngauss, ig, xi, w)
         wl = w*self%length/2
         n1 = (1 - xi)/2
         n2 = (1 + xi)/2
         call gauss_strain(self, xe, n1, n2, rl, c, s, g1, g2, phi)     ! (27)
         if (present(strain)) strain = max(strain, abs(g1), abs(g2))
         if (present(section)) section(:, ig) = [c, s, phi]
         sp = ea*g1                                                ! (30)
         sv = ga*g2
         sm = self%ei*kap
         call add_point_force(p, wl, rl, c, s, g1, g2, sp, sv, sm, n1, n2)
         if (.not. present(k)) cycle
         g13 = 0
         g23 = 0
         g33 = 0
         if (max(abs(g1), abs(g2), abs(xe(6) - xe(3))) > kg_strain) then
            g13 = -s*sp - c*sv
            g23 = c*sp - s*sv
            g33 = -(1 + g1)*sp - g2*sv
         end if
         ! (43)-(44) by blocks (see above).
         ca = wl*rl*rl*ea
         cb = wl*rl*rl*ga
         m11 = m11 + (ca*c*c + cb*s*s)
         m12 = m12 + (ca - cb)*c*s
         m22 = m22 + (ca*s*s + cb*c*c)
         hx = wl*rl*(ea*g2*c + ga*(1 + g1)*s + g13)
         hy = wl*rl*(ea*g2*s - ga*(1 + g1)*c + g23)
         th(:, 1) = th(:, 1) + [hx, hy]*n1
         th(:, 2) = th(:, 2) + [hx, hy]*n2
         r = wl*(ea*g2*g2 + ga*(1 + g1)**2 + g33)
         rr = rr + r*[n1*n1, n1*n2, n2*n2]
         ei = ei + wl*self%ei*rl*rl
      end do
      if (present(k)) call spread_tangent(m11, m12, m22, th, rr, ei, k)
   end subroutine beam_residual

   !> r(edof(:, e)) += p_e for every element e at xe = q(edof(:, e)): the
   !> residual's element loop (fekap_assembly_assemble's assemble_residual),
   !> here so that the one-point element force (one_point_force) is computed
   !> inline, without a call and its optional arguments per element, on
   !> contiguous arrays: the same operations in the same order as
   !> beam_residual's p (from +0) added into r. With `section`, each
   !> element's sections at xe (beam_residual's).
   pure subroutine add_beam_residuals(elements, edof, q, r, section)
      type(beam_type), intent(in) :: elements(:)
      integer, contiguous, intent(in) :: edof(:, :)
      real(dp), contiguous, intent(in) :: q(:)
      real(dp), contiguous, intent(inout) :: r(:)
      real(dp), intent(out), optional :: section(section_values, max_gauss, size(elements))
      real(dp) :: pe(6), xe(6), c, s, phi, g1, g2
      integer :: e, i
      logical :: keep
      keep = present(section)
      do e = 1, size(elements)
         do i = 1, 6
            xe(i) = q(edof(i, e))
         end do
         if (elements(e)%ngauss == 1) then
            call one_point_force(elements(e), xe, pe, c, s, phi, g1, g2)
            if (keep) then
               section(1, 1, e) = c
               section(2, 1, e) = s
               section(3, 1, e) = phi
            end if
         else if (keep) then
            call beam_residual(elements(e), xe, pe, section=section(:, :, e))
         else
            call beam_residual(elements(e), xe, pe)
         end if
         do i = 1, 6
            r(edof(i, e)) = r(edof(i, e)) + pe(i)
         end do
      end do
   end subroutine add_beam_residuals

   !> The one-point element force p (38) at xe (one Gauss point, xi = 0,
   !> w = 2), and the section's cos c, sin s and angle phi and strains g1,
   !> g2 there: beam_residual's operations in its order, p from +0.
   pure subroutine one_point_force(self, xe, p, c, s, phi, g1, g2)
      type(beam_type), intent(in) :: self
      real(dp), intent(in) :: xe(6)
      real(dp), intent(out) :: p(6), c, s, phi, g1, g2
      real(dp), parameter :: xi = 0, w = 2
      real(dp) :: wl, n1, n2, kap, sp, sv, sm, rl
      rl = 1/self%length
      kap = (xe(6) - xe(3))*rl
      p = 0
      wl = w*self%length/2
      n1 = (1 - xi)/2
      n2 = (1 + xi)/2
      call gauss_strain(self, xe, n1, n2, rl, c, s, g1, g2, phi)     ! (27)
      sp = self%ea*g1                                           ! (30)
      sv = self%kga*g2
      sm = self%ei*kap
      call add_point_force(p, wl, rl, c, s, g1, g2, sp, sv, sm, n1, n2)
   end subroutine one_point_force

   !> beam_residual's p without the tangent, with one Gauss point (the
   !> default rule): the same operations in the same order on the point's
   !> constants (xi = 0, w = 2), without the loop and the tangent's tests
   !> (four of a step's six element evaluations on Example 1).
   pure subroutine one_point_residual(self, xe, p, strain, section)
      type(beam_type), intent(in) :: self
      real(dp), intent(in) :: xe(6)
      real(dp), intent(out) :: p(6)
      real(dp), intent(out), optional :: strain
      real(dp), intent(out), optional :: section(section_values, max_gauss)
      real(dp) :: c, s, g1, g2, phi
      call one_point_force(self, xe, p, c, s, phi, g1, g2)
      if (present(strain)) strain = max(abs(xe(6) - xe(3)), abs(g1), abs(g2))
      if (present(section)) section(:, 1) = [c, s, phi]
   end subroutine one_point_residual

   !> (38): p += wl (P b1 + V b2 + M bk) at one Gauss point, by parts: its
   !> weight times half the length wl, 1/L rl, the section's cos and sin c,
   !> s, the strains g1, g2, the resultants sp, sv, sm (30) and the shape
   !> functions n1, n2 there.
   pure subroutine add_point_force(p, wl, rl, c, s, g1, g2, sp, sv, sm, n1, n2)
      real(dp), intent(inout) :: p(6)
      real(dp), intent(in) :: wl, rl, c, s, g1, g2, sp, sv, sm, n1, n2
      real(dp) :: fx, fy, fm, fk
      fx = wl*rl*(sp*c - sv*s)
      fy = wl*rl*(sp*s + sv*c)
      fm = wl*(sp*g2 - sv*(1 + g1))
      fk = wl*sm*rl
      p(1) = p(1) - fx
      p(2) = p(2) - fy
      p(3) = p(3) + fm*n1 - fk
      p(4) = p(4) + fx
      p(5) = p(5) + fy
      p(6) = p(6) + fm*n2 + fk
   end subroutine add_point_force

   !> The element tangent from its blocks (see beam_residual): dofs
   !> (x1, y1, theta1, x2, y2, theta2); th(d, b) = sum h(d) n_b, rr = sum r
   !> (n1 n1, n1 n2, n2 n2), ei = sum wl EI / L^2.
   pure subroutine spread_tangent(m11, m12, m22, th, rr, ei, k)
      real(dp), intent(in) :: m11, m12, m22, th(2, 2), rr(3), ei
      real(dp), intent(out) :: k(6, 6)
      ! Translations of both nodes.
      k(1:2, 1) = [m11, m12]
      k(1:2, 2) = [m12, m22]
      k(4:5, 4:5) = k(1:2, 1:2)
      k(1:2, 4:5) = -k(1:2, 1:2)
      k(4:5, 1:2) = -k(1:2, 1:2)
      ! Rotations.
      k(3, 3) = rr(1) + ei
      k(3, 6) = rr(2) - ei
      k(6, 3) = k(3, 6)
      k(6, 6) = rr(3) + ei
      ! Translation-rotation, and its mirror image.
      k(1:2, 3) = -th(:, 1)
      k(4:5, 3) = th(:, 1)
      k(1:2, 6) = -th(:, 2)
      k(4:5, 6) = th(:, 2)
      k(3, 1:2) = k(1:2, 3)
      k(3, 4:5) = k(4:5, 3)
      k(6, 1:2) = k(1:2, 6)
      k(6, 4:5) = k(4:5, 6)
   end subroutine spread_tangent

   !> Second directional derivative d2p = d^2 p / dd^2 [v, v] of the internal
   !> force: the term (dK/dt) v of the acceleration equations (48)-(53),
   !> exact at any configuration (at a stress-free one it reduces to (49)).
   !> With vw = Bw v (the rates of x1', x2', phi) at a Gauss point,
   !>   d2p = sum wl Bw^T y,  y = sum_m [S_m T_m + 2 C_m (grad_m . vw) H_m vw + C_m (vw . H_m vw) grad_m]
   !> over Gamma1, Gamma2 (S = P, V; C = EA, kGA): grad_m, H_m and T_m are the
   !> first, second and (contracted twice with vw) third derivatives of
   !> Gamma_m in w. kappa is linear in the dofs: no term. Bw^T y is
   !> (1/L) (-y1, -y2, 0, y1, y2, 0) + y3 (0, 0, n1, 0, 0, n2).
   pure subroutine beam_second_derivative(self, xe, v, d2p, section)
      type(beam_type), intent(in) :: self
      real(dp), intent(in) :: xe(6), v(6)
      real(dp), intent(out) :: d2p(6)
      !> cos and sin of the section angles at xe, from beam_residual: spares
      !> their evaluation (a third of the sincos calls of a step).
      real(dp), intent(in), optional :: section(section_values, max_gauss)
      real(dp) :: xi, w, wl, n1, n2, c, s, g1, g2, rl, vw1, vw2, vp, d1, d2, vp2
      real(dp) :: sp, sv, gv1, gv2, q1, q2, y(3)
      integer :: ig
      rl = 1/self%length
      vw1 = (v(4) - v(1))*rl
      vw2 = (v(5) - v(2))*rl
      d2p = 0
      do ig = 1, self%ngauss
         call rule_point(self%ngauss, ig, xi, w)
         wl = w*self%length/2
         n1 = (1 - xi)/2
         n2 = (1 + xi)/2
         if (present(section)) then
            c = section(1, ig)
            s = section(2, ig)
            call section_strain(xe, rl, c, s, g1, g2)
         else
            call point_strain(self, xe, n1, n2, rl, c, s, g1, g2)
         end if
         sp = self%ea*g1
         sv = self%kga*g2
         vp = n1*v(3) + n2*v(6)
         vp2 = vp*vp
         ! vw in the section's frame (e1, e2).
         d1 = c*vw1 + s*vw2
         d2 = -s*vw1 + c*vw2
         ! grad_m . vw and vw . H_m vw.
         gv1 = d1 + g2*vp
         gv2 = d2 - (1 + g1)*vp
         q1 = 2*vp*d2 - (1 + g1)*vp2
         q2 = -2*vp*d1 - g2*vp2
         ! Gamma1: T_1 = (-c vp^2, -s vp^2, -2 vp d1 - Gamma2 vp^2), H_1 vw = (-s vp, c vp, gv2).
         y(1) = sp*(-c*vp2) + 2*self%ea*gv1*(-s*vp) + self%ea*q1*c
         y(2) = sp*(-s*vp2) + 2*self%ea*gv1*(c*vp) + self%ea*q1*s
         y(3) = sp*(-2*vp*d1 - g2*vp2) + 2*self%ea*gv1*gv2 + self%ea*q1*g2
         ! Gamma2: T_2 = (s vp^2, -c vp^2, -2 vp d2 + (1 + Gamma1) vp^2), H_2 vw = (-c vp, -s vp, -gv1).
         y(1) = y(1) + sv*(s*vp2) + 2*self%kga*gv2*(-c*vp) - self%kga*q2*s
         y(2) = y(2) + sv*(-c*vp2) + 2*self%kga*gv2*(-s*vp) + self%kga*q2*c
         y(3) = y(3) + sv*(-2*vp*d2 + (1 + g1)*vp2) - 2*self%kga*gv2*gv1 - self%kga*q2*(1 + g1)
         y = wl*y
         d2p(1) = d2p(1) - rl*y(1)
         d2p(2) = d2p(2) - rl*y(2)
         d2p(3) = d2p(3) + n1*y(3)
         d2p(4) = d2p(4) + rl*y(1)
         d2p(5) = d2p(5) + rl*y(2)
         d2p(6) = d2p(6) + n2*y(3)
      end do
   end subroutine beam_second_derivative

   !> Largest strain magnitude at the Gauss points: |Gamma1|, |Gamma2|, |kappa|*length.
   pure real(dp) function beam_max_strain(self, xe) result(strain)
      type(beam_type), intent(in) :: self
      real(dp), intent(in) :: xe(6)
      real(dp) :: xi, w, rl, c, s, g1, g2
      integer :: ig
      rl = 1/self%length
      ! |kappa| L = |theta2 - theta1|, the same along the element.
      strain = abs(xe(6) - xe(3))
      do ig = 1, self%ngauss
         call rule_point(self%ngauss, ig, xi, w)
         call point_strain(self, xe, (1 - xi)/2, (1 + xi)/2, rl, c, s, g1, g2)
         strain = max(strain, abs(g1), abs(g2))
      end do
   end function beam_max_strain

   !> Stress resultants (P, V, M) (30) averaged over the Gauss points.
   pure function beam_resultants(self, xe) result(sig)
      type(beam_type), intent(in) :: self
      real(dp), intent(in) :: xe(6)
      real(dp) :: sig(3)
      real(dp) :: xi, w, rl, c, s, g1, g2
      integer :: ig
      rl = 1/self%length
      sig = 0
      do ig = 1, self%ngauss
         call rule_point(self%ngauss, ig, xi, w)
         call point_strain(self, xe, (1 - xi)/2, (1 + xi)/2, rl, c, s, g1, g2)
         sig = sig + [self%ea*g1, self%kga*g2, self%ei*((xe(6) - xe(3))*rl)]/self%ngauss
      end do
   end function beam_resultants

   !> Strain energy of the element, 1/2 (EA Gamma1^2 + kGA Gamma2^2 + EI kappa^2)
   !> integrated with the element's own rule: beam_residual's p is its gradient.
   pure real(dp) function beam_strain_energy(self, xe) result(energy)
      type(beam_type), intent(in) :: self
      real(dp), intent(in) :: xe(6)
      real(dp) :: xi, w, rl, c, s, g1, g2, kap
      integer :: ig
      rl = 1/self%length
      kap = (xe(6) - xe(3))*rl
      energy = 0
      do ig = 1, self%ngauss
         call rule_point(self%ngauss, ig, xi, w)
         call point_strain(self, xe, (1 - xi)/2, (1 + xi)/2, rl, c, s, g1, g2)
         energy = energy + w*self%length/4*(self%ea*g1**2 + self%kga*g2**2 + self%ei*kap**2)
      end do
   end function beam_strain_energy

end module fekap_element_beam
