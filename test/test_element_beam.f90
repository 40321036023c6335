!> Tests of fekap_element_beam: tangent and second derivative against finite
!> differences, symmetry, rigid motions of any size; the sparse element
!> kernels against a straightforward dense reference of the same equations.
module test_element_beam
   use fekap_kinds, only: dp
   use fekap_testing, only: unittest_type, new_unittest, check, error_type, next_random
   use fekap_element_beam, only: beam_type, new_beam, beam_residual, beam_second_derivative, beam_max_strain, &
      & max_gauss
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
         & new_unittest('beam_max_strain', test_max_strain), &
         & new_unittest('beam_kernels_reference', test_kernels_reference) &
         & ]
   end subroutine collect_element_beam

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

   !> d2p[v, v] equals the central second difference of p along v; given
   !> the section angles that beam_residual found at xe, the same to the bit.
   subroutine test_second_derivative(error)
      type(error_type), allocatable, intent(out) :: error
      type(beam_type) :: beam
      real(dp) :: xe(6), v(6), d2p(6), pp(6), pm(6), p0(6), fd(6), d2s(6), section(2, max_gauss)
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
         section = 7
         call beam_residual(beam, xe, p0, section=section)
         call beam_second_derivative(beam, xe, v, d2s, section)
         call check(error, all(d2s == d2p), 'with the section angles of beam_residual: the same')
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

   !> The element kernels (which work on the few nonzeros of the B vectors)
   !> agree with a dense reference of (27)-(53) to round-off: residual,
   !> tangent with kg everywhere, nowhere and at strained Gauss points only,
   !> second derivative, largest strain.
   subroutine test_kernels_reference(error)
      type(error_type), allocatable, intent(out) :: error
      type(beam_type) :: beam
      real(dp) :: xe(6), v(6), p(6), k(6, 6), pr(6), kr(6, 6), d2p(6), d2r(6), above(3)
      real(dp), parameter :: tol = 1.0e-13_dp
      integer :: state, icase, j, ng
      character(len=64) :: label
      state = 31337
      do ng = 1, 2
         do icase = 1, 60
            call random_case(state, ng, beam, xe)
            do j = 1, 6
               v(j) = 2*next_random(state) - 1
            end do
            write (label, '(a,i0,a,i0)') 'gauss ', ng, ', case ', icase
            call beam_residual(beam, xe, p)
            call reference_residual(beam, xe, 0.0_dp, pr, kr)
            call check(error, maxval(abs(p - pr))/maxval(abs(pr)), 0.0_dp, 'residual, '//trim(label), abs=tol)
            ! Thresholds: kg everywhere, only where strained more than Gauss point 1
            ! (kg nowhere with one point), nowhere.
            above = [0.0_dp, reference_strain(beam, xe, 1)*(1 + 1.0e-9_dp), huge(1.0_dp)]
            do j = 1, 3
               call beam_residual(beam, xe, p, k, above(j))
               call reference_residual(beam, xe, above(j), pr, kr)
               call check(error, maxval(abs(p - pr))/maxval(abs(pr)), 0.0_dp, 'residual with tangent, '//trim(label), &
                  & abs=tol)
               call check(error, maxval(abs(k - kr))/maxval(abs(kr)), 0.0_dp, 'tangent, '//trim(label), abs=tol)
            end do
            call beam_second_derivative(beam, xe, v, d2p)
            call reference_second_derivative(beam, xe, v, d2r)
            call check(error, maxval(abs(d2p - d2r))/maxval(abs(d2r)), 0.0_dp, 'second derivative, '//trim(label), &
               & abs=tol)
            call check(error, beam_max_strain(beam, xe), &
               & max(reference_strain(beam, xe, 1), reference_strain(beam, xe, ng)), 'max strain, '//trim(label), &
               & rel=tol)
            if (allocated(error)) return
         end do
      end do
   end subroutine test_kernels_reference

   !> Strain state at Gauss point ig, dense: the map Bw from element dofs to
   !> w = (x1', x2', phi), strains (27), gradients and Hessians of Gamma1, Gamma2 in w.
   subroutine reference_point(beam, xe, ig, wl, bw, gam, grad, hess)
      type(beam_type), intent(in) :: beam
      real(dp), intent(in) :: xe(6)
      integer, intent(in) :: ig
      real(dp), intent(out) :: wl, bw(3, 6), gam(3), grad(3, 2), hess(3, 3, 2)
      real(dp) :: xi, n1, n2, a(2), phi, c, s
      xi = 0
      wl = beam%length
      if (beam%ngauss == 2) then
         xi = merge(-1, 1, ig == 1)/sqrt(3.0_dp)
         wl = beam%length/2
      end if
      n1 = (1 - xi)/2
      n2 = (1 + xi)/2
      bw = 0
      bw(1, 1) = -1/beam%length
      bw(1, 4) = 1/beam%length
      bw(2, 2) = -1/beam%length
      bw(2, 5) = 1/beam%length
      bw(3, 3) = n1
      bw(3, 6) = n2
      a = (xe(4:5) - xe(1:2))/beam%length
      phi = beam%angle + n1*xe(3) + n2*xe(6)
      c = cos(phi)
      s = sin(phi)
      gam = [c*a(1) + s*a(2) - 1, -s*a(1) + c*a(2), (xe(6) - xe(3))/beam%length]
      grad(:, 1) = [c, s, gam(2)]
      grad(:, 2) = [-s, c, -(1 + gam(1))]
      hess(:, :, 1) = reshape([0.0_dp, 0.0_dp, -s, 0.0_dp, 0.0_dp, c, -s, c, -(1 + gam(1))], [3, 3])
      hess(:, :, 2) = reshape([0.0_dp, 0.0_dp, -c, 0.0_dp, 0.0_dp, -s, -c, -s, -gam(2)], [3, 3])
   end subroutine reference_point

   !> Largest strain of Gauss point ig: |Gamma1|, |Gamma2|, |kappa| L.
   real(dp) function reference_strain(beam, xe, ig)
      type(beam_type), intent(in) :: beam
      real(dp), intent(in) :: xe(6)
      integer, intent(in) :: ig
      real(dp) :: wl, bw(3, 6), gam(3), grad(3, 2), hess(3, 3, 2)
      call reference_point(beam, xe, ig, wl, bw, gam, grad, hess)
      reference_strain = max(abs(gam(1)), abs(gam(2)), abs(gam(3))*beam%length)
   end function reference_strain

   !> p = sum wl (P b1 + V b2 + M bk) (38) and
   !> k = sum wl [EA b1 b1^T + kGA b2 b2^T + EI bk bk^T + Bw^T (P H1 + V H2) Bw] (43)-(44)
   !> as dense products, b_m = Bw^T grad Gamma_m; kg only where the strain exceeds `above`.
   subroutine reference_residual(beam, xe, above, p, k)
      type(beam_type), intent(in) :: beam
      real(dp), intent(in) :: xe(6), above
      real(dp), intent(out) :: p(6), k(6, 6)
      real(dp) :: wl, bw(3, 6), gam(3), grad(3, 2), hess(3, 3, 2), sig(3), b(6, 3), kg(3, 3), cs(3)
      integer :: ig, m
      cs = [beam%ea, beam%kga, beam%ei]
      p = 0
      k = 0
      do ig = 1, beam%ngauss
         call reference_point(beam, xe, ig, wl, bw, gam, grad, hess)
         sig = cs*gam
         b(:, 1) = matmul(grad(:, 1), bw)
         b(:, 2) = matmul(grad(:, 2), bw)
         b(:, 3) = [0.0_dp, 0.0_dp, -1/beam%length, 0.0_dp, 0.0_dp, 1/beam%length]
         do m = 1, 3
            p = p + wl*sig(m)*b(:, m)
            k = k + wl*cs(m)*spread(b(:, m), 2, 6)*spread(b(:, m), 1, 6)
         end do
         if (reference_strain(beam, xe, ig) > above) then
            kg = sig(1)*hess(:, :, 1) + sig(2)*hess(:, :, 2)
            k = k + wl*matmul(transpose(bw), matmul(kg, bw))
         end if
      end do
   end subroutine reference_residual

   !> d2p = sum wl sum_m [S_m Bw^T T_m + 2 C_m (b_m . v) Bw^T H_m vw + C_m (vw . H_m vw) b_m], vw = Bw v.
   subroutine reference_second_derivative(beam, xe, v, d2p)
      type(beam_type), intent(in) :: beam
      real(dp), intent(in) :: xe(6), v(6)
      real(dp), intent(out) :: d2p(6)
      real(dp) :: wl, bw(3, 6), gam(3), grad(3, 2), hess(3, 3, 2), sig(3), t3(3, 2), vw(3), bm(6), phi, c, s, vp
      real(dp) :: cs(3)
      integer :: ig, m
      cs = [beam%ea, beam%kga, beam%ei]
      d2p = 0
      do ig = 1, beam%ngauss
         call reference_point(beam, xe, ig, wl, bw, gam, grad, hess)
         sig = cs*gam
         vw = matmul(bw, v)
         vp = vw(3)
         phi = beam%angle + bw(3, 3)*xe(3) + bw(3, 6)*xe(6)
         c = cos(phi)
         s = sin(phi)
         t3(:, 1) = [-c*vp**2, -s*vp**2, -2*vp*(c*vw(1) + s*vw(2)) - gam(2)*vp**2]
         t3(:, 2) = [s*vp**2, -c*vp**2, 2*vp*(s*vw(1) - c*vw(2)) + (1 + gam(1))*vp**2]
         do m = 1, 2
            bm = matmul(grad(:, m), bw)
            d2p = d2p + wl*(sig(m)*matmul(t3(:, m), bw) &
               & + 2*cs(m)*dot_product(bm, v)*matmul(matmul(hess(:, :, m), vw), bw) &
               & + cs(m)*dot_product(vw, matmul(hess(:, :, m), vw))*bm)
         end do
      end do
   end subroutine reference_second_derivative

end module test_element_beam
