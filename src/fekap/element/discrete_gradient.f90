!> The discrete gradient of the 2-node Simo-Reissner beam's strain energy over
!> a time step with rotations updated by the Cayley map (Gonzalez, Time
!> integration and discrete Hamiltonian systems, J. Nonlinear Sci. 6, 1996;
!> Simo, Tarnow & Doblare, Int. J. Numer. Meth. Eng. 38, 1995, who use the
!> Cayley transform for the same reason): internal forces p(x0, x1) conjugate
!> to the step's increments z = (Delta x1, psi1, Delta x2, psi2), each node's
!> rotation increment in Cayley form psi = 2 tan(Delta theta/2), with
!>   p . z = W(x1) - W(x0) + chi/2 sum_g wl (Delta eps_g)^T D (Delta eps_g)
!> exactly, W the element's strain energy with its Gauss points (one or two).
!>
!> At a Gauss point with shape functions n1, n2 the strains are
!> Gamma = R(phi)^T x' - e1 (x' = (x2 - x1)/L, phi = angle + n1 theta1 + n2 theta2) and
!> kappa = (theta2 - theta1)/L. With the nodes' half increments d_i = Delta theta_i/2,
!> the section's delta = n1 d1 + n2 d2, Rb = R(phi) at the section's mean angle and
!> a = (x0' + x1')/2, exactly (R(phi1) - R(phi0) = 2 sin(delta) Rb J, J the
!> rotation by +90 degrees):
!>   Gamma1 - Gamma0 = cos(delta) [Rb^T (x1' - x0') + psi_g (Rb J)^T a],  psi_g = 2 tan(delta),
!>   psi_g = a1 psi1 + a2 psi2,  cos(delta) a_i = sigma_i cos(d_i),  sigma_i = sin(n_i D)/sin(D),
!>   kappa1 - kappa0 = s (psi2 - psi1)/L,  s = cos(d1) cos(d2)/sinc(D),  D = d1 - d2,
!> (tan A - tan B = sin(A - B)/(cos A cos B) gives a_i and s, a1 + a2 = 1). So
!> Delta eps = B_alg z exactly, and p = sum_g wl B_alg^T S_g with
!> S_g = D ((eps0 + eps1)/2 + chi/2 (eps1 - eps0)): chi = 0 conserves the energy,
!> chi > 0 dissipates (Armero & Romero's form, of order h). B_alg annihilates
!> rigid translations (z = (c, 0, c, 0)) and, since a1 + a2 = 1, the rigid
!> rotation about the mean configuration (Delta x_i = J xbar_i, psi_i = 1):
!> (J + J^T) Rb^T a = 0. So p has no net force and no net moment about the
!> mean configuration: the midpoint rule on z keeps linear and angular
!> momentum exactly (docs/dynamics.md).
module fekap_element_discrete_gradient
   use fekap_kinds, only: dp
   use fekap_element_beam, only: beam_type, gauss_point, point_strain
   implicit none
   private

   public :: beam_discrete_gradient, cayley_increment

contains

   !> The Cayley form psi = 2 tan(d/2) of a rotation increment d and its
   !> derivative dpsi/dd = 1 + psi^2/4.
   elemental subroutine cayley_increment(d, psi, dpsi)
      real(dp), intent(in) :: d
      real(dp), intent(out) :: psi, dpsi
      psi = 2*tan(0.5_dp*d)
      dpsi = 1 + 0.25_dp*psi*psi
   end subroutine cayley_increment

   !> Internal force p(x0, x1) of the element over a step from x0 to x1,
   !> conjugate to (Delta x1, Delta y1, psi1, Delta x2, Delta y2, psi2), and,
   !> if asked, its derivative k = dp/dx1 by the dofs of x1 (not symmetric).
   pure subroutine beam_discrete_gradient(self, x0, x1, chi, p, k)
      type(beam_type), intent(in) :: self
      real(dp), intent(in) :: x0(6), x1(6)
      !> Dissipation: 0 conserves, > 0 dissipates (S at (1 + chi)/2 of eps1).
      real(dp), intent(in) :: chi
      real(dp), intent(out) :: p(6)
      real(dp), intent(out), optional :: k(6, 6)
      real(dp) :: rl, len, t0(2), t1(2), a(2), u(2), g0(2), g1(2), phi0, phi1, pb, cb, sb, c0, s0, c1, s1
      real(dp) :: kap0, kap1, sn, sv, sm, cg, sg, rs(2), rjs(2), f(2), gq, ha, hv, hm, xi, w, wl, n(2)
      real(dp) :: d(2), cd(2), sd(2), dd, sig(2), dsig(2), scd, dscd, ss, dss(2), ci(2), dci(2, 2)
      real(dp) :: df_dt(2, 2), df_dd(2), dg_dt(2), dg_dd, dsdt(2, 2), dsdphi(2), jtu(2)
      integer :: ig, i, ngauss
      len = self%length
      rl = 1/len
      ngauss = self%ngauss
      t0 = [(x0(4) - x0(1))*rl, (x0(5) - x0(2))*rl]
      t1 = [(x1(4) - x1(1))*rl, (x1(5) - x1(2))*rl]
      a = 0.5_dp*(t0 + t1)
      kap0 = (x0(6) - x0(3))*rl
      kap1 = (x1(6) - x1(3))*rl
      ! The nodes' half increments, and the terms of a_i and s in them.
      d = 0.5_dp*[x1(3) - x0(3), x1(6) - x0(6)]
      cd = cos(d)
      sd = sin(d)
      dd = d(1) - d(2)
      call sinc(dd, scd, dscd)
      ss = cd(1)*cd(2)/scd
      ! ds/dd1, ds/dd2 (D = d1 - d2).
      dss = [-sd(1)*cd(2)/scd - ss*dscd/scd, -cd(1)*sd(2)/scd + ss*dscd/scd]
      sm = self%ei*(0.5_dp*(kap0 + kap1) + 0.5_dp*chi*(kap1 - kap0))
      hm = 0.5_dp*(1 + chi)*self%ei
      ha = 0.5_dp*(1 + chi)*self%ea
      hv = 0.5_dp*(1 + chi)*self%kga
      ! Bending: kappa1 - kappa0 = s (psi2 - psi1)/L.
      p = 0
      p(3) = -ss*sm
      p(6) = ss*sm
      if (present(k)) then
         k = 0
         ! d(s sm)/dd_i, with dsm/dd_i = -/+ 2 hm/L; dd_i/dtheta_i = 1/2.
         k(6, 3) = 0.5_dp*(dss(1)*sm - ss*2*hm*rl)
         k(6, 6) = 0.5_dp*(dss(2)*sm + ss*2*hm*rl)
         k(3, 3) = -k(6, 3)
         k(3, 6) = -k(6, 6)
      end if
      do ig = 1, ngauss
         call gauss_point(ngauss, ig, xi, w)
         wl = w*len/2
         n = [(1 - xi)/2, (1 + xi)/2]
         phi0 = self%angle + n(1)*x0(3) + n(2)*x0(6)
         phi1 = self%angle + n(1)*x1(3) + n(2)*x1(6)
         call point_strain(self, x0, n(1), n(2), rl, c0, s0, g0(1), g0(2))     ! (27)
         call point_strain(self, x1, n(1), n(2), rl, c1, s1, g1(1), g1(2))
         pb = 0.5_dp*(phi0 + phi1)
         cb = cos(pb)
         sb = sin(pb)
         ! The section's half increment is delta = n1 d1 + n2 d2.
         cg = cos(0.5_dp*(phi1 - phi0))
         sg = sin(0.5_dp*(phi1 - phi0))
         u = [cb*a(1) + sb*a(2), -sb*a(1) + cb*a(2)]
         sn = self%ea*(0.5_dp*(g0(1) + g1(1)) + 0.5_dp*chi*(g1(1) - g0(1)))
         sv = self%kga*(0.5_dp*(g0(2) + g1(2)) + 0.5_dp*chi*(g1(2) - g0(2)))
         rs = [cb*sn - sb*sv, sb*sn + cb*sv]
         f = wl*rl*cg*rs
         ! S . J^T u, J^T u = (u2, -u1).
         gq = wl*(sn*u(2) - sv*u(1))
         do i = 1, 2
            call sine_ratio(n(i), dd, sig(i), dsig(i))
         end do
         ci = sig*cd
         p(1:2) = p(1:2) - f
         p(4:5) = p(4:5) + f
         p(3) = p(3) + ci(1)*gq
         p(6) = p(6) + ci(2)*gq
         if (.not. present(k)) cycle
         ! Derivatives by x1' (t) and the section's delta; then chained to the dofs.
         dsdt(1, :) = ha*[c1, s1]
         dsdt(2, :) = hv*[-s1, c1]
         ! dS/dphi1 (phi1 = phi0 + 2 delta).
         dsdphi = [ha*g1(2), -hv*(1 + g1(1))]
         rjs = [-(sb*sn + cb*sv), cb*sn - sb*sv]          ! Rb J S
         do i = 1, 2
            df_dt(:, i) = wl*rl*cg*[cb*dsdt(1, i) - sb*dsdt(2, i), sb*dsdt(1, i) + cb*dsdt(2, i)]
         end do
         df_dd = wl*rl*(-sg*rs + cg*rjs + 2*cg*[cb*dsdphi(1) - sb*dsdphi(2), sb*dsdphi(1) + cb*dsdphi(2)])
         jtu = [u(2), -u(1)]
         dg_dt = wl*(matmul(jtu, dsdt) + 0.5_dp*rjs)
         dg_dd = wl*(2*dot_product(jtu, dsdphi) - (sn*u(1) + sv*u(2)))
         ! d(sigma_i cos d_i)/dd_j (dci(i, j)).
         dci(1, :) = [dsig(1)*cd(1) - sig(1)*sd(1), -dsig(1)*cd(1)]
         dci(2, :) = [dsig(2)*cd(2), -dsig(2)*cd(2) - sig(2)*sd(2)]
         ! d/dx2 = rl d/dt1, d/dx1 = -rl d/dt1, d/dtheta_i = n_i/2 d/ddelta (+ 1/2 d/dd_i).
         k(4:5, 1:2) = k(4:5, 1:2) - rl*df_dt
         k(4:5, 4:5) = k(4:5, 4:5) + rl*df_dt
         k(4:5, 3) = k(4:5, 3) + 0.5_dp*n(1)*df_dd
         k(4:5, 6) = k(4:5, 6) + 0.5_dp*n(2)*df_dd
         do i = 1, 2
            associate (row => 3*i)
               k(row, 1:2) = k(row, 1:2) - rl*ci(i)*dg_dt
               k(row, 4:5) = k(row, 4:5) + rl*ci(i)*dg_dt
               k(row, 3) = k(row, 3) + 0.5_dp*(ci(i)*n(1)*dg_dd + dci(i, 1)*gq)
               k(row, 6) = k(row, 6) + 0.5_dp*(ci(i)*n(2)*dg_dd + dci(i, 2)*gq)
            end associate
         end do
      end do
      if (present(k)) k(1:2, :) = -k(4:5, :)
   end subroutine beam_discrete_gradient

   !> sigma = sin(n x)/sin(x) = n sinc(n x)/sinc(x) (n at x = 0) and its derivative.
   pure subroutine sine_ratio(n, x, sigma, dsigma)
      real(dp), intent(in) :: n, x
      real(dp), intent(out) :: sigma, dsigma
      real(dp) :: snx, dsnx, sx, dsx
      call sinc(n*x, snx, dsnx)
      call sinc(x, sx, dsx)
      sigma = n*snx/sx
      dsigma = n*(n*dsnx*sx - snx*dsx)/(sx*sx)
   end subroutine sine_ratio

   !> sin(x)/x and its derivative, by their series near 0.
   pure subroutine sinc(x, s, ds)
      real(dp), intent(in) :: x
      real(dp), intent(out) :: s, ds
      real(dp) :: x2
      x2 = x*x
      if (abs(x) < 1.0e-3_dp) then
         s = 1 - x2/6*(1 - x2/20)
         ds = -x/3*(1 - x2/10)
      else
         s = sin(x)/x
         ds = (x*cos(x) - sin(x))/x2
      end if
   end subroutine sinc

end module fekap_element_discrete_gradient
