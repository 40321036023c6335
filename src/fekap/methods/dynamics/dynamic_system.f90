!> The equations of motion of the finite element mesh and their iteration
!> matrix (docs/dynamics.md):
!>   R(q, qd, qdd, t) = M qdd + D(q, qd) + P(q) - F^c(q) - g(t) = 0 on the free dofs,
!> M the consistent mass (fekap_element_inertia) with the point masses, D the
!> damping force: Rayleigh's alpha M qd + beta K_m(q) qd of each element's
!> section (the beta part objective: the viscous stresses of the material
!> strain rates at q, fekap_element_beam_damping) and the slidelines'
!> dashpots c (N_s(q) . qd) N_s(q) (`damping=`, at the gap's gradient at q),
!> P the beams' internal forces, F^c the slidelines' penalty forces, g the
!> weights and the loads at time t. With qd and qdd functions of q through
!> the integrator (qd' = c1, qdd' = c2), the iteration matrix is
!> dR/dq = K + dD/dq + c1 dD/dqd + c2 M, in the FEM's band storage; the
!> damping's dD/dq is not symmetric (the band then holds both triangles and
!> is factored by LU). On the constrained dofs R is what the supports and
!> drives apply.
module fekap_dynamics_dynamic_system
   use fekap_kinds, only: dp
   use fekap_model, only: model_type, dof_rot, joint_prismatic
   use fekap_model_work, only: work_counts_type
   use fekap_assembly_mesh, only: mesh_type, point_masses
   use fekap_element_beam, only: beam_strain_energy
   use fekap_element_beam_damping, only: beam_damping_force, beam_strain_change
   use fekap_element_inertia, only: beam_mass_matrix, beam_gravity_force
   use fekap_fem_linear_system, only: linear_system_type, assemble_system, assemble_system_residual
   use fekap_assembly_tracking, only: slide_position
   use fekap_assembly_assemble, only: scatter, scatter_element, gather, subtract
   use fekap_contact_slideline, only: slide_energy, slide_tie_energy, slide_dashpot, slide_geometry
   implicit none
   private

   public :: dynamic_system_type, new_dynamic_system, external_forces, assemble_dynamics
   public :: kinetic_energy, strain_energy, momentum, has_damping, times6
   public :: has_slide_damping, penalty_energy, element_damping_force, slide_damping_force, damping_work

   type :: dynamic_system_type
      !> (6, 6, nelem): each element's consistent mass matrix.
      real(dp), allocatable :: me(:, :, :)
      !> (nelem): Rayleigh coefficients of each element's section.
      real(dp), allocatable :: alpha(:), beta(:)
      !> (ndof): point masses on translations, rotary inertias on rotations.
      real(dp), allocatable :: point_mass(:)
      !> (ndof): the weights (consistent element weights and point masses' weights).
      real(dp), allocatable :: weight(:)
      !> (ndof) work.
      real(dp), allocatable :: work(:)
      !> (nslide): each slideline's dashpot on its gap rate.
      real(dp), allocatable :: slide_c(:)
   end type dynamic_system_type

contains

   !> The masses, weights, damping and loads of `model` on its mesh.
   subroutine new_dynamic_system(self, model, mesh)
      type(dynamic_system_type), intent(out) :: self
      type(model_type), intent(in) :: model
      type(mesh_type), intent(in) :: mesh
      integer :: e, i, ne
      ne = size(mesh%elements)
      allocate (self%me(6, 6, ne), source=0.0_dp)
      allocate (self%alpha(ne), self%beta(ne), source=0.0_dp)
      allocate (self%point_mass(mesh%ndof), self%weight(mesh%ndof), self%work(mesh%ndof), source=0.0_dp)
      allocate (self%slide_c(size(mesh%slides)), source=0.0_dp)
      do i = 1, size(mesh%slides)
         self%slide_c(i) = model%slidelines(i)%damping
      end do
      do e = 1, ne
         associate (s => model%sections(model%links(mesh%elink(e))%section), el => mesh%elements(e))
            self%me(:, :, e) = beam_mass_matrix(el%length, s%rho_a, s%rho_i)
            self%alpha(e) = s%alpha
            self%beta(e) = s%beta
            self%weight(mesh%edof(:, e)) = self%weight(mesh%edof(:, e)) + &
               & beam_gravity_force(el%length, s%rho_a, model%gravity)
         end associate
      end do
      self%point_mass = point_masses(mesh, model)
      if (allocated(model%masses)) then
         do i = 1, size(model%masses)
            associate (m => model%masses(i))
               self%weight(mesh%tdof(:, m%node)) = self%weight(mesh%tdof(:, m%node)) + m%mass*model%gravity
            end associate
         end do
      end if
   end subroutine new_dynamic_system

   !> Whether some element is damped.
   pure logical function has_damping(self)
      type(dynamic_system_type), intent(in) :: self
      has_damping = any(self%alpha /= 0 .or. self%beta /= 0)
   end function has_damping

   !> Whether some slideline has a dashpot.
   pure logical function has_slide_damping(self)
      type(dynamic_system_type), intent(in) :: self
      has_slide_damping = any(self%slide_c /= 0)
   end function has_slide_damping

   !> The damping force of element e at (q, v) over its dofs (edof):
   !> alpha M_e v_e + beta K_m(q_e) v_e (beam_damping_force) and, if asked,
   !> beta's share of the iteration matrix k = dD_e/dq_e + c1 dD_e/dv_e (not
   !> symmetric; zero when beta is; alpha's c1 alpha M_e goes with the mass).
   pure subroutine element_damping(self, mesh, e, q, v, fe, c1, ke)
      type(dynamic_system_type), intent(in) :: self
      type(mesh_type), intent(in) :: mesh
      integer, intent(in) :: e
      real(dp), intent(in) :: q(:), v(:)
      real(dp), intent(out) :: fe(6)
      real(dp), intent(in), optional :: c1
      real(dp), intent(out), optional :: ke(6, 6)
      real(dp) :: ve(6), fb(6)
      ve = gather(v, mesh%edof(:, e))
      fe = self%alpha(e)*times6(self%me, e, ve)
      if (present(ke)) ke = 0
      if (self%beta(e) == 0) return
      if (present(ke)) then
         call beam_damping_force(mesh%elements(e), gather(q, mesh%edof(:, e)), ve, self%beta(e), fb, c1, ke)
      else
         call beam_damping_force(mesh%elements(e), gather(q, mesh%edof(:, e)), ve, self%beta(e), fb)
      end if
      fe = fe + fb
   end subroutine element_damping

   !> Element e's damping force at (q, v) over its dofs (element_damping).
   pure function element_damping_force(self, mesh, e, q, v) result(fe)
      type(dynamic_system_type), intent(in) :: self
      type(mesh_type), intent(in) :: mesh
      integer, intent(in) :: e
      real(dp), intent(in) :: q(:), v(:)
      real(dp) :: fe(6)
      call element_damping(self, mesh, e, q, v, fe)
   end function element_damping_force

   !> Slideline i's dashpot at (q, v) on its master segment seg: the force
   !> c (N_s . v) N_s it resists with (slide_dashpot) on the dofs `dofs`
   !> (0: a ground guide's point) and, if asked, its iteration matrix's share.
   pure subroutine slide_damping_force(self, mesh, i, q, v, seg, f, dofs, c1, k)
      type(dynamic_system_type), intent(in) :: self
      type(mesh_type), intent(in) :: mesh
      integer, intent(in) :: i, seg
      real(dp), intent(in) :: q(:), v(:)
      real(dp), intent(out) :: f(6)
      integer, intent(out) :: dofs(6)
      real(dp), intent(in), optional :: c1
      real(dp), intent(out), optional :: k(6, 6)
      real(dp) :: xs(2), x1(2), x2(2)
      call slide_position(mesh, mesh%slides(i), seg, q, xs, x1, x2, dofs)
      call slide_dashpot(xs, x1, x2, self%slide_c(i), gather(v, dofs), f, c1, k)
   end subroutine slide_damping_force

   !> The energy the damping dissipated over a step of length h from (q0, v0)
   !> to (q1, v1) (seg: the step's master segments): alpha/2 dq^T M_e (v0 + v1),
   !> the trapezoidal rule as the loads' work, and beta/h L |Delta eps|_D^2 per
   !> element and c Delta g^2 / h per dashpot, the work of the viscous forces at
   !> the strain and gap rates Delta eps/h and Delta g/h: objective (no work in a
   !> rigid step), never negative, and equal to the trapezoidal rule of the
   !> forces on dq for a linear system under the trapezoidal integrator. The
   !> energy-momentum step's damping does exactly this work with v0 = v1 = z/h
   !> and its increments z (Cayley's on rotations) as dq.
   pure real(dp) function damping_work(self, mesh, q0, v0, q1, v1, seg, h, z) result(work)
      type(dynamic_system_type), intent(in) :: self
      type(mesh_type), intent(in) :: mesh
      real(dp), intent(in) :: q0(:), v0(:), q1(:), v1(:), h
      integer, intent(in) :: seg(:)
      !> The step's increments, if not q1 - q0.
      real(dp), intent(in), optional :: z(:)
      real(dp) :: x0(6), x1(6), dq(6), xs(2, 2), xa(2, 2), xb(2, 2), g(2), alpha, s1
      integer :: e, i, k, dofs(6)
      work = 0
      do e = 1, size(mesh%elements)
         if (self%alpha(e) == 0 .and. self%beta(e) == 0) cycle
         x0 = gather(q0, mesh%edof(:, e))
         x1 = gather(q1, mesh%edof(:, e))
         dq = x1 - x0
         if (present(z)) dq = gather(z, mesh%edof(:, e))
         work = work + 0.5_dp*self%alpha(e)*dot_product(dq, times6(self%me, e, gather(v0, mesh%edof(:, e)) + &
            & gather(v1, mesh%edof(:, e))))
         if (self%beta(e) /= 0) work = work + self%beta(e)*beam_strain_change(mesh%elements(e), x0, x1)/h
      end do
      do i = 1, size(self%slide_c)
         if (self%slide_c(i) == 0) cycle
         call slide_position(mesh, mesh%slides(i), seg(i), q0, xs(:, 1), xa(:, 1), xb(:, 1), dofs)
         call slide_position(mesh, mesh%slides(i), seg(i), q1, xs(:, 2), xa(:, 2), xb(:, 2), dofs)
         do k = 1, 2
            call slide_geometry(xs(:, k), xa(:, k), xb(:, k), g(k), alpha, s1)
         end do
         work = work + self%slide_c(i)*(g(2) - g(1))**2/h
      end do
   end function damping_work

   !> The slidelines' penalty energy at q: kp g^2/2 of each gap spring and
   !> kr e^2/2 of each prismatic tie (F^c is minus its gradient).
   pure real(dp) function penalty_energy(mesh, q, seg) result(energy)
      type(mesh_type), intent(in) :: mesh
      real(dp), intent(in) :: q(:)
      integer, intent(in) :: seg(:)
      real(dp) :: xs(2), x1(2), x2(2)
      integer :: i, dofs(6)
      energy = 0
      do i = 1, size(mesh%slides)
         associate (sl => mesh%slides(i))
            call slide_position(mesh, sl, seg(i), q, xs, x1, x2, dofs)
            energy = energy + slide_energy(xs, x1, x2, sl%kp)
            if (sl%kind == joint_prismatic) energy = energy + &
               & slide_tie_energy(q(sl%slave_rot), x1, x2, sl%c0(seg(i)), sl%kr)
         end associate
      end do
   end function penalty_energy

   !> g(t): the weights and the loads at time t (the mesh's load set: the
   !> loads with a law at its value, the others times the load factor t).
   subroutine external_forces(self, mesh, t, g)
      type(dynamic_system_type), intent(in) :: self
      type(mesh_type), intent(in) :: mesh
      real(dp), intent(in) :: t
      real(dp), intent(out) :: g(:)
      call mesh%loads%at(t, g)
      g = g + self%weight
   end subroutine external_forces

   !> The residual R over all dofs at time t into system%r, and with `c1`, `c2`
   !> the iteration matrix K + dD/dq + c1 dD/dqd + c2 M into the system's band
   !> (and free-driven block): not symmetric with beta damping or dashpots.
   subroutine assemble_dynamics(self, system, mesh, q, v, acc, t, seg, counts, c1, c2)
      type(dynamic_system_type), intent(inout) :: self
      type(linear_system_type), intent(inout) :: system
      type(mesh_type), intent(in) :: mesh
      real(dp), contiguous, intent(in) :: q(:), v(:), acc(:)
      real(dp), intent(in) :: t
      integer, intent(in) :: seg(:)
      type(work_counts_type), intent(inout) :: counts
      real(dp), intent(in), optional :: c1, c2
      real(dp) :: me(36), k, ae(6), fe(6), fd(6), ke(6, 6)
      integer :: e, i, dofs(6)
      logical :: damped, tangent
      damped = has_damping(self)
      tangent = present(c2)
      if (tangent) then
         ! Full geometric stiffness: the motion strains the links.
         call assemble_system(system, mesh, q, t, seg, 0.0_dp, counts)
      else
         call assemble_system_residual(system, mesh, q, t, seg, counts)
      end if
      ! The assembly subtracted the loads at t; the weights are the masses'.
      associate (r => system%r)
         r = r - self%weight + self%point_mass*acc
         do e = 1, size(mesh%elements)
            do i = 1, 6
               ae(i) = acc(mesh%edof(i, e))
            end do
            fe = times6(self%me, e, ae)
            if (damped .and. tangent) then
               ! The damping at the iterate (q, v), and its share of the iteration matrix.
               call element_damping(self, mesh, e, q, v, fd, c1, ke)
               fe = fe + fd
               if (self%beta(e) /= 0) call scatter(mesh, mesh%edof(:, e), ke, system%kff, system%kfd, general=.true.)
            else if (damped) then
               call element_damping(self, mesh, e, q, v, fd)
               fe = fe + fd
            end if
            do i = 1, 6
               r(mesh%edof(i, e)) = r(mesh%edof(i, e)) + fe(i)
            end do
         end do
         ! The slidelines' dashpots at (q, v).
         do i = 1, size(self%slide_c)
            if (self%slide_c(i) == 0) cycle
            if (tangent) then
               call slide_damping_force(self, mesh, i, q, v, seg(i), fe, dofs, c1, ke)
               call scatter(mesh, dofs, ke, system%kff, system%kfd, general=.true.)
            else
               call slide_damping_force(self, mesh, i, q, v, seg(i), fe, dofs)
            end if
            call subtract(r, dofs, -fe)
         end do
      end associate
      if (.not. tangent) return
      do e = 1, size(mesh%elements)
         ! c2 M_e and alpha's c1 alpha M_e (beta's share went in with the damping force).
         call scaled(self%me(:, :, e), c2 + c1*self%alpha(e), me)
         call scatter_element(mesh%scatter_map(:, mesh%scatter_start(e):), mesh%scatter_count(1, e), &
            & mesh%scatter_count(2, e), me, system%kff%a, system%kfd)
      end do
      do i = 1, mesh%nfree
         k = self%point_mass(mesh%eq_dof(i))
         if (k /= 0) call system%kff%add(i, i, c2*k)
      end do
   end subroutine assemble_dynamics

   !> c m, as 36 numbers in memory order.
   pure subroutine scaled(m, c, mc)
      real(dp), intent(in) :: m(36), c
      real(dp), intent(out) :: mc(36)
      mc = c*m
   end subroutine scaled

   !> y = m(:, :, e) x for element e's 6 x 6 matrix of m (6, 6, nelem),
   !> without a copy of it (m is contiguous, so its slice is passed in place).
   pure function times6(m, e, x) result(y)
      real(dp), contiguous, intent(in) :: m(:, :, :)
      integer, intent(in) :: e
      real(dp), intent(in) :: x(6)
      real(dp) :: y(6)
      y = product6(m(:, :, e), x)
   end function times6

   !> a x for a 6 x 6 matrix of explicit shape (the compiler knows its
   !> strides), summed in a local (registers), not through the result.
   pure function product6(a, x) result(y)
      real(dp), intent(in) :: a(6, 6), x(6)
      real(dp) :: y(6)
      real(dp) :: w(6)
      integer :: j
      w = a(:, 1)*x(1)
      do j = 2, 6
         w = w + a(:, j)*x(j)
      end do
      y = w
   end function product6

   !> Kinetic energy 1/2 v^T M v.
   pure real(dp) function kinetic_energy(self, mesh, v) result(energy)
      type(dynamic_system_type), intent(in) :: self
      type(mesh_type), intent(in) :: mesh
      real(dp), intent(in) :: v(:)
      real(dp) :: ve(6)
      integer :: e, i
      energy = 0.5_dp*sum(self%point_mass*v**2)
      do e = 1, size(mesh%elements)
         do i = 1, 6
            ve(i) = v(mesh%edof(i, e))
         end do
         energy = energy + 0.5_dp*dot_product(ve, times6(self%me, e, ve))
      end do
   end function kinetic_energy

   !> Strain energy of the beams at q.
   pure real(dp) function strain_energy(mesh, q) result(energy)
      type(mesh_type), intent(in) :: mesh
      real(dp), intent(in) :: q(:)
      real(dp) :: xe(6)
      integer :: e, i
      energy = 0
      do e = 1, size(mesh%elements)
         do i = 1, 6
            xe(i) = q(mesh%edof(i, e))
         end do
         energy = energy + beam_strain_energy(mesh%elements(e), xe)
      end do
   end function strain_energy

   !> Linear momentum (px, py) and angular momentum about the origin of the
   !> motion (q, v): sum of M v over the translations, and the integral of
   !> rhoA x cross v + rhoI omega (exact for the linear interpolation:
   !> x cross v is quadratic along an element) with the point masses.
   pure function momentum(self, mesh, q, v) result(p)
      type(dynamic_system_type), intent(in) :: self
      type(mesh_type), intent(in) :: mesh
      real(dp), intent(in) :: q(:), v(:)
      real(dp) :: p(3)
      real(dp) :: mv(6), xe(6), ve(6), c(2)
      integer :: e, ip
      p = 0
      do ip = 1, mesh%npoint
         associate (d => mesh%tdof(:, ip))
            p(1:2) = p(1:2) + self%point_mass(d)*v(d)
            p(3) = p(3) + self%point_mass(d(1))*(q(d(1))*v(d(2)) - q(d(2))*v(d(1)))
         end associate
      end do
      do e = 1, size(mesh%elements)
         do ip = 1, 6
            xe(ip) = q(mesh%edof(ip, e))
            ve(ip) = v(mesh%edof(ip, e))
         end do
         mv = times6(self%me, e, ve)
         p(1:2) = p(1:2) + mv(1:2) + mv(4:5)
         ! int rhoA x cross v with x, v linear: the mass matrix's weights.
         c(1) = xe(1)*mv(2) - xe(2)*mv(1)
         c(2) = xe(4)*mv(5) - xe(5)*mv(4)
         p(3) = p(3) + c(1) + c(2) + mv(3) + mv(6)
      end do
      ! Rotary inertias at link ends.
      do ip = 1, mesh%ndof
         if (mesh%dof_kind(ip) == dof_rot) p(3) = p(3) + self%point_mass(ip)*v(ip)
      end do
   end function momentum

end module fekap_dynamics_dynamic_system
