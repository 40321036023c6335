!> The convergence contract of a dynamics step (both integrators' Newton
!> solves): the deck's tolerances against the forces in play in the step,
!> and the integrators' words for a step whose Newton solve failed.
module fekap_dynamics_step_contract
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, analysis_error
   use fekap_assembly_mesh, only: dof_free
   use fekap_strings, only: es_text
   use fekap_fem_convergence, only: divergence_length
   use fekap_stepping_newton, only: newton_contract_type, newton_report_type, stop_spent, stop_not_finite, &
      & stop_singular
   use fekap_dynamics_dynamic_system, only: times6
   use fekap_dynamics_dynamic_data, only: dynamic_data_type
   implicit none
   private

   public :: step_contract, newton_failure, singular_matrix

contains

   !> Both integrators' convergence contract (fekap_stepping_newton): the
   !> deck's tolerance relative to the forces in play in the step
   !> (step_force_scale), its length tolerance times the model size, its
   !> iterations; the round-off floor of the mesh's stiffness as the last resort.
   !> Divergence is a correction longer than the model sizes of
   !> divergence_length plus the predictor's own move: a first correction may
   !> undo a long extrapolation (a step far longer than a stiff mode's period,
   !> where q0 + h v0 + h^2/2 a0 runs off) without Newton diverging.
   function step_contract(self) result(contract)
      class(dynamic_data_type), intent(in) :: self
      type(newton_contract_type) :: contract
      contract%tolerance = self%model%analysis%tol
      contract%length = self%model%analysis%length_tol*self%model_length
      contract%max_iterations = self%model%analysis%max_iter
      contract%force_scale = step_force_scale(self)
      contract%floor = self%residual_floor
      contract%divergence = divergence_length*self%model_length + &
         & maxval(abs(self%qt - self%state%q)*self%dof_length)
   end function step_contract

   !> The forces in play in a step: the largest Euclidean norm (over all
   !> dofs) of the weights and loads at its end (gt), of the inertia M a of
   !> its predicted accelerations (acct), and of the reactions of supports
   !> and drives at its start (the residual on the constrained dofs). The
   !> element forces balance these (or are their reactions); a residual is
   !> small when it is small against them, not against the stiffness.
   function step_force_scale(self) result(scale)
      class(dynamic_data_type), intent(in) :: self
      real(dp) :: scale
      real(dp) :: inertia(self%mesh%ndof), ae(6)
      integer :: e, i
      associate (mesh => self%mesh, dyn => self%dynamics)
         inertia = dyn%point_mass*self%acct
         do e = 1, size(mesh%elements)
            do i = 1, 6
               ae(i) = self%acct(mesh%edof(i, e))
            end do
            ae = times6(dyn%me, e, ae)
            do i = 1, 6
               inertia(mesh%edof(i, e)) = inertia(mesh%edof(i, e)) + ae(i)
            end do
         end do
         scale = max(norm2(self%gt), norm2(inertia), norm2(merge(self%state%r, 0.0_dp, mesh%status /= dof_free)))
      end associate
   end function step_force_scale

   !> A Newton solve of a step that did not converge (newton_solve's error):
   !> its message in the integrators' words (the iteration matrix named by `what`).
   subroutine newton_failure(report, what, error)
      type(newton_report_type), intent(in) :: report
      character(*), intent(in) :: what
      type(error_type), allocatable, intent(inout) :: error
      character(len=300) :: msg
      select case (report%stopped)
      case (stop_not_finite)
         deallocate (error)
         call analysis_error(error, 'the residual of the equations of motion is not finite (the step is '// &
            & 'too long for the motion, or the mechanism has a dof without mass and stiffness)')
      case (stop_spent)
         deallocate (error)
         write (msg, '(a,i0,a,a,a,a)') 'Newton did not converge in ', report%iterations, ' iterations (residual ', &
            & es_text(report%last_residual, 12, 5), ', first ', es_text(report%first_residual, 12, 5)//')'
         call analysis_error(error, trim(msg))
      case (stop_singular)
         deallocate (error)
         call singular_matrix(error, what, report%info)
      case default
         ! Divergence and interrupts keep newton_solve's message.
      end select
   end subroutine newton_failure

   !> The iteration matrix (named by `what`) has no factor.
   subroutine singular_matrix(error, what, info)
      type(error_type), allocatable, intent(out) :: error
      character(*), intent(in) :: what
      integer, intent(in) :: info
      character(len=300) :: msg
      write (msg, '(a,a,a,i0,a)') 'the iteration matrix ', what, ' is singular at equation ', info, &
         & ' (a free dof with neither mass nor stiffness)'
      call analysis_error(error, trim(msg))
   end subroutine singular_matrix

end module fekap_dynamics_step_contract
