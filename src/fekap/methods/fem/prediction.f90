!> The FEM stepper's predictor record: the last step's predictor, whether it
!> was a smooth (Hermite or Adams) extrapolation of the history, and the
!> length tolerance it was made with. fekap_fem_predict makes it (begin at
!> the start of a prediction, record at its end, replace when the guard
!> swaps an extrapolation for the last configuration); the branch check
!> (fekap_fem_converged) and Newton (fekap_fem_newton) read it. Fortran has
!> no read-only components: they are public for reading without a copy, and
!> only this module's procedures assign them (test/app/test_layers.py checks).
module fekap_fem_prediction
   use fekap_kinds, only: dp
   implicit none
   private

   public :: prediction_type, new_prediction

   type :: prediction_type
      !> The last predictor over all dofs.
      real(dp), allocatable :: q(:)
      !> Whether it was a smooth (Hermite or Adams) extrapolation of the history.
      logical :: smooth = .false.
      !> The length tolerance of the step's predictor (the Adams-Bashforth
      !> choice, see adams_margin, and the acceptance at the predictor, see
      !> predictor_margin): the length tolerance, or the round-off of the
      !> dofs over predictor_margin where that is larger (fem_predict's
      !> roundoff_length).
      real(dp) :: length = 0
   contains
      !> A prediction begins with this length tolerance, not smooth (yet).
      procedure :: begin => prediction_begin
      !> The prediction made: its positions, and whether it was smooth.
      procedure :: record => prediction_record
      !> The guard replaced the extrapolation by these positions (not smooth).
      procedure :: replace => prediction_replace
   end type prediction_type

contains

   !> A record for n dofs, its predictor zero.
   pure subroutine new_prediction(self, n)
      type(prediction_type), intent(out) :: self
      integer, intent(in) :: n
      allocate (self%q(n), source=0.0_dp)
   end subroutine new_prediction

   pure subroutine prediction_begin(self, length)
      class(prediction_type), intent(inout) :: self
      real(dp), intent(in) :: length
      self%smooth = .false.
      self%length = length
   end subroutine prediction_begin

   pure subroutine prediction_record(self, q, smooth)
      class(prediction_type), intent(inout) :: self
      real(dp), contiguous, intent(in) :: q(:)
      logical, intent(in) :: smooth
      self%q = q
      self%smooth = smooth
   end subroutine prediction_record

   pure subroutine prediction_replace(self, q)
      class(prediction_type), intent(inout) :: self
      real(dp), contiguous, intent(in) :: q(:)
      self%q = q
      self%smooth = .false.
   end subroutine prediction_replace

end module fekap_fem_prediction
