!> Bad input for dynamics: a free motion with neither mass nor stiffness.
!> Generalized-alpha's Newton factors K + c1 C + c2 M; where the free dofs
!> can move without straining an element (a mechanism motion that the drives
!> and supports leave free) and without moving a mass, that matrix is
!> singular and nothing determines the motion. Both K (the material tangent)
!> and M (consistent element masses and point masses) are symmetric positive
!> semi-definite, so K + M is singular exactly when such a motion exists: this
!> check factors K/k + M/m (k, m their largest diagonal entries, so that
!> neither hides the other) over the free dofs and names the dof whose pivot
!> collapses. The dynamics stepper calls it at its initial configuration.
module fekap_dynamics_free_motion
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, input_error
   use fekap_model, only: model_type
   use fekap_assembly_mesh, only: mesh_type, describe_dof, dof_free, point_masses
   use fekap_linalg_band, only: band_matrix_type, new_band_matrix
   use fekap_assembly_assemble, only: assemble_tangent
   use fekap_element_inertia, only: beam_mass_matrix
   implicit none
   private

   public :: check_free_motion

   !> A pivot below this fraction of its diagonal entry is a collapse: the
   !> round-off of a singular matrix, far below any physical mass or stiffness ratio.
   real(dp), parameter :: collapse = 1.0e-12_dp

contains

   !> An input error when, at configuration q (time t, slideline segments
   !> seg), some free motion has neither mass nor stiffness (see the module's
   !> header); the message names a dof that takes part in it and what to do.
   subroutine check_free_motion(mesh, model, q, t, seg, error)
      type(mesh_type), intent(in) :: mesh
      type(model_type), intent(in) :: model
      real(dp), intent(in) :: q(:), t
      integer, intent(in) :: seg(:)
      type(error_type), allocatable, intent(out) :: error
      type(band_matrix_type) :: k, m
      real(dp), allocatable :: r(:), kfd(:, :), point_mass(:)
      real(dp) :: strain, k_scale, m_scale, me(6, 6), pivot, worst
      integer :: element, e, i, j, di, dj, info, weakest
      if (mesh%nfree == 0) return
      call new_band_matrix(k, mesh%nfree, mesh%kd, top=mesh%envelope)
      call new_band_matrix(m, mesh%nfree, mesh%kd, top=mesh%envelope)
      allocate (r(mesh%ndof), kfd(mesh%nfree, mesh%ndriven), point_mass(mesh%ndof), source=0.0_dp)
      call assemble_tangent(mesh, q, t, seg, r, k, kfd, huge(1.0_dp), strain, element)
      call m%zero()
      do e = 1, size(mesh%elements)
         associate (s => model%sections(model%links(mesh%elink(e))%section))
            me = beam_mass_matrix(mesh%elements(e)%length, s%rho_a, s%rho_i)
         end associate
         do j = 1, 6
            dj = mesh%edof(j, e)
            if (mesh%status(dj) /= dof_free) cycle
            do i = 1, 6
               di = mesh%edof(i, e)
               if (mesh%status(di) /= dof_free) cycle
               call m%add(mesh%eq(di), mesh%eq(dj), me(i, j))
            end do
         end do
      end do
      point_mass = point_masses(mesh, model)
      do i = 1, mesh%nfree
         call m%add(i, i, point_mass(mesh%eq_dof(i)))
      end do
      k_scale = maxval(abs(k%a(mesh%kd + 1, :)))
      m_scale = maxval(abs(m%a(mesh%kd + 1, :)))
      if (k_scale <= 0) k_scale = 1
      if (m_scale <= 0) m_scale = 1
      k%a = k%a/k_scale + m%a/m_scale
      call k%factor(info)
      weakest = info
      if (info == 0) then
         ! A positive but collapsed pivot is the round-off of a singular matrix.
         worst = huge(1.0_dp)
         do j = 1, k%n
            pivot = k%column_pivot(j)
            if (k%diag(j) > 0) pivot = pivot/k%diag(j)
            if (pivot < worst) then
               worst = pivot
               weakest = j
            end if
         end do
         if (worst >= collapse) return
      end if
      call input_error(error, model%file//': dynamics: '//describe_dof(mesh, model, mesh%eq_dof(weakest))// &
         & ' can move with neither mass nor stiffness (a free motion of the mechanism that carries no mass): '// &
         & 'give the links that move in it a density (rho= or rhoA= [rhoI=] on SECTions) or a mass '// &
         & '(MASSes), or hold the motion with a drive (DRIVes) or a support (SUPPorts)')
   end subroutine check_free_motion

end module fekap_dynamics_free_motion
