!> Step-doubling verification's record (fekap_fem's verify_step): a stack
!> with one level per halving of a step (0: a step of the run), each holding
!> the step accepted pending verification: the state before it and the
!> hinged pair that crossed collinear (link, link, node) with its turn. The
!> branch check (fekap_fem_converged's branch_jump) pushes a level when it
!> asks for verification; verify_step reads it. Whether a step awaits
!> verification, or a verification could not be completed, travels as
!> values (the branch verdict, verify_step's `failed`), not in the record.
module fekap_fem_verification
   use fekap_kinds, only: dp
   use fekap_model, only: model_type
   use fekap_fem_branch, only: max_verify_depth
   use fekap_fem_accepted, only: fem_state_type
   implicit none
   private

   public :: verification_type, verification_stack_type

   !> A step awaiting verification.
   type :: verification_type
      type(fem_state_type) :: before
      integer :: crossing(3) = 0
      real(dp) :: turn = 0
   end type verification_type

   type :: verification_stack_type
      type(verification_type) :: level(0:max_verify_depth)
   contains
      !> Whether a step at this depth may still be verified by halving it.
      procedure :: can_verify => stack_can_verify
      !> Record the step at this depth as awaiting verification.
      procedure :: push => stack_push
      !> 'links L1 and L2 at node N': the pair of the step at this depth.
      procedure :: pair_text => stack_pair_text
   end type verification_stack_type

contains

   pure logical function stack_can_verify(self, depth) result(can)
      class(verification_stack_type), intent(in) :: self
      integer, intent(in) :: depth
      can = depth < ubound(self%level, 1)
   end function stack_can_verify

   subroutine stack_push(self, depth, before, crossing, turn)
      class(verification_stack_type), intent(inout) :: self
      integer, intent(in) :: depth
      type(fem_state_type), intent(in) :: before
      integer, intent(in) :: crossing(3)
      real(dp), intent(in) :: turn
      associate (level => self%level(depth))
         level%before = before
         level%crossing = crossing
         level%turn = turn
      end associate
   end subroutine stack_push

   function stack_pair_text(self, depth, model) result(text)
      class(verification_stack_type), intent(in) :: self
      integer, intent(in) :: depth
      type(model_type), intent(in) :: model
      character(:), allocatable :: text
      associate (c => self%level(depth)%crossing)
         text = 'links '//model%links(c(1))%name//' and '//model%links(c(2))%name//' at node '// &
            & model%nodes(c(3))%name
      end associate
   end function stack_pair_text

end module fekap_fem_verification
