!> Statics: the equilibrium of the flexible scene under its loads at each
!> time, R(q) = P(q) - F^c(q) - f(t) = 0 on the free dofs (docs/dynamics.md),
!> solved by the FEM's stepper on its loaded path (Newton on the full
!> residual with the full tangent, step cuts), with f(t) the LOADs (the load
!> factor t, or their laws) and the weights of the masses under GRAVity (a
!> dead load); fekap_reactions_reaction_stepper runs it. After each step the
!> reactions, in fekap_model_reactions' rows:
!> at the drives and supports the residual there, r_c = R_c(q) (what the
!> drive or support applies to the scene); at a sliding joint its penalty
!> force on the slave; at a link end the end force of the link's element
!> there, P_e(q_e) - f_e (f_e the element's own weight).
module fekap_reactions_statics
   use fekap_kinds, only: dp
   use fekap_assembly_mesh, only: mesh_type
   use fekap_assembly_assemble, only: assemble_residual
   use fekap_element_beam, only: beam_residual
   use fekap_reactions_kinetostatics, only: kinetostatics_type, element_own_loads, slider_force
   implicit none
   private

   public :: static_reactions

contains

   !> The reactions (3, reaction_count) of the equilibrium q at time t (see
   !> the module's header); r and zero are work over the dofs (zero = 0).
   subroutine static_reactions(rows, mesh, q, t, seg, r, zero, reactions)
      type(kinetostatics_type), intent(in) :: rows
      type(mesh_type), intent(in) :: mesh
      ! contiguous: assemble_residual's (no temporary copies).
      real(dp), contiguous, intent(in) :: q(:)
      real(dp), intent(in) :: t
      integer, intent(in) :: seg(:)
      real(dp), contiguous, intent(inout) :: r(:)
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

end module fekap_reactions_statics
