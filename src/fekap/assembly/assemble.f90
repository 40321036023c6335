!> Global assembly of the beam elements: internal force P(q) over all dofs,
!> the free-free tangent in band storage, the free-driven coupling block, and
!> the second directional derivative used by the acceleration analysis.
module fekap_assembly_assemble
   use fekap_kinds, only: dp
   use fekap_assembly_mesh, only: mesh_type
   use fekap_assembly_band, only: band_matrix_type
   use fekap_element_beam, only: beam_residual, beam_second_derivative, beam_max_strain
   implicit none
   private

   public :: assemble_residual, assemble_tangent, assemble_second_derivative, max_strain

contains

   !> r = P(q) - lambda f_ext over all dofs (reactions at fixed and driven dofs included).
   pure subroutine assemble_residual(mesh, q, lambda, r)
      type(mesh_type), intent(in) :: mesh
      real(dp), intent(in) :: q(:), lambda
      real(dp), intent(out) :: r(:)
      real(dp) :: pe(6)
      integer :: e
      r = -lambda*mesh%f_ext
      do e = 1, size(mesh%elements)
         call beam_residual(mesh%elements(e), q(mesh%edof(:, e)), pe)
         r(mesh%edof(:, e)) = r(mesh%edof(:, e)) + pe
      end do
   end subroutine assemble_residual

   !> Residual as assemble_residual, and the tangent: free-free part into the
   !> band matrix (equation order), free-driven part into kfd(eq, drive).
   pure subroutine assemble_tangent(mesh, q, lambda, r, kff, kfd)
      type(mesh_type), intent(in) :: mesh
      real(dp), intent(in) :: q(:), lambda
      real(dp), intent(out) :: r(:)
      type(band_matrix_type), intent(inout) :: kff
      real(dp), intent(out) :: kfd(:, :)
      real(dp) :: pe(6), ke(6, 6)
      integer :: e, i, j, ei, ej, dj
      r = -lambda*mesh%f_ext
      call kff%zero()
      kfd = 0
      do e = 1, size(mesh%elements)
         call beam_residual(mesh%elements(e), q(mesh%edof(:, e)), pe, ke)
         r(mesh%edof(:, e)) = r(mesh%edof(:, e)) + pe
         do j = 1, 6
            dj = mesh%edof(j, e)
            ej = mesh%eq(dj)
            do i = 1, 6
               ei = mesh%eq(mesh%edof(i, e))
               if (ei == 0) cycle
               if (ej > 0) then
                  call kff%add(ei, ej, ke(i, j))
               else if (mesh%drive_col(dj) > 0) then
                  kfd(ei, mesh%drive_col(dj)) = kfd(ei, mesh%drive_col(dj)) + ke(i, j)
               end if
            end do
         end do
      end do
   end subroutine assemble_tangent

   !> d2 = d^2 P / dq^2 [v, v] over all dofs (the velocity-dependent term of
   !> the acceleration equations (48)-(53)).
   pure subroutine assemble_second_derivative(mesh, q, v, d2)
      type(mesh_type), intent(in) :: mesh
      real(dp), intent(in) :: q(:), v(:)
      real(dp), intent(out) :: d2(:)
      real(dp) :: de(6)
      integer :: e
      d2 = 0
      do e = 1, size(mesh%elements)
         call beam_second_derivative(mesh%elements(e), q(mesh%edof(:, e)), v(mesh%edof(:, e)), de)
         d2(mesh%edof(:, e)) = d2(mesh%edof(:, e)) + de
      end do
   end subroutine assemble_second_derivative

   !> Largest element strain and the element where it occurs.
   pure subroutine max_strain(mesh, q, strain, element)
      type(mesh_type), intent(in) :: mesh
      real(dp), intent(in) :: q(:)
      real(dp), intent(out) :: strain
      integer, intent(out) :: element
      real(dp) :: s
      integer :: e
      strain = 0
      element = 0
      do e = 1, size(mesh%elements)
         s = beam_max_strain(mesh%elements(e), q(mesh%edof(:, e)))
         if (s > strain .or. element == 0) then
            strain = s
            element = e
         end if
      end do
   end subroutine max_strain

end module fekap_assembly_assemble
