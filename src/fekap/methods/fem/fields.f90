!> What a step's result holds of an FEM configuration: the model's nodes and
!> links read off the mesh's dofs, and for VTK output the mesh-level fields
!> (every point, every element as a line cell with its link and stress
!> resultants).
module fekap_fem_fields
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
      integer :: i, k
      ! The nodes' coordinates are the mesh's first points' (tdof's first
      ! columns), gathered through explicit-shape arrays: the result's
      ! components written through their descriptors cost several times as
      ! much (each store could change a descriptor, reloaded for the next).
      call gather3(q, v, a, size(q), mesh%tdof, 1, 2*size(model%nodes), result%pos, result%vel, result%acc)
      if (model%output%mesh_nodes) then
         if (.not. allocated(result%interior)) allocate (result%interior(2, mesh%npoint - size(model%nodes)))
         do i = 1, size(result%interior, 2)
            result%interior(:, i) = q(mesh%tdof(:, size(model%nodes) + i))
         end do
      end if
      ! Each link's first end rotation (link_rot's first row) and its angle
      ! from the link's initial direction.
      call gather3(q, v, a, size(q), mesh%link_rot, 2, size(model%links), result%angle, result%omega, result%alpha)
      result%angle(:) = mesh%link_angle0(1:size(model%links)) + result%angle(:)
      if (.not. allocated(mesh%chord_links)) return
      do k = 1, size(mesh%chord_links)
         i = mesh%chord_links(k)
         call chord_angle(mesh, model, i, q, v, a, result%angle(i), result%omega(i), result%alpha(i))
      end do
   end subroutine fill_nodes_links

   !> x(i), y(i), z(i) = q(d), v(d), a(d) for d = dofs(1, i), i = 1..n (q,
   !> v, a of ndof values)
   !> (dofs(1, :) a row of an array of `stride` rows, or with stride 1 a
   !> whole array in its element order; x, y, z arrays of any rank).
   pure subroutine gather3(q, v, a, ndof, dofs, stride, n, x, y, z)
      integer, intent(in) :: ndof, stride, n
      real(dp), intent(in) :: q(ndof), v(ndof), a(ndof)
      integer, intent(in) :: dofs(stride, n)
      real(dp), intent(out) :: x(n), y(n), z(n)
      integer :: i
      do i = 1, n
         x(i) = q(dofs(1, i))
         y(i) = v(dofs(1, i))
         z(i) = a(dofs(1, i))
      end do
   end subroutine gather3

   !> The direction of link `l`'s chord (its first end node to its last) and
   !> its rates: theta = atan2(y, x) of the chord r = (x, y), theta' = (r x
   !> r')/|r|^2, theta'' = (r x r'')/|r|^2 - 2 (r . r') theta'/|r|^2. The
   !> angle is not wrapped: it is taken within pi of the mean of the link's
   !> end rotations (the chord's direction for a circular arc), so it follows
   !> the link round. A chord shrunk to nothing (a link rolled into a full
   !> circle) has no direction: the mean of the end rotations stands for it.
   pure subroutine chord_angle(mesh, model, l, q, v, a, angle, omega, alpha)
      type(mesh_type), intent(in) :: mesh
      type(model_type), intent(in) :: model
      integer, intent(in) :: l
      real(dp), intent(in) :: q(:), v(:), a(:)
      real(dp), intent(out) :: angle, omega, alpha
      !> A chord shorter than this fraction of the link's length has no direction.
      real(dp), parameter :: shortest = 1.0e-8_dp
      real(dp), parameter :: pi = acos(-1.0_dp)
      real(dp) :: r(2), dv(2), da(2), r2, mean, length
      integer :: n1, n2, rot1, rot2
      n1 = model%links(l)%node(1)
      n2 = model%links(l)%node(2)
      rot1 = mesh%link_rot(1, l)
      rot2 = mesh%link_rot(2, l)
      mean = mesh%link_angle0(l) + (q(rot1) + q(rot2))/2
      r = q(mesh%tdof(:, n2)) - q(mesh%tdof(:, n1))
      r2 = r(1)**2 + r(2)**2
      length = norm2(model%nodes(n2)%x - model%nodes(n1)%x)
      if (r2 <= (shortest*length)**2) then
         angle = mean
         omega = (v(rot1) + v(rot2))/2
         alpha = (a(rot1) + a(rot2))/2
         return
      end if
      dv = v(mesh%tdof(:, n2)) - v(mesh%tdof(:, n1))
      da = a(mesh%tdof(:, n2)) - a(mesh%tdof(:, n1))
      angle = mean + (modulo(atan2(r(2), r(1)) - mean + pi, 2*pi) - pi)
      omega = (r(1)*dv(2) - r(2)*dv(1))/r2
      alpha = (r(1)*da(2) - r(2)*da(1))/r2 - 2*(r(1)*dv(1) + r(2)*dv(2))*omega/r2
   end subroutine chord_angle

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

end module fekap_fem_fields
