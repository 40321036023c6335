!> Statics: the equilibrium of the flexible scene under its loads at each
!> time, R(q) = P(q) - F^c(q) - f(t) = 0 on the free dofs (docs/dynamics.md),
!> solved by the FEM's stepper on its loaded path (Newton on the full
!> residual with the full tangent, step cuts), with f(t) the LOADs (the load
!> factor t, or their laws) and the weights of the masses under GRAVity (a
!> dead load). After each step the reactions, in fekap_model_reactions' rows:
!> at the drives and supports the residual there, r_c = R_c(q) (what the
!> drive or support applies to the scene); at a sliding joint its penalty
!> force on the slave; at a link end the end force of the link's element
!> there, P_e(q_e) - f_e (f_e the element's own weight).
module fekap_effects_statics
   use fekap_kinds, only: dp
   use fekap_error, only: error_type
   use fekap_model_results, only: step_result_type
   use fekap_model_reactions, only: reaction_count
   use fekap_solver_stepper, only: stepper_type
   use fekap_solver_fem, only: fem_stepper_type
   use fekap_assembly_mesh, only: mesh_type
   use fekap_assembly_assemble, only: assemble_residual
   use fekap_element_beam, only: beam_residual
   use fekap_effects_kinetostatics, only: kinetostatics_type, new_kinetostatics, element_own_loads, slider_force
   implicit none
   private

   public :: statics_stepper_type, new_statics_stepper, static_reactions

   type, extends(stepper_type) :: statics_stepper_type
      type(fem_stepper_type) :: fem
      !> The masses (for the elements' own weights) and the reaction rows.
      type(kinetostatics_type) :: rows
      !> Work over the dofs: the residual, and zero accelerations.
      real(dp), allocatable :: r(:), zero(:)
   contains
      procedure :: start => statics_start
      procedure :: advance => statics_advance
      procedure :: plan_text => statics_plan_text
   end type statics_stepper_type

contains

   !> Statics on a new FEM stepper (new_fem_stepper) of the model.
   subroutine new_statics_stepper(self, fem)
      type(statics_stepper_type), intent(out) :: self
      type(fem_stepper_type), intent(in) :: fem
      self%fem = fem
      call new_kinetostatics(self%rows, fem%model, fem%mesh)
      allocate (self%r(fem%mesh%ndof), self%zero(fem%mesh%ndof), source=0.0_dp)
   end subroutine new_statics_stepper

   function statics_plan_text(self) result(text)
      class(statics_stepper_type), intent(in) :: self
      character(:), allocatable :: text
      text = self%fem%plan_text()
   end function statics_plan_text

   subroutine statics_start(self, result, error)
      class(statics_stepper_type), intent(inout) :: self
      type(step_result_type), intent(inout) :: result
      type(error_type), allocatable, intent(out) :: error
      call self%fem%start(result, error)
      self%counts = self%fem%counts
      if (allocated(error)) return
      call add_reactions(self, result)
   end subroutine statics_start

   subroutine statics_advance(self, t, result, error)
      class(statics_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      type(step_result_type), intent(inout) :: result
      type(error_type), allocatable, intent(out) :: error
      call self%fem%advance(t, result, error)
      self%counts = self%fem%counts
      if (allocated(error)) return
      call add_reactions(self, result)
   end subroutine statics_advance

   subroutine add_reactions(self, result)
      type(statics_stepper_type), intent(inout) :: self
      type(step_result_type), intent(inout) :: result
      if (.not. allocated(result%reactions)) allocate (result%reactions(3, reaction_count(self%fem%model)))
      call static_reactions(self%rows, self%fem%mesh, self%fem%state%q, self%fem%state%t, self%fem%state%seg, &
         & self%r, self%zero, result%reactions)
      result%has_reactions = all(abs(result%reactions) <= huge(1.0_dp))
   end subroutine add_reactions

   !> The reactions (3, reaction_count) of the equilibrium q at time t (see
   !> the module's header); r and zero are work over the dofs (zero = 0).
   subroutine static_reactions(rows, mesh, q, t, seg, r, zero, reactions)
      type(kinetostatics_type), intent(in) :: rows
      type(mesh_type), intent(in) :: mesh
      real(dp), intent(in) :: q(:), t
      integer, intent(in) :: seg(:)
      real(dp), intent(inout) :: r(:)
      real(dp), intent(in) :: zero(:)
      real(dp), intent(out) :: reactions(:, :)
      real(dp) :: pe(6)
      integer :: row, e, k, dof
      call assemble_residual(mesh, q, t, seg, r)
      reactions = 0
      do row = 1, size(reactions, 2)
         e = rows%row_element(row)
         if (e > 0) then
            call beam_residual(mesh%elements(e), q(mesh%edof(:, e)), pe)
            pe = pe - element_own_loads(rows, mesh, e, zero)
            reactions(:, row) = pe(3*rows%row_end(row) - 2:3*rows%row_end(row))
         else if (rows%row_slide(row) > 0) then
            call slider_force(mesh, rows%row_slide(row), q, seg, reactions(:, row))
         else
            do k = 1, 3
               dof = rows%row_dof(k, row)
               if (dof > 0) reactions(k, row) = r(dof)
            end do
         end if
      end do
   end subroutine static_reactions

end module fekap_effects_statics
