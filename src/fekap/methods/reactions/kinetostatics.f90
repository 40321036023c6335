!> Kinetostatics of a fully driven mechanism: the forces its masses ask for
!> along the computed motion (docs/dynamics.md).
!>
!> At an accepted configuration q with accelerations a, the loads are the
!> inertia forces and the weight, f = -M a + M_g g (the consistent element
!> mass of fekap_element_inertia, point masses at nodes). The elastic links
!> answer with a small deflection u: K_ff u_f = f_f on the free dofs (u = 0 on
!> the supported and driven ones), K the material tangent at q, which the
!> stepper has factored for the rates already (or B_f, K = B^T W B, in the
!> square-root form: fekap_fem_state's solve_at_accepted); the constrained dofs carry the
!> reactions r_c = (K u)_c - f_c: the drive torques and forces (the driven
!> dofs) and the support reactions. The force a joint exerts on a link end is
!> the end force of the link's element there, g_e = K_e u_e - f_e, with f_e the
!> element's own inertia and weight; the force a sliding joint exerts on its
!> slave is its penalty force, linearised: K^c u. The rows of the reactions
!> are fekap_model_reactions' (drives, supports, sliders, link ends).
!> Statics (fekap_reactions_statics) fills the same rows from the full
!> residual at its loaded configuration.
module fekap_reactions_kinetostatics
   use fekap_kinds, only: dp
   use fekap_model, only: model_type, dof_x, dof_y, dof_rot, joint_prismatic
   use fekap_model_reactions, only: reaction_row_type, reaction_rows, reaction_count, reaction_drive, &
      & reaction_support, reaction_slider
   use fekap_assembly_mesh, only: mesh_type, point_masses
   use fekap_assembly_tracking, only: slide_position
   use fekap_assembly_assemble, only: gather
   use fekap_contact_slideline, only: slide_force, slide_tie_force
   use fekap_element_beam, only: beam_residual
   use fekap_element_inertia, only: beam_inertia_force, beam_gravity_force
   implicit none
   private

   public :: kinetostatics_type, new_kinetostatics, kinetostatic_loads, kinetostatic_reactions, element_own_loads, &
      & slider_force

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
      !> (nrow): for slider rows, the slideline; 0 otherwise.
      integer, allocatable :: row_slide(:)
      !> (ndof) work: the assembled K u.
      real(dp), allocatable :: ku(:)
   end type kinetostatics_type

contains

   !> The masses of `model` on its mesh, and the reaction rows.
   subroutine new_kinetostatics(self, model, mesh)
      type(kinetostatics_type), intent(out) :: self
      type(model_type), intent(in) :: model
      type(mesh_type), intent(in) :: mesh
      integer :: e, i, l, row, end_
      integer, allocatable :: first(:), last(:)
      type(reaction_row_type), allocatable :: rows(:)
      allocate (self%rho_a(size(mesh%elements)), self%rho_i(size(mesh%elements)))
      do e = 1, size(mesh%elements)
         associate (s => model%sections(model%links(mesh%elink(e))%section))
            self%rho_a(e) = s%rho_a
            self%rho_i(e) = s%rho_i
         end associate
      end do
      allocate (self%ku(mesh%ndof), source=0.0_dp)
      self%point_mass = point_masses(mesh, model)
      self%gravity = model%gravity

      ! A link's elements run from its first node to its second.
      allocate (first(size(model%links)), last(size(model%links)), source=0)
      do e = size(mesh%elements), 1, -1
         first(mesh%elink(e)) = e
      end do
      do e = 1, size(mesh%elements)
         last(mesh%elink(e)) = e
      end do
      rows = reaction_rows(model)
      allocate (self%row_dof(3, size(rows)), source=0)
      allocate (self%row_element(size(rows)), self%row_end(size(rows)), self%row_slide(size(rows)), source=0)
      do row = 1, size(rows)
         i = rows(row)%item
         select case (rows(row)%kind)
         case (reaction_drive)
            self%row_dof(model%drives(i)%dof, row) = mesh%driven_dof(i)
         case (reaction_support)
            associate (s => model%supports(i))
               if (s%fix(dof_x)) self%row_dof(dof_x, row) = mesh%tdof(1, s%node)
               if (s%fix(dof_y)) self%row_dof(dof_y, row) = mesh%tdof(2, s%node)
               if (s%fix(dof_rot)) self%row_dof(dof_rot, row) = &
                  & mesh%link_rot(merge(1, 2, model%links(s%link)%node(1) == s%node), s%link)
            end associate
         case (reaction_slider)
            self%row_slide(row) = i
         case default
            ! reaction_joint: one end of link i.
            l = i
            end_ = rows(row)%end
            self%row_element(row) = merge(first(l), last(l), end_ == 1)
            self%row_end(row) = end_
         end select
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
         f(mesh%edof(:, e)) = f(mesh%edof(:, e)) + element_own_loads(self, mesh, e, a)
      end do
   end subroutine kinetostatic_loads

   !> The element's own loads: its inertia forces (for accelerations a) and weight.
   pure function element_own_loads(self, mesh, e, a) result(fe)
      type(kinetostatics_type), intent(in) :: self
      type(mesh_type), intent(in) :: mesh
      integer, intent(in) :: e
      real(dp), intent(in) :: a(:)
      real(dp) :: fe(6)
      real(dp) :: length
      length = mesh%elements(e)%length
      fe = beam_inertia_force(length, self%rho_a(e), self%rho_i(e), a(mesh%edof(:, e))) + &
         & beam_gravity_force(length, self%rho_a(e), self%gravity)
   end function element_own_loads

   !> The reactions (3, reaction_count) at q, with accelerations a, loads f
   !> (kinetostatic_loads, and any external loads) and the deflection u (zero
   !> on constrained dofs, K_ff u_f = f_f): drive and support rows
   !> r_c = (K u)_c - f_c, slider rows the linearised penalty force on the
   !> slave K^c u, joint rows the element end forces K_e u_e - f_e. K = K_beams
   !> - K^c is the material tangent at q, seg the slidelines' master segments.
   subroutine kinetostatic_reactions(self, mesh, q, seg, a, f, u, reactions)
      type(kinetostatics_type), intent(inout) :: self
      type(mesh_type), intent(in) :: mesh
      real(dp), intent(in) :: q(:), a(:), f(:), u(:)
      integer, intent(in) :: seg(:)
      real(dp), intent(out) :: reactions(:, :)
      real(dp) :: ke(6, 6), pe(6), ge(6)
      integer :: e, row, k, dof, i
      self%ku = 0
      do e = 1, size(mesh%elements)
         call beam_residual(mesh%elements(e), q(mesh%edof(:, e)), pe, ke, geometric_above=huge(1.0_dp))
         ge = matmul(ke, u(mesh%edof(:, e)))
         self%ku(mesh%edof(:, e)) = self%ku(mesh%edof(:, e)) + ge
      end do
      ! The penalty forces of the deflection: K^c u (f^c(q) = 0 at a mechanism configuration).
      do i = 1, size(mesh%slides)
         call add_slider(i)
      end do
      reactions = 0
      do row = 1, size(reactions, 2)
         e = self%row_element(row)
         if (e > 0) then
            call beam_residual(mesh%elements(e), q(mesh%edof(:, e)), pe, ke, geometric_above=huge(1.0_dp))
            ge = matmul(ke, u(mesh%edof(:, e))) - element_own_loads(self, mesh, e, a)
            reactions(:, row) = ge(3*self%row_end(row) - 2:3*self%row_end(row))
         else if (self%row_slide(row) > 0) then
            call slider_force(mesh, self%row_slide(row), q, seg, reactions(:, row), u)
         else
            do k = 1, 3
               dof = self%row_dof(k, row)
               if (dof > 0) reactions(k, row) = self%ku(dof) - f(dof)
            end do
         end if
      end do

   contains

      !> ku -= K^c u over the slideline's dofs.
      subroutine add_slider(islide)
         integer, intent(in) :: islide
         real(dp) :: xs(2), x1(2), x2(2), fc(6), kc(6, 6), ft(5), kt(5, 5)
         integer :: dofs(6), tdofs(5), j
         associate (sl => mesh%slides(islide))
            call slide_position(mesh, sl, seg(islide), q, xs, x1, x2, dofs)
            call slide_force(xs, x1, x2, sl%kp, fc, kc)
            fc = matmul(kc, gather(u, dofs))
            do j = 1, 6
               if (dofs(j) > 0) self%ku(dofs(j)) = self%ku(dofs(j)) - fc(j)
            end do
            if (sl%kind == joint_prismatic) then
               tdofs = [sl%slave_rot, dofs(3:6)]
               call slide_tie_force(q(sl%slave_rot), x1, x2, sl%c0(seg(islide)), sl%kr, ft, kt)
               ft = matmul(kt, gather(u, tdofs))
               do j = 1, 5
                  if (tdofs(j) > 0) self%ku(tdofs(j)) = self%ku(tdofs(j)) - ft(j)
               end do
            end if
         end associate
      end subroutine add_slider

   end subroutine kinetostatic_reactions

   !> The force (fx, fy) and, for a prismatic joint, the moment that sliding
   !> joint `islide` exerts on its slave at q: the penalty force f^c(q), and
   !> with a deflection u its linearisation f^c(q) + K^c u.
   pure subroutine slider_force(mesh, islide, q, seg, force, u)
      type(mesh_type), intent(in) :: mesh
      integer, intent(in) :: islide
      real(dp), intent(in) :: q(:)
      integer, intent(in) :: seg(:)
      real(dp), intent(out) :: force(3)
      real(dp), intent(in), optional :: u(:)
      real(dp) :: xs(2), x1(2), x2(2), fc(6), kc(6, 6), ft(5), kt(5, 5)
      integer :: dofs(6), tdofs(5)
      force = 0
      associate (sl => mesh%slides(islide))
         call slide_position(mesh, sl, seg(islide), q, xs, x1, x2, dofs)
         call slide_force(xs, x1, x2, sl%kp, fc, kc)
         if (present(u)) then
            fc = fc + matmul(kc, gather(u, dofs))
         end if
         force(1:2) = fc(1:2)
         if (sl%kind == joint_prismatic) then
            tdofs = [sl%slave_rot, dofs(3:6)]
            call slide_tie_force(q(sl%slave_rot), x1, x2, sl%c0(seg(islide)), sl%kr, ft, kt)
            if (present(u)) then
               ft = ft + matmul(kt, gather(u, tdofs))
            end if
            force(3) = ft(1)
         end if
      end associate
   end subroutine slider_force

end module fekap_reactions_kinetostatics
