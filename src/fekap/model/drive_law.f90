!> Time laws of drives and loads: value, rate and second rate, all exact.
module fekap_model_drive_law
   use fekap_kinds, only: dp
   implicit none
   private

   public :: law_type, law_beyond, new_rate_law, new_harmonic_law, new_polynomial_law, new_table_law, new_constant_law, &
      & new_linear_law

   !> Law kinds; constant and linear (a piecewise-linear table) are taken by LOADs only.
   integer, parameter, public :: law_rate = 1, law_harmonic = 2, law_polynomial = 3, law_table = 4, &
      & law_constant = 5, law_linear = 6

   !> A time law f(t) with exact f'(t) and f''(t).
   type :: law_type
      !> law_rate, law_harmonic, law_polynomial, law_table, law_constant or law_linear.
      integer :: kind = 0
      !> rate: (omega, v0); harmonic: (mean, amplitude, omega, phase); polynomial: c0, c1, ...;
      !> constant: (value)
      real(dp), allocatable :: c(:)
      !> rate only: false when v0 was not given (the drive starts from the initial configuration).
      logical :: absolute = .true.
      !> table and linear: knots and values; table only: the natural cubic spline's second derivatives.
      real(dp), allocatable :: tt(:), tv(:), tm(:)
   contains
      procedure :: eval => law_eval
   end type law_type

contains

   !> f(t) = v0 + omega*t; without v0 the law is relative to the initial configuration.
   pure subroutine new_rate_law(self, omega, v0)
      type(law_type), intent(out) :: self
      real(dp), intent(in) :: omega
      real(dp), intent(in), optional :: v0
      self%kind = law_rate
      self%c = [omega, 0.0_dp]
      self%absolute = present(v0)
      if (present(v0)) self%c(2) = v0
   end subroutine new_rate_law

   !> f(t) = mean + amplitude*cos(omega*t + phase).
   pure subroutine new_harmonic_law(self, mean, amplitude, omega, phase)
      type(law_type), intent(out) :: self
      real(dp), intent(in) :: mean, amplitude, omega, phase
      self%kind = law_harmonic
      self%c = [mean, amplitude, omega, phase]
   end subroutine new_harmonic_law

   !> f(t) = c(1) + c(2)*t + c(3)*t**2 + ...
   pure subroutine new_polynomial_law(self, coeff)
      type(law_type), intent(out) :: self
      real(dp), intent(in) :: coeff(:)
      self%kind = law_polynomial
      self%c = coeff
   end subroutine new_polynomial_law

   !> f(t) = value.
   pure subroutine new_constant_law(self, value)
      type(law_type), intent(out) :: self
      real(dp), intent(in) :: value
      self%kind = law_constant
      self%c = [value]
   end subroutine new_constant_law

   !> Piecewise-linear through (t(i), v(i)), t strictly increasing, at least 2
   !> points; before the first point and after the last the end values hold
   !> (a hat function rises and falls back to a lasting zero).
   pure subroutine new_linear_law(self, t, v)
      type(law_type), intent(out) :: self
      real(dp), intent(in) :: t(:), v(:)
      self%kind = law_linear
      self%tt = t
      self%tv = v
   end subroutine new_linear_law

   !> Natural cubic spline through (t(i), v(i)); t strictly increasing, at least 2 points.
   pure subroutine new_table_law(self, t, v)
      type(law_type), intent(out) :: self
      real(dp), intent(in) :: t(:), v(:)
      integer :: n, i
      real(dp), allocatable :: diag(:), rhs(:)
      real(dp) :: h0, h1, w
      self%kind = law_table
      self%tt = t
      self%tv = v
      n = size(t)
      allocate (self%tm(n), source=0.0_dp)
      if (n < 3) return
      ! Tridiagonal system for the interior second derivatives (Thomas algorithm).
      allocate (diag(n), rhs(n), source=0.0_dp)
      do i = 2, n - 1
         h0 = t(i) - t(i - 1)
         h1 = t(i + 1) - t(i)
         diag(i) = 2*(h0 + h1)
         rhs(i) = 6*((v(i + 1) - v(i))/h1 - (v(i) - v(i - 1))/h0)
      end do
      do i = 3, n - 1
         w = (t(i) - t(i - 1))/diag(i - 1)
         diag(i) = diag(i) - w*(t(i) - t(i - 1))
         rhs(i) = rhs(i) - w*rhs(i - 1)
      end do
      do i = n - 1, 2, -1
         self%tm(i) = (rhs(i) - (t(i + 1) - t(i))*self%tm(i + 1))/diag(i)
      end do
   end subroutine new_table_law

   !> Whether the law at t is beyond the deck's numbers: its value, rate or
   !> second rate above 1e100 in magnitude, or not a number (a polynomial of
   !> high degree over a long span, a table interval of 1e-300).
   pure logical function law_beyond(self, t) result(beyond)
      type(law_type), intent(in) :: self
      real(dp), intent(in) :: t
      real(dp) :: f, df, ddf
      call self%eval(t, f, df, ddf)
      beyond = .not. (abs(f) <= 1.0e100_dp .and. abs(df) <= 1.0e100_dp .and. abs(ddf) <= 1.0e100_dp)
   end function law_beyond

   !> Value, rate and second rate of the law at time t.
   elemental subroutine law_eval(self, t, f, df, ddf)
      class(law_type), intent(in) :: self
      real(dp), intent(in) :: t
      real(dp), intent(out) :: f, df, ddf
      integer :: k, lo, hi
      real(dp) :: arg, h, a, b
      select case (self%kind)
      case (law_rate)
         f = self%c(2) + self%c(1)*t
         df = self%c(1)
         ddf = 0
      case (law_harmonic)
         arg = self%c(3)*t + self%c(4)
         f = self%c(1) + self%c(2)*cos(arg)
         df = -self%c(2)*self%c(3)*sin(arg)
         ddf = -self%c(2)*self%c(3)**2*cos(arg)
      case (law_polynomial)
         f = 0
         df = 0
         ddf = 0
         do k = size(self%c), 1, -1   ! Horner for the value and both derivatives
            ddf = ddf*t + 2*df
            df = df*t + f
            f = f*t + self%c(k)
         end do
      case (law_table)
         ! Locate the interval by bisection; outside the table the end cubic is extended.
         lo = knot_interval(self%tt, t)
         hi = lo + 1
         h = self%tt(hi) - self%tt(lo)
         a = (self%tt(hi) - t)/h
         b = (t - self%tt(lo))/h
         f = a*self%tv(lo) + b*self%tv(hi) + ((a**3 - a)*self%tm(lo) + (b**3 - b)*self%tm(hi))*h**2/6
         df = (self%tv(hi) - self%tv(lo))/h + (-(3*a**2 - 1)*self%tm(lo) + (3*b**2 - 1)*self%tm(hi))*h/6
         ddf = a*self%tm(lo) + b*self%tm(hi)
      case (law_constant)
         f = self%c(1)
         df = 0
         ddf = 0
      case (law_linear)
         ! Rate of the segment that t is in (at a knot, the one after it); 0 outside.
         ddf = 0
         if (t < self%tt(1)) then
            f = self%tv(1)
            df = 0
         else if (t >= self%tt(size(self%tt))) then
            f = self%tv(size(self%tv))
            df = 0
         else
            lo = knot_interval(self%tt, t)
            hi = lo + 1
            h = self%tt(hi) - self%tt(lo)
            b = (t - self%tt(lo))/h
            f = (1 - b)*self%tv(lo) + b*self%tv(hi)
            df = (self%tv(hi) - self%tv(lo))/h
         end if
      case default
         f = 0
         df = 0
         ddf = 0
      end select
   end subroutine law_eval

   !> The interval [tt(lo), tt(lo + 1)) of the increasing knots tt that t is
   !> in, by bisection: 1 before the second knot, size(tt) - 1 from the last
   !> but one on.
   pure integer function knot_interval(tt, t) result(lo)
      real(dp), intent(in) :: tt(:), t
      integer :: hi, i
      lo = 1
      hi = size(tt)
      do while (hi - lo > 1)
         i = (lo + hi)/2
         if (t >= tt(i)) then
            lo = i
         else
            hi = i
         end if
      end do
   end function knot_interval

end module fekap_model_drive_law
