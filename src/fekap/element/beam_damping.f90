!> Objective stiffness-proportional (Rayleigh beta) damping of the 2-node
!> Simo-Reissner beam (docs/dynamics.md, "Damping"): the viscous stresses
!> beta D epsd of the material strain rates epsd = B(q) v at the configuration
!> where the force is evaluated, so that a rigid motion of any size and speed
!> (whose strain rates are zero) is not damped:
!>   f = beta sum over Gauss points wl B(q)^T D B(q) v = beta K_m(q) v,
!> K_m the material tangent of (46) at q, D = diag(EA, kGA, EI). With
!> w = (x1', x2', phi) = Bw xe at a Gauss point and the strains' gradients
!> g1 = (c, s, Gamma2), g2 = (-s, c, -(1 + Gamma1)) in w, the rates are
!> Gammad_m = g_m . Bw v and kappad = (theta2d - theta1d)/L, and
!>   df/dxe = sum wl Bw^T [S1 H1 + S2 H2 + beta EA g1 (H1 Bw v)^T + beta kGA g2 (H2 Bw v)^T] Bw
!> (S_m = beta C_m Gammad_m the viscous stresses, H_m the strains' Hessians in w,
!> those of beam_second_derivative's header), not symmetric; df/dv = beta K_m.
module fekap_element_beam_damping
   use fekap_kinds, only: dp
   use fekap_element_beam, only: beam_type, gauss_point, point_strain
   implicit none
   private

   public :: beam_damping_force, beam_strain_change

contains

   !> The damping force f = beta K_m(xe) ve of the element at the
   !> configuration xe moving at ve and, if asked, the iteration matrix's
   !> share k = df/dxe + c1 df/dve (ve moving with xe at the rate c1, as the
   !> integrator makes it; without c1, df/dxe alone).
   pure subroutine beam_damping_force(self, xe, ve, beta, f, c1, k)
      type(beam_type), intent(in) :: self
      real(dp), intent(in) :: xe(6), ve(6), beta
      real(dp), intent(out) :: f(6)
      real(dp), intent(in), optional :: c1
      real(dp), intent(out), optional :: k(6, 6)
      real(dp) :: xi, w, wl, n1, n2, c, s, g1, g2, rl, vw(3), gr1(3), gr2(3), h1(3, 3), h2(3, 3)
      real(dp) :: rate1, rate2, ratek, s1, s2, sk, a(3, 3), bw(3, 6), bk(6), rate_c1
      integer :: ig
      rate_c1 = 0
      if (present(c1)) rate_c1 = c1
      rl = 1/self%length
      ratek = (ve(6) - ve(3))*rl
      sk = beta*self%ei*ratek
      bk = [0.0_dp, 0.0_dp, -rl, 0.0_dp, 0.0_dp, rl]
      f = 0
      if (present(k)) k = 0
      do ig = 1, self%ngauss
         call gauss_point(self%ngauss, ig, xi, w)
         wl = w*self%length/2
         n1 = (1 - xi)/2
         n2 = (1 + xi)/2
         call point_strain(self, xe, n1, n2, rl, c, s, g1, g2)     ! (27)
         bw = 0
         bw(1, [1, 4]) = [-rl, rl]
         bw(2, [2, 5]) = [-rl, rl]
         bw(3, [3, 6]) = [n1, n2]
         vw = matmul(bw, ve)
         gr1 = [c, s, g2]
         gr2 = [-s, c, -(1 + g1)]
         ! The material strain rates and the viscous stresses.
         rate1 = dot_product(gr1, vw)
         rate2 = dot_product(gr2, vw)
         s1 = beta*self%ea*rate1
         s2 = beta*self%kga*rate2
         f = f + wl*(matmul(s1*gr1 + s2*gr2, bw) + sk*bk)
         if (.not. present(k)) cycle
         h1 = reshape([0.0_dp, 0.0_dp, -s, 0.0_dp, 0.0_dp, c, -s, c, -(1 + g1)], [3, 3])
         h2 = reshape([0.0_dp, 0.0_dp, -c, 0.0_dp, 0.0_dp, -s, -c, -s, -g2], [3, 3])
         ! The outer products g_m (H_m vw + c1 g_m)^T.
         a = s1*h1 + s2*h2 + beta*self%ea*matmul(reshape(gr1, [3, 1]), reshape(matmul(h1, vw) + rate_c1*gr1, [1, 3])) + &
            & beta*self%kga*matmul(reshape(gr2, [3, 1]), reshape(matmul(h2, vw) + rate_c1*gr2, [1, 3]))
         k = k + wl*matmul(transpose(bw), matmul(a, bw))
         ! Bending: c1 beta EI bk bk^T.
         k([3, 6], [3, 6]) = k([3, 6], [3, 6]) + rate_c1*wl*beta*self%ei*rl**2*reshape([1, -1, -1, 1], [2, 2])
      end do
   end subroutine beam_damping_force

   !> sum over Gauss points wl (eps1 - eps0)^T D (eps1 - eps0): L |Delta eps|_D^2
   !> with one Gauss point, the energy-momentum step's damping times h / beta.
   pure real(dp) function beam_strain_change(self, x0, x1) result(change)
      type(beam_type), intent(in) :: self
      real(dp), intent(in) :: x0(6), x1(6)
      real(dp) :: xi, w, rl, c, s, e0(2), e1(2), dk
      integer :: ig
      rl = 1/self%length
      dk = ((x1(6) - x1(3)) - (x0(6) - x0(3)))*rl
      change = 0
      do ig = 1, self%ngauss
         call gauss_point(self%ngauss, ig, xi, w)
         call point_strain(self, x0, (1 - xi)/2, (1 + xi)/2, rl, c, s, e0(1), e0(2))
         call point_strain(self, x1, (1 - xi)/2, (1 + xi)/2, rl, c, s, e1(1), e1(2))
         change = change + w*self%length/2*(self%ea*(e1(1) - e0(1))**2 + self%kga*(e1(2) - e0(2))**2 + self%ei*dk**2)
      end do
   end function beam_strain_change

end module fekap_element_beam_damping
