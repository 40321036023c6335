!> Tests of fekap_classical_constraints and fekap_classical_bodies: the
!> Jacobian Phi_q against central differences of Phi, the velocity
!> right-hand side against -Phi_t, and gamma against the second difference
!> of Phi along (q', 1), at configurations off the constraint manifold, for
!> welded bodies (Example 2), a moving slot (Example 5) and a ground guide.
module test_classical_constraints
   use fekap_kinds, only: dp
   use fekap_testing, only: unittest_type, new_unittest, check, test_failed, error_type
   use fekap_model, only: model_type
   use fekap_classical_constraints, only: constraint_system_type, new_constraint_system
   use classical_models, only: appendage_model, quick_return_model, slider_crank_model, peaucellier_model, &
      & double_crank_model, prismatic_slider_model, slider_drive_model
   implicit none
   private
   public :: collect_classical_constraints

contains

   subroutine collect_classical_constraints(tests)
      type(unittest_type), allocatable, intent(out) :: tests(:)
      tests = [ &
         & new_unittest('bodies_and_equations', test_counts), &
         & new_unittest('derivatives_appendage', test_appendage), &
         & new_unittest('derivatives_quick_return', test_quick_return), &
         & new_unittest('derivatives_slider_crank', test_slider_crank), &
         & new_unittest('derivatives_peaucellier', test_peaucellier), &
         & new_unittest('derivatives_prismatic', test_prismatic), &
         & new_unittest('derivatives_coordinate_drive', test_coordinate_drive) &
         & ]
   end subroutine collect_classical_constraints

   !> Bodies, coordinates and equations of the examples; the initial
   !> configuration satisfies every equation.
   subroutine test_counts(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(constraint_system_type) :: sys
      real(dp), allocatable :: phi(:)
      call appendage_model(model)
      call new_constraint_system(sys, model, error)
      if (allocated(error)) return
      call check(error, sys%bodies%nbody, 3, 'appendage bodies')
      call check(error, sys%m, 9, 'appendage equations')
      allocate (phi(sys%m))
      call sys%residual(sys%bodies%q0, 0.0_dp, phi)
      call check(error, maxval(abs(phi)), 0.0_dp, 'appendage initial residual', abs=1.0e-14_dp)
      ! The coupler body's reference point is the length-weighted centre of B-M, M-C and M-P.
      call check(error, sys%bodies%q0(4), (2*2.25_dp + 2*2.75_dp + 1.5_dp*(2.5_dp - 0.75_dp*sqrt(15.0_dp)/4)) &
         & /5.5_dp, 'coupler mass centre x')
      call check(error, sys%bodies%q0(6), atan2(sqrt(15.0_dp)/2, 0.5_dp), 'coupler angle is that of B-M')
      call double_crank_model(model)
      call new_constraint_system(sys, model, error)
      if (allocated(error)) return
      call check(error, sys%n, 12, 'double crank coordinates')
      call check(error, sys%m, 13, 'double crank equations')
      call quick_return_model(model)
      call new_constraint_system(sys, model, error)
      if (allocated(error)) return
      call check(error, sys%n, 9, 'quick return coordinates')
      call check(error, sys%m, 9, 'quick return equations')
      deallocate (phi)
      allocate (phi(sys%m))
      call sys%residual(sys%bodies%q0, 0.0_dp, phi)
      call check(error, maxval(abs(phi)), 0.0_dp, 'quick return initial residual', abs=1.0e-12_dp)
   end subroutine test_counts

   subroutine test_appendage(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      call appendage_model(model)
      call check_derivatives(error, model)
   end subroutine test_appendage

   subroutine test_quick_return(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      call quick_return_model(model)
      call check_derivatives(error, model)
   end subroutine test_quick_return

   subroutine test_slider_crank(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      call slider_crank_model(model)
      call check_derivatives(error, model)
   end subroutine test_slider_crank

   subroutine test_peaucellier(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      call peaucellier_model(model)
      call check_derivatives(error, model)
   end subroutine test_peaucellier

   subroutine test_prismatic(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      call prismatic_slider_model(model)
      call check_derivatives(error, model)
   end subroutine test_prismatic

   subroutine test_coordinate_drive(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      call slider_drive_model(model)
      call check_derivatives(error, model)
   end subroutine test_coordinate_drive

   !> At q = q0 + perturbation, with arbitrary rates q' and time t:
   !> Phi_q by central differences (worst entry reported), -Phi_t and gamma
   !> = -d2/ds2 Phi(q + s q', t + s) by differences.
   subroutine check_derivatives(error, model)
      type(error_type), allocatable, intent(inout) :: error
      type(model_type), intent(in) :: model
      type(constraint_system_type) :: sys
      real(dp), allocatable :: q(:), qd(:), jac(:, :), phip(:), phim(:), phi0(:), nu(:), gamma(:), fd(:)
      real(dp) :: h, t, worst, scale
      integer :: n, m, j, i, wi, wj
      character(len=80) :: where

      call new_constraint_system(sys, model, error)
      if (allocated(error)) return
      n = sys%n
      m = sys%m
      allocate (q(n), qd(n), jac(m, n), phip(m), phim(m), phi0(m), nu(m), gamma(m), fd(m))
      scale = maxval(abs(sys%bodies%q0))
      do j = 1, n
         q(j) = sys%bodies%q0(j) + 0.05_dp*scale*sin(1.7_dp*j)
         qd(j) = cos(0.9_dp*j + 0.3_dp)*merge(1.0_dp, scale, mod(j, 3) == 0)
      end do
      t = 0.37_dp
      call sys%jacobian(q, jac)
      h = 1.0e-6_dp
      worst = 0
      wi = 0
      wj = 0
      do j = 1, n
         q(j) = q(j) + h
         call sys%residual(q, t, phip)
         q(j) = q(j) - 2*h
         call sys%residual(q, t, phim)
         q(j) = q(j) + h
         fd = (phip - phim)/(2*h)
         do i = 1, m
            if (abs(fd(i) - jac(i, j)) > worst) then
               worst = abs(fd(i) - jac(i, j))
               wi = i
               wj = j
            end if
         end do
      end do
      if (worst > 1.0e-7_dp*max(1.0_dp, scale)) then
         write (where, '(a,es10.2,a,i0,a,i0,a)') 'Jacobian by differences: worst error ', worst, ' at (', wi, ', ', wj, ')'
         call test_failed(error, trim(where))
         return
      end if
      ! nu = -Phi_t.
      call sys%velocity_rhs(t, nu)
      call sys%residual(q, t + h, phip)
      call sys%residual(q, t - h, phim)
      fd = -(phip - phim)/(2*h)
      do i = 1, m
         call check(error, nu(i), fd(i), 'velocity right-hand side', abs=1.0e-7_dp)
      end do
      ! gamma = -d2/ds2 Phi(q + s q', t + s).
      call sys%acceleration_rhs(q, qd, t, gamma)
      h = 1.0e-4_dp
      call sys%residual(q + h*qd, t + h, phip)
      call sys%residual(q - h*qd, t - h, phim)
      call sys%residual(q, t, phi0)
      fd = -(phip - 2*phi0 + phim)/h**2
      do i = 1, m
         write (where, '(a,i0)') 'gamma of equation ', i
         call check(error, gamma(i), fd(i), trim(where), abs=1.0e-5_dp*max(1.0_dp, scale))
      end do
   end subroutine check_derivatives

end module test_classical_constraints
