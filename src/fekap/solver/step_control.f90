!> Step control shared by every method: a step that fails (Newton does not
!> converge, or converges to a rejected configuration) is cut in halves, at
!> most max_cuts times, and the sub-step grows back after each success; the
!> first and the last reasons for a rejection are kept for the listing.
module fekap_solver_step_control
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, analysis_error
   implicit none
   private

   public :: step_cuts_type

   !> Step cuts (halvings) allowed within one step before it is given up.
   integer, parameter, public :: max_cuts = 8

   !> The halvings of one step: the sub-step length, its growth back after a
   !> success, and the first and last reasons for a rejection (for the listing).
   type :: step_cuts_type
      !> The end of the step, the full step and the current sub-step length.
      real(dp) :: t_end = 0, h_full = 0, h = 0
      !> Cuts so far in this step.
      integer :: cuts = 0
      character(:), allocatable :: first, last
   contains
      !> Start a step from t_from to t_end.
      procedure :: begin => cuts_begin
      !> The time of the next try from the accepted time t_from.
      procedure :: next => cuts_next
      !> A try failed: halve the sub-step, or give up after max_cuts.
      procedure :: reject => cuts_reject
      !> A try was replaced by shorter ones that the method solved itself:
      !> count it as cut, with its reason, without halving.
      procedure :: replaced => cuts_replaced
      !> A try succeeded at an intermediate time: let the sub-step grow back.
      procedure :: grow => cuts_grow
      !> The listing note of a cut step ('' if not cut).
      procedure :: note => cuts_note
   end type step_cuts_type

contains

   pure subroutine cuts_begin(self, t_from, t_end)
      class(step_cuts_type), intent(inout) :: self
      real(dp), intent(in) :: t_from, t_end
      self%cuts = 0
      if (allocated(self%first)) deallocate (self%first)
      if (allocated(self%last)) deallocate (self%last)
      self%t_end = t_end
      self%h_full = t_end - t_from
      self%h = self%h_full
   end subroutine cuts_begin

   !> The time of the next try from the accepted time t_from (the end of the
   !> step when within rounding of it).
   pure real(dp) function cuts_next(self, t_from) result(t_try)
      class(step_cuts_type), intent(in) :: self
      real(dp), intent(in) :: t_from
      t_try = min(t_from + self%h, self%t_end)
      if (self%t_end - t_try < 1.0e-12_dp*abs(self%h_full)) t_try = self%t_end
   end function cuts_next

   !> A try failed with `reason`: halve the sub-step; after max_cuts cuts,
   !> the reason with what to try becomes the step's analysis error.
   pure subroutine cuts_reject(self, reason, error)
      class(step_cuts_type), intent(inout) :: self
      type(error_type), intent(in) :: reason
      type(error_type), allocatable, intent(out) :: error
      character(len=80) :: advice
      self%cuts = self%cuts + 1
      if (self%cuts > max_cuts) then
         write (advice, '(a,i0,a)') ' (after ', max_cuts, ' step cuts; try a smaller time step or another predictor)'
         call analysis_error(error, reason%message//trim(advice))
         return
      end if
      call keep_reason(self, reason%message)
      self%h = self%h/2
   end subroutine cuts_reject

   pure subroutine cuts_replaced(self, reason)
      class(step_cuts_type), intent(inout) :: self
      character(*), intent(in) :: reason
      self%cuts = self%cuts + 1
      call keep_reason(self, reason)
   end subroutine cuts_replaced

   !> Keep the first and the last reason for a cut.
   pure subroutine keep_reason(self, reason)
      class(step_cuts_type), intent(inout) :: self
      character(*), intent(in) :: reason
      if (allocated(self%first)) then
         self%last = reason
      else
         self%first = reason
      end if
   end subroutine keep_reason

   pure subroutine cuts_grow(self)
      class(step_cuts_type), intent(inout) :: self
      self%h = min(2*self%h, self%h_full)
   end subroutine cuts_grow

   !> 'step cut k time(s); first rejection: ...; last rejection: ...'.
   pure function cuts_note(self) result(text)
      class(step_cuts_type), intent(in) :: self
      character(:), allocatable :: text
      character(len=40) :: head
      text = ''
      if (.not. allocated(self%first)) return
      write (head, '(a,i0,a)') 'step cut ', self%cuts, ' time(s); first rejection: '
      text = trim(head)//' '//self%first
      if (allocated(self%last)) text = text//'; last rejection: '//self%last
   end function cuts_note

end module fekap_solver_step_control
