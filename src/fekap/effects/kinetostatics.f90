!> Kinetostatics of a fully driven mechanism: the forces its masses ask for
!> along the computed motion (docs/dynamics.md).
!>
!> At an accepted configuration q with accelerations a, the loads are the
!> inertia forces and the weight, f = -M a + M_g g (the consistent element
!> mass of fekap_element_inertia, point masses at nodes). The elastic links
!> answer with a small deflection u: K_ff u_f = f_f on the free dofs (u = 0 on
!> the supported and driven ones), K the material tangent at q, which the
!> stepper has factored for the rates already; the constrained dofs carry the
!> reactions r_c = (K u)_c - f_c: the drive torques and forces (the driven
!> dofs) and the support reactions. The force a joint exerts on a link end is
!> the end force of the link's element there, g_e = K_e u_e - f_e, with f_e the
!> element's own inertia and weight. The rows of the reactions, in order:
!> one per drive (model%drives), one per support (model%supports), two per
!> link (model%links: its first end, then its second).
module fekap_effects_kinetostatics
   use fekap_kinds, only: dp
   use fekap_model, only: model_type, dof_x, dof_y, dof_rot
   use fekap_assembly_mesh, only: mesh_type
   use fekap_element_beam, only: beam_residual
   use fekap_element_inertia, only: beam_inertia_force, beam_gravity_force
   implicit none
   private

   public :: kinetostatics_type, new_kinetostatics, kinetostatic_loads, kinetostatic_reactions, reaction_count

   !> Kinds of reaction rows.
   integer, parameter, public :: reaction_drive = 1, reaction_support = 2, reaction_joint = 3

   !> The masses in mesh terms and the reaction rows.
   type :: kinetostatics_type
      !> (nelem): mass and rotary inertia per length of each element.
      real(dp), allocatable :: rho_a(:), rho_i(:)
      !> (ndof): point masses on translations, rotary inertias on rotations.
      real(dp), allocatable :: point_mass(:)
      real(dp) :: gravity(2) = 0
      !> (3, nrow): the dofs whose reactions make each row's (fx, fy, m), 0
      !> where there is none (drives and supports).
      integer, allocatable :: row_dof(:, :)
      !> (nrow): for joint rows, the link's element at the end and which of
      !> its ends (1, 2); 0 for drives and supports.
      integer, allocatable :: row_element(:), row_end(:)
      !> (ndof) work: the assembled K u.
      real(dp), allocatable :: ku(:)
   end type kinetostatics_type

contains

   !> Number of reaction rows of a model: drives, supports, two per link.
   pure integer function reaction_count(model) result(n)
      type(model_type), intent(in) :: model
      n = 2*size(model%links)
      if (allocated(model%drives)) n = n + size(model%drives)
      if (allocated(model%supports)) n = n + size(model%supports)
   end function reaction_count

   !> The masses of `model` on its mesh, and the reaction rows.
   subroutine new_kinetostatics(self, model, mesh)
      type(kinetostatics_type), intent(out) :: self
      type(model_type), intent(in) :: model
      type(mesh_type), intent(in) :: mesh
      integer :: e, i, l, row, end_, dof
      integer, allocatable :: first(:), last(:)
      allocate (self%rho_a(size(mesh%elements)), self%rho_i(size(mesh%elements)))
      do e = 1, size(mesh%elements)
         associate (s => model%sections(model%links(mesh%elink(e))%section))
            self%rho_a(e) = s%rho_a
            self%rho_i(e) = s%rho_i
         end associate
      end do
      allocate (self%point_mass(mesh%ndof), self%ku(mesh%ndof), source=0.0_dp)
      if (allocated(model%masses)) then
         do i = 1, size(model%masses)
            associate (m => model%masses(i))
               self%point_mass(mesh%tdof(:, m%node)) = self%point_mass(mesh%tdof(:, m%node)) + m%mass
               if (m%link > 0) then
                  dof = mesh%link_rot(merge(1, 2, model%links(m%link)%node(1) == m%node), m%link)
                  self%point_mass(dof) = self%point_mass(dof) + m%inertia
               end if
            end associate
         end do
      end if
      self%gravity = model%gravity

      ! A link's elements run from its first node to its second.
      allocate (first(size(model%links)), last(size(model%links)), source=0)
      do e = size(mesh%elements), 1, -1
         first(mesh%elink(e)) = e
      end do
      do e = 1, size(mesh%elements)
         last(mesh%elink(e)) = e
      end do
      allocate (self%row_dof(3, reaction_count(model)), source=0)
      allocate (self%row_element(reaction_count(model)), self%row_end(reaction_count(model)), source=0)
      row = 0
      if (allocated(model%drives)) then
         do i = 1, size(model%drives)
            row = row + 1
            self%row_dof(model%drives(i)%dof, row) = mesh%driven_dof(i)
         end do
      end if
      if (allocated(model%supports)) then
         do i = 1, size(model%supports)
            row = row + 1
            associate (s => model%supports(i))
               if (s%fix(dof_x)) self%row_dof(dof_x, row) = mesh%tdof(1, s%node)
               if (s%fix(dof_y)) self%row_dof(dof_y, row) = mesh%tdof(2, s%node)
               if (s%fix(dof_rot)) self%row_dof(dof_rot, row) = &
                  & mesh%link_rot(merge(1, 2, model%links(s%link)%node(1) == s%node), s%link)
            end associate
         end do
      end if
      do l = 1, size(model%links)
         do end_ = 1, 2
            row = row + 1
            self%row_element(row) = merge(first(l), last(l), end_ == 1)
            self%row_end(row) = end_
         end do
      end do
   end subroutine new_kinetostatics

   !> The loads f = -M a + M_g g over all dofs, for accelerations a.
   pure subroutine kinetostatic_loads(self, mesh, a, f)
      type(kinetostatics_type), intent(in) :: self
      type(mesh_type), intent(in) :: mesh
      real(dp), intent(in) :: a(:)
      real(dp), intent(out) :: f(:)
      integer :: e, ip
      f = -self%point_mass*a
      do ip = 1, mesh%npoint
         f(mesh%tdof(:, ip)) = f(mesh%tdof(:, ip)) + self%point_mass(mesh%tdof(:, ip))*self%gravity
      end do
      do e = 1, size(mesh%elements)
         f(mesh%edof(:, e)) = f(mesh%edof(:, e)) + element_loads(self, mesh, e, a)
      end do
   end subroutine kinetostatic_loads

   !> The element's own loads: its inertia forces and weight.
   pure function element_loads(self, mesh, e, a) result(fe)
      type(kinetostatics_type), intent(in) :: self
      type(mesh_type), intent(in) :: mesh
      integer, intent(in) :: e
      real(dp), intent(in) :: a(:)
      real(dp) :: fe(6)
      real(dp) :: length
      length = mesh%elements(e)%length
      fe = beam_inertia_force(length, self%rho_a(e), self%rho_i(e), a(mesh%edof(:, e))) + &
         & beam_gravity_force(length, self%rho_a(e), self%gravity)
   end function element_loads

   !> The reactions (3, reaction_count) at q, with accelerations a, loads f
   !> (kinetostatic_loads) and the deflection u (zero on constrained dofs,
   !> K_ff u_f = f_f): drive and support rows r_c = (K u)_c - f_c, joint rows
   !> the element end forces K_e u_e - f_e. K is the material tangent at q.
   subroutine kinetostatic_reactions(self, mesh, q, a, f, u, reactions)
      type(kinetostatics_type), intent(inout) :: self
      type(mesh_type), intent(in) :: mesh
      real(dp), intent(in) :: q(:), a(:), f(:), u(:)
      real(dp), intent(out) :: reactions(:, :)
      real(dp) :: ke(6, 6), pe(6), ge(6)
      integer :: e, row, k, dof
      self%ku = 0
      do e = 1, size(mesh%elements)
         call beam_residual(mesh%elements(e), q(mesh%edof(:, e)), pe, ke, geometric_above=huge(1.0_dp))
         ge = matmul(ke, u(mesh%edof(:, e)))
         self%ku(mesh%edof(:, e)) = self%ku(mesh%edof(:, e)) + ge
      end do
      reactions = 0
      do row = 1, size(reactions, 2)
         e = self%row_element(row)
         if (e > 0) then
            call beam_residual(mesh%elements(e), q(mesh%edof(:, e)), pe, ke, geometric_above=huge(1.0_dp))
            ge = matmul(ke, u(mesh%edof(:, e))) - element_loads(self, mesh, e, a)
            reactions(:, row) = ge(3*self%row_end(row) - 2:3*self%row_end(row))
         else
            do k = 1, 3
               dof = self%row_dof(k, row)
               if (dof > 0) reactions(k, row) = self%ku(dof) - f(dof)
            end do
         end if
      end do
   end subroutine kinetostatic_reactions

end module fekap_effects_kinetostatics
