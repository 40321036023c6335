!> What an accepted dynamics step reports: its nodes, links and fields, its
!> reactions in kinetostatics' rows (each integrator's own end forces) and
!> its energies and momenta (energy.csv's columns, energy_names).
module fekap_dynamics_step_result
   use fekap_kinds, only: dp
   use fekap_model, only: model_type, integrator_energy_momentum
   use fekap_model_results, only: step_result_type
   use fekap_model_reactions, only: reaction_count
   use fekap_assembly_mesh, only: mesh_type
   use fekap_assembly_tracking, only: slide_position
   use fekap_fem_fields, only: fill_nodes_links, fill_fields
   use fekap_reactions_kinetostatics, only: slider_force
   use fekap_dynamics_dynamic_system, only: momentum, times6, element_damping_force, slide_damping_force
   use fekap_dynamics_energy_momentum, only: em_dissipation
   use fekap_dynamics_dynamic_data, only: dynamic_data_type, energy_count
   implicit none
   private

   public :: fill_result, keep_step_start

contains

   !> The result of the accepted state: nodes and links, reactions, energy;
   !> only its time when the step's rows are not written (at fine steps most
   !> are not, and the reactions and momenta cost a tenth of a step).
   subroutine fill_result(self, result)
      class(dynamic_data_type), intent(inout) :: self
      type(step_result_type), intent(inout) :: result
      real(dp) :: p(3)
      associate (state => self%state, mesh => self%mesh, dyn => self%dynamics)
         result%t = state%t
         result%floor = self%try_floor
         result%estimate = self%advance_estimate
         result%has_velocity = .true.
         result%has_acceleration = .true.
         if (.not. result%written) return
         call fill_nodes_links(mesh, self%model, state%q, state%v, state%acc, result)
         if (self%model%output%vtk) call fill_fields(mesh, state%q, state%v, state%acc, result)
         ! The reactions and the energies go to reactions.csv and energy.csv only.
         if (.not. self%model%output%csv) return
         if (.not. allocated(result%reactions)) allocate (result%reactions(3, reaction_count(self%model)))
         call fill_reactions(self, result%reactions)
         result%has_reactions = all(abs(result%reactions) <= huge(1.0_dp))
         p = momentum(dyn, mesh, state%q, state%v)
         if (.not. allocated(result%energy)) allocate (result%energy(energy_count))
         result%energy = [state%kinetic, state%strain, state%penalty, &
            & state%energy - state%kinetic - state%strain - state%penalty, state%work_loads, &
            & state%work_drives, state%dissipated, &
            & state%energy - state%work_loads - state%work_drives + state%dissipated - self%energy0, p(1), p(2), p(3)]
         result%has_energy = .true.
      end associate
   end subroutine fill_result

   !> The reactions in kinetostatics' rows: drives and supports the residual
   !> on their dofs; joints the end forces of the link's element there,
   !> P_e + M_e acc_e + C_e v_e - weight_e (each element in equilibrium
   !> under its end forces and its own inertia, damping and weight).
   subroutine fill_reactions(self, reactions)
      class(dynamic_data_type), intent(in) :: self
      real(dp), intent(out) :: reactions(:, :)
      integer :: row, e, k, dof
      real(dp) :: pe(6)
      logical :: em_step
      reactions = 0
      ! Energy-momentum's residual (the supports' and drives' rows) is that of
      ! its step's equations: the joints' and sliders' rows too (em_end_forces).
      em_step = self%model%analysis%integrator == integrator_energy_momentum .and. self%em_h > 0
      associate (state => self%state, mesh => self%mesh, dyn => self%dynamics, rows => self%rows)
         do row = 1, size(reactions, 2)
            e = rows%row_element(row)
            if (e > 0) then
               if (em_step) then
                  call em_end_forces(self, e, pe)
               else
                  call end_forces(e, pe)
               end if
               reactions(:, row) = pe(3*rows%row_end(row) - 2:3*rows%row_end(row))
            else if (rows%row_slide(row) > 0 .and. em_step) then
               call em_slider_force(self, rows%row_slide(row), reactions(:, row))
            else if (rows%row_slide(row) > 0) then
               ! A sliding joint: the penalty force on the slave, and its dashpot's.
               call slider_force(mesh, rows%row_slide(row), state%q, state%seg, reactions(:, row))
               if (self%slide_damped) call add_dashpot(rows%row_slide(row), reactions(1:2, row))
            else
               do k = 1, 3
                  dof = rows%row_dof(k, row)
                  if (dof > 0) reactions(k, row) = state%r(dof)
               end do
            end if
         end do
      end associate
   contains
      !> force -= the dashpot's force on the slave's translations (slideline i's).
      subroutine add_dashpot(i, force)
         integer, intent(in) :: i
         real(dp), intent(inout) :: force(2)
         real(dp) :: f(6)
         integer :: dofs(6)
         call slide_damping_force(self%dynamics, self%mesh, i, self%state%q, self%state%v, self%state%seg(i), f, dofs)
         force = force - f(1:2)
      end subroutine add_dashpot
      subroutine end_forces(e, fe)
         integer, intent(in) :: e
         real(dp), intent(out) :: fe(6)
         real(dp) :: xe(6), ae(6), weight(6)
         integer :: i
         do i = 1, 6
            xe(i) = self%state%q(self%mesh%edof(i, e))
            ae(i) = self%state%acc(self%mesh%edof(i, e))
         end do
         call element_force(self%mesh, e, xe, fe)
         ! The element's own weight (point masses belong to the pins).
         weight = element_weight(self%model, self%mesh, e)
         fe = fe + times6(self%dynamics%me, e, ae) - weight
         if (self%damped) fe = fe + element_damping_force(self%dynamics, self%mesh, e, self%state%q, self%state%v)
      end subroutine end_forces
   end subroutine fill_reactions

   !> Energy-momentum: the step's start (q0, v0, master segments: those its
   !> forces used) and length, for its reactions (fill_reactions).
   subroutine keep_step_start(self, h)
      class(dynamic_data_type), intent(inout) :: self
      real(dp), intent(in) :: h
      self%em_q0 = self%state%q
      self%em_v0 = self%state%v
      self%em_seg = self%state%seg
      self%em_h = h
   end subroutine keep_step_start

   !> Element e's end forces in the last energy-momentum step's equations
   !> (assemble_em): its discrete gradient p(q0, q1) with the dissipation
   !> chi + 2 beta/h, M_e (v1 - v0)/h, alpha M_e z/h, less its weight; so that
   !> each node's joint rows add up to its support, drive and slider rows
   !> (the step's residual there), as generalized-alpha's do.
   subroutine em_end_forces(self, e, fe)
      use fekap_element_discrete_gradient, only: beam_discrete_gradient, cayley_increment
      use fekap_model, only: dof_rot
      class(dynamic_data_type), intent(in) :: self
      integer, intent(in) :: e
      real(dp), intent(out) :: fe(6)
      real(dp) :: x0(6), x1(6), am(6), z(6), chi_e, h, dpsi
      integer :: i, d
      h = self%em_h
      do i = 1, 6
         d = self%mesh%edof(i, e)
         x0(i) = self%em_q0(d)
         x1(i) = self%state%q(d)
         am(i) = (self%state%v(d) - self%em_v0(d))/h
         z(i) = x1(i) - x0(i)
         if (self%mesh%dof_kind(d) == dof_rot) call cayley_increment(x1(i) - x0(i), z(i), dpsi)
      end do
      chi_e = em_dissipation(self%model%analysis%rho_inf) + 2*self%dynamics%beta(e)/h
      call beam_discrete_gradient(self%mesh%elements(e), x0, x1, chi_e, fe)
      fe = fe + times6(self%dynamics%me, e, am) - element_weight(self%model, self%mesh, e)
      if (self%dynamics%alpha(e) /= 0) fe = fe + self%dynamics%alpha(e)*times6(self%dynamics%me, e, z/h)
   end subroutine em_end_forces

   !> Slideline i's force on its slave in the last energy-momentum step's
   !> equations: minus the penalty spring's discrete gradient on the step's
   !> master segment (assemble_em; as slider_force, the force the spring applies).
   subroutine em_slider_force(self, i, force)
      use fekap_contact_slide_gradient, only: slide_discrete_gradient
      class(dynamic_data_type), intent(in) :: self
      integer, intent(in) :: i
      real(dp), intent(out) :: force(3)
      real(dp) :: x0(6), x1(6), pe(6)
      integer :: dofs(6)
      call slide_position(self%mesh, self%mesh%slides(i), self%em_seg(i), self%em_q0, x0(1:2), x0(3:4), x0(5:6), dofs)
      call slide_position(self%mesh, self%mesh%slides(i), self%em_seg(i), self%state%q, x1(1:2), x1(3:4), x1(5:6), &
         & dofs)
      call slide_discrete_gradient(x0, x1, self%mesh%slides(i)%kp, pe)
      force = [-pe(1), -pe(2), 0.0_dp]
   end subroutine em_slider_force

   subroutine element_force(mesh, e, xe, pe)
      use fekap_element_beam, only: beam_residual
      type(mesh_type), intent(in) :: mesh
      integer, intent(in) :: e
      real(dp), intent(in) :: xe(6)
      real(dp), intent(out) :: pe(6)
      call beam_residual(mesh%elements(e), xe, pe)
   end subroutine element_force

   pure function element_weight(model, mesh, e) result(w)
      use fekap_element_inertia, only: beam_gravity_force
      type(model_type), intent(in) :: model
      type(mesh_type), intent(in) :: mesh
      integer, intent(in) :: e
      real(dp) :: w(6)
      w = beam_gravity_force(mesh%elements(e)%length, model%sections(model%links(mesh%elink(e))%section)%rho_a, &
         & model%gravity)
   end function element_weight

end module fekap_dynamics_step_result
