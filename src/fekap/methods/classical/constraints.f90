!> Constraint equations of the Cartesian-coordinate method (Nikravesh's KAP,
!> the paper's (13)-(26) generalised): scalar equations Phi(q, t) = 0 on the
!> body coordinates q, their Jacobian Phi_q, the velocity right-hand side
!> nu = -Phi_t and the acceleration right-hand side
!> gamma = -(Phi_q q')_q q' - 2 Phi_qt q' - Phi_tt.
!>
!> Three kinds of scalar equation cover every joint:
!>  - point:  (r_i)_c - (r_j)_c - const - d(t), a component c of the difference
!>            of a point of body i and a point of body j (or a ground point):
!>            revolute joints, ground supports, x/y drives;
!>  - angle:  phi_i - phi_j - const - d(t): clamps, rotation drives, the angle
!>            part of a prismatic joint;
!>  - slot:   n . (r_i - p), the slave point r_i on the master line through
!>            p with unit direction u (n = u rotated +90 deg), the line fixed
!>            to body j or to ground: pin-in-slot and prismatic joints.
!> d(t) is the value of a drive (0 for equations without one).
module fekap_classical_constraints
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, input_error
   use fekap_model, only: model_type, dof_x, dof_y, dof_rot, joint_prismatic
   use fekap_model_drive_law, only: law_type
   use fekap_classical_bodies, only: body_map_type, new_body_map, rotate, perp
   use fekap_classical_stepping, only: drive_value
   implicit none
   private

   public :: constraint_system_type, new_constraint_system, equation_type

   integer, parameter, public :: eq_point = 1, eq_angle = 2, eq_slot = 3

   !> One scalar constraint equation.
   type :: equation_type
      !> eq_point, eq_angle or eq_slot.
      integer :: kind = 0
      !> Body i (> 0) and body j (0: ground).
      integer :: bi = 0, bj = 0
      !> Local coordinates of the point on body i, and of the point on body j
      !> (for ground: the point's global coordinates).
      real(dp) :: si(2) = 0, sj(2) = 0
      !> eq_point: the component, 1 (x) or 2 (y).
      integer :: comp = 0
      !> eq_slot: unit direction of the master line, local in body j (ground: global).
      real(dp) :: dir(2) = 0
      real(dp) :: const = 0
      !> Index into the drives (0: none).
      integer :: drive = 0
      !> The joint this equation belongs to, for messages.
      character(:), allocatable :: label
   end type equation_type

   !> A master link of a slideline: its body and the local coordinates of its ends.
   type :: segment_type
      integer :: body = 0
      real(dp) :: p1(2) = 0, p2(2) = 0
      !> Initial angle of the master body (for the prismatic angle equation).
      real(dp) :: phi0 = 0
   end type segment_type

   !> A slideline with a master chain: its equations follow the segment the slave is on.
   type :: slide_type
      !> Index of the slot equation and of the prismatic angle equation (0: pin-in-slot).
      integer :: slot = 0, angle = 0
      !> Initial angle of the slave body.
      real(dp) :: phi0 = 0
      type(segment_type), allocatable :: segments(:)
      !> The segment the equations follow (0: none chosen yet).
      integer :: current = 0
   end type slide_type

   !> All equations of a model.
   type :: constraint_system_type
      type(body_map_type) :: bodies
      !> Number of coordinates (3 per body) and of equations.
      integer :: n = 0, m = 0
      type(equation_type), allocatable :: eq(:)
      !> Drive laws, the initial values of the driven quantities and the start time.
      type(law_type), allocatable :: laws(:)
      real(dp), allocatable :: initial(:)
      real(dp) :: t_start = 0
      type(slide_type), allocatable :: slides(:)
   contains
      !> Phi(q, t) of every equation.
      procedure :: residual => system_residual
      !> Phi_q(q), dense (m, n).
      procedure :: jacobian => system_jacobian
      !> nu = -Phi_t(t), the right-hand side of the velocity equations.
      procedure :: velocity_rhs => system_velocity_rhs
      !> gamma(q, q', t), the right-hand side of the acceleration equations.
      procedure :: acceleration_rhs => system_acceleration_rhs
      !> Put every slideline with a master chain on the segment its slave is on.
      procedure :: select_segments => system_select_segments
      !> Whether some slideline has a master chain (its equation changes with the segment).
      procedure :: has_chains => system_has_chains
      !> Changes of the driven quantities between two times.
      procedure :: drive_increments => system_drive_increments
   end type constraint_system_type

contains

   !> Bodies and equations of `model`. Loads are ignored (kinematics only).
   subroutine new_constraint_system(self, model, error)
      type(constraint_system_type), intent(out) :: self
      type(model_type), intent(in) :: model
      type(error_type), allocatable, intent(out) :: error
      type(equation_type) :: e
      integer :: nnode, ndrive, i, j, k, b, c, l
      integer, allocatable :: at(:)

      if (.not. allocated(model%links) .or. .not. allocated(model%nodes)) then
         call input_error(error, 'the model has no links')
         return
      end if
      if (size(model%links) == 0) then
         call input_error(error, 'the model has no links')
         return
      end if
      call new_body_map(self%bodies, model, error)
      if (allocated(error)) return
      self%n = 3*self%bodies%nbody
      self%t_start = model%analysis%t_start
      nnode = size(self%bodies%x0, 2)
      allocate (self%eq(0))

      ! Revolute joints: at each node, every further body with a link end there
      ! is hinged to the first one.
      do k = 1, nnode
         at = bodies_at(model, self%bodies, k)
         do j = 2, size(at)
            do c = 1, 2
               e = equation_type(kind=eq_point, bi=at(1), bj=at(j), comp=c)
               e%si = self%bodies%local(at(1), self%bodies%x0(:, k))
               e%sj = self%bodies%local(at(j), self%bodies%x0(:, k))
               e%label = 'the revolute joint at '//model%nodes(k)%name//' (links ' &
                  & //model%links(link_at(model, self%bodies, k, at(1)))%name//', ' &
                  & //model%links(link_at(model, self%bodies, k, at(j)))%name//')'
               call append(self%eq, e)
            end do
         end do
      end do

      ! Ground supports and clamps.
      if (allocated(model%supports)) then
         do i = 1, size(model%supports)
            associate (s => model%supports(i))
               b = self%bodies%node_body(s%node)
               if (b == 0) cycle
               do c = dof_x, dof_y
                  if (.not. s%fix(c)) cycle
                  e = equation_type(kind=eq_point, bi=b, bj=0, comp=c)
                  e%si = self%bodies%node_local(:, s%node)
                  e%sj = self%bodies%x0(:, s%node)
                  e%label = 'the ground support at '//model%nodes(s%node)%name
                  call append(self%eq, e)
               end do
               if (s%fix(dof_rot)) then
                  l = s%link
                  if (l > 0) b = self%bodies%link_body(l)
                  e = equation_type(kind=eq_angle, bi=b, bj=0, const=self%bodies%q0(3*b))
                  e%label = 'the clamp at '//model%nodes(s%node)%name
                  call append(self%eq, e)
               end if
            end associate
         end do
      end if

      ! Drives: d(t) = initial + law(t) - law(t_start).
      ndrive = 0
      if (allocated(model%drives)) ndrive = size(model%drives)
      allocate (self%laws(ndrive), self%initial(ndrive))
      do i = 1, ndrive
         associate (d => model%drives(i))
            self%laws(i) = d%law
            if (d%dof == dof_rot) then
               l = d%link
               if (l == 0) l = link_at(model, self%bodies, d%node, self%bodies%node_body(d%node))
               if (l == 0) then
                  call input_error(error, 'a rotation drive at node '//model%nodes(d%node)%name//' drives no link')
                  return
               end if
               b = self%bodies%link_body(l)
               ! phi_b + offset_l = d(t)
               e = equation_type(kind=eq_angle, bi=b, bj=0, const=-self%bodies%link_offset(l), drive=i)
               self%initial(i) = self%bodies%q0(3*b) + self%bodies%link_offset(l)
               e%label = 'the rotation drive of link '//model%links(l)%name
            else
               b = self%bodies%node_body(d%node)
               if (b == 0) then
                  call input_error(error, 'the drive of node '//model%nodes(d%node)%name//' moves a node on no link')
                  return
               end if
               e = equation_type(kind=eq_point, bi=b, bj=0, comp=d%dof, drive=i)
               e%si = self%bodies%node_local(:, d%node)
               self%initial(i) = self%bodies%x0(d%dof, d%node)
               e%label = 'the '//merge('x', 'y', d%dof == dof_x)//' drive of node '//model%nodes(d%node)%name
            end if
            call append(self%eq, e)
         end associate
      end do

      ! Slidelines.
      allocate (self%slides(0))
      if (allocated(model%slidelines)) then
         do i = 1, size(model%slidelines)
            call add_slideline(self, model, i, error)
            if (allocated(error)) return
         end do
      end if
      self%m = size(self%eq)
      call self%select_segments(self%bodies%q0)
   end subroutine new_constraint_system

   !> The slot equation of slideline i, and for a prismatic joint the angle equation.
   subroutine add_slideline(self, model, i, error)
      type(constraint_system_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      integer, intent(in) :: i
      type(error_type), allocatable, intent(out) :: error
      type(equation_type) :: e
      type(slide_type) :: slide
      integer :: b, k, l
      real(dp) :: g(2)

      associate (s => model%slidelines(i))
         b = self%bodies%node_body(s%slave)
         if (s%kind == joint_prismatic) then
            if (s%slave_link < 1) then
               call input_error(error, 'slideline '//s%name//': a prismatic joint needs its slave link')
               return
            end if
            b = self%bodies%link_body(s%slave_link)
         end if
         if (b == 0) then
            call input_error(error, 'slideline '//s%name//': the slave node '//model%nodes(s%slave)%name//' is on no link')
            return
         end if
         slide%phi0 = self%bodies%q0(3*b)
         e = equation_type(kind=eq_slot, bi=b, bj=0)
         e%si = self%bodies%local(b, self%bodies%x0(:, s%slave))
         e%label = 'slideline '//s%name
         if (s%ground .or. .not. allocated(s%master_links)) then
            g = s%guide(:, 2) - s%guide(:, 1)
            if (norm2(g) <= 0) then
               call input_error(error, 'slideline '//s%name//': the ground guide has zero length')
               return
            end if
            e%sj = s%guide(:, 1)
            e%dir = g/norm2(g)
            allocate (slide%segments(0))
         else
            if (size(s%master_links) == 0) then
               call input_error(error, 'slideline '//s%name//' has no master line')
               return
            end if
            allocate (slide%segments(size(s%master_links)))
            do k = 1, size(s%master_links)
               l = s%master_links(k)
               slide%segments(k)%body = self%bodies%link_body(l)
               slide%segments(k)%p1 = self%bodies%local(slide%segments(k)%body, self%bodies%x0(:, model%links(l)%node(1)))
               slide%segments(k)%p2 = self%bodies%local(slide%segments(k)%body, self%bodies%x0(:, model%links(l)%node(2)))
               slide%segments(k)%phi0 = self%bodies%q0(3*slide%segments(k)%body)
            end do
         end if
         call append(self%eq, e)
         slide%slot = size(self%eq)
         if (s%kind == joint_prismatic) then
            e = equation_type(kind=eq_angle, bi=b, bj=0, const=slide%phi0)
            e%label = 'slideline '//s%name//' (prismatic)'
            call append(self%eq, e)
            slide%angle = size(self%eq)
         end if
         self%slides = [self%slides, slide]
      end associate
   end subroutine add_slideline

   !> Distinct bodies with a link end at node k, in link order.
   pure function bodies_at(model, bodies, k) result(at)
      type(model_type), intent(in) :: model
      type(body_map_type), intent(in) :: bodies
      integer, intent(in) :: k
      integer, allocatable :: at(:)
      integer :: l
      allocate (at(0))
      do l = 1, size(model%links)
         if (.not. any(model%links(l)%node == k)) cycle
         if (any(at == bodies%link_body(l))) cycle
         at = [at, bodies%link_body(l)]
      end do
   end function bodies_at

   !> The first link of body b with an end at node k (0 if none).
   pure integer function link_at(model, bodies, k, b) result(l)
      type(model_type), intent(in) :: model
      type(body_map_type), intent(in) :: bodies
      integer, intent(in) :: k, b
      do l = 1, size(model%links)
         if (any(model%links(l)%node == k) .and. bodies%link_body(l) == b) return
      end do
      l = 0
   end function link_at

   pure subroutine append(list, e)
      type(equation_type), allocatable, intent(inout) :: list(:)
      type(equation_type), intent(in) :: e
      list = [list, e]
   end subroutine append

   !> For each slideline with a master chain, the segment the slave is on at q:
   !> the master link whose span contains the slave's projection with the least
   !> normal distance, or else the nearest link. changed: whether some
   !> slideline's segment is another than before.
   pure subroutine system_select_segments(self, q, changed)
      class(constraint_system_type), intent(inout) :: self
      real(dp), intent(in) :: q(:)
      logical, intent(out), optional :: changed
      integer :: i, k, best
      real(dp) :: rs(2), p1(2), p2(2), v(2), lambda, dist, best_dist
      logical :: inside, best_inside

      if (present(changed)) changed = .false.
      do i = 1, size(self%slides)
         associate (slide => self%slides(i), e => self%eq(self%slides(i)%slot))
            if (size(slide%segments) == 0) cycle
            rs = point(q, e%bi, e%si)
            best = 1
            best_dist = huge(1.0_dp)
            best_inside = .false.
            do k = 1, size(slide%segments)
               p1 = point(q, slide%segments(k)%body, slide%segments(k)%p1)
               p2 = point(q, slide%segments(k)%body, slide%segments(k)%p2)
               v = p2 - p1
               lambda = dot_product(rs - p1, v)/dot_product(v, v)
               inside = lambda >= 0 .and. lambda <= 1
               dist = norm2(rs - (p1 + max(0.0_dp, min(1.0_dp, lambda))*v))
               if ((inside .and. .not. best_inside) .or. ((inside .eqv. best_inside) .and. dist < best_dist)) then
                  best = k
                  best_dist = dist
                  best_inside = inside
               end if
            end do
            if (present(changed) .and. best /= slide%current) changed = .true.
            slide%current = best
            associate (seg => slide%segments(best))
               e%bj = seg%body
               e%sj = seg%p1
               e%dir = (seg%p2 - seg%p1)/norm2(seg%p2 - seg%p1)
               if (slide%angle > 0) then
                  self%eq(slide%angle)%bj = seg%body
                  self%eq(slide%angle)%const = slide%phi0 - seg%phi0
               end if
            end associate
         end associate
      end do
   end subroutine system_select_segments

   pure logical function system_has_chains(self) result(chains)
      class(constraint_system_type), intent(in) :: self
      integer :: i
      chains = .false.
      do i = 1, size(self%slides)
         if (size(self%slides(i)%segments) > 1) chains = .true.
      end do
   end function system_has_chains

   !> d(t1) - d(t0) of every drive, and whether it drives a rotation (else a coordinate).
   pure subroutine system_drive_increments(self, t0, t1, increment, rotation)
      class(constraint_system_type), intent(in) :: self
      real(dp), intent(in) :: t0, t1
      !> (ndrive) the increments.
      real(dp), intent(out) :: increment(:)
      !> (ndrive) whether each drive is a rotation drive.
      logical, intent(out) :: rotation(:)
      integer :: k
      real(dp) :: f0, f1, df, ddf
      increment = 0
      rotation = .false.
      do k = 1, self%m
         associate (e => self%eq(k))
            if (e%drive == 0) cycle
            call drive_value(self%laws(e%drive), self%initial(e%drive), self%t_start, t0, f0, df, ddf)
            call drive_value(self%laws(e%drive), self%initial(e%drive), self%t_start, t1, f1, df, ddf)
            increment(e%drive) = f1 - f0
            rotation(e%drive) = e%kind == eq_angle
         end associate
      end do
   end subroutine system_drive_increments

   !> Position of the point with local coordinates s on body b (b = 0: s is global).
   pure function point(q, b, s) result(r)
      real(dp), intent(in) :: q(:), s(2)
      integer, intent(in) :: b
      real(dp) :: r(2)
      if (b == 0) then
         r = s
      else
         r = q(3*b - 2:3*b - 1) + rotate(q(3*b), s)
      end if
   end function point

   !> A(phi_b) s, zero for ground.
   pure function arm(q, b, s) result(r)
      real(dp), intent(in) :: q(:), s(2)
      integer, intent(in) :: b
      real(dp) :: r(2)
      if (b == 0) then
         r = 0
      else
         r = rotate(q(3*b), s)
      end if
   end function arm

   !> Angle of body b (0 for ground).
   pure real(dp) function angle_of(q, b) result(phi)
      real(dp), intent(in) :: q(:)
      integer, intent(in) :: b
      phi = 0
      if (b > 0) phi = q(3*b)
   end function angle_of

   !> Master line of a slot equation at q: unit direction u and point p.
   pure subroutine master_line(e, q, u, p)
      type(equation_type), intent(in) :: e
      real(dp), intent(in) :: q(:)
      real(dp), intent(out) :: u(2), p(2)
      if (e%bj == 0) then
         u = e%dir
      else
         u = rotate(q(3*e%bj), e%dir)
      end if
      p = point(q, e%bj, e%sj)
   end subroutine master_line

   !> Value and rates of the drive of equation e at time t (0 without a drive).
   pure subroutine drive_of(self, e, t, f, df, ddf)
      class(constraint_system_type), intent(in) :: self
      type(equation_type), intent(in) :: e
      real(dp), intent(in) :: t
      real(dp), intent(out) :: f, df, ddf
      f = 0
      df = 0
      ddf = 0
      if (e%drive > 0) call drive_value(self%laws(e%drive), self%initial(e%drive), self%t_start, t, f, df, ddf)
   end subroutine drive_of

   pure subroutine system_residual(self, q, t, phi)
      class(constraint_system_type), intent(in) :: self
      real(dp), intent(in) :: q(:), t
      !> (m) Phi(q, t).
      real(dp), intent(out) :: phi(:)
      integer :: k
      real(dp) :: f, df, ddf, u(2), p(2), ri(2), rj(2)
      do k = 1, self%m
         associate (e => self%eq(k))
            call drive_of(self, e, t, f, df, ddf)
            select case (e%kind)
            case (eq_point)
               ri = point(q, e%bi, e%si)
               rj = point(q, e%bj, e%sj)
               phi(k) = ri(e%comp) - rj(e%comp) - e%const - f
            case (eq_angle)
               phi(k) = angle_of(q, e%bi) - angle_of(q, e%bj) - e%const - f
            case default
               call master_line(e, q, u, p)
               phi(k) = dot_product(perp(u), point(q, e%bi, e%si) - p)
            end select
         end associate
      end do
   end subroutine system_residual

   pure subroutine system_jacobian(self, q, jac)
      class(constraint_system_type), intent(in) :: self
      real(dp), intent(in) :: q(:)
      !> (m, n) Phi_q(q).
      real(dp), intent(out) :: jac(:, :)
      integer :: k, i, j
      real(dp) :: u(2), p(2), n(2), rs(2), v(2)
      jac = 0
      do k = 1, self%m
         associate (e => self%eq(k))
            i = e%bi
            j = e%bj
            select case (e%kind)
            case (eq_point)
               v = perp(arm(q, i, e%si))
               jac(k, 3*i - 3 + e%comp) = 1
               jac(k, 3*i) = v(e%comp)
               if (j > 0) then
                  v = perp(arm(q, j, e%sj))
                  jac(k, 3*j - 3 + e%comp) = jac(k, 3*j - 3 + e%comp) - 1
                  jac(k, 3*j) = jac(k, 3*j) - v(e%comp)
               end if
            case (eq_angle)
               jac(k, 3*i) = 1
               if (j > 0) jac(k, 3*j) = jac(k, 3*j) - 1
            case default
               call master_line(e, q, u, p)
               n = perp(u)
               rs = point(q, i, e%si)
               jac(k, 3*i - 2:3*i - 1) = n
               jac(k, 3*i) = dot_product(u, arm(q, i, e%si))
               if (j > 0) then
                  jac(k, 3*j - 2:3*j - 1) = jac(k, 3*j - 2:3*j - 1) - n
                  jac(k, 3*j) = jac(k, 3*j) - dot_product(u, rs - q(3*j - 2:3*j - 1))
               end if
            end select
         end associate
      end do
   end subroutine system_jacobian

   pure subroutine system_velocity_rhs(self, t, nu)
      class(constraint_system_type), intent(in) :: self
      real(dp), intent(in) :: t
      !> (m) -Phi_t: the drive rates.
      real(dp), intent(out) :: nu(:)
      integer :: k
      real(dp) :: f, df, ddf
      do k = 1, self%m
         call drive_of(self, self%eq(k), t, f, df, ddf)
         nu(k) = df
      end do
   end subroutine system_velocity_rhs

   !> gamma = -(Phi_q q')_q q' - 2 Phi_qt q' - Phi_tt (Phi_qt = 0 here):
   !>  point: phi_i'**2 (A_i s_i)_c - phi_j'**2 (A_j s_j)_c + d'';
   !>  angle: d'';
   !>  slot:  phi_j'**2 n.(e - A_j s_j) + 2 phi_j' u.e' + phi_i'**2 n.(A_i s_i), e = r_i - p.
   pure subroutine system_acceleration_rhs(self, q, qd, t, gamma_rhs)
      class(constraint_system_type), intent(in) :: self
      real(dp), intent(in) :: q(:), qd(:), t
      !> (m) gamma.
      real(dp), intent(out) :: gamma_rhs(:)
      integer :: k, i, j
      real(dp) :: f, df, ddf, u(2), p(2), n(2), ai(2), aj(2), wi, wj, ed(2)
      do k = 1, self%m
         associate (e => self%eq(k))
            call drive_of(self, e, t, f, df, ddf)
            i = e%bi
            j = e%bj
            wi = angle_of(qd, i)
            wj = angle_of(qd, j)
            ai = arm(q, i, e%si)
            select case (e%kind)
            case (eq_point)
               aj = arm(q, j, e%sj)
               gamma_rhs(k) = wi**2*ai(e%comp) - wj**2*aj(e%comp) + ddf
            case (eq_angle)
               gamma_rhs(k) = ddf
            case default
               call master_line(e, q, u, p)
               n = perp(u)
               gamma_rhs(k) = wi**2*dot_product(n, ai)
               if (j > 0) then
                  aj = arm(q, j, e%sj)
                  ed = qd(3*i - 2:3*i - 1) + wi*perp(ai) - qd(3*j - 2:3*j - 1) - wj*perp(aj)
                  gamma_rhs(k) = gamma_rhs(k) + wj**2*dot_product(n, point(q, i, e%si) - p - aj) + 2*wj*dot_product(u, ed)
               end if
            end select
         end associate
      end do
   end subroutine system_acceleration_rhs

end module fekap_classical_constraints
