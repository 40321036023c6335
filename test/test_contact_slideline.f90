!> Tests of fekap_contact_slideline: geometry and its invariance, the contact force's
!> tangent and second derivative against central differences at random states
!> (master inclinations from horizontal to vertical), the rotational tie, the walk
!> along the slideline and the default penalties.
module test_contact_slideline
   use fekap_kinds, only: dp
   use fekap_testing, only: unittest_type, new_unittest, check, error_type
   use fekap_contact_slideline, only: slide_geometry, slide_force, slide_second_derivative, &
      & slide_tie_offset, slide_tie_force, slide_tie_second_derivative, slide_locate, &
      & default_penalty, default_tie_penalty, slide_on_element, slide_moved, slide_off_end
   implicit none
   private
   public :: collect_contact_slideline

   real(dp), parameter :: pi = 3.14159265358979323846264338327950288_dp
   !> Master inclinations tried besides random ones: horizontal, vertical (both ways), steep.
   real(dp), parameter :: betas(6) = [0.0_dp, pi/2, -pi/2, 89.99_dp*pi/180, pi, 2.3_dp]

contains

   subroutine collect_contact_slideline(tests)
      type(unittest_type), allocatable, intent(out) :: tests(:)
      tests = [ &
         & new_unittest('slide_geometry', test_geometry), &
         & new_unittest('slide_geometry_invariance', test_invariance), &
         & new_unittest('slide_force', test_force), &
         & new_unittest('slide_force_on_master', test_force_on_master), &
         & new_unittest('slide_second_derivative', test_second_derivative), &
         & new_unittest('slide_tie_force', test_tie_force), &
         & new_unittest('slide_tie_second_derivative', test_tie_second_derivative), &
         & new_unittest('slide_locate', test_locate), &
         & new_unittest('default_penalty', test_default_penalty) &
         & ]
   end subroutine collect_contact_slideline

   !> A reproducible stream of random numbers.
   subroutine seed_random()
      integer :: n, i
      call random_seed(size=n)
      call random_seed(put=[(20260 + 37*i, i=1, n)])
   end subroutine seed_random

   !> A random number in [a, b).
   function uniform(a, b) result(x)
      real(dp), intent(in) :: a, b
      real(dp) :: x
      call random_number(x)
      x = a + (b - a)*x
   end function uniform

   !> Random contact positions d = (xs, x1, x2): master of length in [0.5, 2] at angle beta
   !> through a random x1, slave at coordinate alpha in [-0.3, 1.3] and gap `gap`.
   function random_state(beta, gap) result(d)
      real(dp), intent(in) :: beta, gap
      real(dp) :: d(6), t(2), n(2), s1, alpha
      t = [cos(beta), sin(beta)]
      n = [-t(2), t(1)]
      s1 = uniform(0.5_dp, 2.0_dp)
      alpha = uniform(-0.3_dp, 1.3_dp)
      d(3:4) = [uniform(-3.0_dp, 3.0_dp), uniform(-3.0_dp, 3.0_dp)]
      d(5:6) = d(3:4) + s1*t
      d(1:2) = d(3:4) + alpha*s1*t + gap*n
   end function random_state

   !> Random velocities with entries in [-2, 2).
   function random_vector(n) result(v)
      integer, intent(in) :: n
      real(dp) :: v(n)
      call random_number(v)
      v = 4*v - 2
   end function random_vector

   !> Contact force at d = (xs, x1, x2).
   function force_at(d, kp) result(f)
      real(dp), intent(in) :: d(6), kp
      real(dp) :: f(6)
      call slide_force(d(1:2), d(3:4), d(5:6), kp, f)
   end function force_at

   function tangent_at(d, kp) result(k)
      real(dp), intent(in) :: d(6), kp
      real(dp) :: k(6, 6), f(6)
      call slide_force(d(1:2), d(3:4), d(5:6), kp, f, k)
   end function tangent_at

   !> Tie force at d = (theta_s, x1, x2).
   function tie_force_at(d, c0, kr) result(f)
      real(dp), intent(in) :: d(5), c0, kr
      real(dp) :: f(5)
      call slide_tie_force(d(1), d(2:3), d(4:5), c0, kr, f)
   end function tie_force_at

   function tie_tangent_at(d, c0, kr) result(k)
      real(dp), intent(in) :: d(5), c0, kr
      real(dp) :: k(5, 5), f(5)
      call slide_tie_force(d(1), d(2:3), d(4:5), c0, kr, f, k)
   end function tie_tangent_at

   !> got equals want within rel times the largest entry of want; names the worst entry.
   subroutine check_close(error, got, want, rel, what)
      type(error_type), allocatable, intent(inout) :: error
      real(dp), intent(in) :: got(:), want(:), rel
      character(*), intent(in) :: what
      integer :: i
      character(len=40) :: where
      if (allocated(error)) return
      i = maxloc(abs(got - want), 1)
      write (where, '(a,i0,a)') ' (entry ', i, ')'
      call check(error, got(i), want(i), what//trim(where), abs=rel*max(maxval(abs(want)), tiny(1.0_dp)))
   end subroutine check_close

   subroutine test_geometry(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: g, alpha, s1
      ! Horizontal master from (1, 1) to (5, 1); slave above it is to the left: g > 0.
      call slide_geometry([2.0_dp, 1.5_dp], [1.0_dp, 1.0_dp], [5.0_dp, 1.0_dp], g, alpha, s1)
      call check(error, s1, 4.0_dp)
      call check(error, g, 0.5_dp)
      call check(error, alpha, 0.25_dp)
      ! Reversed master: the same slave is now to the right, alpha measured from the other end.
      call slide_geometry([2.0_dp, 1.5_dp], [5.0_dp, 1.0_dp], [1.0_dp, 1.0_dp], g, alpha, s1)
      call check(error, g, -0.5_dp)
      call check(error, alpha, 0.75_dp)
      ! Vertical master upwards from the origin; slave at (-1, 3): left of it, beyond x2.
      call slide_geometry([-1.0_dp, 3.0_dp], [0.0_dp, 0.0_dp], [0.0_dp, 2.0_dp], g, alpha, s1)
      call check(error, g, 1.0_dp)
      call check(error, alpha, 1.5_dp)
      ! At the nodes.
      call slide_geometry([0.0_dp, 2.0_dp], [0.0_dp, 0.0_dp], [0.0_dp, 2.0_dp], g, alpha, s1)
      call check(error, g, 0.0_dp, abs=0.0_dp)
      call check(error, alpha, 1.0_dp)
   end subroutine test_geometry

   !> g and alpha do not change under a rigid rotation and translation of all three points.
   subroutine test_invariance(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: d(6), x(2, 3), q(2, 2), c(2), g0, a0, s0, g, alpha, s1, phi
      integer :: i, j
      call seed_random()
      do i = 1, 20
         d = random_state(uniform(-pi, pi), uniform(-1.0_dp, 1.0_dp))
         call slide_geometry(d(1:2), d(3:4), d(5:6), g0, a0, s0)
         phi = uniform(-pi, pi)
         q = reshape([cos(phi), sin(phi), -sin(phi), cos(phi)], [2, 2])
         c = [uniform(-10.0_dp, 10.0_dp), uniform(-10.0_dp, 10.0_dp)]
         do j = 1, 3
            x(:, j) = matmul(q, d(2*j - 1:2*j)) + c
         end do
         call slide_geometry(x(:, 1), x(:, 2), x(:, 3), g, alpha, s1)
         call check(error, g, g0, 'gap', abs=1.0e-12_dp)
         call check(error, alpha, a0, 'alpha', abs=1.0e-12_dp)
         call check(error, s1, s0, 'length', rel=1.0e-13_dp)
         if (allocated(error)) return
      end do
   end subroutine test_invariance

   !> f = -kp g N_s with the paper's (61); forces and moments balance; the tangent is the
   !> central difference of the force at random states, master inclinations included.
   subroutine test_force(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp), parameter :: kp = 250.0_dp, h = 1.0e-6_dp
      real(dp) :: d(6), dp_(6), f(6), k(6, 6), kfd(6, 6), g, alpha, s1, beta, ns(6), moment
      integer :: i, j
      call seed_random()
      do i = 1, 40
         beta = uniform(-pi, pi)
         if (i <= size(betas)) beta = betas(i)
         d = random_state(beta, uniform(-0.8_dp, 0.8_dp))
         call slide_force(d(1:2), d(3:4), d(5:6), kp, f, k)
         call slide_geometry(d(1:2), d(3:4), d(5:6), g, alpha, s1)
         ns = [-sin(beta), cos(beta), (1 - alpha)*sin(beta), -(1 - alpha)*cos(beta), &
            & alpha*sin(beta), -alpha*cos(beta)]
         call check_close(error, f, -kp*g*ns, 1.0e-12_dp, 'force (65)')
         call check(error, sum(f(1::2)), 0.0_dp, 'x forces balance', abs=1.0e-12_dp*kp)
         call check(error, sum(f(2::2)), 0.0_dp, 'y forces balance', abs=1.0e-12_dp*kp)
         moment = 0
         do j = 1, 3
            moment = moment + d(2*j - 1)*f(2*j) - d(2*j)*f(2*j - 1)
         end do
         call check(error, moment, 0.0_dp, 'moments balance', abs=1.0e-11_dp*kp)
         do j = 1, 6
            dp_ = d
            dp_(j) = d(j) + h
            kfd(:, j) = force_at(dp_, kp)
            dp_(j) = d(j) - h
            kfd(:, j) = (kfd(:, j) - force_at(dp_, kp))/(2*h)
         end do
         call check_close(error, reshape(k, [36]), reshape(kfd, [36]), 1.0e-7_dp, 'tangent (72)')
         call check_close(error, reshape(k, [36]), reshape(transpose(k), [36]), 1.0e-14_dp, 'symmetry')
         if (allocated(error)) return
      end do
   end subroutine test_force

   !> With the slave on the master (g = 0) the force and k_g (75) vanish: k = -kp N_s N_s^T.
   subroutine test_force_on_master(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp), parameter :: kp = 1.0e4_dp
      real(dp) :: d(6), f(6), k(6, 6), ns(6), g, alpha, s1, beta
      integer :: i, j
      ! Exactly representable points on the master: g is exactly zero.
      call slide_force([2.0_dp, 2.0_dp], [1.0_dp, 1.0_dp], [5.0_dp, 5.0_dp], kp, f, k)
      call check_close(error, f, [(0.0_dp, i=1, 6)], 0.0_dp, 'force')
      call seed_random()
      do i = 1, 20
         beta = uniform(-pi, pi)
         if (i <= size(betas)) beta = betas(i)
         d = random_state(beta, 0.0_dp)
         call slide_force(d(1:2), d(3:4), d(5:6), kp, f, k)
         call slide_geometry(d(1:2), d(3:4), d(5:6), g, alpha, s1)
         call check(error, abs(g) < 1.0e-14_dp, 'gap is round-off')
         call check(error, maxval(abs(f)) <= kp*1.0e-14_dp, 'force vanishes')
         ns = [-sin(beta), cos(beta), (1 - alpha)*sin(beta), -(1 - alpha)*cos(beta), &
            & alpha*sin(beta), -alpha*cos(beta)]
         call check_close(error, reshape(k, [36]), reshape(-kp*spread(ns, 2, 6)*spread(ns, 1, 6), [36]), &
            & 1.0e-13_dp, 'k = k_s (74)')
         if (allocated(error)) return
      end do
   end subroutine test_force_on_master

   !> d2f[v, v] equals the central second difference of the force and the central
   !> difference of k v, at random states with g /= 0 and g = 0.
   subroutine test_second_derivative(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp), parameter :: kp = 300.0_dp, h2 = 1.0e-4_dp, h1 = 1.0e-6_dp
      real(dp) :: d(6), v(6), d2f(6), fd2(6), fd1(6), beta, gap
      integer :: i
      call seed_random()
      do i = 1, 40
         beta = uniform(-pi, pi)
         if (i <= size(betas)) beta = betas(i)
         gap = merge(0.0_dp, uniform(-0.8_dp, 0.8_dp), mod(i, 2) == 0)
         d = random_state(beta, gap)
         v = random_vector(6)
         call slide_second_derivative(d(1:2), d(3:4), d(5:6), kp, v, d2f)
         fd2 = (force_at(d + h2*v, kp) - 2*force_at(d, kp) + force_at(d - h2*v, kp))/h2**2
         fd1 = matmul(tangent_at(d + h1*v, kp) - tangent_at(d - h1*v, kp), v)/(2*h1)
         call check_close(error, d2f, fd2, 1.0e-5_dp, 'second difference of f')
         call check_close(error, d2f, fd1, 1.0e-7_dp, 'difference of k v')
         if (allocated(error)) return
      end do
   end subroutine test_second_derivative

   !> The tie: zero in the initial configuration and under a rigid rotation of the slave
   !> link and the master together; tangent against central differences; a whole turn of
   !> the slave link changes nothing.
   subroutine test_tie_force(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp), parameter :: kr = 40.0_dp, h = 1.0e-6_dp
      real(dp) :: d(5), dp_(5), x1(2), x2(2), f(5), k(5, 5), kfd(5, 5), c0, theta, phi, q(2, 2), c(2)
      integer :: i, j
      call seed_random()
      do i = 1, 30
         theta = uniform(-pi, pi)
         x1 = [uniform(-2.0_dp, 2.0_dp), uniform(-2.0_dp, 2.0_dp)]
         phi = uniform(-pi, pi)
         if (i <= size(betas)) phi = betas(i)
         x2 = x1 + uniform(0.5_dp, 2.0_dp)*[cos(phi), sin(phi)]
         c0 = slide_tie_offset(theta, x1, x2)
         call slide_tie_force(theta, x1, x2, c0, kr, f)
         call check_close(error, f, [(0.0_dp, j=1, 5)], 0.0_dp, 'initial force')
         call check(error, maxval(abs(f)) <= 1.0e-13_dp*kr, 'no force initially')
         ! Rigid rotation by phi about c of everything: the slave link turns by phi too.
         phi = uniform(-pi, pi)
         q = reshape([cos(phi), sin(phi), -sin(phi), cos(phi)], [2, 2])
         c = [uniform(-5.0_dp, 5.0_dp), uniform(-5.0_dp, 5.0_dp)]
         call slide_tie_force(theta + phi, matmul(q, x1) + c, matmul(q, x2) + c, c0, kr, f)
         call check(error, maxval(abs(f)) <= 1.0e-12_dp*kr, 'no force under a rigid rotation')
         call slide_tie_force(theta + phi + 4*pi, matmul(q, x1) + c, matmul(q, x2) + c, c0, kr, f)
         call check(error, maxval(abs(f)) <= 1.0e-12_dp*kr, 'no force after two whole turns')
         ! Now strain it: turn the slave link alone and move the master nodes.
         d = [theta + uniform(-0.5_dp, 0.5_dp), x1 + 0.2_dp*random_vector(2), x2 + 0.2_dp*random_vector(2)]
         call slide_tie_force(d(1), d(2:3), d(4:5), c0, kr, f, k)
         call check(error, abs(sum(f(2::2))) + abs(sum(f(3::2))) <= 1.0e-13_dp*maxval(abs(f)), &
            & 'tie forces balance')
         call check(error, f(1) + d(2)*f(3) - d(3)*f(2) + d(4)*f(5) - d(5)*f(4), 0.0_dp, &
            & 'tie moments balance', abs=1.0e-12_dp*maxval(abs(f))*(1 + maxval(abs(d))))
         do j = 1, 5
            dp_ = d
            dp_(j) = d(j) + h
            kfd(:, j) = tie_force_at(dp_, c0, kr)
            dp_(j) = d(j) - h
            kfd(:, j) = (kfd(:, j) - tie_force_at(dp_, c0, kr))/(2*h)
         end do
         call check_close(error, reshape(k, [25]), reshape(kfd, [25]), 1.0e-7_dp, 'tie tangent')
         call check_close(error, reshape(k, [25]), reshape(transpose(k), [25]), 1.0e-14_dp, 'symmetry')
         if (allocated(error)) return
      end do
   end subroutine test_tie_force

   !> The tie's second directional derivative against differences, strained and free.
   subroutine test_tie_second_derivative(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp), parameter :: kr = 40.0_dp, h2 = 1.0e-4_dp, h1 = 1.0e-6_dp
      real(dp) :: d(5), v(5), d2f(5), fd2(5), fd1(5), c0, phi
      integer :: i
      call seed_random()
      do i = 1, 30
         phi = uniform(-pi, pi)
         if (i <= size(betas)) phi = betas(i)
         d(2:3) = [uniform(-2.0_dp, 2.0_dp), uniform(-2.0_dp, 2.0_dp)]
         d(4:5) = d(2:3) + uniform(0.5_dp, 2.0_dp)*[cos(phi), sin(phi)]
         d(1) = uniform(-pi, pi)
         c0 = slide_tie_offset(d(1), d(2:3), d(4:5))
         if (mod(i, 2) == 1) c0 = c0 + uniform(-0.5_dp, 0.5_dp)
         v = random_vector(5)
         call slide_tie_second_derivative(d(1), d(2:3), d(4:5), c0, kr, v, d2f)
         fd2 = (tie_force_at(d + h2*v, c0, kr) - 2*tie_force_at(d, c0, kr) + tie_force_at(d - h2*v, c0, kr))/h2**2
         fd1 = matmul(tie_tangent_at(d + h1*v, c0, kr) - tie_tangent_at(d - h1*v, c0, kr), v)/(2*h1)
         call check_close(error, d2f, fd2, 1.0e-5_dp, 'second difference of the tie force')
         call check_close(error, d2f, fd1, 1.0e-7_dp, 'difference of k v')
         if (allocated(error)) return
      end do
   end subroutine test_tie_second_derivative

   subroutine test_locate(error)
      type(error_type), allocatable, intent(out) :: error
      integer :: next, status
      ! Inside, and just outside within the hysteresis.
      call slide_locate(0.5_dp, 2, 3, next, status)
      call check(error, status, slide_on_element, 'inside')
      call check(error, next, 2, 'inside')
      call slide_locate(-1.0e-10_dp, 2, 3, next, status)
      call check(error, status, slide_on_element, 'hysteresis at 0')
      call slide_locate(1 + 1.0e-10_dp, 2, 3, next, status)
      call check(error, status, slide_on_element, 'hysteresis at 1')
      call check(error, next, 2, 'hysteresis at 1')
      ! Crossing forward and backward.
      call slide_locate(1.2_dp, 2, 3, next, status)
      call check(error, status, slide_moved, 'forward')
      call check(error, next, 3, 'forward')
      call slide_locate(-0.1_dp, 2, 3, next, status)
      call check(error, status, slide_moved, 'backward')
      call check(error, next, 1, 'backward')
      ! Off both ends of the chain.
      call slide_locate(1.01_dp, 3, 3, next, status)
      call check(error, status, slide_off_end, 'off the last element')
      call check(error, next, 3, 'off the last element keeps it')
      call slide_locate(-0.01_dp, 1, 3, next, status)
      call check(error, status, slide_off_end, 'off the first element')
      call check(error, next, 1, 'off the first element keeps it')
      call slide_locate(-0.01_dp, 1, 1, next, status)
      call check(error, status, slide_off_end, 'single element')
      ! A wider tolerance keeps it on.
      call slide_locate(1.01_dp, 3, 3, next, status, tol=0.02_dp)
      call check(error, status, slide_on_element, 'wider tolerance')
   end subroutine test_locate

   subroutine test_default_penalty(error)
      type(error_type), allocatable, intent(out) :: error
      call check(error, default_penalty(2.0e8_dp, 1.0e8_dp, 2.0_dp, 0.5_dp), 2.0e8_dp, 'slave stiffer')
      call check(error, default_penalty(6.0e8_dp, 1.0e8_dp, 2.0_dp, 0.5_dp), 3.0e8_dp, 'master stiffer')
      call check(error, default_penalty(0.0_dp, 1.0e8_dp, 0.0_dp, 0.5_dp), 2.0e8_dp, 'ground guide')
      call check(error, default_penalty(2.0e8_dp, 1.0e8_dp, 2.0_dp, 0.5_dp, factor=10.0_dp), 2.0e9_dp, 'scaled')
      call check(error, default_tie_penalty(3.0e4_dp, 1.0e4_dp, 1.5_dp, 1.0_dp), 2.0e4_dp, 'tie')
   end subroutine test_default_penalty

end module test_contact_slideline
