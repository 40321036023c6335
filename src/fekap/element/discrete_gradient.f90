!> The discrete gradient of the 2-node Simo-Reissner beam's strain energy over
!> a time step (Gonzalez, Time integration and discrete Hamiltonian systems,
!> J. Nonlinear Sci. 6, 1996; Simo & Tarnow, The discrete energy-momentum
!> method, ZAMP 43, 1992): internal forces p(x0, x1) with
!>   p . (x1 - x0) = W(x1) - W(x0) + chi/2 L (Delta eps)^T D (Delta eps)
!> exactly, W the element's strain energy with one Gauss point.
!>
!> With one Gauss point the strains are eps = (Gamma, kappa), Gamma = R(phi)^T x' - e1
!> (x' = (x2 - x1)/L, phi = angle + (theta1 + theta2)/2) and kappa = (theta2 - theta1)/L.
!> Over a step, kappa is linear in the dofs and, with Rb = R(phib) at the mean
!> section angle, delta = (phi1 - phi0)/2 and a = (x0' + x1')/2,
!>   Gamma1 - Gamma0 = cos(delta) Rb^T (x1' - x0') + 2 sin(delta) (Rb J)^T a
!> exactly (R(phi1) - R(phi0) = 2 sin(delta) Rb J, (R(phi1) + R(phi0))/2 = cos(delta) Rb;
!> J the rotation by +90 degrees). So B_alg, with Delta eps = B_alg Delta d exactly, is
!>   d Gamma / d(x2 - x1) = cos(delta) Rb^T / L,  d Gamma / d theta_i = sinc(delta) (Rb J)^T a / 2,
!> and p = L B_alg^T S with S = D ((eps0 + eps1)/2 + chi/2 (eps1 - eps0)): chi = 0
!> conserves the energy, chi > 0 dissipates chi/2 L |Delta eps|_D^2 >= 0 (a strain-rate
!> damping of order h, Armero & Romero's EDMC form of dissipation). B_alg annihilates rigid
!> translations (linear momentum is kept exactly); the moment of p about the mean
!> configuration is L (sinc(delta) - cos(delta)) (Rb J S) . a = O(delta^2), so angular
!> momentum is kept to second order, not exactly.
module fekap_element_discrete_gradient
   use fekap_kinds, only: dp
   use fekap_element_beam, only: beam_type
   implicit none
   private

   public :: beam_discrete_gradient

contains

   !> Internal force p(x0, x1) of the element over a step from x0 to x1 and,
   !> if asked, its derivative k = dp/dx1 (not symmetric). One Gauss point.
   pure subroutine beam_discrete_gradient(self, x0, x1, chi, p, k)
      type(beam_type), intent(in) :: self
      real(dp), intent(in) :: x0(6), x1(6)
      !> Dissipation: 0 conserves, > 0 dissipates (S at (1 + chi)/2 of eps1).
      real(dp), intent(in) :: chi
      real(dp), intent(out) :: p(6)
      real(dp), intent(out), optional :: k(6, 6)
      real(dp) :: rl, len, t0(2), t1(2), a(2), u(2), g0(2), g1(2), phi0, phi1, pb, dl, cb, sb, c1, s1
      real(dp) :: kap0, kap1, sn, sv, sm, cd, sd, sc, dsc, rs(2), rjs(2), f(2), gq, ha, hv, hm
      real(dp) :: df_dt(2, 2), df_dphi(2), dg_dt(2), dg_dphi, dp_dt(2), dp_dphi, dsdt(2, 2), dsdphi(2), jtu(2)
      integer :: i
      len = self%length
      rl = 1/len
      t0 = [(x0(4) - x0(1))*rl, (x0(5) - x0(2))*rl]
      t1 = [(x1(4) - x1(1))*rl, (x1(5) - x1(2))*rl]
      phi0 = self%angle + 0.5_dp*(x0(3) + x0(6))
      phi1 = self%angle + 0.5_dp*(x1(3) + x1(6))
      kap0 = (x0(6) - x0(3))*rl
      kap1 = (x1(6) - x1(3))*rl
      g0 = frame(phi0, t0) - [1.0_dp, 0.0_dp]
      c1 = cos(phi1)
      s1 = sin(phi1)
      g1 = [c1*t1(1) + s1*t1(2) - 1, -s1*t1(1) + c1*t1(2)]
      ! Mean section angle and half the increment.
      pb = 0.5_dp*(phi0 + phi1)
      dl = 0.5_dp*(phi1 - phi0)
      cb = cos(pb)
      sb = sin(pb)
      cd = cos(dl)
      sd = sin(dl)
      call sinc(dl, sc, dsc)
      a = 0.5_dp*(t0 + t1)
      u = [cb*a(1) + sb*a(2), -sb*a(1) + cb*a(2)]
      ! The algorithmic stress resultants.
      sn = self%ea*(0.5_dp*(g0(1) + g1(1)) + 0.5_dp*chi*(g1(1) - g0(1)))
      sv = self%kga*(0.5_dp*(g0(2) + g1(2)) + 0.5_dp*chi*(g1(2) - g0(2)))
      sm = self%ei*(0.5_dp*(kap0 + kap1) + 0.5_dp*chi*(kap1 - kap0))
      rs = [cb*sn - sb*sv, sb*sn + cb*sv]
      f = cd*rs
      ! S . J^T u, J^T u = (u2, -u1).
      gq = sn*u(2) - sv*u(1)
      p(1:2) = -f
      p(4:5) = f
      p(3) = 0.5_dp*len*sc*gq - sm
      p(6) = 0.5_dp*len*sc*gq + sm
      if (.not. present(k)) return
      ! Derivatives by x1' (t) and phi1; then chained to the dofs.
      ha = 0.5_dp*(1 + chi)*self%ea
      hv = 0.5_dp*(1 + chi)*self%kga
      hm = 0.5_dp*(1 + chi)*self%ei
      ! dS/dt1 = Dh R1^T, dS/dphi1 = Dh (Gamma1_2, -(1 + Gamma1_1)).
      dsdt(1, :) = ha*[c1, s1]
      dsdt(2, :) = hv*[-s1, c1]
      dsdphi = [ha*g1(2), -hv*(1 + g1(1))]
      ! f = cos(delta) Rb S.
      rjs = [-(sb*sn + cb*sv), cb*sn - sb*sv]          ! Rb J S
      do i = 1, 2
         df_dt(:, i) = cd*[cb*dsdt(1, i) - sb*dsdt(2, i), sb*dsdt(1, i) + cb*dsdt(2, i)]
      end do
      df_dphi = 0.5_dp*(-sd*rs + cd*rjs) + cd*[cb*dsdphi(1) - sb*dsdphi(2), sb*dsdphi(1) + cb*dsdphi(2)]
      ! gq = S . J^T Rb^T a.
      jtu = [u(2), -u(1)]
      dg_dt = matmul(jtu, dsdt) + 0.5_dp*rjs
      dg_dphi = dot_product(jtu, dsdphi) - 0.5_dp*(sn*u(1) + sv*u(2))
      dp_dt = 0.5_dp*len*sc*dg_dt
      dp_dphi = 0.5_dp*len*(0.5_dp*dsc*gq + sc*dg_dphi)
      ! Chain: d/dx2 = rl d/dt1, d/dx1 = -rl d/dt1, d/dtheta_i = 1/2 d/dphi1.
      k(4:5, 1:2) = -rl*df_dt
      k(4:5, 4:5) = rl*df_dt
      k(4:5, 3) = 0.5_dp*df_dphi
      k(4:5, 6) = 0.5_dp*df_dphi
      k(1:2, :) = -k(4:5, :)
      k(3, 1:2) = -rl*dp_dt
      k(3, 4:5) = rl*dp_dt
      k(3, 3) = 0.5_dp*dp_dphi + hm*rl
      k(3, 6) = 0.5_dp*dp_dphi - hm*rl
      k(6, 1:2) = k(3, 1:2)
      k(6, 4:5) = k(3, 4:5)
      k(6, 3) = 0.5_dp*dp_dphi - hm*rl
      k(6, 6) = 0.5_dp*dp_dphi + hm*rl
   end subroutine beam_discrete_gradient

   !> R(phi)^T v.
   pure function frame(phi, v) result(w)
      real(dp), intent(in) :: phi, v(2)
      real(dp) :: w(2)
      w = [cos(phi)*v(1) + sin(phi)*v(2), -sin(phi)*v(1) + cos(phi)*v(2)]
   end function frame

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
