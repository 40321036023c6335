!> The equations of motion of the finite element mesh and their iteration
!> matrix (docs/dynamics.md):
!>   R(q, qd, qdd, t) = M qdd + C qd + P(q) - F^c(q) - g(t) = 0 on the free dofs,
!> M the consistent mass (fekap_element_inertia) with the point masses, C the
!> Rayleigh damping alpha M + beta K_m of each element's section (K_m the
!> material tangent, taken at the configuration of the step's start so that
!> C is constant over a step), P the beams' internal forces, F^c the
!> slidelines' penalty forces, g the weights and the loads at time t. A
!> slideline with `damping=` adds its dashpot c N_s N_s^T (N_s the gap's
!> gradient at the step's start, so constant over the step as Rayleigh's) to C.
!> With
!> qd and qdd functions of q through the integrator (qd' = c1, qdd' = c2),
!> the iteration matrix is dR/dq = K + c1 C + c2 M, in the FEM's band storage.
!> On the constrained dofs R is what the supports and drives apply.
module fekap_effects_dynamic_system
   use fekap_kinds, only: dp
   use fekap_model, only: model_type, dof_rot, joint_prismatic
   use fekap_model_work, only: work_counts_type
   use fekap_assembly_mesh, only: mesh_type, point_masses
   use fekap_element_beam, only: beam_residual, beam_strain_energy
   use fekap_element_inertia, only: beam_mass_matrix, beam_gravity_force
   use fekap_solver_linear_system, only: linear_system_type, assemble_system, assemble_system_residual
   use fekap_assembly_tracking, only: slide_position
   use fekap_assembly_assemble, only: scatter, scatter_element, gather
   use fekap_contact_slideline, only: slide_energy, slide_tie_energy, slide_gap_gradient
   implicit none
   private

   public :: dynamic_system_type, new_dynamic_system, external_forces, assemble_dynamics, update_damping
   public :: kinetic_energy, strain_energy, momentum, has_damping, times6
   public :: has_slide_damping, update_slide_damping, slide_damping_work, penalty_energy

   type :: dynamic_system_type
      !> (6, 6, nelem): each element's consistent mass and damping matrices.
      real(dp), allocatable :: me(:, :, :), ce(:, :, :)
      !> (nelem): Rayleigh coefficients of each element's section.
      real(dp), allocatable :: alpha(:), beta(:)
      !> (ndof): point masses on translations, rotary inertias on rotations.
      real(dp), allocatable :: point_mass(:)
      !> (ndof): the weights (consistent element weights and point masses' weights).
      real(dp), allocatable :: weight(:)
      !> (ndof) work.
      real(dp), allocatable :: work(:)
      !> (nslide): each slideline's dashpot on its gap rate; (6, 6, nslide):
      !> its damping matrix c N_s N_s^T of the step, on the dofs slide_dofs
      !> (6, nslide) (0: a ground guide's point).
      real(dp), allocatable :: slide_c(:), cs(:, :, :)
      integer, allocatable :: slide_dofs(:, :)
   end type dynamic_system_type

contains

   !> The masses, weights, damping and loads of `model` on its mesh.
   subroutine new_dynamic_system(self, model, mesh)
      type(dynamic_system_type), intent(out) :: self
      type(model_type), intent(in) :: model
      type(mesh_type), intent(in) :: mesh
      integer :: e, i, ne
      ne = size(mesh%elements)
      allocate (self%me(6, 6, ne), self%ce(6, 6, ne), source=0.0_dp)
      allocate (self%alpha(ne), self%beta(ne), source=0.0_dp)
      allocate (self%point_mass(mesh%ndof), self%weight(mesh%ndof), self%work(mesh%ndof), source=0.0_dp)
      allocate (self%slide_c(size(mesh%slides)), self%cs(6, 6, size(mesh%slides)), source=0.0_dp)
      allocate (self%slide_dofs(6, size(mesh%slides)), source=0)
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

   !> Each damped slideline's matrix c N_s N_s^T at q (its master segment
   !> seg): the dashpot for the step that starts at q.
   pure subroutine update_slide_damping(self, mesh, q, seg)
      type(dynamic_system_type), intent(inout) :: self
      type(mesh_type), intent(in) :: mesh
      real(dp), intent(in) :: q(:)
      integer, intent(in) :: seg(:)
      real(dp) :: xs(2), x1(2), x2(2), ns(6)
      integer :: i, j
      do i = 1, size(mesh%slides)
         if (self%slide_c(i) == 0) cycle
         call slide_position(mesh, mesh%slides(i), seg(i), q, xs, x1, x2, self%slide_dofs(:, i))
         ns = slide_gap_gradient(xs, x1, x2)
         do j = 1, 6
            self%cs(:, j, i) = self%slide_c(i)*ns*ns(j)
         end do
      end do
   end subroutine update_slide_damping

   !> The energy the slidelines' dashpots dissipated over a step: the
   !> trapezoidal rule of C_s v on the displacement dq (C_s of the step).
   pure real(dp) function slide_damping_work(self, v0, v1, dq) result(work)
      type(dynamic_system_type), intent(in) :: self
      real(dp), intent(in) :: v0(:), v1(:), dq(:)
      integer :: i
      work = 0
      do i = 1, size(self%slide_c)
         if (self%slide_c(i) == 0) cycle
         associate (dofs => self%slide_dofs(:, i))
            work = work + 0.5_dp*dot_product(gather(dq, dofs), matmul(self%cs(:, :, i), gather(v0, dofs) + gather(v1, dofs)))
         end associate
      end do
   end function slide_damping_work

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

   !> Each element's damping matrix alpha M + beta K_m at q (the material
   !> tangent): C for the step that starts at q.
   pure subroutine update_damping(self, mesh, q)
      type(dynamic_system_type), intent(inout) :: self
      type(mesh_type), intent(in) :: mesh
      real(dp), intent(in) :: q(:)
      real(dp) :: pe(6), ke(6, 6)
      integer :: e
      do e = 1, size(mesh%elements)
         self%ce(:, :, e) = self%alpha(e)*self%me(:, :, e)
         if (self%beta(e) /= 0) then
            call beam_residual(mesh%elements(e), q(mesh%edof(:, e)), pe, ke, geometric_above=huge(1.0_dp))
            self%ce(:, :, e) = self%ce(:, :, e) + self%beta(e)*ke
         end if
      end do
   end subroutine update_damping

   !> The residual R over all dofs at time t into system%r, and with `c1`, `c2` the iteration matrix K + c1 C + c2 M into the
   !> system's band (and free-driven block).
   subroutine assemble_dynamics(self, system, mesh, q, v, acc, t, seg, counts, c1, c2)
      type(dynamic_system_type), intent(inout) :: self
      type(linear_system_type), intent(inout) :: system
      type(mesh_type), intent(in) :: mesh
      real(dp), contiguous, intent(in) :: q(:), v(:), acc(:)
      real(dp), intent(in) :: t
      integer, intent(in) :: seg(:)
      type(work_counts_type), intent(inout) :: counts
      real(dp), intent(in), optional :: c1, c2
      real(dp) :: me(36), k, ae(6), ve(6), fe(6)
      integer :: e, i, j
      logical :: damped, slide_damped
      damped = has_damping(self)
      slide_damped = has_slide_damping(self)
      if (present(c2)) then
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
               ve(i) = v(mesh%edof(i, e))
            end do
            fe = times6(self%me, e, ae)
            if (damped) fe = fe + times6(self%ce, e, ve)
            do i = 1, 6
               r(mesh%edof(i, e)) = r(mesh%edof(i, e)) + fe(i)
            end do
         end do
         if (slide_damped) then
            ! The slidelines' dashpots: C_s v on their dofs.
            do i = 1, size(self%slide_c)
               if (self%slide_c(i) == 0) cycle
               fe = matmul(self%cs(:, :, i), gather(v, self%slide_dofs(:, i)))
               do j = 1, 6
                  if (self%slide_dofs(j, i) > 0) r(self%slide_dofs(j, i)) = r(self%slide_dofs(j, i)) + fe(j)
               end do
            end do
         end if
      end associate
      if (.not. present(c2)) return
      if (slide_damped) then
         do i = 1, size(self%slide_c)
            if (self%slide_c(i) /= 0) call scatter(mesh, self%slide_dofs(:, i), c1*self%cs(:, :, i), system%kff, &
               & system%kfd)
         end do
      end if
      do e = 1, size(mesh%elements)
         call combine(self%me(:, :, e), self%ce(:, :, e), c1, c2, me)
         call scatter_element(mesh%scatter_map(:, :, e), mesh%scatter_count(1, e), mesh%scatter_count(2, e), me, &
            & system%kff%a, system%kfd)
      end do
      do i = 1, mesh%nfree
         k = self%point_mass(mesh%eq_dof(i))
         if (k /= 0) call system%kff%add(i, i, c2*k)
      end do
   end subroutine assemble_dynamics

   !> c2 m + c1 c, as 36 numbers in memory order.
   pure subroutine combine(m, c, c1, c2, mc)
      real(dp), intent(in) :: m(36), c(36), c1, c2
      real(dp), intent(out) :: mc(36)
      mc = c2*m + c1*c
   end subroutine combine

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

end module fekap_effects_dynamic_system
