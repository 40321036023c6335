!> The FEM stepper's accepted state: everything a step changes, in one type
!> so that step-doubling verification and the step over a change point save
!> and restore it by one assignment.
module fekap_fem_accepted
   use fekap_kinds, only: dp
   use fekap_model_results, only: note_length
   use fekap_stepping_predictor, only: predictor_history_type
   implicit none
   private

   public :: fem_state_type

   !> The accepted state of the stepper.
   type :: fem_state_type
      !> Time, configuration, velocity and acceleration over all dofs.
      real(dp) :: t = 0
      real(dp), allocatable :: q(:), v(:), a(:)
      !> Whether v (and a) belong to the configuration.
      logical :: has_velocity = .false., has_acceleration = .false.
      !> The last accepted configurations, for the predictor.
      type(predictor_history_type) :: history
      !> Master segment of each slideline.
      integer, allocatable :: seg(:)
      !> Linear response of every dof to unit changes of the drives, (ndof,
      !> ndriven), kept by the branch-jump check whatever rates the run
      !> computes, and whether it is known.
      real(dp), allocatable :: jump_response(:, :)
      logical :: has_jump_response = .false.
      !> Largest pivot ratio of a tangent at an accepted configuration so far
      !> (the reference for singular and near-singular configurations).
      real(dp) :: reference_pivot = 0
      !> Largest reciprocal condition number (system_rcond) of the material
      !> tangent at an accepted configuration so far: the reference of the
      !> change-point detection and of the trust in a drive response.
      real(dp) :: reference_rcond = 0
      !> Remark on the configuration for the listing (empty if none).
      character(len=note_length) :: note = ''
   end type fem_state_type

end module fekap_fem_accepted
