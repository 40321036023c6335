!> The two-node geometrically exact beam on SE(3) in relative-frame form
!> (Sonneville, Cardona & Brüls, CMAME 268 (2014), sections 4-5), and the
!> co-rotational truss, a two-force member for links between spherical joints.
!>
!> A node is a frame H = (R, x): a position in global axes and a rotation
!> matrix. Its increments are (dx, dtheta): dx added in global axes, dtheta a
!> body rotation, R <- R exp(dtheta^) (fekap_element_se3's so3_update). The
!> beam's deformation is the relative motion of its end frames,
!>   d = log(H_A^-1 H_B),  H_A^-1 H_B = (R_A^T R_B, R_A^T (x_B - x_A)),
!> constant along the element (the helicoidal interpolation of the paper's
!> eq. (40)), and its generalized strain e = d - d0, d0 the reference value;
!> the section strains are eps = e/L (axial and shear, torsion and bending,
!> in the axes of node A). With the section stiffness C in node axes,
!>   energy      = 1/2 e^T k e,  k = C/L,
!>   compatibility de = B dq,  B = P blockdiag(R_A^T, I, R_B^T, I),
!>                 P = [-T^-1(-d), T^-1(d)]       (paper eqs. (56)-(58)),
!>   internal force f = B^T k e,
!>   tangent     K = B^T k B  (material)
!>                 + blockdiag(R_A^T, I, R_B^T, I)^T [D(-d, g); D(d, g)] B
!>                 - (R_A (P^T g)_xA^, at (xA, thetaA); the same for B)  (geometric),
!> g = k e, D(d, g) = d/dd (T^-1(d)^T g) (fekap_element_se3). The geometric
!> part vanishes where the element is stress free (g = 0), which is every
!> kinematic configuration: there the material tangent is the exact one.
!> A rigid motion (Q, c) of both frames leaves H_A^-1 H_B, hence e, unchanged
!> (objectivity, by construction).
!>
!> The section is given as NASTRAN's CBAR gives it: stiffnesses
!> (EA, GA2, GA3, GJ, EI2, EI3) in the section axes (e1 along the beam from
!> A to B, e2 the part of an orientation vector v normal to e1, e3 = e1 x e2):
!> GA2, GA3 shear along e2, e3; GJ torsion about e1; EI2, EI3 bending about
!> e2, e3.
module fekap_element_se3_beam
   use fekap_kinds, only: dp
   use fekap_vectors, only: cross
   use fekap_error, only: error_type, input_error
   use fekap_element_se3, only: hat, se3_log, se3_tangent_inverse, se3_tangent_inverse_derivative, &
      & se3_tangent_inverse_directional
   implicit none
   private

   public :: se3_beam_type, new_se3_beam, se3_beam_strain, se3_beam_residual, se3_beam_resultants, se3_beam_convective
   public :: truss_type, new_truss, truss_residual, truss_convective

   !> Immutable definition of one beam element.
   type :: se3_beam_type
      !> Reference length.
      real(dp) :: length = 1
      !> Relative motion of the end frames in the reference configuration.
      real(dp) :: d0(6) = 0
      !> k = C/L in the axes of node A (6 x 6, symmetric), or the balanced
      !> weights of new_se3_beam.
      real(dp) :: k(6, 6) = 0
      !> Section axes (e1, e2, e3) as columns, in the axes of node A.
      real(dp) :: axes(3, 3) = 0
      !> The section stiffnesses (EA, GA2, GA3, GJ, EI2, EI3).
      real(dp) :: section(6) = 0
   end type se3_beam_type

   !> Immutable definition of one co-rotational truss element.
   type :: truss_type
      real(dp) :: length = 1
      real(dp) :: ea = 1
   end type truss_type

contains

   !> Element from its end frames in the reference configuration (x1, r1),
   !> (x2, r2), the section stiffnesses (EA, GA2, GA3, GJ, EI2, EI3) and the
   !> orientation vector v (global axes). Input errors: coincident ends, a
   !> stiffness not positive, v parallel to the beam.
   !>
   !> With balanced, k weighs the strains isotropically instead:
   !> k = (s/L) blockdiag(I, L^2 I), s = max(EA, GA2, GA3, GJ/L^2, EI2/L^2,
   !> EI3/L^2), a rotation strain counting as its displacement over the
   !> length (the section is kept for the resultants). The kinematic
   !> solution is the stress-free state, whatever the weights (every
   !> element's strain vanishes there), and so are its rates, but Newton's
   !> convergence and the rates' round-off are not: with the section's own
   !> k, spread over k_max/k_min, an iterate's stiff strains carry forces
   !> that the material tangent's soft part cannot balance, and Newton
   !> converges only from within about k_min/k_max of the solution
   !> (docs/spatial.md, the spread table).
   pure subroutine new_se3_beam(self, x1, r1, x2, r2, section, orientation, error, balanced)
      type(se3_beam_type), intent(out) :: self
      real(dp), intent(in) :: x1(3), r1(3, 3), x2(3), r2(3, 3), section(6), orientation(3)
      type(error_type), allocatable, intent(out) :: error
      logical, intent(in), optional :: balanced
      real(dp) :: e1(3), e2(3), lv, q(6, 6), s
      integer :: i
      self%length = norm2(x2 - x1)
      if (.not. self%length > 0) then
         call input_error(error, 'the two nodes of a beam coincide: give them distinct positions')
         return
      end if
      if (.not. all(section > 0)) then
         call input_error(error, 'every section stiffness (EA, GA2, GA3, GJ, EI2, EI3) must be positive')
         return
      end if
      e1 = (x2 - x1)/self%length
      e2 = orientation - dot_product(orientation, e1)*e1
      lv = norm2(orientation)
      if (.not. norm2(e2) > 1.0e-6_dp*lv) then
         call input_error(error, 'the orientation vector of a beam is zero or parallel to the beam: '// &
            & 'give a vector in the plane of the section axes 1 and 2, not along the beam')
         return
      end if
      e2 = e2/norm2(e2)
      ! Section axes in global axes, then in the axes of node A.
      self%axes(:, 1) = e1
      self%axes(:, 2) = e2
      self%axes(:, 3) = [e1(2)*e2(3) - e1(3)*e2(2), e1(3)*e2(1) - e1(1)*e2(3), e1(1)*e2(2) - e1(2)*e2(1)]
      self%axes = matmul(transpose(r1), self%axes)
      self%section = section
      self%d0 = se3_log(matmul(transpose(r1), r2), matmul(x2 - x1, r1))
      q = 0
      q(1:3, 1:3) = self%axes
      q(4:6, 4:6) = self%axes
      self%k = 0
      do i = 1, 6
         self%k(i, i) = section(i)/self%length
      end do
      self%k = matmul(q, matmul(self%k, transpose(q)))
      if (.not. present(balanced)) return
      if (.not. balanced) return
      s = max(maxval(section(1:3)), maxval(section(4:6))/self%length**2)
      self%k = 0
      do i = 1, 3
         self%k(i, i) = s/self%length
         self%k(i + 3, i + 3) = s*self%length
      end do
   end subroutine new_se3_beam

   !> The relative motion d = log(H_A^-1 H_B) of frames (x(:, n), r(:, :, n)), n = 1, 2.
   pure function relative_motion(x, r) result(d)
      real(dp), intent(in) :: x(3, 2), r(3, 3, 2)
      real(dp) :: d(6)
      d = se3_log(matmul(transpose(r(:, :, 1)), r(:, :, 2)), matmul(x(:, 2) - x(:, 1), r(:, :, 1)))
   end function relative_motion

   !> The generalized strain e = d - d0 (L times the section strains, node A's axes).
   pure function se3_beam_strain(self, x, r) result(e)
      type(se3_beam_type), intent(in) :: self
      real(dp), intent(in) :: x(3, 2), r(3, 3, 2)
      real(dp) :: e(6)
      e = relative_motion(x, r) - self%d0
   end function se3_beam_strain

   !> Internal force f (dofs dx_A, dtheta_A, dx_B, dtheta_B) and, if asked,
   !> the tangent k (material + geometric, or only the material part with
   !> material_only). Optionally the strain e and the compatibility matrix B.
   pure subroutine se3_beam_residual(self, x, r, f, k, material_only, strain, compatibility)
      type(se3_beam_type), intent(in) :: self
      real(dp), intent(in) :: x(3, 2), r(3, 3, 2)
      real(dp), intent(out) :: f(12)
      real(dp), intent(out), optional :: k(12, 12)
      logical, intent(in), optional :: material_only
      real(dp), intent(out), optional :: strain(6), compatibility(6, 12)
      real(dp) :: d(6), e(6), g(6), p(6, 12), b(6, 12), dg(12, 6), y(12)
      logical :: geometric
      integer :: n
      d = relative_motion(x, r)
      e = d - self%d0
      g = matmul(self%k, e)
      p(:, 1:6) = -se3_tangent_inverse(-d)
      p(:, 7:12) = se3_tangent_inverse(d)
      y = matmul(g, p)
      ! B = P blockdiag(R_A^T, I, R_B^T, I): de/dx_n = P_x R_n^T.
      b = p
      do n = 1, 2
         b(:, 6*n - 5:6*n - 3) = matmul(p(:, 6*n - 5:6*n - 3), transpose(r(:, :, n)))
      end do
      f = y
      do n = 1, 2
         f(6*n - 5:6*n - 3) = matmul(r(:, :, n), y(6*n - 5:6*n - 3))
      end do
      if (present(strain)) strain = e
      if (present(compatibility)) compatibility = b
      if (.not. present(k)) return
      k = matmul(transpose(b), matmul(self%k, b))
      geometric = .true.
      if (present(material_only)) geometric = .not. material_only
      if (.not. geometric) return
      ! d/dd (P^T g) = [D(-d, g); D(d, g)], then the rotations of the node axes.
      dg(1:6, :) = se3_tangent_inverse_derivative(-d, g)
      dg(7:12, :) = se3_tangent_inverse_derivative(d, g)
      do n = 1, 2
         dg(6*n - 5:6*n - 3, :) = matmul(r(:, :, n), dg(6*n - 5:6*n - 3, :))
      end do
      k = k + matmul(dg, b)
      ! f_x = R (P^T g)_x and R <- R exp(dtheta^): d f_x = -R (P^T g)_x^ dtheta.
      do n = 1, 2
         k(6*n - 5:6*n - 3, 6*n - 2:6*n) = k(6*n - 5:6*n - 3, 6*n - 2:6*n) &
            & - matmul(r(:, :, n), hat(y(6*n - 5:6*n - 3)))
      end do
   end subroutine se3_beam_residual

   !> The convective term of the strain's second rate: d^2 e/ds^2 at s = 0
   !> along the motion x_n(s) = x_n + s v_n, R_n(s) = R_n exp(s w_n + s^2/2 a_n)
   !> (v_n global, w_n and a_n body vectors of node n): the strain's
   !> acceleration less B times the nodes' accelerations. With the body
   !> velocities z = (R_A^T v_A, w_A, R_B^T v_B, w_B), d' = P z and
   !>   d/ds (P z) = dT^-1(-d)[d'] z_A + dT^-1(d)[d'] z_B + P z' + P (0, a_A, 0, a_B),
   !>   z_x' = -w x z_x   (R^T v in turning axes).
   pure function se3_beam_convective(x, r, v, w, a) result(c)
      real(dp), intent(in) :: x(3, 2), r(3, 3, 2), v(3, 2), w(3, 2), a(3, 2)
      real(dp) :: c(6)
      real(dp) :: d(6), z(12), zd(12), p(6, 12), dd(6)
      integer :: n
      d = relative_motion(x, r)
      p(:, 1:6) = -se3_tangent_inverse(-d)
      p(:, 7:12) = se3_tangent_inverse(d)
      do n = 1, 2
         z(6*n - 5:6*n - 3) = matmul(v(:, n), r(:, :, n))
         z(6*n - 2:6*n) = w(:, n)
         zd(6*n - 5:6*n - 3) = -cross(w(:, n), z(6*n - 5:6*n - 3))
         zd(6*n - 2:6*n) = a(:, n)
      end do
      dd = matmul(p, z)
      c = matmul(se3_tangent_inverse_directional(-d, dd), z(1:6)) &
         & + matmul(se3_tangent_inverse_directional(d, dd), z(7:12)) + matmul(p, zd)
   end function se3_beam_convective

   !> Section resultants (N, V2, V3, T, M2, M3) = C eps in the section axes.
   pure function se3_beam_resultants(self, x, r) result(sig)
      type(se3_beam_type), intent(in) :: self
      real(dp), intent(in) :: x(3, 2), r(3, 3, 2)
      real(dp) :: sig(6), e(6)
      e = se3_beam_strain(self, x, r)
      sig(1:3) = matmul(e(1:3), self%axes)
      sig(4:6) = matmul(e(4:6), self%axes)
      sig = self%section*sig/self%length
   end function se3_beam_resultants

   !> Truss between two points at distance length in the reference, axial stiffness ea.
   pure subroutine new_truss(self, x1, x2, ea, error)
      type(truss_type), intent(out) :: self
      real(dp), intent(in) :: x1(3), x2(3), ea
      type(error_type), allocatable, intent(out) :: error
      self%length = norm2(x2 - x1)
      if (.not. self%length > 0) then
         call input_error(error, 'the two nodes of a truss coincide: give them distinct positions')
         return
      end if
      if (.not. ea > 0) then
         call input_error(error, 'the axial stiffness EA of a truss must be positive')
         return
      end if
      self%ea = ea
   end subroutine new_truss

   !> The convective term of the truss's strain: d^2 e/ds^2 along x_n + s v_n,
   !> (|dv|^2 - (u . dv)^2)/l, dv = v_B - v_A.
   pure real(dp) function truss_convective(x, v) result(c)
      real(dp), intent(in) :: x(3, 2), v(3, 2)
      real(dp) :: a(3), dv(3), l
      a = x(:, 2) - x(:, 1)
      l = norm2(a)
      dv = v(:, 2) - v(:, 1)
      c = (dot_product(dv, dv) - (dot_product(a, dv)/l)**2)/l
   end function truss_convective

   !> Co-rotational truss: e = |x_B - x_A| - L, energy 1/2 (EA/L) e^2 over the
   !> translations (x_A, x_B) only: f = N (-u, u), N = (EA/L) e, u the unit
   !> axis; k = (EA/L) [u u^T] + (N/l) [I - u u^T] (blocks -/+ for unlike nodes).
   !> Its spin about its own axis has no dof: nothing to leave free.
   pure subroutine truss_residual(self, x, f, k, strain)
      type(truss_type), intent(in) :: self
      real(dp), intent(in) :: x(3, 2)
      real(dp), intent(out) :: f(6)
      real(dp), intent(out), optional :: k(6, 6)
      real(dp), intent(out), optional :: strain
      real(dp) :: a(3), l, u(3), n, kb(3, 3)
      integer :: i
      a = x(:, 2) - x(:, 1)
      l = norm2(a)
      u = a/l
      n = self%ea/self%length*(l - self%length)
      f(1:3) = -n*u
      f(4:6) = n*u
      if (present(strain)) strain = l - self%length
      if (.not. present(k)) return
      do i = 1, 3
         kb(:, i) = (self%ea/self%length - n/l)*u*u(i)
         kb(i, i) = kb(i, i) + n/l
      end do
      k(1:3, 1:3) = kb
      k(4:6, 4:6) = kb
      k(1:3, 4:6) = -kb
      k(4:6, 1:3) = -kb
   end subroutine truss_residual

end module fekap_element_se3_beam
