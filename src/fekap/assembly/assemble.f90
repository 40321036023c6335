!> Global assembly of the residual R(q) = P(q) - F^c(q) - f(t): beam
!> internal forces P, slideline contact forces F^c (76), external loads at
!> time t (mesh%loads: the load factor t times f_ext, and loads with laws); its
!> tangent K - K^c (77) with the free-free part in band storage and the
!> free-driven block dense; and its second directional derivative, the
!> velocity term of the acceleration equations (48)-(53), (81)-(95).
module fekap_assembly_assemble
   use fekap_kinds, only: dp
   use fekap_model, only: joint_prismatic
   use fekap_assembly_mesh, only: mesh_type, slide_type
   use fekap_linalg_band, only: band_matrix_type
   use fekap_element_beam, only: beam_residual, add_beam_residuals, beam_second_derivative, beam_max_strain, max_gauss, &
      & section_values
   use fekap_assembly_tracking, only: slide_position
   use fekap_contact_slideline, only: slide_force, slide_second_derivative, slide_tie_force, &
      & slide_tie_second_derivative
   implicit none
   private

   public :: assemble_residual, assemble_tangent, assemble_drive_block
   public :: assemble_second_derivative, max_strain
   public :: gather, scatter, scatter_element, subtract

contains

   !> r = R(q) over all dofs (reactions at fixed and driven dofs included).
   !> seg(i) is the master segment slideline i is on. With `section`, each
   !> element's sections at q are kept (as assemble_tangent's): the
   !> square-root form's B at the same q takes their cosines and sines.
   pure subroutine assemble_residual(mesh, q, t, seg, r, section)
      type(mesh_type), intent(in) :: mesh
      !> The configuration and the time (of the loads).
      real(dp), contiguous, intent(in) :: q(:)
      real(dp), intent(in) :: t
      integer, intent(in) :: seg(:)
      real(dp), contiguous, intent(out) :: r(:)
      real(dp), intent(out), optional :: section(section_values, max_gauss, size(mesh%elements))
      call mesh%loads%at(t, r, negated=.true.)
      call add_beam_residuals(mesh%elements, mesh%edof, q, r, section)
      ! (No call without slidelines: its set-up cost more than the empty loop.)
      if (size(mesh%slides) > 0) call add_contact(mesh, q, seg, r)
   end subroutine assemble_residual

   !> Residual as assemble_residual, and the tangent dR/dq: free-free part into
   !> the band matrix (equation order), free-driven part into kfd(eq, drive).
   !> `geometric_above` leaves out the beams' geometric stiffness where they are
   !> strained less (see beam_residual; huge: the material tangent only, (46)).
   !> `strain` and `element` are max_strain's, found on the way.
   !> `section` keeps each element's section cosines and sines for
   !> assemble_second_derivative at the same q.
   pure subroutine assemble_tangent(mesh, q, t, seg, r, kff, kfd, geometric_above, strain, element, section)
      type(mesh_type), intent(in) :: mesh
      !> The configuration and the time (of the loads).
      real(dp), intent(in) :: q(:), t
      integer, intent(in) :: seg(:)
      real(dp), contiguous, intent(out) :: r(:)
      type(band_matrix_type), intent(inout) :: kff
      real(dp), contiguous, intent(out) :: kfd(:, :)
      real(dp), intent(in), optional :: geometric_above
      real(dp), intent(out) :: strain
      integer, intent(out) :: element
      real(dp), intent(out), optional :: section(section_values, max_gauss, size(mesh%elements))
      real(dp) :: pe(6), ke(6, 6), xe(6), s
      integer :: e, i
      call mesh%loads%at(t, r, negated=.true.)
      call kff%zero()
      kfd = 0
      strain = 0
      element = 0
      do e = 1, size(mesh%elements)
         do i = 1, 6
            xe(i) = q(mesh%edof(i, e))
         end do
         if (present(section)) then
            call beam_residual(mesh%elements(e), xe, pe, ke, geometric_above, s, section(:, :, e))
         else
            call beam_residual(mesh%elements(e), xe, pe, ke, geometric_above, s)
         end if
         if (s > strain .or. element == 0) then
            strain = s
            element = e
         end if
         do i = 1, 6
            r(mesh%edof(i, e)) = r(mesh%edof(i, e)) + pe(i)
         end do
         call scatter_element(mesh%scatter_map(:, mesh%scatter_start(e):), mesh%scatter_count(1, e), &
            & mesh%scatter_count(2, e), ke, kff%a, kfd)
      end do
      call add_contact(mesh, q, seg, r, kff, kfd)
   end subroutine assemble_tangent

   !> The residual as assemble_tangent's and, of the tangent, the free-driven
   !> block kfd alone: an element's tangent only where it has entries there
   !> (mesh%scatter_count(2, e) > 0), the same sums in the same order as
   !> assemble_tangent's kfd. What the square-root form needs of K at a
   !> configuration whose B_f it factors (K_fd scales the next step's
   !> residual test); `strain`, `element` and `section` as assemble_tangent's.
   pure subroutine assemble_drive_block(mesh, q, t, seg, r, kfd, geometric_above, strain, element, section)
      type(mesh_type), intent(in) :: mesh
      !> The configuration and the time (of the loads).
      real(dp), intent(in) :: q(:), t
      integer, intent(in) :: seg(:)
      real(dp), contiguous, intent(out) :: r(:)
      real(dp), contiguous, intent(out) :: kfd(:, :)
      real(dp), intent(in) :: geometric_above
      real(dp), intent(out) :: strain
      integer, intent(out) :: element
      real(dp), intent(out) :: section(section_values, max_gauss, size(mesh%elements))
      real(dp) :: pe(6), ke(6, 6), xe(6), s
      integer :: e, i
      call mesh%loads%at(t, r, negated=.true.)
      kfd = 0
      strain = 0
      element = 0
      do e = 1, size(mesh%elements)
         do i = 1, 6
            xe(i) = q(mesh%edof(i, e))
         end do
         if (mesh%scatter_count(2, e) > 0) then
            call beam_residual(mesh%elements(e), xe, pe, ke, geometric_above, s, section(:, :, e))
         else
            call beam_residual(mesh%elements(e), xe, pe, strain=s, section=section(:, :, e))
         end if
         if (s > strain .or. element == 0) then
            strain = s
            element = e
         end if
         do i = 1, 6
            r(mesh%edof(i, e)) = r(mesh%edof(i, e)) + pe(i)
         end do
         if (mesh%scatter_count(2, e) > 0) then
            call scatter_element_driven(mesh%scatter_map(:, mesh%scatter_start(e):), mesh%scatter_count(1, e), &
               & mesh%scatter_count(2, e), ke, kfd)
         end if
      end do
      if (size(mesh%slides) > 0) call add_contact(mesh, q, seg, r, kfd=kfd)
   end subroutine assemble_drive_block

   !> scatter_element's free-driven entries alone.
   pure subroutine scatter_element_driven(map, nb, nd, ke, driven)
      integer, intent(in) :: nb, nd, map(2, nb + nd)
      real(dp), intent(in) :: ke(36)
      real(dp), intent(inout) :: driven(*)
      integer :: m
      do m = nb + 1, nb + nd
         driven(map(2, m)) = driven(map(2, m)) + ke(map(1, m))
      end do
   end subroutine scatter_element_driven

   !> Add an element tangent through its precomputed lists of destinations
   !> (see mesh_type%scatter_map): nb entries into the band storage, then nd
   !> into the free-driven block, each array taken in memory order (one index
   !> per entry instead of a row and a column).
   pure subroutine scatter_element(map, nb, nd, ke, band, driven)
      integer, intent(in) :: nb, nd, map(2, nb + nd)
      real(dp), intent(in) :: ke(36)
      !> The band storage, (kd + 1) * nfree, and the free-driven block, nfree * ndriven.
      real(dp), intent(inout) :: band(*), driven(*)
      integer :: m
      do m = 1, nb
         band(map(2, m)) = band(map(2, m)) + ke(map(1, m))
      end do
      do m = nb + 1, nb + nd
         driven(map(2, m)) = driven(map(2, m)) + ke(map(1, m))
      end do
   end subroutine scatter_element

   !> Add ke on the dofs `dofs` (0: no dof, a fixed ground point) to the
   !> free-free band and the free-driven block; ke symmetric, or with
   !> `general` any ke (band_add_general: both triangles of the band).
   pure subroutine scatter(mesh, dofs, ke, kff, kfd, general)
      type(mesh_type), intent(in) :: mesh
      integer, intent(in) :: dofs(:)
      real(dp), intent(in) :: ke(:, :)
      type(band_matrix_type), intent(inout) :: kff
      real(dp), intent(inout) :: kfd(:, :)
      logical, intent(in), optional :: general
      integer :: i, j, ei, ej, dj
      logical :: any_entry
      any_entry = .false.
      if (present(general)) any_entry = general
      do j = 1, size(dofs)
         dj = dofs(j)
         if (dj == 0) cycle
         ej = mesh%eq(dj)
         do i = 1, size(dofs)
            if (dofs(i) == 0) cycle
            ei = mesh%eq(dofs(i))
            if (ei == 0) cycle
            if (ej > 0 .and. any_entry) then
               call kff%add_general(ei, ej, ke(i, j))
            else if (ej > 0) then
               call kff%add(ei, ej, ke(i, j))
            else if (mesh%drive_col(dj) > 0) then
               kfd(ei, mesh%drive_col(dj)) = kfd(ei, mesh%drive_col(dj)) + ke(i, j)
            end if
         end do
      end do
   end subroutine scatter

   !> r -= F^c and, when given, K -= K^c: the gap springs (65), (72) and the
   !> rotational ties of prismatic joints. With kfd alone, its part of K^c
   !> alone (scatter_driven).
   pure subroutine add_contact(mesh, q, seg, r, kff, kfd)
      type(mesh_type), intent(in) :: mesh
      real(dp), intent(in) :: q(:)
      integer, intent(in) :: seg(:)
      real(dp), intent(inout) :: r(:)
      type(band_matrix_type), intent(inout), optional :: kff
      real(dp), intent(inout), optional :: kfd(:, :)
      real(dp) :: xs(2), x1(2), x2(2), f(6), k(6, 6), ft(5), kt(5, 5)
      integer :: i, dofs(6), tdofs(5)
      do i = 1, size(mesh%slides)
         associate (sl => mesh%slides(i))
            call slide_position(mesh, sl, seg(i), q, xs, x1, x2, dofs)
            if (present(kff)) then
               call slide_force(xs, x1, x2, sl%kp, f, k)
               call scatter(mesh, dofs, -k, kff, kfd)
            else if (present(kfd)) then
               call slide_force(xs, x1, x2, sl%kp, f, k)
               call scatter_driven(mesh, dofs, -k, kfd)
            else
               call slide_force(xs, x1, x2, sl%kp, f)
            end if
            call subtract(r, dofs, f)
            if (sl%kind == joint_prismatic) then
               tdofs = [sl%slave_rot, dofs(3:6)]
               if (present(kff)) then
                  call slide_tie_force(q(sl%slave_rot), x1, x2, sl%c0(seg(i)), sl%kr, ft, kt)
                  call scatter(mesh, tdofs, -kt, kff, kfd)
               else if (present(kfd)) then
                  call slide_tie_force(q(sl%slave_rot), x1, x2, sl%c0(seg(i)), sl%kr, ft, kt)
                  call scatter_driven(mesh, tdofs, -kt, kfd)
               else
                  call slide_tie_force(q(sl%slave_rot), x1, x2, sl%c0(seg(i)), sl%kr, ft)
               end if
               call subtract(r, tdofs, ft)
            end if
         end associate
      end do
   end subroutine add_contact

   !> scatter's free-driven entries alone: ke on the dofs `dofs` (0: none)
   !> into kfd, in scatter's order.
   pure subroutine scatter_driven(mesh, dofs, ke, kfd)
      type(mesh_type), intent(in) :: mesh
      integer, intent(in) :: dofs(:)
      real(dp), intent(in) :: ke(:, :)
      real(dp), intent(inout) :: kfd(:, :)
      integer :: i, j, ei, dj
      do j = 1, size(dofs)
         dj = dofs(j)
         if (dj == 0) cycle
         if (mesh%eq(dj) > 0 .or. mesh%drive_col(dj) <= 0) cycle
         do i = 1, size(dofs)
            if (dofs(i) == 0) cycle
            ei = mesh%eq(dofs(i))
            if (ei == 0) cycle
            kfd(ei, mesh%drive_col(dj)) = kfd(ei, mesh%drive_col(dj)) + ke(i, j)
         end do
      end do
   end subroutine scatter_driven

   !> r(dofs) -= f, skipping absent dofs.
   pure subroutine subtract(r, dofs, f)
      real(dp), intent(inout) :: r(:)
      integer, intent(in) :: dofs(:)
      real(dp), intent(in) :: f(:)
      integer :: i
      do i = 1, size(dofs)
         if (dofs(i) > 0) r(dofs(i)) = r(dofs(i)) - f(i)
      end do
   end subroutine subtract

   !> d2 = d^2 R / dq^2 [v, v] over all dofs; with `section`, the sections'
   !> cosines and sines that assemble_tangent found at the same q.
   pure subroutine assemble_second_derivative(mesh, q, v, seg, d2, section)
      type(mesh_type), intent(in) :: mesh
      real(dp), intent(in) :: q(:), v(:)
      integer, intent(in) :: seg(:)
      real(dp), intent(out) :: d2(:)
      real(dp), intent(in), optional :: section(section_values, max_gauss, size(mesh%elements))
      real(dp) :: de(6), xs(2), x1(2), x2(2), ve(6), vt(5), dt(5), xe(6)
      integer :: e, i, dofs(6), tdofs(5)
      d2 = 0
      do e = 1, size(mesh%elements)
         do i = 1, 6
            xe(i) = q(mesh%edof(i, e))
            ve(i) = v(mesh%edof(i, e))
         end do
         if (present(section)) then
            call beam_second_derivative(mesh%elements(e), xe, ve, de, section(:, :, e))
         else
            call beam_second_derivative(mesh%elements(e), xe, ve, de)
         end if
         do i = 1, 6
            d2(mesh%edof(i, e)) = d2(mesh%edof(i, e)) + de(i)
         end do
      end do
      do i = 1, size(mesh%slides)
         associate (sl => mesh%slides(i))
            call slide_position(mesh, sl, seg(i), q, xs, x1, x2, dofs)
            ve = gather(v, dofs)
            call slide_second_derivative(xs, x1, x2, sl%kp, ve, de)
            call subtract(d2, dofs, de)
            if (sl%kind == joint_prismatic) then
               tdofs = [sl%slave_rot, dofs(3:6)]
               vt = gather(v, tdofs)
               call slide_tie_second_derivative(q(sl%slave_rot), x1, x2, sl%c0(seg(i)), sl%kr, vt, dt)
               call subtract(d2, tdofs, dt)
            end if
         end associate
      end do
   end subroutine assemble_second_derivative

   !> v(dofs), with 0 for absent dofs (a fixed guide does not move); the
   !> square-root form's strain rates use it too.
   pure function gather(v, dofs) result(ve)
      real(dp), intent(in) :: v(:)
      integer, intent(in) :: dofs(:)
      real(dp) :: ve(size(dofs))
      integer :: i
      ve = 0
      do i = 1, size(dofs)
         if (dofs(i) > 0) ve(i) = v(dofs(i))
      end do
   end function gather

   !> Largest element strain and the element where it occurs.
   pure subroutine max_strain(mesh, q, strain, element)
      type(mesh_type), intent(in) :: mesh
      real(dp), intent(in) :: q(:)
      real(dp), intent(out) :: strain
      integer, intent(out) :: element
      real(dp) :: s, xe(6)
      integer :: e, i
      strain = 0
      element = 0
      do e = 1, size(mesh%elements)
         do i = 1, 6
            xe(i) = q(mesh%edof(i, e))
         end do
         s = beam_max_strain(mesh%elements(e), xe)
         if (s > strain .or. element == 0) then
            strain = s
            element = e
         end if
      end do
   end subroutine max_strain

end module fekap_assembly_assemble
