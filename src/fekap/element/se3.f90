!> The Lie groups SO(3) and SE(3) as the spatial beam needs them: the
!> exponential and logarithm maps and their right-trivialised tangent
!> operators, in the convention of Sonneville, Cardona & Brüls, "Geometrically
!> exact beam finite element formulated on the special Euclidean group SE(3)",
!> CMAME 268 (2014) 451-474 (their eqs. (12)-(20), translation first):
!>
!>   a frame is H = (R, x); an se(3) vector is d = (U, W), U translational;
!>   exp(d) = (expSO3(W), T_SO3(W)^T U),   log(R, x) = (T_SO3^-1(W)^T x, W),
!>   exp(d)^-1 d/dt exp(d) = (T(d) d')^,
!>   T_SO3(W)    = I - a1 W^ + a2 W^2,          T_SO3^-1(W) = I + W^/2 + ci W^2,
!>   T(d)        = [T_SO3, T_UW; 0, T_SO3],     T^-1(d) = [Ti, -Ti T_UW Ti; 0, Ti],
!>   T_UW(U, W)  = -U^/2 + a2 (W^U^ + U^W^ - W^U^W^)
!>                 - b (W^W^U^ + U^W^W^ - 3 W^U^W^) + c (W^U^W^W^ + W^W^U^W^)
!>
!> (T_UW is Barfoot's Q(-U, -W)), with phi = |W| and
!>   s = sin(phi)/phi, a1 = (1 - cos phi)/phi^2, a2 = (phi - sin phi)/phi^3,
!>   b = (phi^2 + 2 cos phi - 2)/(2 phi^4), c = (2 phi - 3 sin phi + phi cos phi)/(2 phi^5),
!>   ci = (1 - (phi/2) cot(phi/2))/phi^2.
!> Below phi = 1 the coefficients come from their Taylor series (ci from the
!> Bernoulli series of x cot x): the closed forms cancel there (c loses
!> about 4 log10(1/phi) digits). The logarithm goes through the unit
!> quaternion of R, extracted by Shepperd's method (the largest of the four
!> pivots), so that it stays accurate up to phi = pi; it returns |W| <= pi.
!> T^-1 is singular at phi = 2 pi: it is meant for the relative motion inside
!> one element, which stays far from there, never for a total rotation.
module fekap_element_se3
   use fekap_kinds, only: dp
   implicit none
   private

   public :: hat, so3_exp, so3_log, so3_quaternion, so3_tangent, so3_tangent_inverse, so3_update
   public :: se3_exp, se3_log, se3_tangent, se3_tangent_inverse, se3_tangent_inverse_derivative
   public :: se3_tangent_inverse_directional
   public :: rotation_coefficients, so3_coefficients

   !> Below this angle the coefficients come from their series.
   real(dp), parameter :: series_below = 1

   !> The scalar functions of phi = |W| used by the maps, and the derivatives
   !> (d/dphi f)/phi of those that T^-1 depends on (for its derivative).
   type :: rotation_coefficients
      real(dp) :: phi = 0
      real(dp) :: s = 1, a1 = 0.5_dp, a2 = 1/6.0_dp, b = 1/24.0_dp, c = 1/120.0_dp, ci = 1/12.0_dp
      real(dp) :: da2 = 0, db = 0, dc = 0, dci = 0
   end type rotation_coefficients

   ! Series in x = phi^2, f = sum_m f_m x^m, m = 0 .. nterms - 1: every
   ! term below 1e-17 of the first at phi <= 1.
   integer, parameter :: nterms = 12

contains

   !> The skew matrix w^ with w^ v = w x v.
   pure function hat(w) result(a)
      real(dp), intent(in) :: w(3)
      real(dp) :: a(3, 3)
      a(:, 1) = [0.0_dp, w(3), -w(2)]
      a(:, 2) = [-w(3), 0.0_dp, w(1)]
      a(:, 3) = [w(2), -w(1), 0.0_dp]
   end function hat

   !> The coefficients at angle phi >= 0 (see the module's description).
   pure function so3_coefficients(phi) result(co)
      real(dp), intent(in) :: phi
      type(rotation_coefficients) :: co
      real(dp) :: x, sn, cs, h, dh
      real(dp) :: ks(nterms), ka1(nterms), ka2(nterms), kb(nterms), kc(nterms), kci(nterms)
      integer :: m
      co%phi = phi
      x = phi*phi
      if (phi < series_below) then
         do m = 0, nterms - 1
            ks(m + 1) = (-1)**m/factorial(2*m + 1)
            ka1(m + 1) = (-1)**m/factorial(2*m + 2)
            ka2(m + 1) = (-1)**m/factorial(2*m + 3)
            kb(m + 1) = (-1)**m/factorial(2*m + 4)
            kc(m + 1) = (-1)**m*(m + 1)/factorial(2*m + 5)
            kci(m + 1) = bernoulli_coefficient(m)
         end do
         co%s = series(ks, x)
         co%a1 = series(ka1, x)
         co%a2 = series(ka2, x)
         co%b = series(kb, x)
         co%c = series(kc, x)
         co%ci = series(kci, x)
         co%da2 = derivative_series(ka2, x)
         co%db = derivative_series(kb, x)
         co%dc = derivative_series(kc, x)
         co%dci = derivative_series(kci, x)
      else
         sn = sin(phi)
         cs = cos(phi)
         co%s = sn/phi
         co%a1 = (1 - cs)/x
         co%a2 = (phi - sn)/(x*phi)
         co%b = (x + 2*cs - 2)/(2*x*x)
         co%c = (2*phi - 3*sn + phi*cs)/(2*x*x*phi)
         ! h = (phi/2) cot(phi/2) = phi sin(phi) / (2 (1 - cos phi)).
         h = phi*sn/(2*(1 - cs))
         co%ci = (1 - h)/x
         ! (df/dphi)/phi from differentiating the closed forms.
         co%da2 = (co%a1 - 3*co%a2)/x
         co%db = (co%a2 - 4*co%b)/x
         co%dc = (co%a1 - co%s/2)/(x*x) - 5*co%c/x
         ! dh/dphi = cot(phi/2)/2 - (phi/4)/sin^2(phi/2) = h/phi - phi/(2 (1 - cos phi)).
         dh = h/phi - phi/(2*(1 - cs))
         co%dci = (-dh/phi - 2*co%ci)/x
      end if
   end function so3_coefficients

   !> n! as a real.
   pure real(dp) function factorial(n)
      integer, intent(in) :: n
      integer :: i
      factorial = 1
      do i = 2, n
         factorial = factorial*i
      end do
   end function factorial

   !> The coefficient of phi^(2m) in ci = (1 - (phi/2) cot(phi/2))/phi^2 =
   !> sum_(n>=1) |B_2n| phi^(2n-2) / (2n)!, B_2n the Bernoulli numbers.
   pure real(dp) function bernoulli_coefficient(m) result(k)
      integer, intent(in) :: m
      ! |B_2|, |B_4|, ..., |B_24|.
      real(dp), parameter :: b2n(12) = [1/6.0_dp, 1/30.0_dp, 1/42.0_dp, 1/30.0_dp, 5/66.0_dp, 691/2730.0_dp, &
         & 7/6.0_dp, 3617/510.0_dp, 43867/798.0_dp, 174611/330.0_dp, 854513/138.0_dp, 236364091/2730.0_dp]
      k = b2n(m + 1)/factorial(2*m + 2)
   end function bernoulli_coefficient

   !> sum_m k(m+1) x^m by Horner's rule.
   pure real(dp) function series(k, x) result(f)
      real(dp), intent(in) :: k(:), x
      integer :: m
      f = k(size(k))
      do m = size(k) - 1, 1, -1
         f = f*x + k(m)
      end do
   end function series

   !> (df/dphi)/phi of f = sum_m k(m+1) phi^(2m): sum_(m>=1) 2 m k(m+1) phi^(2m-2).
   pure real(dp) function derivative_series(k, x) result(f)
      real(dp), intent(in) :: k(:), x
      integer :: m
      f = 2*(size(k) - 1)*k(size(k))
      do m = size(k) - 1, 2, -1
         f = f*x + 2*(m - 1)*k(m)
      end do
   end function derivative_series

   !> The rotation matrix exp(w^) = I + s w^ + a1 w^2 (Rodrigues).
   pure function so3_exp(w) result(r)
      real(dp), intent(in) :: w(3)
      real(dp) :: r(3, 3)
      real(dp) :: wh(3, 3), phi, s, a1
      integer :: i, m
      ! Only s and a1: exp is taken at any angle (a driven revolute joint's
      ! total angle), where ci, singular at 2 pi, must not be evaluated.
      phi = norm2(w)
      if (phi < series_below) then
         s = 0
         a1 = 0
         do m = nterms - 1, 0, -1
            s = s*phi*phi + (-1)**m/factorial(2*m + 1)
            a1 = a1*phi*phi + (-1)**m/factorial(2*m + 2)
         end do
      else
         s = sin(phi)/phi
         a1 = (1 - cos(phi))/(phi*phi)
      end if
      wh = hat(w)
      r = s*wh + a1*matmul(wh, wh)
      do i = 1, 3
         r(i, i) = r(i, i) + 1
      end do
   end function so3_exp

   !> The unit quaternion (q0, q1, q2, q3), q0 >= 0, of a rotation matrix, by
   !> Shepperd's method: the largest of 1 + tr R and 1 + 2 R_ii - tr R is the
   !> square root taken, so no division by a small number.
   pure function so3_quaternion(r) result(q)
      real(dp), intent(in) :: r(3, 3)
      real(dp) :: q(0:3)
      real(dp) :: tr, piv(0:3), qi
      integer :: i, j, k
      tr = r(1, 1) + r(2, 2) + r(3, 3)
      piv = [tr, r(1, 1), r(2, 2), r(3, 3)]
      i = maxloc(piv, 1) - 1
      if (i == 0) then
         q(0) = sqrt(1 + tr)/2
         q(1) = (r(3, 2) - r(2, 3))/(4*q(0))
         q(2) = (r(1, 3) - r(3, 1))/(4*q(0))
         q(3) = (r(2, 1) - r(1, 2))/(4*q(0))
      else
         j = mod(i, 3) + 1
         k = mod(j, 3) + 1
         qi = sqrt(1 + 2*r(i, i) - tr)/2
         q(i) = qi
         q(0) = (r(k, j) - r(j, k))/(4*qi)
         q(j) = (r(j, i) + r(i, j))/(4*qi)
         q(k) = (r(k, i) + r(i, k))/(4*qi)
      end if
      if (q(0) < 0) q = -q
   end function so3_quaternion

   !> The rotation vector w, |w| <= pi, with exp(w^) = r: from the quaternion,
   !> angle 2 atan2(|qv|, q0), which is accurate at any angle.
   pure function so3_log(r) result(w)
      real(dp), intent(in) :: r(3, 3)
      real(dp) :: w(3)
      real(dp) :: q(0:3), sv
      q = so3_quaternion(r)
      sv = norm2(q(1:3))
      if (sv > 0) then
         w = q(1:3)*(2*atan2(sv, q(0))/sv)
      else
         w = 0
      end if
   end function so3_log

   !> r <- r exp(dtheta^): a body-frame increment, the update of every node
   !> frame. Products of rotation matrices drift from orthonormal linearly in
   !> their number, so each update ends with one Newton-Schulz step
   !> r <- r (3 I - r^T r)/2, which takes a deviation delta to O(delta^2):
   !> the frame stays orthonormal to round-off however many turns it makes.
   pure subroutine so3_update(r, dtheta)
      real(dp), intent(inout) :: r(3, 3)
      real(dp), intent(in) :: dtheta(3)
      real(dp) :: a(3, 3)
      integer :: i
      r = matmul(r, so3_exp(dtheta))
      a = -matmul(transpose(r), r)/2
      do i = 1, 3
         a(i, i) = a(i, i) + 1.5_dp
      end do
      r = matmul(r, a)
   end subroutine so3_update

   !> T_SO3(w) = I - a1 w^ + a2 w^2.
   pure function so3_tangent(w) result(t)
      real(dp), intent(in) :: w(3)
      real(dp) :: t(3, 3)
      type(rotation_coefficients) :: co
      co = so3_coefficients(norm2(w))
      t = tangent_of(w, co)
   end function so3_tangent

   pure function tangent_of(w, co) result(t)
      real(dp), intent(in) :: w(3)
      type(rotation_coefficients), intent(in) :: co
      real(dp) :: t(3, 3), wh(3, 3)
      integer :: i
      wh = hat(w)
      t = -co%a1*wh + co%a2*matmul(wh, wh)
      do i = 1, 3
         t(i, i) = t(i, i) + 1
      end do
   end function tangent_of

   !> T_SO3^-1(w) = I + w^/2 + ci w^2.
   pure function so3_tangent_inverse(w) result(t)
      real(dp), intent(in) :: w(3)
      real(dp) :: t(3, 3)
      type(rotation_coefficients) :: co
      co = so3_coefficients(norm2(w))
      t = inverse_of(w, co)
   end function so3_tangent_inverse

   pure function inverse_of(w, co) result(t)
      real(dp), intent(in) :: w(3)
      type(rotation_coefficients), intent(in) :: co
      real(dp) :: t(3, 3), wh(3, 3)
      integer :: i
      wh = hat(w)
      t = wh/2 + co%ci*matmul(wh, wh)
      do i = 1, 3
         t(i, i) = t(i, i) + 1
      end do
   end function inverse_of

   !> T_UW(U, W), the off-diagonal block of T(d).
   pure function coupling(u, w, co) result(t)
      real(dp), intent(in) :: u(3), w(3)
      type(rotation_coefficients), intent(in) :: co
      real(dp) :: t(3, 3), uh(3, 3), wh(3, 3), wu(3, 3), uw(3, 3), ww(3, 3), wuw(3, 3)
      uh = hat(u)
      wh = hat(w)
      wu = matmul(wh, uh)
      uw = matmul(uh, wh)
      ww = matmul(wh, wh)
      wuw = matmul(wu, wh)
      t = -uh/2 + co%a2*(wu + uw - wuw) - co%b*(matmul(ww, uh) + matmul(uh, ww) - 3*wuw) &
         & + co%c*(matmul(wuw, wh) + matmul(wh, wuw))
   end function coupling

   !> The derivative of T_UW(U, W) in the direction (du, dw).
   pure function coupling_derivative(u, w, du, dw, co) result(t)
      real(dp), intent(in) :: u(3), w(3), du(3), dw(3)
      type(rotation_coefficients), intent(in) :: co
      real(dp) :: t(3, 3)
      real(dp) :: uh(3, 3), wh(3, 3), wu(3, 3), uw(3, 3), ww(3, 3), wuw(3, 3)
      real(dp) :: duh(3, 3), dwh(3, 3), dwu(3, 3), duw(3, 3), dww(3, 3), dwuw(3, 3), wdw
      uh = hat(u)
      wh = hat(w)
      duh = hat(du)
      dwh = hat(dw)
      wu = matmul(wh, uh)
      uw = matmul(uh, wh)
      ww = matmul(wh, wh)
      wuw = matmul(wu, wh)
      dwu = matmul(dwh, uh) + matmul(wh, duh)
      duw = matmul(duh, wh) + matmul(uh, dwh)
      dww = matmul(dwh, wh) + matmul(wh, dwh)
      dwuw = matmul(dwu, wh) + matmul(wu, dwh)
      ! d phi = w . dw / phi: the coefficients' derivatives are (df/dphi)/phi.
      wdw = dot_product(w, dw)
      t = -duh/2 + co%da2*wdw*(wu + uw - wuw) + co%a2*(dwu + duw - dwuw) &
         & - co%db*wdw*(matmul(ww, uh) + matmul(uh, ww) - 3*wuw) &
         & - co%b*(matmul(dww, uh) + matmul(ww, duh) + matmul(duh, ww) + matmul(uh, dww) - 3*dwuw) &
         & + co%dc*wdw*(matmul(wuw, wh) + matmul(wh, wuw)) &
         & + co%c*(matmul(dwuw, wh) + matmul(wuw, dwh) + matmul(dwh, wuw) + matmul(wh, dwuw))
   end function coupling_derivative

   !> exp(d) = (R, x) = (expSO3(W), T_SO3(W)^T U).
   pure subroutine se3_exp(d, r, x)
      real(dp), intent(in) :: d(6)
      real(dp), intent(out) :: r(3, 3), x(3)
      type(rotation_coefficients) :: co
      co = so3_coefficients(norm2(d(4:6)))
      r = so3_exp(d(4:6))
      x = matmul(d(1:3), tangent_of(d(4:6), co))
   end subroutine se3_exp

   !> log(R, x) = (T_SO3^-1(W)^T x, W), W = log(R), |W| <= pi.
   pure function se3_log(r, x) result(d)
      real(dp), intent(in) :: r(3, 3), x(3)
      real(dp) :: d(6)
      type(rotation_coefficients) :: co
      d(4:6) = so3_log(r)
      co = so3_coefficients(norm2(d(4:6)))
      d(1:3) = matmul(x, inverse_of(d(4:6), co))
   end function se3_log

   !> T(d) = [T_SO3(W), T_UW(U, W); 0, T_SO3(W)].
   pure function se3_tangent(d) result(t)
      real(dp), intent(in) :: d(6)
      real(dp) :: t(6, 6)
      type(rotation_coefficients) :: co
      co = so3_coefficients(norm2(d(4:6)))
      t(1:3, 1:3) = tangent_of(d(4:6), co)
      t(4:6, 4:6) = t(1:3, 1:3)
      t(1:3, 4:6) = coupling(d(1:3), d(4:6), co)
      t(4:6, 1:3) = 0
   end function se3_tangent

   !> T^-1(d) = [Ti, -Ti T_UW Ti; 0, Ti], Ti = T_SO3^-1(W).
   pure function se3_tangent_inverse(d) result(t)
      real(dp), intent(in) :: d(6)
      real(dp) :: t(6, 6)
      type(rotation_coefficients) :: co
      co = so3_coefficients(norm2(d(4:6)))
      t(1:3, 1:3) = inverse_of(d(4:6), co)
      t(4:6, 4:6) = t(1:3, 1:3)
      t(1:3, 4:6) = -matmul(t(1:3, 1:3), matmul(coupling(d(1:3), d(4:6), co), t(1:3, 1:3)))
      t(4:6, 1:3) = 0
   end function se3_tangent_inverse

   !> The derivative of T^-1 at d in the direction dir: d/ds T^-1(d + s dir)
   !> at s = 0, by the product rule on [Ti, -Ti T_UW Ti; 0, Ti] (the
   !> convective term of the beam's strain rates).
   pure function se3_tangent_inverse_directional(d, dir) result(dt)
      real(dp), intent(in) :: d(6), dir(6)
      real(dp) :: dt(6, 6)
      type(rotation_coefficients) :: co
      co = so3_coefficients(norm2(d(4:6)))
      dt = directional_of(d, dir, co)
   end function se3_tangent_inverse_directional

   pure function directional_of(d, dir, co) result(dt)
      real(dp), intent(in) :: d(6), dir(6)
      type(rotation_coefficients), intent(in) :: co
      real(dp) :: dt(6, 6)
      real(dp) :: ti(3, 3), tuw(3, 3), dti(3, 3), dtuw(3, 3), wh(3, 3), dwh(3, 3)
      ti = inverse_of(d(4:6), co)
      tuw = coupling(d(1:3), d(4:6), co)
      wh = hat(d(4:6))
      dwh = hat(dir(4:6))
      ! d phi = w . dw / phi: the coefficients' derivatives are (df/dphi)/phi.
      dti = dwh/2 + co%dci*dot_product(d(4:6), dir(4:6))*matmul(wh, wh) + co%ci*(matmul(dwh, wh) + matmul(wh, dwh))
      dtuw = coupling_derivative(d(1:3), d(4:6), dir(1:3), dir(4:6), co)
      dt(1:3, 1:3) = dti
      dt(4:6, 4:6) = dti
      dt(4:6, 1:3) = 0
      dt(1:3, 4:6) = -matmul(dti, matmul(tuw, ti)) - matmul(ti, matmul(dtuw, ti)) - matmul(ti, matmul(tuw, dti))
   end function directional_of

   !> D = d/dd (T^-1(d)^T g) for a fixed g: the part of the beam's geometric
   !> tangent that comes from the strain-dependence of its compatibility
   !> operator. Column j is (dT^-1[e_j])^T g.
   pure function se3_tangent_inverse_derivative(d, g) result(dm)
      real(dp), intent(in) :: d(6), g(6)
      real(dp) :: dm(6, 6)
      type(rotation_coefficients) :: co
      real(dp) :: dir(6)
      integer :: j
      co = so3_coefficients(norm2(d(4:6)))
      do j = 1, 6
         dir = 0
         dir(j) = 1
         dm(:, j) = matmul(g, directional_of(d, dir, co))
      end do
   end function se3_tangent_inverse_derivative

end module fekap_element_se3
