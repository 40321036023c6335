!> What a step's result holds of an FEM configuration: the model's nodes and
!> links read off the mesh's dofs, and for VTK output the mesh-level fields
!> (every point, every element as a line cell with its link and stress
!> resultants).
module fekap_solver_fields
   use fekap_kinds, only: dp
   use fekap_model, only: model_type
   use fekap_model_results, only: step_result_type
   use fekap_assembly_mesh, only: mesh_type
   use fekap_element_beam, only: beam_resultants
   implicit none
   private

   public :: fill_nodes_links, fill_fields

contains

   !> Node positions, velocities, accelerations and link angles and rates of
   !> the configuration q with rates v, a.
   subroutine fill_nodes_links(mesh, model, q, v, a, result)
      type(mesh_type), intent(in) :: mesh
      type(model_type), intent(in) :: model
      real(dp), contiguous, intent(in) :: q(:), v(:), a(:)
      type(step_result_type), intent(inout) :: result
      integer :: i, k, dof
      do i = 1, size(model%nodes)
         do k = 1, 2
            dof = mesh%tdof(k, i)
            result%pos(k, i) = q(dof)
            result%vel(k, i) = v(dof)
            result%acc(k, i) = a(dof)
         end do
      end do
      if (model%output%mesh_nodes) then
         if (.not. allocated(result%interior)) allocate (result%interior(2, mesh%npoint - size(model%nodes)))
         do i = 1, size(result%interior, 2)
            result%interior(:, i) = q(mesh%tdof(:, size(model%nodes) + i))
         end do
      end if
      do i = 1, size(model%links)
         dof = mesh%link_rot(1, i)
         result%angle(i) = mesh%link_angle0(i) + q(dof)
         result%omega(i) = v(dof)
         result%alpha(i) = a(dof)
      end do
   end subroutine fill_nodes_links

   !> The mesh-level fields of the configuration q with rates v, a: point
   !> positions and rates, and each element's stress resultants (the cells,
   !> which do not change, on the first call).
   subroutine fill_fields(mesh, q, v, a, result)
      type(mesh_type), intent(in) :: mesh
      real(dp), contiguous, intent(in) :: q(:), v(:), a(:)
      type(step_result_type), intent(inout) :: result
      integer :: ip, e, k
      real(dp) :: xe(6)
      if (.not. allocated(result%mesh_pos)) then
         allocate (result%mesh_pos(2, mesh%npoint), result%mesh_vel(2, mesh%npoint), &
            & result%mesh_acc(2, mesh%npoint), result%cell_force(3, size(mesh%elements)))
         allocate (result%cells(2, size(mesh%elements)), result%cell_link(size(mesh%elements)))
         do e = 1, size(mesh%elements)
            result%cells(:, e) = mesh%dof_point(mesh%edof([1, 4], e))
            result%cell_link(e) = mesh%elink(e)
         end do
      end if
      do ip = 1, mesh%npoint
         result%mesh_pos(:, ip) = q(mesh%tdof(:, ip))
         result%mesh_vel(:, ip) = v(mesh%tdof(:, ip))
         result%mesh_acc(:, ip) = a(mesh%tdof(:, ip))
      end do
      do e = 1, size(mesh%elements)
         do k = 1, 6
            xe(k) = q(mesh%edof(k, e))
         end do
         result%cell_force(:, e) = beam_resultants(mesh%elements(e), xe)
      end do
   end subroutine fill_fields

end module fekap_solver_fields
