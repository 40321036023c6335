!> The sliding-joint (slideline) contact element of the paper, equations (55)-(95):
!> a slave node s kept on a master element 1-2 by a penalty spring on the gap g.
!>
!> Everything works on CURRENT positions: `xs` of the slave node, `x1` and `x2`
!> of the master element's nodes. The six contact dofs are ordered as in (67):
!> (xs, ys, x1, y1, x2, y2).
!>
!> Sign convention: `f` is the force the penalty spring applies to the nodes,
!> f = -dE/dd with the spring energy E = kp g**2/2, so f = -kp g N_s (65), and
!> `k` = df/dd (71)-(72). The global assembly therefore adds f to F^c and k to K^c
!> and uses them as in (76)-(77): residual P - F^c, Newton matrix K - K^c.
!>
!> All geometric quantities follow from g as a function of the six coordinates:
!> N_s = grad g (61), its Hessian H = -(T_s N_m^T + N_m T_s^T + (g/s1) N_m N_m^T)/s1,
!> so that k = -kp (N_s N_s^T + g H), which is (72)-(75).
!> The master length s1 must be positive (a degenerate master element is the
!> caller's error; the beam element has failed long before).
module fekap_contact_slideline
   use fekap_kinds, only: dp
   implicit none
   private

   public :: slide_geometry, slide_force, slide_second_derivative
   public :: slide_tie_offset, slide_tie_force, slide_tie_second_derivative
   public :: slide_locate, default_penalty
   public :: slide_energy, slide_tie_energy, slide_gap_gradient, slide_dashpot

   !> Status of `slide_locate`: the slave stays on its master element.
   integer, parameter, public :: slide_on_element = 0
   !> Status of `slide_locate`: the slave moves on to the neighbouring element `next`.
   integer, parameter, public :: slide_moved = 1
   !> Status of `slide_locate`: the slave has left the slideline past its first or last element.
   integer, parameter, public :: slide_off_end = 2

   !> Hysteresis of `slide_locate`: alpha in [-tol, 1 + tol] keeps the slave on its element.
   real(dp), parameter, public :: slide_hysteresis = 1.0e-9_dp

   !> The master element's frame and the slave's place in it.
   type :: frame_type
      !> Master length s1, gap g (59), coordinate alpha (60).
      real(dp) :: s1 = 0, g = 0, alpha = 0
      !> Unit tangent t = (cos beta, sin beta) and normal n_r = (-sin beta, cos beta) (58).
      real(dp) :: t(2) = 0, n(2) = 0
      !> N_s (61), N_m (62), T_s (63), and M_t = (0, 0, -t, t).
      real(dp) :: ns(6) = 0, nm(6) = 0, ts(6) = 0, mt(6) = 0
   end type frame_type

   real(dp), parameter :: pi = 3.14159265358979323846264338327950288_dp

contains

   !> The master frame, gap and coordinate of the slave at positions xs, x1, x2.
   pure subroutine master_frame(xs, x1, x2, fr)
      real(dp), intent(in) :: xs(2), x1(2), x2(2)
      type(frame_type), intent(out) :: fr
      real(dp) :: r(2)
      fr%s1 = norm2(x2 - x1)
      fr%t = (x2 - x1)/fr%s1
      fr%n = [-fr%t(2), fr%t(1)]
      r = xs - x1
      fr%g = dot_product(r, fr%n)
      fr%alpha = dot_product(r, fr%t)/fr%s1
      fr%ns = [fr%n, -(1 - fr%alpha)*fr%n, -fr%alpha*fr%n]
      fr%nm = [0.0_dp, 0.0_dp, -fr%n, fr%n]
      fr%ts = [fr%t, -(1 - fr%alpha)*fr%t, -fr%alpha*fr%t]
      fr%mt = [0.0_dp, 0.0_dp, -fr%t, fr%t]
   end subroutine master_frame

   !> Outer product a b^T, by loops: spread's two temporaries per product were
   !> a tenth of the instructions of a flexible slider-crank's dynamics step.
   pure function outer(a, b) result(c)
      real(dp), intent(in) :: a(:), b(:)
      real(dp) :: c(size(a), size(b))
      integer :: i, j
      do j = 1, size(b)
         do i = 1, size(a)
            c(i, j) = a(i)*b(j)
         end do
      end do
   end function outer

   !> Master length s1, gap g (59) and coordinate alpha (60) of the slave node.
   !> g > 0 when the slave lies to the left of the direction x1 -> x2;
   !> alpha = 0 at x1 and 1 at x2 (the projection of xs on the master line).
   pure subroutine slide_geometry(xs, x1, x2, g, alpha, s1)
      !> Current position of the slave node.
      real(dp), intent(in) :: xs(2)
      !> Current positions of the master element's first and second node.
      real(dp), intent(in) :: x1(2), x2(2)
      !> Gap (59), positive to the left of x1 -> x2.
      real(dp), intent(out) :: g
      !> Coordinate (60) of the slave's projection along the master element.
      real(dp), intent(out) :: alpha
      !> Current master length.
      real(dp), intent(out) :: s1
      type(frame_type) :: fr
      call master_frame(xs, x1, x2, fr)
      g = fr%g
      alpha = fr%alpha
      s1 = fr%s1
   end subroutine slide_geometry

   !> Contact force f = -kp g N_s (65) on the dofs (xs, ys, x1, y1, x2, y2) (67), and
   !> optionally its exact derivative k = df/dd (72) = k_s (74) + k_g (75).
   !> f is the force the spring applies (f = -dE/dd, E = kp g**2/2): assemble it into
   !> F^c and k into K^c, residual P - F^c and Newton matrix K - K^c (76)-(77).
   !> When the slave is on the master (g = 0), f = 0 and k = k_s = -kp N_s N_s^T.
   pure subroutine slide_force(xs, x1, x2, kp, f, k)
      !> Current position of the slave node.
      real(dp), intent(in) :: xs(2)
      !> Current positions of the master element's nodes.
      real(dp), intent(in) :: x1(2), x2(2)
      !> Penalty constant k_p (force per length).
      real(dp), intent(in) :: kp
      !> Contact force (65), ordered as (67).
      real(dp), intent(out) :: f(6)
      !> Contact tangent df/dd (72), symmetric.
      real(dp), intent(out), optional :: k(6, 6)
      type(frame_type) :: fr
      call master_frame(xs, x1, x2, fr)
      f = -kp*fr%g*fr%ns
      ! g H = -(g/s1) A (gap_hessian).
      if (present(k)) k = -kp*(outer(fr%ns, fr%ns) - fr%g/fr%s1*gap_hessian(fr))
   end subroutine slide_force

   !> Exact second directional derivative d2f = d^2 f/dd^2 [v, v] of the contact
   !> force (65) along the contact dofs' velocities v, at any configuration (g /= 0 too).
   !> This is the contact term of the differentiated (81)/(83) that goes to the
   !> acceleration right-hand side: (K - K^c) a = ... + d2F^c[v, v].
   !>
   !> With the rates along v of the master's stretch lambda = t.(v2 - v1)/s1, chord
   !> rotation omega = n.(v2 - v1)/s1, gap g' = N_s.v and alpha' = (T_s.v + g omega)/s1:
   !> N_s' = -omega T_s - alpha' N_m, g'' = N_s'.v,
   !> alpha'' = 2 (omega g' - alpha' lambda s1 - g omega lambda)/s1,
   !> N_s'' = 2 omega lambda T_s - omega**2 N_s + 2 omega alpha' M_t - alpha'' N_m, and
   !> d2f = -kp (g'' N_s + 2 g' N_s' + g N_s'').
   !> At g = 0 the paper's (83) keeps only -kp (g'' N_s + g' N_s'); the second
   !> g' N_s' comes from k_g (75), whose rate is not zero even where g is.
   pure subroutine slide_second_derivative(xs, x1, x2, kp, v, d2f)
      !> Current position of the slave node.
      real(dp), intent(in) :: xs(2)
      !> Current positions of the master element's nodes.
      real(dp), intent(in) :: x1(2), x2(2)
      !> Penalty constant k_p.
      real(dp), intent(in) :: kp
      !> Velocities of the contact dofs, ordered as (67).
      real(dp), intent(in) :: v(6)
      !> d^2 f/dd^2 [v, v], ordered as (67).
      real(dp), intent(out) :: d2f(6)
      type(frame_type) :: fr
      real(dp) :: dv(2), lambda, omega, gd, ad, gdd, add, nsd(6), nsdd(6)
      call master_frame(xs, x1, x2, fr)
      dv = v(5:6) - v(3:4)
      lambda = dot_product(fr%t, dv)/fr%s1
      omega = dot_product(fr%n, dv)/fr%s1
      gd = dot_product(fr%ns, v)
      ad = (dot_product(fr%ts, v) + fr%g*omega)/fr%s1
      nsd = -omega*fr%ts - ad*fr%nm
      gdd = dot_product(nsd, v)
      add = 2*(omega*gd - ad*lambda*fr%s1 - fr%g*omega*lambda)/fr%s1
      nsdd = 2*omega*lambda*fr%ts - omega**2*fr%ns + 2*omega*ad*fr%mt - add*fr%nm
      d2f = -kp*(gdd*fr%ns + 2*gd*nsd + fr%g*nsdd)
   end subroutine slide_second_derivative

   !> A = T_s N_m^T + N_m T_s^T + (g/s1) N_m N_m^T, so that the gap's Hessian
   !> is H = -A/s1 (the header): the tangents of slide_force and slide_dashpot.
   pure function gap_hessian(fr) result(a)
      type(frame_type), intent(in) :: fr
      real(dp) :: a(6, 6)
      a = outer(fr%ts, fr%nm) + outer(fr%nm, fr%ts) + fr%g/fr%s1*outer(fr%nm, fr%nm)
   end function gap_hessian

   !> Energy E = kp g**2/2 of the gap spring at xs, x1, x2: f of slide_force is -dE/dd.
   pure real(dp) function slide_energy(xs, x1, x2, kp) result(energy)
      real(dp), intent(in) :: xs(2), x1(2), x2(2), kp
      type(frame_type) :: fr
      call master_frame(xs, x1, x2, fr)
      energy = 0.5_dp*kp*fr%g**2
   end function slide_energy

   !> The gap's gradient N_s = grad g (61) over the contact dofs (67): the gap
   !> rate is N_s . v. The solver takes N_s from its frame; this is the tests'
   !> reference for it (checked against finite differences of the gap).
   pure function slide_gap_gradient(xs, x1, x2) result(ns)
      real(dp), intent(in) :: xs(2), x1(2), x2(2)
      real(dp) :: ns(6)
      type(frame_type) :: fr
      call master_frame(xs, x1, x2, fr)
      ns = fr%ns
   end function slide_gap_gradient

   !> A dashpot c on the gap rate g' = N_s . v (N_s = grad g (61) at the
   !> current positions): f = c g' N_s over the contact dofs (67), the force
   !> it resists with (the equations of motion add f, the joint applies -f),
   !> and, if asked, the iteration matrix's share
   !> k = df/dd + c1 df/dv = c (N_s (H v)^T + g' H) + c1 c N_s N_s^T
   !> (v moving with d at the rate c1; H the gap's Hessian, see the header),
   !> not symmetric where the master moves.
   pure subroutine slide_dashpot(xs, x1, x2, c, v, f, c1, k)
      !> Current positions of the slave node and the master element's nodes.
      real(dp), intent(in) :: xs(2), x1(2), x2(2)
      !> The dashpot (force per gap rate) and the contact dofs' velocities (67).
      real(dp), intent(in) :: c, v(6)
      real(dp), intent(out) :: f(6)
      real(dp), intent(in), optional :: c1
      real(dp), intent(out), optional :: k(6, 6)
      type(frame_type) :: fr
      real(dp) :: rate, h(6, 6)
      call master_frame(xs, x1, x2, fr)
      rate = dot_product(fr%ns, v)
      f = c*rate*fr%ns
      if (.not. present(k)) return
      h = -gap_hessian(fr)/fr%s1
      k = c*(outer(fr%ns, matmul(h, v)) + rate*h)
      if (present(c1)) k = k + c1*c*outer(fr%ns, fr%ns)
   end subroutine slide_dashpot

   !> Offset c0 of the rotational tie of a prismatic joint, chosen so that the tie
   !> is free in the given (initial) configuration: c0 = phi_master - theta_s.
   pure function slide_tie_offset(theta_s, x1, x2) result(c0)
      !> Rotation of the slave link at the slave node.
      real(dp), intent(in) :: theta_s
      !> Positions of the master element's nodes.
      real(dp), intent(in) :: x1(2), x2(2)
      real(dp) :: c0
      c0 = atan2(x2(2) - x1(2), x2(1) - x1(1)) - theta_s
   end function slide_tie_offset

   !> The tie's gradient G = grad e over (theta_s, x1, y1, x2, y2), its master
   !> frame, and the relative angle e = theta_s - phi + c0 wrapped into [-pi, pi).
   pure subroutine tie_frame(theta_s, x1, x2, c0, e, grad, s1, t, n)
      real(dp), intent(in) :: theta_s, x1(2), x2(2), c0
      real(dp), intent(out) :: e, grad(5), s1, t(2), n(2)
      s1 = norm2(x2 - x1)
      t = (x2 - x1)/s1
      n = [-t(2), t(1)]
      e = theta_s - atan2(t(2), t(1)) + c0
      e = modulo(e + pi, 2*pi) - pi
      grad = [1.0_dp, n/s1, -n/s1]
   end subroutine tie_frame

   !> Rotational tie of a prismatic joint (beyond the paper): a penalty spring of
   !> energy E = kr e**2/2 on the relative angle e = theta_s - phi + c0, with phi the
   !> chord angle of the master element (atan2 of x2 - x1) and c0 from slide_tie_offset.
   !> Dofs (theta_s, x1, y1, x2, y2). Same convention as slide_force: f = -dE/dd = -kr e G
   !> with G = (1, n/s1, -n/s1), and k = df/dd = -kr (G G^T + (e/s1**2) B),
   !> B = [0 0 0; 0 S -S; 0 -S S], S = t n^T + n t^T. The angle e is wrapped into
   !> [-pi, pi), so whole turns of the slave link do not matter.
   pure subroutine slide_tie_force(theta_s, x1, x2, c0, kr, f, k)
      !> Current rotation of the slave link at the slave node.
      real(dp), intent(in) :: theta_s
      !> Current positions of the master element's nodes.
      real(dp), intent(in) :: x1(2), x2(2)
      !> Offset from slide_tie_offset.
      real(dp), intent(in) :: c0
      !> Rotational penalty constant (moment per radian).
      real(dp), intent(in) :: kr
      !> Tie forces on (theta_s, x1, y1, x2, y2): a moment and four forces.
      real(dp), intent(out) :: f(5)
      !> Tie tangent df/dd, symmetric.
      real(dp), intent(out), optional :: k(5, 5)
      real(dp) :: e, grad(5), s1, t(2), n(2), s(2, 2)
      call tie_frame(theta_s, x1, x2, c0, e, grad, s1, t, n)
      f = -kr*e*grad
      if (present(k)) then
         s = (e/s1**2)*(outer(t, n) + outer(n, t))
         k = outer(grad, grad)
         k(2:3, 2:3) = k(2:3, 2:3) + s
         k(4:5, 4:5) = k(4:5, 4:5) + s
         k(2:3, 4:5) = k(2:3, 4:5) - s
         k(4:5, 2:3) = k(4:5, 2:3) - s
         k = -kr*k
      end if
   end subroutine slide_tie_force

   !> Energy E = kr e**2/2 of a prismatic joint's rotational tie (e wrapped as
   !> in slide_tie_force, whose f is -dE/dd).
   pure real(dp) function slide_tie_energy(theta_s, x1, x2, c0, kr) result(energy)
      real(dp), intent(in) :: theta_s, x1(2), x2(2), c0, kr
      real(dp) :: e, grad(5), s1, t(2), n(2)
      call tie_frame(theta_s, x1, x2, c0, e, grad, s1, t, n)
      energy = 0.5_dp*kr*e**2
   end function slide_tie_energy

   !> Exact second directional derivative d^2 f/dd^2 [v, v] of the tie force along
   !> v = (theta_s', x1', y1', x2', y2'), for the acceleration right-hand side.
   !> With lambda = t.(v2 - v1)/s1 and omega = n.(v2 - v1)/s1 (so phi' = omega and
   !> phi'' = -2 omega lambda): e' = theta_s' - omega, e'' = 2 omega lambda,
   !> G' = (0, u, -u), u = -(omega t + lambda n)/s1,
   !> G'' = (0, u', -u'), u' = (4 omega lambda t + 2 (lambda**2 - omega**2) n)/s1, and
   !> d2f = -kr (e'' G + 2 e' G' + e G'').
   pure subroutine slide_tie_second_derivative(theta_s, x1, x2, c0, kr, v, d2f)
      !> Current rotation of the slave link at the slave node.
      real(dp), intent(in) :: theta_s
      !> Current positions of the master element's nodes.
      real(dp), intent(in) :: x1(2), x2(2)
      !> Offset from slide_tie_offset.
      real(dp), intent(in) :: c0
      !> Rotational penalty constant.
      real(dp), intent(in) :: kr
      !> Velocities of (theta_s, x1, y1, x2, y2).
      real(dp), intent(in) :: v(5)
      !> d^2 f/dd^2 [v, v] on (theta_s, x1, y1, x2, y2).
      real(dp), intent(out) :: d2f(5)
      real(dp) :: e, grad(5), s1, t(2), n(2), dv(2), lambda, omega, u(2), ud(2)
      call tie_frame(theta_s, x1, x2, c0, e, grad, s1, t, n)
      dv = v(4:5) - v(2:3)
      lambda = dot_product(t, dv)/s1
      omega = dot_product(n, dv)/s1
      u = -(omega*t + lambda*n)/s1
      ud = (4*omega*lambda*t + 2*(lambda**2 - omega**2)*n)/s1
      d2f = -kr*(2*omega*lambda*grad + 2*(v(1) - omega)*[0.0_dp, u, -u] + e*[0.0_dp, ud, -ud])
   end subroutine slide_tie_second_derivative

   !> Where the slave goes next along a slideline of `nelem` master elements in a chain
   !> (element i ends where element i + 1 starts). With alpha in [-tol, 1 + tol] it stays
   !> on `ielem` (slide_on_element); past an end of `ielem` it moves on to ielem - 1 or
   !> ielem + 1 (slide_moved), and past the ends of the chain it stays on `ielem` and
   !> reports slide_off_end. It moves one element per call: the caller recomputes alpha
   !> on `next` (slide_geometry) and calls again until slide_on_element or slide_off_end
   !> (at most nelem times). At a convex kink of the chain a slave may project outside
   !> both elements; the caller should not move back to the element it came from.
   pure subroutine slide_locate(alpha, ielem, nelem, next, status, tol)
      !> Coordinate (60) of the slave on its current master element.
      real(dp), intent(in) :: alpha
      !> Current master element, 1 to nelem along the slideline.
      integer, intent(in) :: ielem
      !> Number of master elements of the slideline.
      integer, intent(in) :: nelem
      !> The master element for the slave from now on.
      integer, intent(out) :: next
      !> slide_on_element, slide_moved or slide_off_end.
      integer, intent(out) :: status
      !> Hysteresis tolerance on alpha; default slide_hysteresis.
      real(dp), intent(in), optional :: tol
      real(dp) :: tol_
      tol_ = slide_hysteresis
      if (present(tol)) tol_ = tol
      next = ielem
      status = slide_on_element
      if (alpha < -tol_) then
         next = ielem - 1
      else if (alpha > 1 + tol_) then
         next = ielem + 1
      else
         return
      end if
      status = slide_moved
      if (next < 1 .or. next > nelem) then
         next = ielem
         status = slide_off_end
      end if
   end subroutine slide_locate

   !> Default penalty constant factor * max(S/L) over the elements a penalty
   !> spring couples (the master element and the slave's element), S their
   !> stiffness: EA for the gap spring k_p (force per length), EI for a
   !> prismatic joint's rotational tie k_r (moment per radian). Pass S = 0 for
   !> an absent element (a ground guide). Why this scale: at a converged
   !> kinematic configuration all forces vanish, so the gap is zero whatever
   !> k_p is, and k_p only affects the iteration. Too small a k_p makes the
   !> gap direction soft against the links, so Newton first strains the links
   !> and needs more iterations; too large a k_p dominates K - K^c and
   !> ill-conditions it. The stiffest stiffness it couples is the largest
   !> scale already present in K, so it adds no new one to the condition
   !> number; EI/L is likewise the scale of the beams' own rotational stiffness.
   pure function default_penalty(stiff_master, stiff_slave, l_master, l_slave, factor) result(kp)
      !> Stiffness (EA or EI) of the master element and of the slave's element.
      real(dp), intent(in) :: stiff_master, stiff_slave
      !> Lengths of the master element and of the slave's element.
      real(dp), intent(in) :: l_master, l_slave
      !> Factor on the stiffness; default 1.
      real(dp), intent(in), optional :: factor
      real(dp) :: kp
      kp = 0
      if (l_master > 0) kp = max(kp, stiff_master/l_master)
      if (l_slave > 0) kp = max(kp, stiff_slave/l_slave)
      if (present(factor)) kp = factor*kp
   end function default_penalty

end module fekap_contact_slideline
