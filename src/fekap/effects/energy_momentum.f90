!> One step of the energy-momentum integrator (docs/dynamics.md): the
!> midpoint rule with the beams' discrete gradient (Simo & Tarnow, ZAMP 43,
!> 1992; Gonzalez, J. Nonlinear Sci. 6, 1996), unknown q1 = q_n+1,
!>   v1 = 2 (q1 - q0)/h - v0,                                 (q1 - q0 = h (v0 + v1)/2)
!>   R = M (v1 - v0)/h + alpha M (q1 - q0)/h + p(q0, q1) - (g(t_n) + g(t_n+1))/2 = 0,
!> on the free dofs, p the elements' discrete gradients
!> (fekap_element_discrete_gradient), Rayleigh's beta in them as the stress
!> beta/h D Delta eps (the dissipation chi + 2 beta/h). Contracted with q1 - q0 the free rows
!> give the energy balance of the step exactly:
!>   T1 - T0 + W1 - W0 + V1 - V0 = work of loads and drives - h alpha |v_mid|_M^2
!>     - sum (beta/h + chi/2) L |Delta eps|_D^2,
!> (V the gravity potential): chi = 0 conserves the energy, chi > 0 makes it
!> decay. The iteration matrix dR/dq1 = dp/dq1 + alpha M/h + 2 M/h^2 is not
!> symmetric: it is factored by LAPACK's band LU (dgbtrf) in its own storage.
module fekap_effects_energy_momentum
   use fekap_kinds, only: dp
   use fekap_assembly_mesh, only: mesh_type
   use fekap_assembly_lapack, only: band_lu_factor, band_lu_solve
   use fekap_element_discrete_gradient, only: beam_discrete_gradient
   use fekap_effects_dynamic_system, only: dynamic_system_type, times6
   implicit none
   private

   public :: em_system_type, new_em_system, em_dissipation, assemble_em, factor_em, solve_em
   public :: em_free_velocities, massless_dofs

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
   !> alpha M damps the mean rate (q1 - q0)/h), g0 and g1 the external forces
   !> at the step's ends; with `tangent`, the iteration matrix into self.
   subroutine assemble_em(self, dyn, mesh, q0, q1, v0, v1, g0, g1, h, chi, damped, r, tangent)
      type(em_system_type), intent(inout) :: self
      type(dynamic_system_type), intent(in) :: dyn
      type(mesh_type), intent(in) :: mesh
      real(dp), contiguous, intent(in) :: q0(:), q1(:), v0(:), v1(:), g0(:), g1(:)
      real(dp), intent(in) :: h, chi
      logical, intent(in) :: damped
      real(dp), contiguous, intent(out) :: r(:)
      logical, intent(in) :: tangent
      real(dp) :: x0(6), x1(6), am(6), vm(6), pe(6), ke(6, 6), c1, c2, chi_e
      integer :: e, i, j, ei, ej, d
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
            vm(i) = (x1(i) - x0(i))/h
         end do
         ! Rayleigh's beta damps the strain rate Delta eps / h: a stress beta/h D Delta eps in the
         ! discrete gradient, objective (zero for a rigid step) and of work beta/h L |Delta eps|_D^2.
         chi_e = chi
         if (damped) chi_e = chi + 2*dyn%beta(e)/h
         if (tangent) then
            call beam_discrete_gradient(mesh%elements(e), x0, x1, chi_e, pe, ke)
            ke = ke + (c2 + c1*dyn%alpha(e))*dyn%me(:, :, e)
         else
            call beam_discrete_gradient(mesh%elements(e), x0, x1, chi_e, pe)
         end if
         pe = pe + times6(dyn%me, e, am)
         if (damped) pe = pe + dyn%alpha(e)*times6(dyn%me, e, vm)
         do i = 1, 6
            d = mesh%edof(i, e)
            r(d) = r(d) + pe(i)
         end do
         if (.not. tangent) cycle
         do j = 1, 6
            ej = mesh%eq(mesh%edof(j, e))
            if (ej == 0) cycle
            do i = 1, 6
               ei = mesh%eq(mesh%edof(i, e))
               if (ei == 0) cycle
               self%ab(2*self%kd + 1 + ei - ej, ej) = self%ab(2*self%kd + 1 + ei - ej, ej) + ke(i, j)
            end do
         end do
      end do
      if (.not. tangent) return
      do i = 1, mesh%nfree
         d = mesh%eq_dof(i)
         self%ab(2*self%kd + 1, i) = self%ab(2*self%kd + 1, i) + c2*dyn%point_mass(d)
      end do
   end subroutine assemble_em

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

   !> The velocities v1 of the free dofs from the iterate q1 over a step of
   !> length h: v1 = 2 (q1 - q0)/h - v0 (the midpoint rule, which the energy
   !> balance needs on every dof with mass). A dof without mass has no
   !> equation for its velocity, and that recursion would carry any error of
   !> it on undamped (v1 + v0 = 2 vm); its velocity is the linear
   !> extrapolation of the last two steps' mean rates vm (vm_prev of the step
   !> of length h_prev before) to t_n+1 (second order), or 2 vm - v0 at the
   !> first step (h_prev = 0).
   pure subroutine em_free_velocities(mesh, massless, h, h_prev, q0, v0, vm_prev, q1, v1)
      type(mesh_type), intent(in) :: mesh
      logical, intent(in) :: massless(:)
      real(dp), intent(in) :: h, h_prev, q0(:), v0(:), vm_prev(:), q1(:)
      real(dp), intent(inout) :: v1(:)
      real(dp) :: vm
      integer :: k, d
      do k = 1, mesh%nfree
         d = mesh%eq_dof(k)
         vm = (q1(d) - q0(d))/h
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

end module fekap_effects_energy_momentum
