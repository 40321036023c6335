!> The local error estimate of a dynamics step and the step length that
!> keeps it at a tolerance: the step's truncation error from its
!> accelerations (Zienkiewicz and Xie 1991), filtered through the step's
!> iteration matrix so that the stiff modes, which the integrator holds on
!> their slow manifold, do not count (Shampine 1980; Hulbert and Jang 1995
!> for generalized-alpha), and the standard controller of adaptive steps.
!>
!> The truncation error e (docs/dynamics.md "Local error estimate and
!> adaptive steps"). The exact motion from the step's start is
!> q(t0 + h) = q0 + h v0 + h^2/2 qdd0 + h^3/6 q''' + O(h^4), with
!> h q''' = qdd1 - qdd0 + O(h^2) (the accelerations at the step's ends).
!> - Generalized-alpha (fekap_dynamics_generalized_alpha) updates
!>   q1 = q0 + h v0 + h^2 ((1/2 - beta) a0 + beta a1), so
!>     e = h^2 ((1/2 - beta) a0 + beta a1 - qdd0/3 - qdd1/6).
!>   Once a is in step with the motion, a = qdd(t + (alpha_m - alpha_f) h)
!>   + O(h^2) (Chung-Hulbert (25); Arnold-Bruls), this is Zienkiewicz and
!>   Xie's (beta - 1/6 + (alpha_m - alpha_f)/2) h^3 q''' (alpha_error_constant).
!>   At the start a0 = qdd0, and there the constant is
!>   beta (1 - alpha_f)/(1 - alpha_m) - 1/6 (0.0905 at rho_inf 0.8, not 0.0864);
!>   the form above holds for both (and after a change of the step length).
!> - Energy-momentum's midpoint rule q1 = q0 + h/2 (v0 + v1) misses by
!>   (1/4 - 1/6) h^3 q''' = h^3 q'''/12; its step's acceleration is the mean
!>   (v1 - v0)/h, the acceleration at the step's middle, so consecutive means
!>   lie (h_prev + h)/2 apart (h/2 from the start's own acceleration):
!>     e = h^3 (abar1 - abar0) / (6 (h_prev + h)).
!>
!> The filter. Put the exact q(t0 + h) into the step's equations R(q) = 0
!> (R = M qdd(q) + D + P - F^c - g, qdd and qd functions of q through the
!> integrator, dR/dq = J the iteration matrix): its accelerations are off by
!> -c2 e and its velocities by -c1 e (c2 = dqdd/dq, c1 = dqd/dq), so
!> R(q(t0 + h)) = -(c2 M + c1 C) e + O(h^4), and the step's q1 misses
!> q(t0 + h) by
!>     e_f = J^-1 (c2 M + c1 C) e.                                    (F)
!> A mode of frequency omega (J = c2 M + c1 C + K) keeps c2/(c2 + omega^2)
!> of e (damping aside): 1 - O(omega^2 h^2) for the slow modes, and as
!> omega h grows the filter tends to the M-orthogonal projection onto the
!> slow modes, as the stiff link's constraint does to the step's error: the
!> change of a link's acceleration along its length (the centripetal part)
!> is in e but not in the step's error. Generalized-alpha:
!> J = K + c1 C + c2 M with c2 = (1 - alpha_m)/((1 - alpha_f) beta h^2),
!> c1 = gamma/(beta h); energy-momentum: J = dp/dq + C/h + 2 M/h^2, c2 = 2/h^2,
!> c1 = 1/h. C in (F) is Rayleigh's alpha M (beta K_m's and the dashpots'
!> share is left out: it would need a product with the tangent). J is the
!> factor the step's Newton solve holds at its end (generalized-alpha's may be
!> kept from an earlier iterate of the step: (F) to first order in the step's
!> motion), so the filter costs one solve, no factorisation.
!> e_f is the step's local error to leading order (the quotient of the two
!> tends to 1 as h shrinks); the terms of higher order change the true error
!> by up to a few tens of percent at the longest steps an adaptive run takes
!> (a step of 2e-2 s on a pendulum turning at 2.5 rad/s). The estimate is
!> bound_factor |e_f|, so that it bounds the step's error and is at most
!> three times it (docs/dynamics.md gives the measured range).
!> The estimate is the largest distance by which a point of the mesh misses
!> (|e_f| of its x and y; rotations are left out: an element's rotation moves
!> points by the element's length, not the model's, and the points' positions
!> carry the links' rotations).
module fekap_dynamics_local_error
   use fekap_kinds, only: dp
   use fekap_model, only: integrator_energy_momentum
   use fekap_assembly_mesh, only: mesh_type
   use fekap_fem_linear_system, only: solve_system
   use fekap_dynamics_generalized_alpha, only: alpha_coefficients_type, new_alpha_coefficients
   use fekap_dynamics_dynamic_system, only: dynamic_system_type, times6
   use fekap_dynamics_energy_momentum, only: solve_em
   use fekap_dynamics_dynamic_data, only: dynamic_data_type
   implicit none
   private

   public :: alpha_error_constant, alpha_local_error, midpoint_local_error, filter_right_side, largest_local_error
   public :: step_local_error, adapted_step

   !> The controller: the new step is h safety (tol/e)^(1/3) (local error
   !> ~ h^3), but never more than grow_most nor less than shrink_most times h.
   real(dp), parameter, public :: step_safety = 0.9_dp, grow_most = 2.0_dp, shrink_most = 0.2_dp
   !> The least adaptive step, relative to the run's span T1 - T0: a step
   !> that must be shorter to meet the tolerance ends the run (an error).
   real(dp), parameter, public :: least_step = 1.0e-12_dp
   !> The estimate is this times the leading term of the local error: a
   !> bound of the error, within a factor of three of it (see above).
   real(dp), parameter, public :: bound_factor = 2.0_dp

contains

   !> Generalized-alpha's constant of h^3 q''' in the local error of q once
   !> its acceleration variable is in step with the motion:
   !> |beta - 1/6 + (alpha_m - alpha_f)/2|.
   pure real(dp) function alpha_error_constant(c) result(k)
      type(alpha_coefficients_type), intent(in) :: c
      k = abs(c%beta - 1.0_dp/6 + 0.5_dp*(c%am - c%af))
   end function alpha_error_constant

   !> Generalized-alpha's truncation error of a step of length c%h whose
   !> accelerations and acceleration variables are acc0, a0 at its start and
   !> acc1, a1 at its end: h^2 ((1/2 - beta) a0 + beta a1 - acc0/3 - acc1/6).
   elemental real(dp) function alpha_local_error(c, acc0, a0, acc1, a1) result(e)
      type(alpha_coefficients_type), intent(in) :: c
      real(dp), intent(in) :: acc0, a0, acc1, a1
      e = c%h**2*((0.5_dp - c%beta)*a0 + c%beta*a1 - acc0/3 - acc1/6)
   end function alpha_local_error

   !> The midpoint rule's truncation error of a step of length h from the
   !> mean accelerations of the last step (h_prev long; h_prev 0: abar0 is
   !> the start's acceleration) and of this one: h^3 (abar1 - abar0)/(6 (h_prev + h)).
   elemental real(dp) function midpoint_local_error(h, h_prev, abar0, abar1) result(e)
      real(dp), intent(in) :: h, h_prev, abar0, abar1
      e = h**3/(6*(h + h_prev))*(abar1 - abar0)
   end function midpoint_local_error

   !> The right side of the filter (F): (c2 M + c1 alpha M) e over the free
   !> equations into b, e over all dofs (zero off the free ones). M is each
   !> element's consistent mass with its Rayleigh alpha, and the point masses
   !> (which the iteration matrix takes with c2 alone).
   pure subroutine filter_right_side(dyn, mesh, c2, c1, e, b)
      type(dynamic_system_type), intent(in) :: dyn
      type(mesh_type), intent(in) :: mesh
      real(dp), intent(in) :: c2, c1
      real(dp), intent(in) :: e(:)
      real(dp), intent(out) :: b(:)
      real(dp) :: y(size(e)), ee(6), fe(6)
      integer :: el, i
      y = c2*dyn%point_mass*e
      do el = 1, size(mesh%elements)
         do i = 1, 6
            ee(i) = e(mesh%edof(i, el))
         end do
         fe = (c2 + c1*dyn%alpha(el))*times6(dyn%me, el, ee)
         do i = 1, 6
            y(mesh%edof(i, el)) = y(mesh%edof(i, el)) + fe(i)
         end do
      end do
      do i = 1, mesh%nfree
         b(i) = y(mesh%eq_dof(i))
      end do
   end subroutine filter_right_side

   !> The largest distance by which a point misses (e over all dofs; tdof:
   !> each point's x and y dof), and the dof of its larger component (0 if
   !> there is no point).
   pure subroutine largest_local_error(e, tdof, estimate, dof)
      real(dp), intent(in) :: e(:)
      integer, intent(in) :: tdof(:, :)
      real(dp), intent(out) :: estimate
      integer, intent(out) :: dof
      integer :: ip
      real(dp) :: ep
      estimate = 0
      dof = 0
      do ip = 1, size(tdof, 2)
         ep = hypot(e(tdof(1, ip)), e(tdof(2, ip)))
         if (ep > estimate .or. dof == 0) then
            estimate = ep
            dof = tdof(merge(1, 2, abs(e(tdof(1, ip))) >= abs(e(tdof(2, ip)))), ip)
         end if
      end do
   end subroutine largest_local_error

   !> The local error estimate of the iterate's step of length h from the
   !> accepted state (generalized-alpha's or the midpoint rule's truncation
   !> error, filtered by (F) with the factor of the step's Newton solve) into
   !> try_estimate and try_estimate_dof. The iterate and the state are not
   !> changed; system%rhs (scratch between Newton solves) holds e_f after it.
   subroutine step_local_error(self, h)
      class(dynamic_data_type), intent(inout) :: self
      real(dp), intent(in) :: h
      real(dp) :: e(self%mesh%ndof), c1, c2
      type(alpha_coefficients_type) :: c
      integer :: k, d, info
      associate (state => self%state, mesh => self%mesh, b => self%system%rhs(:, 1))
         e = 0
         if (self%model%analysis%integrator == integrator_energy_momentum) then
            do k = 1, mesh%nfree
               d = mesh%eq_dof(k)
               e(d) = midpoint_local_error(h, self%h_prev, state%acc(d), self%acct(d))
            end do
            c2 = 2/h**2
            c1 = 1/h
         else
            c = new_alpha_coefficients(self%model%analysis%rho_inf, h)
            do k = 1, mesh%nfree
               d = mesh%eq_dof(k)
               e(d) = alpha_local_error(c, state%acc(d), state%a(d), self%acct(d), self%at(d))
            end do
            c2 = c%c2
            c1 = c%c1
         end if
         call filter_right_side(self%dynamics, mesh, c2, c1, e, b)
         if (self%model%analysis%integrator == integrator_energy_momentum) then
            call solve_em(self%em, b, info)
            ! The factor solved the step's corrections: it is regular (else unfiltered).
            if (info /= 0) b = e(mesh%eq_dof(1:mesh%nfree))
         else
            call solve_system(self%system, self%counts)
         end if
         ! e_f over all dofs (zero off the free ones).
         e = 0
         do k = 1, mesh%nfree
            e(mesh%eq_dof(k)) = b(k)
         end do
         call largest_local_error(e, mesh%tdof, self%try_estimate, self%try_estimate_dof)
         self%try_estimate = bound_factor*self%try_estimate
      end associate
   end subroutine step_local_error

   !> The step after one of length h with local error estimate e, for the
   !> tolerance tol: h safety (tol/e)^(1/3) within [shrink_most h, grow_most h].
   pure real(dp) function adapted_step(h, estimate, tol) result(h_new)
      real(dp), intent(in) :: h, estimate, tol
      real(dp) :: factor
      if (estimate*grow_most**3 <= tol*step_safety**3) then
         factor = grow_most
      else
         factor = min(grow_most, max(shrink_most, step_safety*(tol/estimate)**(1.0_dp/3)))
      end if
      h_new = h*factor
   end function adapted_step

end module fekap_dynamics_local_error
