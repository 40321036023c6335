!> Output files as writers in a list. A writer owns one output (a CSV
!> table, the listing, the VTK files) and is called by the time loop through
!> the list alone: its header before the first step, its rows at every
!> written step, its flushes, and its close at the end. The loop never names
!> a file; adding an output file is one writer and one registration
!> (fekap_driver_outputs). The list calls its writers in the order they were
!> registered, which is the order their rows reach their files and the order
!> the files are flushed (on a disk that fills, the files flushed first keep
!> the most).
module fekap_output_writer
   use fekap_kinds, only: dp
   use fekap_error, only: error_type
   use fekap_model, only: model_type
   use fekap_model_results, only: step_result_type
   use fekap_model_work, only: work_counts_type
   use fekap_output_csv, only: row_prefix_type, new_row_prefix
   implicit none
   private

   public :: writer_type, writer_list_type, run_summary_type, add_error, move_writers

   !> What the run did, for the writers that report it when they close (the
   !> listing's summary).
   type :: run_summary_type
      !> The stepper's counts of the work done.
      type(work_counts_type) :: counts
      !> Rows written to the tables.
      integer :: rows = 0
      !> Seconds in analysis, output and total.
      real(dp) :: seconds(3) = 0
      !> Step files written by the writers that write them (VTK); -1 when
      !> no writer writes step files.
      integer :: step_files = -1
   end type run_summary_type

   !> One output of a run. header, row and flush are what every writer
   !> does; the other hooks do nothing unless a writer needs them.
   type, abstract :: writer_type
      !> The writer's rows start with the step's `step,t,` (row_prefix_type):
      !> the list makes the prefix once per written step when one wants it.
      logical :: prefixed = .false.
      !> The writer writes at every step, written or not (after_step is
      !> called): the list calls after_step of these writers only.
      logical :: every_step = .false.
   contains
      !> Before the first step: the file's header (to its buffer).
      procedure(header_interface), deferred :: header
      !> A written step's rows; `rows` counts the table rows written.
      procedure(row_interface), deferred :: row
      !> Every step, written or not, after the rows of the written ones (for
      !> a writer with every_step).
      procedure :: after_step => writer_after_step
      !> The held rows to disk, checked.
      procedure(flush_interface), deferred :: flush
      !> After a flush of every writer that found every file whole: what a
      !> writer writes beyond its rows at such a point (the VTK collection).
      procedure :: checkpoint => writer_checkpoint
      !> After the last flush, however the run ended: what is left to write.
      procedure :: finish => writer_finish
      !> Step files written so far (-1: the writer writes none).
      procedure :: step_files => writer_step_files
      !> Last: the run's end in the file (`stop`: why it stopped early, if it
      !> did) and the file closed.
      procedure :: close => writer_close
   end type writer_type

   abstract interface
      subroutine header_interface(self, model)
         import :: writer_type, model_type
         implicit none
         class(writer_type), intent(inout) :: self
         type(model_type), intent(in) :: model
      end subroutine header_interface

      subroutine row_interface(self, model, result, prefix, rows, error)
         import :: writer_type, model_type, step_result_type, row_prefix_type, error_type
         implicit none
         class(writer_type), intent(inout) :: self
         type(model_type), intent(in) :: model
         type(step_result_type), intent(in) :: result
         !> The step's `step,t,` (made only when some writer is prefixed).
         type(row_prefix_type), intent(inout) :: prefix
         integer, intent(inout) :: rows
         type(error_type), allocatable, intent(out) :: error
      end subroutine row_interface

      subroutine flush_interface(self, error)
         import :: writer_type, error_type
         implicit none
         class(writer_type), intent(inout) :: self
         type(error_type), allocatable, intent(out) :: error
      end subroutine flush_interface
   end interface

   !> A registered writer.
   type :: writer_slot_type
      class(writer_type), allocatable :: writer
   end type writer_slot_type

   !> The writers of a run, called in the order of registration.
   type :: writer_list_type
      type(writer_slot_type), allocatable :: slots(:)
      integer :: n = 0
      !> Some writer wants the row prefix, made here once per written step.
      logical :: prefixed = .false.
      type(row_prefix_type) :: prefix
      !> The writers with every_step, by their place in slots.
      integer, allocatable :: every(:)
   contains
      !> Register a writer (after the ones registered before).
      procedure :: add => list_add
      !> Every writer's header.
      procedure :: header => list_header
      !> A step: if it is written, the rows of every writer in turn (the
      !> first error stops them and the step); then after_step of the
      !> writers with every_step.
      procedure :: step => list_step
      !> Flush every writer (all of them, whatever fails); the error is the
      !> first writer's. When all succeeded, their checkpoints follow.
      procedure :: flush => list_flush
      !> The last flush (no checkpoint), then every writer's finish; every
      !> error is added to `error`.
      procedure :: finish => list_finish
      !> Step files of all writers (-1: none writes step files).
      procedure :: step_files => list_step_files
      !> Every writer's close; every error is added to `error`.
      procedure :: close => list_close
   end type writer_list_type

contains

   !> Nothing after a step: the default of after_step.
   subroutine writer_after_step(self, result)
      class(writer_type), intent(inout) :: self
      type(step_result_type), intent(in) :: result
   end subroutine writer_after_step

   !> Nothing beyond the rows at a flush: the default of checkpoint.
   subroutine writer_checkpoint(self, error)
      class(writer_type), intent(inout) :: self
      type(error_type), allocatable, intent(out) :: error
   end subroutine writer_checkpoint

   !> Nothing left after the last flush: the default of finish.
   subroutine writer_finish(self, error)
      class(writer_type), intent(inout) :: self
      type(error_type), allocatable, intent(out) :: error
   end subroutine writer_finish

   !> No step files: the default of step_files.
   integer function writer_step_files(self) result(files)
      class(writer_type), intent(in) :: self
      files = -1
   end function writer_step_files

   !> Nothing to close (the flushed file's unit is closed at the exit): the
   !> default of close.
   subroutine writer_close(self, summary, stop, error)
      class(writer_type), intent(inout) :: self
      type(run_summary_type), intent(in) :: summary
      !> Why the run stopped early (not allocated: it did not).
      type(error_type), allocatable, intent(in) :: stop
      type(error_type), allocatable, intent(out) :: error
   end subroutine writer_close

   subroutine list_add(self, writer)
      class(writer_list_type), intent(inout) :: self
      !> The writer, moved into the list.
      class(writer_type), allocatable, intent(inout) :: writer
      type(writer_slot_type), allocatable :: grown(:)
      integer :: i
      if (.not. allocated(self%slots)) allocate (self%slots(4))
      if (self%n == size(self%slots)) then
         allocate (grown(2*self%n))
         do i = 1, self%n
            call move_alloc(self%slots(i)%writer, grown(i)%writer)
         end do
         call move_alloc(grown, self%slots)
      end if
      self%n = self%n + 1
      self%prefixed = self%prefixed .or. writer%prefixed
      if (.not. allocated(self%every)) allocate (self%every(0))
      if (writer%every_step) self%every = [self%every, self%n]
      call move_alloc(writer, self%slots(self%n)%writer)
   end subroutine list_add

   subroutine list_header(self, model)
      class(writer_list_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      integer :: i
      do i = 1, self%n
         call self%slots(i)%writer%header(model)
      end do
   end subroutine list_header

   subroutine list_step(self, model, result, rows, error)
      class(writer_list_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      !> Table rows written so far.
      integer, intent(inout) :: rows
      type(error_type), allocatable, intent(out) :: error
      integer :: i
      if (result%written) then
         if (self%prefixed) call new_row_prefix(self%prefix, result)
         do i = 1, self%n
            call self%slots(i)%writer%row(model, result, self%prefix, rows, error)
            if (allocated(error)) return
         end do
      end if
      if (.not. allocated(self%every)) return
      do i = 1, size(self%every)
         call self%slots(self%every(i))%writer%after_step(result)
      end do
   end subroutine list_step

   !> Every writer is flushed even after one failed: nothing is left in a
   !> unit's buffer for the exit to write unchecked.
   subroutine list_flush(self, error, checkpoint)
      class(writer_list_type), intent(inout) :: self
      type(error_type), allocatable, intent(out) :: error
      !> Call the checkpoints after a flush that found every file whole
      !> (default: yes).
      logical, intent(in), optional :: checkpoint
      type(error_type), allocatable :: failure
      integer :: i
      do i = 1, self%n
         call self%slots(i)%writer%flush(failure)
         if (allocated(failure) .and. .not. allocated(error)) call move_alloc(failure, error)
         if (allocated(failure)) deallocate (failure)
      end do
      if (allocated(error)) return
      if (present(checkpoint)) then
         if (.not. checkpoint) return
      end if
      do i = 1, self%n
         call self%slots(i)%writer%checkpoint(error)
         if (allocated(error)) return
      end do
   end subroutine list_flush

   subroutine list_finish(self, error)
      class(writer_list_type), intent(inout) :: self
      !> The run's error so far; the failures of the last writes are added.
      type(error_type), allocatable, intent(inout) :: error
      type(error_type), allocatable :: failure
      integer :: i
      call self%flush(failure, checkpoint=.false.)
      if (allocated(failure)) call add_error(error, failure)
      do i = 1, self%n
         call self%slots(i)%writer%finish(failure)
         if (allocated(failure)) call add_error(error, failure)
      end do
   end subroutine list_finish

   integer function list_step_files(self) result(files)
      class(writer_list_type), intent(in) :: self
      integer :: i, k
      files = -1
      do i = 1, self%n
         k = self%slots(i)%writer%step_files()
         if (k >= 0) files = max(files, 0) + k
      end do
   end function list_step_files

   subroutine list_close(self, summary, error)
      class(writer_list_type), intent(inout) :: self
      type(run_summary_type), intent(in) :: summary
      !> The run's error so far (why it stopped); the failures of the closes are added.
      type(error_type), allocatable, intent(inout) :: error
      type(error_type), allocatable :: failure
      integer :: i
      do i = 1, self%n
         call self%slots(i)%writer%close(summary, error, failure)
         if (allocated(failure)) call add_error(error, failure)
      end do
   end subroutine list_close

   !> Move the writers of `from` (left empty) into `to`.
   subroutine move_writers(from, to)
      type(writer_list_type), intent(inout) :: from
      type(writer_list_type), intent(out) :: to
      call move_alloc(from%slots, to%slots)
      call move_alloc(from%every, to%every)
      to%n = from%n
      to%prefixed = from%prefixed
      from%n = 0
      from%prefixed = .false.
   end subroutine move_writers

   !> Keep the first error of a run and add a later one's message to it; an
   !> output error after a completed run is the run's error.
   subroutine add_error(error, later)
      type(error_type), allocatable, intent(inout) :: error
      type(error_type), allocatable, intent(inout) :: later
      if (allocated(error)) then
         error%message = error%message//new_line('a')//later%message
         deallocate (later)
      else
         call move_alloc(later, error)
      end if
   end subroutine add_error

end module fekap_output_writer
