!> The discrete gradient of a pin-in-slot slideline's penalty energy
!> E = kp g^2/2 over a time step (Gonzalez, J. Nonlinear Sci. 6, 1996), for the
!> energy-momentum integrator: with g = A/s, A = (x2 - x1) x (xs - x1) and
!> s^2 = Q = |x2 - x1|^2 both quadratic, their midpoint gradients are exact
!> (A1 - A0 = grad A(qm) . Delta q, qm = (q0 + q1)/2), and
!>   g1 - g0 = Gb . Delta q,  Gb = (1/s0 + 1/s1)/2 grad A(qm) - Ab/((s0 + s1) s0 s1) grad Q(qm)
!> (Ab = (A0 + A1)/2), so p = kp (g0 + g1)/2 Gb gives p . Delta q = E1 - E0
!> exactly. A and Q are invariant under rigid motions: their gradients at qm
!> have no net force and no net moment about qm, and neither has p (a moving
!> master keeps the momenta; a ground guide, x1 and x2 fixed, makes g linear
!> in xs and p the force at the mean gap). Dofs (xs, ys, x1, y1, x2, y2) as
!> slide_force's; p is the residual's sign (the spring's force on the nodes is -p).
module fekap_contact_slide_gradient
   use fekap_kinds, only: dp
   implicit none
   private

   public :: slide_discrete_gradient

   ! grad A and grad Q are affine in q (gradients): their Hessians are these
   ! constants (symmetric, so either order of reshape's columns).
   real(dp), parameter :: ha(6, 6) = reshape(real([ &
      & 0, 0, 0, 1, 0, -1, &
      & 0, 0, -1, 0, 1, 0, &
      & 0, -1, 0, 0, 0, 1, &
      & 1, 0, 0, 0, -1, 0, &
      & 0, 1, 0, -1, 0, 0, &
      & -1, 0, 1, 0, 0, 0], dp), [6, 6])
   real(dp), parameter :: hq(6, 6) = reshape(real([ &
      & 0, 0, 0, 0, 0, 0, &
      & 0, 0, 0, 0, 0, 0, &
      & 0, 0, 2, 0, -2, 0, &
      & 0, 0, 0, 2, 0, -2, &
      & 0, 0, -2, 0, 2, 0, &
      & 0, 0, 0, -2, 0, 2], dp), [6, 6])

contains

   !> p(q0, q1) and, if asked, k = dp/dq1 (not symmetric), q = (xs, x1, x2).
   pure subroutine slide_discrete_gradient(q0, q1, kp, p, k)
      real(dp), intent(in) :: q0(6), q1(6), kp
      real(dp), intent(out) :: p(6)
      real(dp), intent(out), optional :: k(6, 6)
      real(dp) :: qm(6), ga(6), gq(6), ga1(6), gq1(6), gb(6)
      real(dp) :: a0, a1, s0, s1, ab, al, ga_, gbar, den, dg1(6), dal(6), dga(6), ds1(6)
      integer :: j
      qm = 0.5_dp*(q0 + q1)
      call invariants(q0, a0, s0)
      call invariants(q1, a1, s1)
      call gradients(qm, ga, gq)
      ab = 0.5_dp*(a0 + a1)
      al = 0.5_dp*(1/s0 + 1/s1)
      den = (s0 + s1)*s0*s1
      ga_ = -ab/den
      gb = al*ga + ga_*gq
      gbar = 0.5_dp*(a0/s0 + a1/s1)
      p = kp*gbar*gb
      if (.not. present(k)) return
      call gradients(q1, ga1, gq1)
      ! ds1/dq1 = grad Q1/(2 s1); d(g1)/dq1 = grad A1/s1 - A1 ds1/s1^2.
      ds1 = gq1/(2*s1)
      dg1 = ga1/s1 - a1*ds1/s1**2
      dal = -0.5_dp*ds1/s1**2
      ! d(ga_)/dq1 = -grad A1/(2 den) + Ab s0 (s0 + 2 s1) ds1/den^2.
      dga = -0.5_dp*ga1/den + ab*s0*(s0 + 2*s1)*ds1/den**2
      do j = 1, 6
         k(:, j) = kp*(0.5_dp*dg1(j)*gb + gbar*(dal(j)*ga + 0.5_dp*al*ha(:, j) + dga(j)*gq + 0.5_dp*ga_*hq(:, j)))
      end do
   end subroutine slide_discrete_gradient

   !> A = (x2 - x1) x (xs - x1) and s = |x2 - x1| at q = (xs, x1, x2).
   pure subroutine invariants(q, a, s)
      real(dp), intent(in) :: q(6)
      real(dp), intent(out) :: a, s
      real(dp) :: d(2), r(2)
      d = q(5:6) - q(3:4)
      r = q(1:2) - q(3:4)
      a = d(1)*r(2) - d(2)*r(1)
      s = norm2(d)
   end subroutine invariants

   !> grad A and grad Q at q (with J a = (-a2, a1): dA/dxs = J d, dA/dx2 = -J r).
   pure subroutine gradients(q, ga, gq)
      real(dp), intent(in) :: q(6)
      real(dp), intent(out) :: ga(6), gq(6)
      real(dp) :: d(2), r(2)
      d = q(5:6) - q(3:4)
      r = q(1:2) - q(3:4)
      ga(1:2) = [-d(2), d(1)]
      ga(5:6) = [r(2), -r(1)]
      ga(3:4) = -ga(1:2) - ga(5:6)
      gq(1:2) = 0
      gq(5:6) = 2*d
      gq(3:4) = -2*d
   end subroutine gradients

end module fekap_contact_slide_gradient
