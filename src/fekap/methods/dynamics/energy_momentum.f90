!> One step of the energy-momentum integrator (docs/dynamics.md): the
!> midpoint rule with the beams' discrete gradient (Simo & Tarnow, ZAMP 43,
!> 1992; Gonzalez, J. Nonlinear Sci. 6, 1996) and rotations updated by the
!> Cayley map (Simo, Tarnow & Doblare, IJNME 38, 1995), unknown q1 = q_n+1.
!> The step's increments z are Delta q on translations and psi = 2 tan(Delta theta/2)
!> on rotations (theta1 = theta0 + 2 atan(psi/2), em_increments), and
!>   v1 = 2 z/h - v0,                                          (z = h (v0 + v1)/2)
!>   R = M (v1 - v0)/h + alpha M z/h + p(q0, q1) - (g(t_n) + g(t_n+1))/2 = 0,
!> on the free dofs, p the elements' discrete gradients, conjugate to z
!> (fekap_element_discrete_gradient), Rayleigh's beta in them as the stress
!> beta/h D Delta eps (the dissipation chi + 2 beta/h), and the pin-in-slot
!> slidelines' (the penalty springs' on the step's segments,
!> fekap_contact_slide_gradient). Contracted with z the free rows give the
!> energy balance of the step exactly:
!>   T1 - T0 + W1 - W0 + V1 - V0 = work of loads and drives (on z) - h alpha |z/h|_M^2
!>     - sum (beta/h + chi/2) L |Delta eps|_D^2,
!> (V the gravity potential, on translations only): chi = 0 conserves the
!> energy, chi > 0 makes it decay. p has no net force and no net moment about
!> the mean configuration, so without loads linear and angular momentum are
!> kept exactly. The iteration matrix dR/dq1 = dp/dq1 + (alpha M/h + 2 M/h^2) dz/dq1
!> is not symmetric: it is factored by LAPACK's band LU (dgbtrf) in its own storage.
module fekap_dynamics_energy_momentum
   use fekap_kinds, only: dp
   use fekap_model, only: dof_rot
   use fekap_assembly_mesh, only: mesh_type
   use fekap_assembly_tracking, only: slide_position
   use fekap_contact_slide_gradient, only: slide_discrete_gradient
   use fekap_linalg_lapack, only: band_lu_factor, band_lu_solve
   use fekap_element_discrete_gradient, only: beam_discrete_gradient, cayley_increment
   use fekap_dynamics_dynamic_system, only: dynamic_system_type, times6
   implicit none
   private

   public :: em_system_type, new_em_system, em_dissipation, assemble_em, factor_em, solve_em
   public :: em_free_velocities, massless_dofs, em_increments

   !> The band LU storage of the free equations' iteration matrix.
   type :: em_system_type
      !> (2 kd + kd + 1, nfree): A(i, j) at ab(2 kd + 1 + i - j, j), rows 1:kd for the fill.
      real(dp), allocatable :: ab(:, :)
      integer, allocatable :: ipiv(:)
      integer :: kd = 0
   end type em_system_type

contains

   !> Storage for the mesh's free equations.
   subroutine new_em_system(self, mesh)
      type(em_system_type), intent(out) :: self
      type(mesh_type), intent(in) :: mesh
      self%kd = mesh%kd
      allocate (self%ab(3*mesh%kd + 1, mesh%nfree), source=0.0_dp)
      allocate (self%ipiv(mesh%nfree), source=0)
   end subroutine new_em_system

   !> The dissipation chi of the discrete gradient for rho_inf in [0, 1]:
   !> chi = (1 - rho)/(1 + rho), so that the strain branch of a linear
   !> oscillator's amplification tends to -rho as omega h grows (1: none).
   pure real(dp) function em_dissipation(rho_inf) result(chi)
      real(dp), intent(in) :: rho_inf
      chi = (1 - rho_inf)/(1 + rho_inf)
   end function em_dissipation

   !> The residual R of the step from (q0, v0) to q1 over all dofs into r
   !> (v1 given for every dof: on the constrained ones the prescribed motion;
   !> alpha M damps the mean rate z/h), g0 and g1 the external forces
   !> at the step's ends, z and dz = dz/dq1 the step's increments
   !> (em_increments at q1); with `tangent`, the iteration matrix into self
   !> (v1 = 2 z/h - v0 on the dofs with mass).
   subroutine assemble_em(self, dyn, mesh, q0, q1, v0, v1, g0, g1, z, dz, h, chi, seg, r, tangent)
      type(em_system_type), intent(inout) :: self
      type(dynamic_system_type), intent(in) :: dyn
      type(mesh_type), intent(in) :: mesh
      real(dp), contiguous, intent(in) :: q0(:), q1(:), v0(:), v1(:), g0(:), g1(:), z(:), dz(:)
      real(dp), intent(in) :: h, chi
      !> The slidelines' master segments of the step.
      integer, intent(in) :: seg(:)
      real(dp), contiguous, intent(out) :: r(:)
      logical, intent(in) :: tangent
      real(dp) :: x0(6), x1(6), am(6), vm(6), pe(6), ke(6, 6), c1, c2, chi_e
      integer :: e, i, j, d, dofs(6)
      c1 = 1/h
      c2 = 2/h**2
      r = dyn%point_mass*(v1 - v0)/h - 0.5_dp*(g0 + g1)
      if (tangent) self%ab = 0
      do e = 1, size(mesh%elements)
         do i = 1, 6
            d = mesh%edof(i, e)
            x0(i) = q0(d)
            x1(i) = q1(d)
            am(i) = (v1(d) - v0(d))/h
            vm(i) = z(d)/h
         end do
         ! Rayleigh's beta damps the strain rate Delta eps / h: a stress beta/h D Delta eps in the
         ! discrete gradient, objective (zero for a rigid step) and of work beta/h L |Delta eps|_D^2.
         chi_e = chi + 2*dyn%beta(e)/h
         if (tangent) then
            call beam_discrete_gradient(mesh%elements(e), x0, x1, chi_e, pe, ke)
            do j = 1, 6
               ! dv1/dq1 = 2/h dz/dq1: M and alpha M act on the columns' Cayley rates.
               ke(:, j) = ke(:, j) + (c2 + c1*dyn%alpha(e))*dz(mesh%edof(j, e))*dyn%me(:, j, e)
            end do
         else
            call beam_discrete_gradient(mesh%elements(e), x0, x1, chi_e, pe)
         end if
         pe = pe + times6(dyn%me, e, am)
         if (dyn%alpha(e) /= 0) pe = pe + dyn%alpha(e)*times6(dyn%me, e, vm)
         do i = 1, 6
            d = mesh%edof(i, e)
            r(d) = r(d) + pe(i)
         end do
         if (tangent) call add_general(self, mesh, mesh%edof(:, e), ke)
      end do
      do e = 1, size(mesh%slides)
         ! A ground guide's points have dof 0 (and the same place at q0, q1).
         call slide_position(mesh, mesh%slides(e), seg(e), q0, x0(1:2), x0(3:4), x0(5:6), dofs)
         call slide_position(mesh, mesh%slides(e), seg(e), q1, x1(1:2), x1(3:4), x1(5:6), dofs)
         if (tangent) then
            call slide_discrete_gradient(x0, x1, mesh%slides(e)%kp, pe, ke)
            call add_general(self, mesh, dofs, ke)
         else
            call slide_discrete_gradient(x0, x1, mesh%slides(e)%kp, pe)
         end if
         do i = 1, 6
            if (dofs(i) > 0) r(dofs(i)) = r(dofs(i)) + pe(i)
         end do
      end do
      if (.not. tangent) return
      do i = 1, mesh%nfree
         d = mesh%eq_dof(i)
         self%ab(2*self%kd + 1, i) = self%ab(2*self%kd + 1, i) + c2*dz(d)*dyn%point_mass(d)
      end do
   end subroutine assemble_em

   !> ke on the dofs `dofs` (0: none) into the free equations' band.
   pure subroutine add_general(self, mesh, dofs, ke)
      type(em_system_type), intent(inout) :: self
      type(mesh_type), intent(in) :: mesh
      integer, intent(in) :: dofs(6)
      real(dp), intent(in) :: ke(6, 6)
      integer :: i, j, ei, ej
      do j = 1, 6
         if (dofs(j) == 0) cycle
         ej = mesh%eq(dofs(j))
         if (ej == 0) cycle
         do i = 1, 6
            if (dofs(i) == 0) cycle
            ei = mesh%eq(dofs(i))
            if (ei == 0) cycle
            self%ab(2*self%kd + 1 + ei - ej, ej) = self%ab(2*self%kd + 1 + ei - ej, ej) + ke(i, j)
         end do
      end do
   end subroutine add_general

   !> The step's increments z over all dofs: q1 - q0 on translations, the
   !> Cayley form psi = 2 tan((q1 - q0)/2) on rotations; dz = dz/dq1.
   pure subroutine em_increments(mesh, q0, q1, z, dz)
      type(mesh_type), intent(in) :: mesh
      real(dp), intent(in) :: q0(:), q1(:)
      real(dp), intent(out) :: z(:)
      real(dp), intent(out), optional :: dz(:)
      real(dp) :: dpsi
      integer :: d
      do d = 1, size(q0)
         z(d) = q1(d) - q0(d)
         dpsi = 1
         if (mesh%dof_kind(d) == dof_rot) call cayley_increment(q1(d) - q0(d), z(d), dpsi)
         if (present(dz)) dz(d) = dpsi
      end do
   end subroutine em_increments

   !> LU factor of the assembled iteration matrix; info > 0: singular there.
   subroutine factor_em(self, info)
      type(em_system_type), intent(inout) :: self
      integer, intent(out) :: info
      call band_lu_factor(self%ab, self%kd, self%kd, self%ipiv, info)
   end subroutine factor_em

   !> Solve with the factor: b becomes the solution.
   subroutine solve_em(self, b, info)
      type(em_system_type), intent(in) :: self
      real(dp), contiguous, intent(inout) :: b(:)
      integer, intent(out) :: info
      call band_lu_solve(self%ab, self%kd, self%kd, self%ipiv, b, info)
   end subroutine solve_em

   !> The velocities v1 of the free dofs from the iterate's increments z
   !> (em_increments) over a step of length h: v1 = 2 z/h - v0 (the midpoint
   !> rule, which the energy balance needs on every dof with mass).
   !> A dof without mass has no equation for its velocity, and that recursion
   !> would carry any error of it on undamped (v1 + v0 = 2 vm); its velocity
   !> is the linear extrapolation of the last two steps' mean rates vm = z/h
   !> (vm_prev of the step of length h_prev before) to t_n+1 (second order),
   !> or 2 vm - v0 at the first step (h_prev = 0).
   pure subroutine em_free_velocities(mesh, massless, h, h_prev, v0, vm_prev, z, v1)
      type(mesh_type), intent(in) :: mesh
      logical, intent(in) :: massless(:)
      real(dp), intent(in) :: h, h_prev, v0(:), vm_prev(:), z(:)
      real(dp), intent(inout) :: v1(:)
      real(dp) :: vm
      integer :: k, d
      do k = 1, mesh%nfree
         d = mesh%eq_dof(k)
         vm = z(d)/h
         if (massless(d) .and. h_prev > 0) then
            v1(d) = vm + (vm - vm_prev(d))*h/(h + h_prev)
         else
            v1(d) = 2*vm - v0(d)
         end if
      end do
   end subroutine em_free_velocities

   !> The dofs whose row of the mass matrix (elements' and point masses) is zero.
   pure function massless_dofs(dyn, mesh) result(massless)
      type(dynamic_system_type), intent(in) :: dyn
      type(mesh_type), intent(in) :: mesh
      logical :: massless(mesh%ndof)
      real(dp) :: diagonal(mesh%ndof)
      integer :: e, i
      diagonal = dyn%point_mass
      do e = 1, size(mesh%elements)
         do i = 1, 6
            diagonal(mesh%edof(i, e)) = diagonal(mesh%edof(i, e)) + dyn%me(i, i, e)
         end do
      end do
      massless = diagonal == 0
   end function massless_dofs

end module fekap_dynamics_energy_momentum
