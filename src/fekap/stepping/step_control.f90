!> Step control shared by every method: a step that fails (Newton does not
!> converge, or converges to a rejected configuration) is cut in halves, at
!> most max_cuts times, and the sub-step grows back after each success; the
!> first and the last reasons for a rejection are kept for the listing.
!> advance_by_cuts is the one loop that does this for the FEM, the
!> constraint-equation methods and the dynamics integrators, around a
!> method's "try a step" (try_interface).
module fekap_stepping_step_control
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, analysis_error, at_time
   use fekap_stepping_stepper, only: stepper_type
   use fekap_stepping_interrupt, only: interrupt_signal
   implicit none
   private

   public :: step_cuts_type, advance_by_cuts, try_interface, between_interface

   !> Outcomes of a method's try of a (sub-)step: accepted at its time;
   !> replaced by shorter steps that the method solved itself (accepted at its
   !> time, counted as cut, `reason` says why); failed (nothing accepted: the
   !> step is cut, `reason` says why); ended (the advance ends at once, with
   !> `reason` as its error if allocated, as when the method found a change
   !> point or an error that cutting cannot mend).
   integer, parameter, public :: try_accepted = 0, try_replaced = 1, try_failed = 2, try_ended = 3

   !> Step cuts (halvings) allowed within one step before it is given up.
   integer, parameter, public :: max_cuts = 8

   !> What a step given up after max_cuts cuts means, and what to try: the
   !> method's (advance_by_cuts' `advice`), after "down to 1/256 of the time
   !> step: ". A kinematic step restarts from an exact configuration, so a
   !> step that fails at 1/256 of dt is not too long: a dead point of the
   !> drive is the usual cause. Loads without drives (statics): a limit
   !> load. A dynamic step restarts from a state the run's steps made: a
   !> smaller time step from the start may well help (the flexible
   !> slider-crank failed at dt 0.01 and ran at 1e-3).
   character(*), parameter, public :: dead_point_advice = 'the mechanism cannot follow its drive past this '// &
      & 'point, as at a dead point, where the driven link reaches a limit; a smaller time step will not help: '// &
      & 'drive another link, end the run before this point, or try another predictor'
   character(*), parameter, public :: limit_load_advice = 'the structure cannot carry its loads past this '// &
      & 'point (a limit load, where it buckles or snaps through, or a part left free to move); a smaller '// &
      & 'time step will not help: lower the loads, or support the structure where it gives way'
   character(*), parameter, public :: dynamics_advice = 'the integrator cannot follow the motion from the '// &
      & 'state the run reached here; a smaller time step for the whole run (--dt) may help, and so may the '// &
      & 'other integrator; if neither does, look for a part left free to move or a load the structure cannot carry'

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

   abstract interface
      !> One try of a method to advance `stepper` from its accepted state to
      !> time t; depth is the nesting of advance_by_cuts (0: a run's step),
      !> for a method that verifies a step by solving it again in parts.
      recursive subroutine try_interface(stepper, t, depth, iterations, outcome, reason)
         import :: stepper_type, dp, error_type
         implicit none
         class(stepper_type), intent(inout) :: stepper
         real(dp), intent(in) :: t
         integer, intent(in) :: depth
         !> Newton iterations of the try (counted whatever its outcome).
         integer, intent(out) :: iterations
         integer, intent(out) :: outcome
         type(error_type), allocatable, intent(out) :: reason
      end subroutine try_interface

      !> A try was accepted at time t short of the step's end (an intermediate
      !> point of a cut step): what the method does there before going on.
      subroutine between_interface(stepper, t)
         import :: stepper_type, dp
         implicit none
         class(stepper_type), intent(inout) :: stepper
         real(dp), intent(in) :: t
      end subroutine between_interface
   end interface

contains

   !> Advance `stepper` from its accepted time t_from to t by the method's
   !> tries: a failed try halves the sub-step (at most max_cuts times, then
   !> its reason is the error), an accepted one lets it grow back; `cuts`
   !> keeps the count and the reasons for the listing, iterations sums the
   !> tries' iterations.
   recursive subroutine advance_by_cuts(stepper, try, between, t_from, t, depth, advice, cuts, iterations, error)
      class(stepper_type), intent(inout) :: stepper
      procedure(try_interface) :: try
      procedure(between_interface) :: between
      real(dp), intent(in) :: t_from, t
      integer, intent(in) :: depth
      !> What a step given up after max_cuts means (dead_point_advice, ...).
      character(*), intent(in) :: advice
      type(step_cuts_type), intent(out) :: cuts
      integer, intent(out) :: iterations
      type(error_type), allocatable, intent(out) :: error
      type(error_type), allocatable :: reason
      real(dp) :: t_accepted, t_try
      integer :: it, outcome
      call cuts%begin(t_from, t)
      t_accepted = t_from
      iterations = 0
      do while (t_accepted < t)
         t_try = cuts%next(t_accepted)
         call try(stepper, t_try, depth, it, outcome, reason)
         iterations = iterations + it
         select case (outcome)
         case (try_ended)
            if (allocated(reason)) call move_alloc(reason, error)
            return
         case (try_failed)
            if (interrupt_signal() /= 0) then
               ! A signal stopped the try: no cut, the run stops.
               call move_alloc(reason, error)
               return
            end if
            call cuts%reject(reason, error, advice)
            if (allocated(error)) return
            cycle
         case (try_replaced)
            call cuts%replaced(reason%message)
         case default
            ! try_accepted: the try's time is the accepted one.
         end select
         t_accepted = t_try
         if (t_accepted < t) then
            call between(stepper, t_accepted)
            call cuts%grow()
         end if
      end do
   end subroutine advance_by_cuts

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
   !> the reason with what it means (`advice`, dead_point_advice if absent)
   !> becomes the step's analysis error.
   pure subroutine cuts_reject(self, reason, error, advice)
      class(step_cuts_type), intent(inout) :: self
      type(error_type), intent(in) :: reason
      type(error_type), allocatable, intent(out) :: error
      character(*), intent(in), optional :: advice
      character(len=60) :: after
      self%cuts = self%cuts + 1
      if (self%cuts > max_cuts) then
         write (after, '(a,i0,a,i0,a)') ' (after ', max_cuts, ' step cuts, down to 1/', 2**max_cuts, &
            & ' of the time step: '
         if (present(advice)) then
            call analysis_error(error, reason%message//trim(after)//' '//advice//')')
         else
            call analysis_error(error, reason%message//trim(after)//' '//dead_point_advice//')')
         end if
         if (allocated(reason%time)) call at_time(error, reason%time)
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

end module fekap_stepping_step_control
