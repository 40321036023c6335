!> Kinematic analysis of a spatial mechanism (fekap_spatial_mechanism) by the
!> paper's method carried to SE(3): every configuration is the stress-free
!> solution of the finite element equations with the drives prescribed,
!> found by Newton-Raphson with the material tangent K = sum G^T B^T k B G
!> (exact at a stress-free state, where the geometric part vanishes); the
!> rates follow from linear solves with the same tangent (Eischen, Sun &
!> Marler, eqs. (47)-(53), here with B the SE(3) compatibility):
!>
!>   velocities     K_ff v_f = -K_fd v_d,
!>   accelerations  K_ff a_f = -K_fd a_d - sum G_f^T B^T k c,
!>
!> c the convective term, the second derivative of each element's strain
!> along q (+) s v (fekap_element_se3_beam), which includes the curvature of
!> the joints' dof maps (a child frame of a turning parent). Generalized
!> dofs q: translations of free points (absolute, global axes), strokes of
!> line points, joint angles (additive), and body rotation increments of free
!> frames (their rotation matrices are the state, updated multiplicatively).
!> The module is over 600 lines (near 800) because the configuration (positions, dof
!> maps and the dofs each depends on), its assembly element by element and
!> the solves that use them are one concept around one configuration type.
module fekap_spatial_kinematics
   use fekap_kinds, only: dp
   use fekap_vectors, only: cross
   use fekap_union_find, only: find_root, join
   use fekap_error, only: error_type, analysis_error
   use fekap_spatial_tangent, only: spatial_tangent_type, new_spatial_tangent
   use fekap_element_se3, only: so3_exp, so3_update
   use fekap_element_se3_beam, only: se3_beam_residual, se3_beam_convective, truss_residual, truss_convective, &
      & se3_beam_strain
   use fekap_spatial_mechanism, only: spatial_mechanism_type, point_free, point_line, frame_free, frame_revolute, &
      & frame_universal, spatial_slide_type, slide_on_segment
   use fekap_spatial_slideline, only: slide_gap, slide_convective
   implicit none
   private

   public :: spatial_state_type, new_spatial_state, spatial_configuration_type, configure, frame_curvature
   public :: assemble_spatial, set_drives, update_state, spatial_rates
   public :: point_position, point_rate, free_dofs, spatial_rates_factored, singular, tangent_for, free_part, largest_strain
   public :: strain_operator_type, convective_strains, operator_load

   !> Where a mechanism is: its generalized dofs and its free frames' rotations.
   type :: spatial_state_type
      real(dp), allocatable :: q(:)
      !> Rotation of each frame that is free (I for the others, unused).
      real(dp), allocatable :: r(:, :, :)
   end type spatial_state_type

   !> The nodes' placement at a state and its derivatives in the dofs:
   !> point positions x and G = dx/dq, frame rotations R and W = dtheta/dq
   !> (body increments).
   type :: spatial_configuration_type
      !> The state's dofs (the slides' strokes).
      real(dp), allocatable :: q(:)
      real(dp), allocatable :: x(:, :), g(:, :, :)
      real(dp), allocatable :: r(:, :, :), w(:, :, :)
      !> The dofs that G of point i depends on, point_dofs(point_start(i):
      !> point_start(i + 1) - 1), and those of W of frame i (its own and its
      !> parent's): the other columns of G and W are zero.
      integer, allocatable :: point_start(:), point_dofs(:), frame_start(:), frame_dofs(:)
   end type spatial_configuration_type

   !> One element's part of the square-root form of the tangent: its strain
   !> rate a x(dofs) (a = B G on its own dofs: a beam's 6 strains, a truss's
   !> elongation, a slide's gap), its stiffness w (K = sum a^T w a) and its
   !> convective strain acceleration c (zero until convective_strains).
   type :: element_rate_type
      integer, allocatable :: dofs(:)
      real(dp), allocatable :: a(:, :), w(:, :), c(:)
   end type element_rate_type

   !> The strain-rate operator of a configuration, element by element
   !> (assemble_spatial's `operator`): the rate solves' residuals
   !> sum a^T w (a x + c) come from it without another assembly.
   type :: strain_operator_type
      type(element_rate_type), allocatable :: element(:)
   end type strain_operator_type

   !> At most this many refinements of a rate solve (rates_solve): each
   !> multiplies the error by about kappa(K) eps, and with EA/EI spreads up
   !> to 1e12 a few are needed; more than this means kappa(K) eps near 1.
   integer, parameter :: max_refinements = 8
   !> A refinement whose correction is within this many units of round-off
   !> of the largest rate ends the refinements.
   real(dp), parameter :: refinement_floor = 8*epsilon(1.0_dp)

contains

   !> The reference configuration: free points at their positions, every
   !> stroke and angle 0, every frame I.
   pure function new_spatial_state(m) result(s)
      type(spatial_mechanism_type), intent(in) :: m
      type(spatial_state_type) :: s
      integer :: i, nf
      allocate (s%q(m%ndof), source=0.0_dp)
      nf = 0
      if (allocated(m%frames)) nf = size(m%frames)
      allocate (s%r(3, 3, nf), source=0.0_dp)
      do i = 1, 3
         s%r(i, i, :) = 1
      end do
      do i = 1, size(m%points)
         if (m%points(i)%kind == point_free) s%q(m%points(i)%dof:m%points(i)%dof + 2) = m%points(i)%x0
      end do
   end function new_spatial_state

   !> The dofs that are not driven.
   pure function free_dofs(m) result(list)
      type(spatial_mechanism_type), intent(in) :: m
      integer, allocatable :: list(:)
      logical :: driven(m%ndof)
      integer :: i
      driven = .false.
      if (allocated(m%drives)) then
         do i = 1, size(m%drives)
            driven(m%drives(i)%dof) = .true.
         end do
      end if
      list = pack([(i, i=1, m%ndof)], .not. driven)
   end function free_dofs

   !> Positions, rotations and their dof derivatives at state s.
   pure subroutine configure(m, s, c)
      type(spatial_mechanism_type), intent(in) :: m
      type(spatial_state_type), intent(in) :: s
      type(spatial_configuration_type), intent(out) :: c
      real(dp) :: rp(3, 3), e1(3, 3), e2(3, 3), et(3, 3)
      integer :: i, k, np, nf
      np = size(m%points)
      nf = size(s%r, 3)
      allocate (c%x(3, np), c%g(3, m%ndof, np), c%r(3, 3, nf), c%w(3, m%ndof, nf), source=0.0_dp)
      call dof_supports(m, c)
      c%q = s%q
      do i = 1, np
         associate (p => m%points(i))
            select case (p%kind)
            case (point_free)
               c%x(:, i) = s%q(p%dof:p%dof + 2)
               do k = 1, 3
                  c%g(k, p%dof + k - 1, i) = 1
               end do
            case (point_line)
               c%x(:, i) = p%x0 + s%q(p%dof)*p%axis
               c%g(:, p%dof, i) = p%axis
            case default                                 ! point_fixed
               c%x(:, i) = p%x0
            end select
         end associate
      end do
      do i = 1, nf
         associate (f => m%frames(i))
            rp = 0
            do k = 1, 3
               rp(k, k) = 1
            end do
            if (f%parent > 0) rp = c%r(:, :, f%parent)
            select case (f%kind)
            case (frame_free)
               c%r(:, :, i) = s%r(:, :, i)
               do k = 1, 3
                  c%w(k, f%dof + k - 1, i) = 1
               end do
            case (frame_revolute)
               e1 = so3_exp(s%q(f%dof)*f%axis)
               c%r(:, :, i) = matmul(rp, e1)
               et = transpose(e1)
               call carry_parent(c, m%frames(i)%parent, i, et)
               c%w(:, f%dof, i) = c%w(:, f%dof, i) + f%axis
            case (frame_universal)
               e1 = so3_exp(s%q(f%dof)*f%axis)
               e2 = so3_exp(s%q(f%dof + 1)*f%axis2)
               c%r(:, :, i) = matmul(rp, matmul(e1, e2))
               et = transpose(matmul(e1, e2))
               call carry_parent(c, m%frames(i)%parent, i, et)
               c%w(:, f%dof, i) = c%w(:, f%dof, i) + matmul(f%axis, e2)
               c%w(:, f%dof + 1, i) = c%w(:, f%dof + 1, i) + f%axis2
            case default                                 ! frame_fixed
               do k = 1, 3
                  c%r(k, k, i) = 1
               end do
            end select
         end associate
      end do
   end subroutine configure

   !> W of frame i from its parent j's, E^T W_p, on the parent's dofs (the others are zero).
   pure subroutine carry_parent(c, j, i, et)
      type(spatial_configuration_type), intent(inout) :: c
      integer, intent(in) :: j, i
      real(dp), intent(in) :: et(3, 3)
      integer, allocatable :: list(:)
      if (j == 0) return
      list = c%frame_dofs(c%frame_start(j):c%frame_start(j + 1) - 1)
      c%w(:, list, i) = matmul(et, c%w(:, list, j))
   end subroutine carry_parent

   !> The dofs each point's position and each frame's rotation depend on:
   !> a free point's 3, a line point's stroke; a free frame's 3, a revolute
   !> (universal) frame's angle (2) after its parent's.
   pure subroutine dof_supports(m, c)
      type(spatial_mechanism_type), intent(in) :: m
      type(spatial_configuration_type), intent(inout) :: c
      integer :: i, k, np, nf, n, own, j
      np = size(m%points)
      nf = size(c%r, 3)
      allocate (c%point_start(np + 1), c%frame_start(nf + 1))
      c%point_start(1) = 1
      do i = 1, np
         select case (m%points(i)%kind)
         case (point_free)
            n = 3
         case (point_line)
            n = 1
         case default
            n = 0
         end select
         c%point_start(i + 1) = c%point_start(i) + n
      end do
      allocate (c%point_dofs(c%point_start(np + 1) - 1))
      do i = 1, np
         do k = c%point_start(i), c%point_start(i + 1) - 1
            c%point_dofs(k) = m%points(i)%dof + k - c%point_start(i)
         end do
      end do
      c%frame_start(1) = 1
      do i = 1, nf
         c%frame_start(i + 1) = c%frame_start(i) + own_dofs(i) + inherited(i)
      end do
      allocate (c%frame_dofs(c%frame_start(nf + 1) - 1))
      do i = 1, nf
         k = c%frame_start(i)
         j = m%frames(i)%parent
         n = inherited(i)
         if (n > 0) c%frame_dofs(k:k + n - 1) = c%frame_dofs(c%frame_start(j):c%frame_start(j + 1) - 1)
         own = own_dofs(i)
         do j = 0, own - 1
            c%frame_dofs(k + n + j) = m%frames(i)%dof + j
         end do
      end do
   contains
      pure integer function own_dofs(i)
         integer, intent(in) :: i
         select case (m%frames(i)%kind)
         case (frame_free)
            own_dofs = 3
         case (frame_revolute)
            own_dofs = 1
         case (frame_universal)
            own_dofs = 2
         case default
            own_dofs = 0
         end select
      end function own_dofs

      pure integer function inherited(i)
         integer, intent(in) :: i
         inherited = 0
         if (m%frames(i)%parent > 0 .and. any(m%frames(i)%kind == [frame_revolute, frame_universal])) then
            inherited = c%frame_start(m%frames(i)%parent + 1) - c%frame_start(m%frames(i)%parent)
         end if
      end function inherited
   end subroutine dof_supports

   !> The dofs of an element: those of its points and frames (0: none), without repeats.
   pure function element_dofs(c, points, frames) result(dofs)
      type(spatial_configuration_type), intent(in) :: c
      integer, intent(in) :: points(:), frames(:)
      integer, allocatable :: dofs(:)
      integer, allocatable :: all(:)
      integer :: i, n
      all = [integer ::]
      do i = 1, size(points)
         all = [all, c%point_dofs(c%point_start(points(i)):c%point_start(points(i) + 1) - 1)]
      end do
      do i = 1, size(frames)
         if (frames(i) > 0) all = [all, c%frame_dofs(c%frame_start(frames(i)):c%frame_start(frames(i) + 1) - 1)]
      end do
      allocate (dofs(size(all)))
      n = 0
      do i = 1, size(all)
         if (any(dofs(1:n) == all(i))) cycle
         n = n + 1
         dofs(n) = all(i)
      end do
      dofs = dofs(1:n)
   end function element_dofs

   !> The dofs of beam i (element_dofs of its nodes' points and frames).
   pure function beam_dofs(m, c, i) result(dofs)
      type(spatial_mechanism_type), intent(in) :: m
      type(spatial_configuration_type), intent(in) :: c
      integer, intent(in) :: i
      integer, allocatable :: dofs(:)
      integer :: points(2), frames(2), n
      do n = 1, 2
         points(n) = m%nodes(m%beams(i)%nodes(n))%point
         frames(n) = m%nodes(m%beams(i)%nodes(n))%frame
      end do
      dofs = element_dofs(c, points, frames)
   end function beam_dofs

   !> The storage of m's tangent: band order from the elements' couplings.
   subroutine tangent_for(m, kt)
      type(spatial_mechanism_type), intent(in) :: m
      type(spatial_tangent_type), intent(out) :: kt
      integer, allocatable :: group_start(:), group_dof(:)
      call element_groups(m, group_start, group_dof)
      call new_spatial_tangent(kt, m%ndof, free_dofs(m), group_start, group_dof)
   end subroutine tangent_for

   !> The dofs each element's strains depend on (a beam's include its
   !> frames' ancestors' in the frame tree): element e's are
   !> group_dof(group_start(e):group_start(e + 1) - 1), the beams first, then
   !> the trusses, then the slides.
   subroutine element_groups(m, group_start, group_dof)
      type(spatial_mechanism_type), intent(in) :: m
      integer, allocatable, intent(out) :: group_start(:), group_dof(:)
      type(spatial_configuration_type) :: c
      integer, allocatable :: dofs(:)
      integer :: i, ne
      call configure(m, new_spatial_state(m), c)
      ne = 0
      if (allocated(m%beams)) ne = ne + size(m%beams)
      if (allocated(m%trusses)) ne = ne + size(m%trusses)
      if (allocated(m%slides)) ne = ne + size(m%slides)
      allocate (group_start(ne + 1))
      group_start(1) = 1
      group_dof = [integer ::]
      ne = 0
      if (allocated(m%beams)) then
         do i = 1, size(m%beams)
            dofs = beam_dofs(m, c, i)
            call add_group()
         end do
      end if
      if (allocated(m%trusses)) then
         do i = 1, size(m%trusses)
            dofs = element_dofs(c, m%trusses(i)%points, [integer ::])
            call add_group()
         end do
      end if
      if (allocated(m%slides)) then
         do i = 1, size(m%slides)
            dofs = slide_line_dofs(c, m%slides(i))
            call add_group()
         end do
      end if
   contains
      subroutine add_group()
         ne = ne + 1
         group_dof = [group_dof, dofs]
         group_start(ne + 1) = size(group_dof) + 1
      end subroutine add_group
   end subroutine element_groups

   !> Grubler's count over each part of the mechanism that its elements
   !> join through their free dofs, as the planar FEM's check_determined
   !> counts: the part's free dofs less the equations that can hold them, a
   !> beam at most 6 (a rigid body in space), a truss 1 (its elongation), a
   !> slide 3 (its gap), each at most as many as its own free dofs. The
   !> equations' rank is at most their count, so a part with more free dofs
   !> than equations moves at every configuration, for any geometry: its
   !> tangent is singular, and round-off hides the zero pivot (a four-bar
   !> without one of its joints ran to its end with the loose part at rest).
   !> excess: 0 when every part is held, else the first loose part's free
   !> dofs less its equations, with its elements (in_part, numbered as
   !> element_groups numbers them); a free dof no element holds is a part of
   !> its own, with no elements.
   subroutine free_part(m, excess, in_part)
      type(spatial_mechanism_type), intent(in) :: m
      integer, intent(out) :: excess
      logical, allocatable, intent(out) :: in_part(:)
      integer, allocatable :: group_start(:), group_dof(:), fdof(:), element_root(:)
      integer :: part(m%ndof), dofs_of(m%ndof), held_by(m%ndof)
      logical :: free(m%ndof)
      integer :: e, i, nb, nt, capacity, nfree, root
      call element_groups(m, group_start, group_dof)
      fdof = free_dofs(m)
      free = .false.
      free(fdof) = .true.
      part = [(i, i=1, m%ndof)]
      nb = 0
      nt = 0
      if (allocated(m%beams)) nb = size(m%beams)
      if (allocated(m%trusses)) nt = size(m%trusses)
      do e = 1, size(group_start) - 1
         associate (dofs => group_dof(group_start(e):group_start(e + 1) - 1))
            root = 0
            do i = 1, size(dofs)
               if (.not. free(dofs(i))) cycle
               if (root == 0) root = dofs(i)
               call join(part, root, dofs(i))
            end do
         end associate
      end do
      dofs_of = 0
      held_by = 0
      do i = 1, size(fdof)
         root = find_root(part, fdof(i))
         dofs_of(root) = dofs_of(root) + 1
      end do
      allocate (element_root(size(group_start) - 1), source=0)
      do e = 1, size(group_start) - 1
         associate (dofs => group_dof(group_start(e):group_start(e + 1) - 1))
            nfree = count(free(dofs))
            if (nfree == 0) cycle
            capacity = 3
            if (e <= nb) then
               capacity = 6
            else if (e <= nb + nt) then
               capacity = 1
            end if
            element_root(e) = find_root(part, dofs(findloc(free(dofs), .true., 1)))
            held_by(element_root(e)) = held_by(element_root(e)) + min(capacity, nfree)
         end associate
      end do
      excess = 0
      do i = 1, size(fdof)
         root = find_root(part, fdof(i))
         if (dofs_of(root) <= held_by(root)) cycle
         excess = dofs_of(root) - held_by(root)
         in_part = element_root == root
         return
      end do
      allocate (in_part(size(element_root)), source=.false.)
   end subroutine free_part

   !> The body angular acceleration each frame has along q (+) s v at s = 0
   !> with no dof acceleration: zero for free and fixed frames; for a child,
   !> R = R_p exp(theta n^) gives omega = E^T omega_p + n theta' and
   !> d omega/ds = -(n theta') x (E^T omega_p) + E^T kappa_p (twice for a
   !> universal joint).
   pure function frame_curvature(m, s, c, v) result(kappa)
      type(spatial_mechanism_type), intent(in) :: m
      type(spatial_state_type), intent(in) :: s
      type(spatial_configuration_type), intent(in) :: c
      real(dp), intent(in) :: v(:)
      real(dp) :: kappa(3, size(c%r, 3))
      real(dp) :: wp(3), kp(3), e1(3, 3), e2(3, 3), w1(3), k1(3)
      integer :: i
      kappa = 0
      do i = 1, size(c%r, 3)
         associate (f => m%frames(i))
            wp = 0
            kp = 0
            if (f%parent > 0) then
               wp = matmul(c%w(:, :, f%parent), v)
               kp = kappa(:, f%parent)
            end if
            select case (f%kind)
            case (frame_revolute)
               e1 = so3_exp(s%q(f%dof)*f%axis)
               kappa(:, i) = -cross(f%axis*v(f%dof), matmul(wp, e1)) + matmul(kp, e1)
            case (frame_universal)
               e1 = so3_exp(s%q(f%dof)*f%axis)
               e2 = so3_exp(s%q(f%dof + 1)*f%axis2)
               w1 = matmul(wp, e1) + f%axis*v(f%dof)
               k1 = -cross(f%axis*v(f%dof), matmul(wp, e1)) + matmul(kp, e1)
               kappa(:, i) = -cross(f%axis2*v(f%dof + 1), matmul(w1, e2)) + matmul(k1, e2)
            case default                                 ! fixed and free frames: none
            end select
         end associate
      end do
   end function frame_curvature

   !> The residual r = sum G^T f and, if asked, the material tangent
   !> K = sum G^T B^T k B G at state s, as a full array (tangent) or in the
   !> band storage of tangent_for (sparse), and the strain-rate operator
   !> (operator): each element's a = B G on its own dofs and its stiffness,
   !> K's square-root form, for the rate solves (spatial_rates_factored).
   !> Each element works on its own dofs only (element_dofs).
   pure subroutine assemble_spatial(m, c, residual, tangent, sparse, operator)
      type(spatial_mechanism_type), intent(in) :: m
      type(spatial_configuration_type), intent(in) :: c
      real(dp), intent(out) :: residual(:)
      real(dp), intent(out), optional :: tangent(:, :)
      type(spatial_tangent_type), intent(inout), optional :: sparse
      type(strain_operator_type), intent(out), optional :: operator
      real(dp) :: x(3, 2), r(3, 3, 2), f(12), ke(12, 12), b(6, 12)
      real(dp) :: ft(6), kt(6, 6), u(3)
      real(dp) :: ra(3, 3), gap(3), ns(3, 10)
      !> The slide on the segment of its line that holds its stroke.
      type(spatial_slide_type) :: on
      real(dp), allocatable :: ge(:, :), gt(:, :), gs(:, :), ng(:, :), kes(:, :)
      integer, allocatable :: dofs(:)
      integer :: i, n, p, fr, e
      logical :: with_tangent
      with_tangent = present(tangent) .or. present(sparse)
      residual = 0
      if (present(tangent)) tangent = 0
      if (present(sparse)) call sparse%zero()
      if (present(operator)) allocate (operator%element(element_count(m)))
      e = 0
      if (allocated(m%beams)) then
         do i = 1, size(m%beams)
            dofs = beam_dofs(m, c, i)
            if (allocated(ge)) deallocate (ge)
            allocate (ge(12, size(dofs)))
            do n = 1, 2
               p = m%nodes(m%beams(i)%nodes(n))%point
               fr = m%nodes(m%beams(i)%nodes(n))%frame
               x(:, n) = c%x(:, p)
               r(:, :, n) = c%r(:, :, fr)
               ge(6*n - 5:6*n - 3, :) = c%g(:, dofs, p)
               ge(6*n - 2:6*n, :) = c%w(:, dofs, fr)
            end do
            if (with_tangent) then
               call se3_beam_residual(m%beams(i)%element, x, r, f, ke, material_only=.true., compatibility=b)
               kes = matmul(transpose(ge), matmul(ke, ge))
               if (present(tangent)) tangent(dofs, dofs) = tangent(dofs, dofs) + kes
               if (present(sparse)) call sparse%add_element(dofs, kes)
            else
               call se3_beam_residual(m%beams(i)%element, x, r, f, compatibility=b)
            end if
            residual(dofs) = residual(dofs) + matmul(f, ge)
            e = e + 1
            if (present(operator)) operator%element(e) = element_rate_type(dofs, matmul(b, ge), &
               & m%beams(i)%element%k, zeros(6))
         end do
      end if
      if (allocated(m%trusses)) then
         do i = 1, size(m%trusses)
            dofs = element_dofs(c, m%trusses(i)%points, [integer ::])
            if (allocated(gt)) deallocate (gt)
            allocate (gt(6, size(dofs)))
            do n = 1, 2
               p = m%trusses(i)%points(n)
               x(:, n) = c%x(:, p)
               gt(3*n - 2:3*n, :) = c%g(:, dofs, p)
            end do
            if (with_tangent) then
               call truss_residual(m%trusses(i)%element, x, ft, kt)
               kes = matmul(transpose(gt), matmul(kt, gt))
               if (present(tangent)) tangent(dofs, dofs) = tangent(dofs, dofs) + kes
               if (present(sparse)) call sparse%add_element(dofs, kes)
            else
               call truss_residual(m%trusses(i)%element, x, ft)
            end if
            residual(dofs) = residual(dofs) + matmul(ft, gt)
            e = e + 1
            if (present(operator)) then
               ! B = (-u, u), k = EA/L: the elongation's rate.
               u = (x(:, 2) - x(:, 1))/norm2(x(:, 2) - x(:, 1))
               operator%element(e) = element_rate_type(dofs, reshape(matmul([-u, u], gt), [1, size(dofs)]), &
                  & reshape([m%trusses(i)%element%ea/m%trusses(i)%element%length], [1, 1]), zeros(1))
            end if
         end do
      end if
      if (allocated(m%slides)) then
         ! Points on lines carried by moving frames (penalty slidelines,
         ! fekap_spatial_slideline): force N^T kp g, tangent kp N^T N.
         do i = 1, size(m%slides)
            on = slide_on_segment(m%slides(i), c%q(m%slides(i)%dof))
            associate (sl => on)
               dofs = slide_dofs(c, sl)
               if (allocated(gs)) deallocate (gs)
               allocate (gs(10, size(dofs)), source=0.0_dp)
               gs(1:3, :) = c%g(:, dofs, sl%point_b)
               gs(4:6, :) = c%g(:, dofs, sl%point_a)
               ra = identity()
               if (sl%frame_a > 0) then
                  ra = c%r(:, :, sl%frame_a)
                  gs(7:9, :) = c%w(:, dofs, sl%frame_a)
               end if
               where (dofs == sl%dof) gs(10, :) = 1
               call slide_gap(c%x(:, sl%point_a), ra, c%x(:, sl%point_b), c%q(sl%dof), sl%offset, sl%axis, gap, ns)
               ng = matmul(ns, gs)
               residual(dofs) = residual(dofs) + sl%kp*matmul(gap, ng)
               if (with_tangent) then
                  kes = sl%kp*matmul(transpose(ng), ng)
                  if (present(tangent)) tangent(dofs, dofs) = tangent(dofs, dofs) + kes
                  if (present(sparse)) call sparse%add_element(dofs, kes)
               end if
               e = e + 1
               if (present(operator)) operator%element(e) = element_rate_type(dofs, ng, sl%kp*identity(), zeros(3))
            end associate
         end do
      end if
   end subroutine assemble_spatial

   !> The largest element strain at configuration c, as the planar FEM
   !> measures it (beam_max_strain: |Gamma|, |kappa| L): a beam's
   !> translational strain over its length and its rotational strain, a
   !> truss's elongation over its length; and its element (beams, then
   !> trusses, as element_groups numbers them; 0 if none).
   pure subroutine largest_strain(m, c, strain, element)
      type(spatial_mechanism_type), intent(in) :: m
      type(spatial_configuration_type), intent(in) :: c
      real(dp), intent(out) :: strain
      integer, intent(out) :: element
      real(dp) :: x(3, 2), r(3, 3, 2), e(6), size_
      integer :: i, n, nb
      strain = 0
      element = 0
      nb = 0
      if (allocated(m%beams)) then
         nb = size(m%beams)
         do i = 1, nb
            do n = 1, 2
               x(:, n) = c%x(:, m%nodes(m%beams(i)%nodes(n))%point)
               r(:, :, n) = c%r(:, :, m%nodes(m%beams(i)%nodes(n))%frame)
            end do
            e = se3_beam_strain(m%beams(i)%element, x, r)
            size_ = max(maxval(abs(e(1:3)))/m%beams(i)%element%length, maxval(abs(e(4:6))))
            if (size_ > strain) then
               strain = size_
               element = i
            end if
         end do
      end if
      if (allocated(m%trusses)) then
         do i = 1, size(m%trusses)
            associate (tr => m%trusses(i))
               size_ = abs(norm2(c%x(:, tr%points(2)) - c%x(:, tr%points(1))) - tr%element%length)/tr%element%length
            end associate
            if (size_ > strain) then
               strain = size_
               element = nb + i
            end if
         end do
      end if
   end subroutine largest_strain

   !> The number of elements: beams, trusses and slides.
   pure integer function element_count(m) result(ne)
      type(spatial_mechanism_type), intent(in) :: m
      ne = 0
      if (allocated(m%beams)) ne = ne + size(m%beams)
      if (allocated(m%trusses)) ne = ne + size(m%trusses)
      if (allocated(m%slides)) ne = ne + size(m%slides)
   end function element_count

   pure function zeros(n) result(z)
      integer, intent(in) :: n
      real(dp) :: z(n)
      z = 0
   end function zeros

   !> Each element's convective strain acceleration c (the second derivative
   !> of its strains along q (+) s v, with the frames' curvature kappa from
   !> frame_curvature) into op, built by assemble_spatial at configuration c
   !> (the elements in its order: beams, trusses, slides).
   pure subroutine convective_strains(m, c, v, kappa, op)
      type(spatial_mechanism_type), intent(in) :: m
      type(spatial_configuration_type), intent(in) :: c
      real(dp), intent(in) :: v(:), kappa(:, :)
      type(strain_operator_type), intent(inout) :: op
      real(dp) :: x(3, 2), r(3, 3, 2), nv(3, 2), nw(3, 2), na(3, 2), ra(3, 3), omega(3), ka(3)
      type(spatial_slide_type) :: on
      integer :: i, n, p, fr, e
      e = 0
      if (allocated(m%beams)) then
         do i = 1, size(m%beams)
            e = e + 1
            associate (dofs => op%element(e)%dofs)
               do n = 1, 2
                  p = m%nodes(m%beams(i)%nodes(n))%point
                  fr = m%nodes(m%beams(i)%nodes(n))%frame
                  x(:, n) = c%x(:, p)
                  r(:, :, n) = c%r(:, :, fr)
                  nv(:, n) = matmul(c%g(:, dofs, p), v(dofs))
                  nw(:, n) = matmul(c%w(:, dofs, fr), v(dofs))
                  na(:, n) = kappa(:, fr)
               end do
            end associate
            op%element(e)%c = se3_beam_convective(x, r, nv, nw, na)
         end do
      end if
      if (allocated(m%trusses)) then
         do i = 1, size(m%trusses)
            e = e + 1
            associate (dofs => op%element(e)%dofs)
               do n = 1, 2
                  p = m%trusses(i)%points(n)
                  x(:, n) = c%x(:, p)
                  nv(:, n) = matmul(c%g(:, dofs, p), v(dofs))
               end do
            end associate
            op%element(e)%c(1) = truss_convective(x, nv)
         end do
      end if
      if (allocated(m%slides)) then
         do i = 1, size(m%slides)
            e = e + 1
            on = slide_on_segment(m%slides(i), c%q(m%slides(i)%dof))
            associate (sl => on, dofs => op%element(e)%dofs)
               ra = identity()
               omega = 0
               ka = 0
               if (sl%frame_a > 0) then
                  ra = c%r(:, :, sl%frame_a)
                  omega = matmul(c%w(:, dofs, sl%frame_a), v(dofs))
                  ka = kappa(:, sl%frame_a)
               end if
               op%element(e)%c = slide_convective(ra, c%q(sl%dof), sl%offset, sl%axis, omega, ka, v(sl%dof))
            end associate
         end do
      end if
   end subroutine convective_strains

   !> sum a^T w (a x + c) over op's elements, every dof's row: K x plus the
   !> convective load, from each element's strain rate a x + c (the
   !> square-root form: no global product K x, whose rounding carries the
   !> squared condition number of k^1/2 B G into the rates).
   pure function operator_load(op, x) result(y)
      type(strain_operator_type), intent(in) :: op
      real(dp), intent(in) :: x(:)
      real(dp) :: y(size(x))
      integer :: e
      y = 0
      do e = 1, size(op%element)
         associate (el => op%element(e))
            y(el%dofs) = y(el%dofs) + matmul(matmul(el%w, matmul(el%a, x(el%dofs)) + el%c), el%a)
         end associate
      end do
   end function operator_load

   !> The dofs a slide's gap depends on: its points', its line frame's and its stroke.
   pure function slide_dofs(c, sl) result(dofs)
      type(spatial_configuration_type), intent(in) :: c
      type(spatial_slide_type), intent(in) :: sl
      integer, allocatable :: dofs(:)
      dofs = element_dofs(c, [sl%point_b, sl%point_a], [sl%frame_a])
      if (.not. any(dofs == sl%dof)) dofs = [dofs, sl%dof]
   end function slide_dofs

   !> The dofs a slide's gap may depend on: slide_dofs over every segment of
   !> its line (the tangent's storage, whatever segment the slider is on).
   pure function slide_line_dofs(c, sl) result(dofs)
      type(spatial_configuration_type), intent(in) :: c
      type(spatial_slide_type), intent(in) :: sl
      integer, allocatable :: dofs(:), more(:)
      integer :: k, i
      dofs = slide_dofs(c, sl)
      if (.not. allocated(sl%seg_point)) return
      do k = 1, size(sl%seg_point)
         more = element_dofs(c, [sl%seg_point(k)], [sl%seg_frame(k)])
         do i = 1, size(more)
            if (.not. any(dofs == more(i))) dofs = [dofs, more(i)]
         end do
      end do
   end function slide_line_dofs

   pure function identity() result(e)
      real(dp) :: e(3, 3)
      integer :: k
      e = 0
      do k = 1, 3
         e(k, k) = 1
      end do
   end function identity

   !> The drives' values at t in s%q; their rates and second rates in vd, ad
   !> (full-length vectors, zero at the free dofs).
   pure subroutine set_drives(m, t, s, vd, ad)
      type(spatial_mechanism_type), intent(in) :: m
      real(dp), intent(in) :: t
      type(spatial_state_type), intent(inout) :: s
      real(dp), intent(out) :: vd(:), ad(:)
      integer :: i
      vd = 0
      ad = 0
      if (.not. allocated(m%drives)) return
      do i = 1, size(m%drives)
         call m%drives(i)%law%eval(t, s%q(m%drives(i)%dof), vd(m%drives(i)%dof), ad(m%drives(i)%dof))
      end do
   end subroutine set_drives

   !> s <- s (+) dq: additive dofs added, free frames turned by their body increments.
   pure subroutine update_state(m, s, dq)
      type(spatial_mechanism_type), intent(in) :: m
      type(spatial_state_type), intent(inout) :: s
      real(dp), intent(in) :: dq(:)
      integer :: i
      s%q = s%q + dq
      do i = 1, size(s%r, 3)
         if (m%frames(i)%kind /= frame_free) cycle
         call so3_update(s%r(:, :, i), dq(m%frames(i)%dof:m%frames(i)%dof + 2))
         s%q(m%frames(i)%dof:m%frames(i)%dof + 2) = 0
      end do
   end subroutine update_state

   !> Velocities v and accelerations a of every dof at state s, time t.
   subroutine spatial_rates(m, t, s, v, a, error)
      type(spatial_mechanism_type), intent(in) :: m
      real(dp), intent(in) :: t
      type(spatial_state_type), intent(in) :: s
      real(dp), intent(out) :: v(:), a(:)
      type(error_type), allocatable, intent(out) :: error
      type(spatial_configuration_type) :: c
      type(spatial_state_type) :: sd
      type(spatial_tangent_type) :: kt
      real(dp) :: res(m%ndof), ad(m%ndof)
      integer :: info
      call tangent_for(m, kt)
      sd = s
      call set_drives(m, t, sd, v, ad)
      call configure(m, s, c)
      call assemble_spatial(m, c, res, sparse=kt)
      call kt%factor(info)
      if (info /= 0) then
         call singular(error, info, t)
         return
      end if
      call spatial_rates_factored(m, s, c, kt, v, ad, a)
   end subroutine spatial_rates

   !> The rates at state s (configuration c, tangent kt assembled there and
   !> factored) given the drives' rates in v and second rates ad (zero at the
   !> free dofs): v and a of every dof. Each solve of the normal equations
   !> K_ff x_f = -K_fd x_d - l takes its right-hand side and its refinements'
   !> residuals in the square-root form, K x + l = sum G^T B^T k (B (G x) +
   !> c) from each element's strain rate (the strain-rate operator of
   !> assemble_spatial, the convective strains c of convective_strains),
   !> not as the global product K x: the semi-normal equations with
   !> refinements, whose error is kappa(k^1/2 B G_f) eps, not its square
   !> (rates_solve). The planar FEM's square B_f solve of docs/hard-cases.md,
   !> section 7, does not apply: the spatial B_f of a planar loop has more
   !> rows than columns, its redundant constraints.
   subroutine spatial_rates_factored(m, s, c, kt, v, ad, a)
      type(spatial_mechanism_type), intent(in) :: m
      type(spatial_state_type), intent(in) :: s
      type(spatial_configuration_type), intent(in) :: c
      type(spatial_tangent_type), intent(in) :: kt
      real(dp), intent(in) :: ad(:)
      real(dp), intent(inout) :: v(:)
      real(dp), intent(out) :: a(:)
      type(strain_operator_type) :: op
      real(dp) :: res(m%ndof), scale(m%ndof)
      scale = merge(1/m%length, 1.0_dp, m%is_length)
      call assemble_spatial(m, c, res, operator=op)
      call rates_solve(op, kt, scale, v)
      call convective_strains(m, c, v, frame_curvature(m, s, c, v), op)
      a = ad
      call rates_solve(op, kt, scale, a)
   end subroutine spatial_rates_factored

   !> x_f of K_ff x_f = -(K_fd x_d + l), l the convective load of op (x_d:
   !> x at the driven dofs; x_f is overwritten): the solve with kt's factor
   !> of the residual operator_load(op, x) at x_f = 0, then refinements
   !> x_f <- x_f - K_ff^-1 operator_load(op, x)_f. A solve with the factor
   !> of K = A^T A (A = k^1/2 B G) errs by about kappa(A)^2 eps, so each
   !> refinement multiplies the error by that until it reaches the residual's
   !> own round-off, kappa(A) eps: with stiffnesses spread over k_max/k_min,
   !> kappa(A)^2 grows with it, and one refinement is not enough beyond about
   !> 1e9. The refinements stop when a correction is within refinement_floor
   !> of the largest rate (lengths scaled by scale), when one does not shrink
   !> (round-off reached: it is not applied), or after max_refinements.
   pure subroutine rates_solve(op, kt, scale, x)
      type(strain_operator_type), intent(in) :: op
      type(spatial_tangent_type), intent(in) :: kt
      real(dp), intent(in) :: scale(:)
      real(dp), intent(inout) :: x(:)
      real(dp), allocatable :: rhs(:)
      real(dp) :: load(size(x)), size_now, size_last
      integer :: pass
      x(kt%fdof) = 0
      size_last = huge(1.0_dp)
      do pass = 0, max_refinements
         load = operator_load(op, x)
         rhs = -load(kt%fdof)
         call kt%solve(rhs)
         size_now = maxval(abs(rhs*scale(kt%fdof)))
         if (pass > 0 .and. .not. size_now < size_last) return
         x(kt%fdof) = x(kt%fdof) + rhs
         if (pass > 0 .and. size_now <= refinement_floor*maxval(abs(x*scale))) return
         size_last = size_now
      end do
   end subroutine rates_solve

   subroutine singular(error, dof, t)
      type(error_type), allocatable, intent(out) :: error
      integer, intent(in) :: dof
      real(dp), intent(in) :: t
      character(len=80) :: text
      write (text, '(a,i0,a,es12.5)') 'singular tangent at dof ', dof, ', t = ', t
      call analysis_error(error, trim(text)//': a mode with no stiffness '// &
         & '(a beam between two spherical joints spins freely: make it a truss)')
   end subroutine singular

   !> The position of point p.
   pure function point_position(c, p) result(x)
      type(spatial_configuration_type), intent(in) :: c
      integer, intent(in) :: p
      real(dp) :: x(3)
      x = c%x(:, p)
   end function point_position

   !> The rate of point p for dof rates v (or its acceleration for dof
   !> accelerations: points move linearly in their dofs).
   pure function point_rate(c, p, v) result(xd)
      type(spatial_configuration_type), intent(in) :: c
      integer, intent(in) :: p
      real(dp), intent(in) :: v(:)
      real(dp) :: xd(3)
      xd = matmul(c%g(:, :, p), v)
   end function point_rate

end module fekap_spatial_kinematics
