!> The writer of the listing `<stem>.lis`: the model and the plan as its
!> header, a line per written step and the notes of every step through its
!> text buffer, and at the end why the run stopped (if it stopped early) and
!> the summary of the work done, after every other file was written.
module fekap_output_listing_writer
   use fekap_error, only: error_type
   use fekap_model, only: model_type
   use fekap_model_results, only: step_result_type, has_note
   use fekap_output_csv, only: row_prefix_type
   use fekap_output_listing, only: write_listing_model, write_listing_plan, write_listing_step_header, &
      & write_listing_step, write_listing_note, write_listing_stop, write_listing_summary
   use fekap_output_checked_file, only: close_checked
   use fekap_output_writer, only: run_summary_type
   use fekap_output_table_writers, only: table_writer_type
   implicit none
   private

   public :: listing_writer

   type, extends(table_writer_type) :: listing_writer_type
      !> FEKAP's version, the run's number of steps and the method's lines on
      !> its discretisation, for the header.
      character(:), allocatable :: version, plan
      integer :: nsteps = 0
   contains
      procedure :: header => listing_header
      procedure :: row => listing_row
      procedure :: after_step => listing_after_step
      procedure :: close => listing_close
   end type listing_writer_type

contains

   !> The writer of the listing (open for formatted stream access: its
   !> header and summary are formatted writes, its step lines many at a time).
   type(listing_writer_type) function listing_writer(version, nsteps, plan) result(writer)
      character(*), intent(in) :: version
      integer, intent(in) :: nsteps
      !> The stepper's plan_text.
      character(*), intent(in) :: plan
      writer%formatted = .true.
      writer%every_step = .true.
      writer%version = version
      writer%nsteps = nsteps
      writer%plan = plan
   end function listing_writer

   !> The echo of the model, the plan of the run and the head of the steps' table.
   subroutine listing_header(self, model)
      class(listing_writer_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      call write_listing_model(self%buffer%unit, model, self%version)
      call write_listing_plan(self%buffer%unit, model, self%nsteps, self%plan)
      call write_listing_step_header(self%buffer%unit)
   end subroutine listing_header

   subroutine listing_row(self, model, result, prefix, rows, error)
      class(listing_writer_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      type(row_prefix_type), intent(inout) :: prefix
      integer, intent(inout) :: rows
      type(error_type), allocatable, intent(out) :: error
      call write_listing_step(self%buffer, result)
   end subroutine listing_row

   !> A note on every step that has one (a near-singular configuration, step cuts).
   subroutine listing_after_step(self, result)
      class(listing_writer_type), intent(inout) :: self
      type(step_result_type), intent(in) :: result
      if (has_note(result%note)) call write_listing_note(self%buffer, result%step, trim(result%note))
   end subroutine listing_after_step

   !> Whatever stopped the run (analysis failure, a VTK file, a signal, an
   !> output file that cannot be written) before the summary; a listing that
   !> could not be written is left as cut back by its flush.
   subroutine listing_close(self, summary, stop, error)
      class(listing_writer_type), intent(inout) :: self
      type(run_summary_type), intent(in) :: summary
      type(error_type), allocatable, intent(in) :: stop
      type(error_type), allocatable, intent(out) :: error
      if (self%buffer%failed) return
      if (allocated(stop)) call write_listing_stop(self%buffer%unit, stop%message)
      if (summary%step_files >= 0) then
         call write_listing_summary(self%buffer%unit, summary%counts, summary%rows, summary%seconds, &
            & vtk_files=summary%step_files)
      else
         call write_listing_summary(self%buffer%unit, summary%counts, summary%rows, summary%seconds)
      end if
      call close_checked(self%buffer%unit, self%buffer%verified, error)
   end subroutine listing_close

end module fekap_output_listing_writer
