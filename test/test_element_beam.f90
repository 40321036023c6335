!> Tests of fekap_element_beam: tangent and second derivative against finite
!> differences, symmetry, rigid motions of any size.
module test_element_beam
   use fekap_kinds, only: dp
   use fekap_testing, only: unittest_type, new_unittest, check, error_type
   use fekap_element_beam, only: beam_type, new_beam, beam_residual, beam_second_derivative, beam_max_strain
   implicit none
   private
   public :: collect_element_beam

contains

   subroutine collect_element_beam(tests)
      type(unittest_type), allocatable, intent(out) :: tests(:)
      tests = [ &
         & new_unittest('new_beam', test_new_beam), &
         & new_unittest('beam_residual_tangent', test_tangent), &
         & new_unittest('beam_residual_symmetry', test_symmetry), &
         & new_unittest('beam_residual_rigid_motion', test_rigid_motion), &
         & new_unittest('beam_residual_material_part', test_material_part), &
         & new_unittest('beam_second_derivative', test_second_derivative), &
         & new_unittest('beam_max_strain', test_max_strain) &
         & ]
   end subroutine collect_element_beam

   !> A reproducible pseudo-random number in [0, 1) (a linear congruential generator).
   real(dp) function next_random(state)
      integer, intent(inout) :: state
      state = modulo(state*16807, 2147483647)
      next_random = real(state, dp)/2147483647.0_dp
   end function next_random

   !> A random element (inclination in [-pi, pi], stiffnesses over decades) and
   !> a random deformed state of it.
   subroutine random_case(state, ngauss, beam, xe)
      integer, intent(inout) :: state
      integer, intent(in) :: ngauss
      type(beam_type), intent(out) :: beam
      real(dp), intent(out) :: xe(6)
      real(dp) :: x1(2), x2(2), pi
      integer :: i
      pi = acos(-1.0_dp)
      x1 = [next_random(state), next_random(state)]*4 - 2
      x2 = x1 + (0.5_dp + 2*next_random(state))*[cos(pi*(2*next_random(state) - 1)), &
         & sin(pi*(2*next_random(state) - 1))]
      call new_beam(beam, x1, x2, [10.0_dp**(4*next_random(state)), 10.0_dp**(4*next_random(state)), &
         & 10.0_dp**(2*next_random(state))], ngauss)
      xe = [x1, 0.0_dp, x2, 0.0_dp]
      do i = 1, 6
         xe(i) = xe(i) + 0.4_dp*(2*next_random(state) - 1)
      end do
      xe(3) = xe(3) + 8*(next_random(state) - 0.5_dp)      ! large rotations
      xe(6) = xe(3) + 0.6_dp*(next_random(state) - 0.5_dp)
   end subroutine random_case

   subroutine test_new_beam(error)
      type(error_type), allocatable, intent(out) :: error
      type(beam_type) :: beam
      call new_beam(beam, [1.0_dp, 1.0_dp], [1.0_dp, 3.0_dp], [1.0_dp, 2.0_dp, 3.0_dp], 1)
      call check(error, beam%length, 2.0_dp)
      call check(error, beam%angle, acos(-1.0_dp)/2)
   end subroutine test_new_beam

   subroutine test_tangent(error)
      type(error_type), allocatable, intent(out) :: error
      type(beam_type) :: beam
      real(dp) :: xe(6), p(6), k(6, 6), pp(6), pm(6), kfd(6, 6), xp(6), scale
      real(dp), parameter :: h = 1.0e-6_dp
      integer :: state, icase, j, ng
      character(len=64) :: label
      state = 12345
      do ng = 1, 2
         do icase = 1, 40
            call random_case(state, ng, beam, xe)
            call beam_residual(beam, xe, p, k)
            do j = 1, 6
               xp = xe
               xp(j) = xe(j) + h
               call beam_residual(beam, xp, pp)
               xp(j) = xe(j) - h
               call beam_residual(beam, xp, pm)
               kfd(:, j) = (pp - pm)/(2*h)
            end do
            scale = maxval(abs(k))
            write (label, '(a,i0,a,i0)') 'tangent vs central differences, gauss ', ng, ', case ', icase
            call check(error, maxval(abs(k - kfd))/scale, 0.0_dp, trim(label), abs=1.0e-7_dp)
            if (allocated(error)) return
         end do
      end do
   end subroutine test_tangent

   subroutine test_symmetry(error)
      type(error_type), allocatable, intent(out) :: error
      type(beam_type) :: beam
      real(dp) :: xe(6), p(6), k(6, 6)
      integer :: state, icase
      state = 777
      do icase = 1, 20
         call random_case(state, 1 + mod(icase, 2), beam, xe)
         call beam_residual(beam, xe, p, k)
         call check(error, maxval(abs(k - transpose(k)))/maxval(abs(k)), 0.0_dp, 'k = k^T', abs=1.0e-14_dp)
      end do
   end subroutine test_symmetry

   !> A rigid motion of any size, including rotations beyond 2*pi, leaves the
   !> element stress free: zero internal force to round-off.
   subroutine test_rigid_motion(error)
      type(error_type), allocatable, intent(out) :: error
      type(beam_type) :: beam
      real(dp) :: x1(2), x2(2), r(2, 2), rot, shift(2), xe(6), p(6), pi
      integer :: state, icase
      pi = acos(-1.0_dp)
      state = 4242
      do icase = 1, 30
         x1 = [next_random(state), next_random(state)]*10
         x2 = x1 + [3*next_random(state) - 1.5_dp, 3*next_random(state) - 1.5_dp]
         call new_beam(beam, x1, x2, [100.0_dp, 83.0_dp, 1.0_dp], 1 + mod(icase, 2))
         rot = 40*pi*(next_random(state) - 0.5_dp)
         shift = [next_random(state), next_random(state)]*100 - 50
         r = reshape([cos(rot), sin(rot), -sin(rot), cos(rot)], [2, 2])
         xe = [matmul(r, x1) + shift, rot, matmul(r, x2) + shift, rot]
         call beam_residual(beam, xe, p)
         call check(error, maxval(abs(p)), 0.0_dp, 'internal force of a rigid motion', abs=1.0e-10_dp)
         call check(error, beam_max_strain(beam, xe), 0.0_dp, 'strain of a rigid motion', abs=1.0e-12_dp)
      end do
   end subroutine test_rigid_motion

   !> With geometric_above above every strain the tangent is the material part:
   !> at a stress-free state it equals the full tangent; when stressed they
   !> differ by kg; with a threshold below the strain kg is back.
   subroutine test_material_part(error)
      type(error_type), allocatable, intent(out) :: error
      type(beam_type) :: beam
      real(dp) :: xe(6), p(6), k(6, 6), km(6, 6), rot
      call new_beam(beam, [0.0_dp, 0.0_dp], [2.0_dp, 1.0_dp], [100.0_dp, 83.0_dp, 1.0_dp], 1)
      rot = 1.3_dp
      xe = [0.0_dp, 0.0_dp, rot, 2*cos(rot) - sin(rot), 2*sin(rot) + cos(rot), rot]
      call beam_residual(beam, xe, p, k)
      call beam_residual(beam, xe, p, km, geometric_above=huge(1.0_dp))
      call check(error, maxval(abs(k - km)), 0.0_dp, 'stress free: k = km', abs=1.0e-12_dp)
      xe(4) = xe(4) + 0.1_dp
      call beam_residual(beam, xe, p, k)
      call beam_residual(beam, xe, p, km, geometric_above=huge(1.0_dp))
      call check(error, maxval(abs(k - km)) > 1.0e-3_dp, 'stressed: kg is not zero')
      if (allocated(error)) return
      ! The stretch 0.1 / 2.24 strains the element by about 0.045.
      call beam_residual(beam, xe, p, km, geometric_above=1.0e-2_dp)
      call check(error, maxval(abs(k - km)), 0.0_dp, 'strain above the threshold: kg kept', abs=1.0e-12_dp)
      if (allocated(error)) return
      call beam_residual(beam, xe, p, km, geometric_above=0.1_dp)
      call check(error, maxval(abs(k - km)) > 1.0e-3_dp, 'strain below the threshold: kg left out')
   end subroutine test_material_part

   !> d2p[v, v] equals the central second difference of p along v.
   subroutine test_second_derivative(error)
      type(error_type), allocatable, intent(out) :: error
      type(beam_type) :: beam
      real(dp) :: xe(6), v(6), d2p(6), pp(6), pm(6), p0(6), fd(6)
      real(dp), parameter :: h = 1.0e-4_dp
      integer :: state, icase, j
      state = 999
      do icase = 1, 40
         call random_case(state, 1 + mod(icase, 2), beam, xe)
         do j = 1, 6
            v(j) = 2*next_random(state) - 1
         end do
         call beam_second_derivative(beam, xe, v, d2p)
         call beam_residual(beam, xe + h*v, pp)
         call beam_residual(beam, xe, p0)
         call beam_residual(beam, xe - h*v, pm)
         fd = (pp - 2*p0 + pm)/h**2
         call check(error, maxval(abs(d2p - fd))/max(1.0_dp, maxval(abs(d2p))), 0.0_dp, &
            & 'second derivative vs second differences', abs=1.0e-5_dp)
         if (allocated(error)) return
      end do
   end subroutine test_second_derivative

   subroutine test_max_strain(error)
      type(error_type), allocatable, intent(out) :: error
      type(beam_type) :: beam
      call new_beam(beam, [0.0_dp, 0.0_dp], [2.0_dp, 0.0_dp], [1.0_dp, 1.0_dp, 1.0_dp], 1)
      ! Stretched by 10 %: Gamma1 = 0.1.
      call check(error, beam_max_strain(beam, [0.0_dp, 0.0_dp, 0.0_dp, 2.2_dp, 0.0_dp, 0.0_dp]), 0.1_dp, &
         & rel=1.0e-12_dp)
      ! Bent: kappa*L = 0.3.
      call check(error, beam_max_strain(beam, [0.0_dp, 0.0_dp, -0.15_dp, 2.0_dp, 0.0_dp, 0.15_dp]), 0.3_dp, &
         & rel=1.0e-12_dp)
   end subroutine test_max_strain

end module test_element_beam
