!> The writers of the files written row by row through a text buffer: the
!> CSV tables points.csv, links.csv, steps.csv, nodes.csv, reactions.csv,
!> energy.csv and deflection.csv (their rows from fekap_output_csv). A table
!> writer is made with what its rows need, then given its open unit by the
!> registry (attach); it never opens its file itself.
module fekap_output_table_writers
   use fekap_error, only: error_type
   use fekap_model, only: model_type
   use fekap_model_results, only: step_result_type
   use fekap_output_buffer, only: text_buffer_type, new_text_buffer, flush_text_buffer
   use fekap_output_csv, only: row_prefix_type, write_points_header, write_points_rows, write_links_header, &
      & write_links_rows, write_header, steps_header, floor_steps_header, dynamics_steps_header, reactions_header, &
      & deflection_header, &
      & write_steps_row, write_nodes_header, write_nodes_row, write_reactions_rows, write_energy_row, &
      & write_deflection_rows
   use fekap_output_writer, only: writer_type
   implicit none
   private

   public :: table_writer_type
   public :: points_writer, links_writer, steps_writer, nodes_writer, reactions_writer, energy_writer, &
      & deflection_writer

   !> A writer whose rows gather in a text buffer, written in large pieces
   !> and checked at each flush (fekap_output_buffer).
   type, abstract, extends(writer_type) :: table_writer_type
      !> Its file is open for formatted stream access (the listing), not
      !> unformatted (the CSV tables, written as bytes).
      logical :: formatted = .false.
      type(text_buffer_type) :: buffer
   contains
      !> Take the unit its file was opened on.
      procedure :: attach => table_attach
      procedure :: flush => table_flush
   end type table_writer_type

   !> points.csv: the tracked points' positions (and rates).
   type, extends(table_writer_type) :: points_writer_type
      logical :: velocities = .false., accelerations = .false.
   contains
      procedure :: header => points_header
      procedure :: row => points_row
   end type points_writer_type

   !> links.csv: the tracked links' angles (and rates).
   type, extends(table_writer_type) :: links_writer_type
      logical :: velocities = .false., accelerations = .false.
   contains
      procedure :: header => links_header
      procedure :: row => links_row
   end type links_writer_type

   !> steps.csv: each step's iterations, residual and cuts (and, but for a
   !> spatial run, the steps at the round-off floor; a dynamics run's error estimate).
   type, extends(table_writer_type) :: steps_writer_type
      !> Whether the header has the `floor` column, and (dynamics) the
      !> `error_estimate` column after it.
      logical :: floor = .false., dynamics = .false.
   contains
      procedure :: header => steps_header_
      procedure :: row => steps_row
   end type steps_writer_type

   !> nodes.csv: every node's position.
   type, extends(table_writer_type) :: nodes_writer_type
   contains
      procedure :: header => nodes_header
      procedure :: row => nodes_row
   end type nodes_writer_type

   !> reactions.csv: the reactions of kinetostatics, statics and dynamics.
   type, extends(table_writer_type) :: reactions_writer_type
   contains
      procedure :: header => reactions_header_
      procedure :: row => reactions_row
   end type reactions_writer_type

   !> energy.csv: a dynamics run's energies, work and momenta.
   type, extends(table_writer_type) :: energy_writer_type
      !> The columns after `step,t,`.
      character(:), allocatable :: names
   contains
      procedure :: header => energy_header
      procedure :: row => energy_row
   end type energy_writer_type

   !> deflection.csv: the elastic deflection of a kinetostatics run.
   type, extends(table_writer_type) :: deflection_writer_type
   contains
      procedure :: header => deflection_header_
      procedure :: row => deflection_row
   end type deflection_writer_type

contains

   subroutine table_attach(self, unit)
      class(table_writer_type), intent(inout) :: self
      !> A unit open for stream access, formatted as `formatted` says.
      integer, intent(in) :: unit
      call new_text_buffer(self%buffer, unit, formatted=self%formatted)
   end subroutine table_attach

   subroutine table_flush(self, error)
      class(table_writer_type), intent(inout) :: self
      type(error_type), allocatable, intent(out) :: error
      call flush_text_buffer(self%buffer, error)
   end subroutine table_flush

   !> The writer of points.csv, with the rate columns asked for.
   type(points_writer_type) function points_writer(velocities, accelerations) result(writer)
      logical, intent(in) :: velocities, accelerations
      writer%prefixed = .true.
      writer%velocities = velocities
      writer%accelerations = accelerations
   end function points_writer

   subroutine points_header(self, model)
      class(points_writer_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      call write_points_header(self%buffer, self%velocities, self%accelerations)
   end subroutine points_header

   subroutine points_row(self, model, result, prefix, rows, error)
      class(points_writer_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      type(row_prefix_type), intent(inout) :: prefix
      integer, intent(inout) :: rows
      type(error_type), allocatable, intent(out) :: error
      call write_points_rows(self%buffer, model, result, prefix, self%velocities, self%accelerations)
      rows = rows + size(model%output%points)
   end subroutine points_row

   !> The writer of links.csv, with the rate columns asked for.
   type(links_writer_type) function links_writer(velocities, accelerations) result(writer)
      logical, intent(in) :: velocities, accelerations
      writer%prefixed = .true.
      writer%velocities = velocities
      writer%accelerations = accelerations
   end function links_writer

   subroutine links_header(self, model)
      class(links_writer_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      call write_links_header(self%buffer, self%velocities, self%accelerations)
   end subroutine links_header

   subroutine links_row(self, model, result, prefix, rows, error)
      class(links_writer_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      type(row_prefix_type), intent(inout) :: prefix
      integer, intent(inout) :: rows
      type(error_type), allocatable, intent(out) :: error
      call write_links_rows(self%buffer, model, result, prefix, self%velocities, self%accelerations)
      rows = rows + size(model%output%links)
   end subroutine links_row

   !> The writer of steps.csv: with the `floor` column for a method whose
   !> Newton reports the round-off floor (`floor`), and with `floor` and
   !> `error_estimate` for `dynamics`. The rows have the columns their
   !> results report (write_steps_row).
   type(steps_writer_type) function steps_writer(dynamics, floor) result(writer)
      logical, intent(in) :: dynamics
      logical, intent(in) :: floor
      writer%prefixed = .true.
      writer%dynamics = dynamics
      writer%floor = floor
   end function steps_writer

   subroutine steps_header_(self, model)
      class(steps_writer_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      if (self%dynamics) then
         call write_header(self%buffer, dynamics_steps_header)
      else if (self%floor) then
         call write_header(self%buffer, floor_steps_header)
      else
         call write_header(self%buffer, steps_header)
      end if
   end subroutine steps_header_

   subroutine steps_row(self, model, result, prefix, rows, error)
      class(steps_writer_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      type(row_prefix_type), intent(inout) :: prefix
      integer, intent(inout) :: rows
      type(error_type), allocatable, intent(out) :: error
      call write_steps_row(self%buffer, result, prefix)
      rows = rows + 1
   end subroutine steps_row

   !> The writer of nodes.csv.
   type(nodes_writer_type) function nodes_writer() result(writer)
      writer%prefixed = .true.
   end function nodes_writer

   subroutine nodes_header(self, model)
      class(nodes_writer_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      call write_nodes_header(self%buffer, model)
   end subroutine nodes_header

   !> A row of every node: not counted among the table rows (the listing's
   !> count is that of the tracked points, links and reactions).
   subroutine nodes_row(self, model, result, prefix, rows, error)
      class(nodes_writer_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      type(row_prefix_type), intent(inout) :: prefix
      integer, intent(inout) :: rows
      type(error_type), allocatable, intent(out) :: error
      call write_nodes_row(self%buffer, model, result, prefix)
   end subroutine nodes_row

   !> The writer of reactions.csv.
   type(reactions_writer_type) function reactions_writer() result(writer)
      writer%prefixed = .true.
   end function reactions_writer

   subroutine reactions_header_(self, model)
      class(reactions_writer_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      call write_header(self%buffer, reactions_header)
   end subroutine reactions_header_

   subroutine reactions_row(self, model, result, prefix, rows, error)
      class(reactions_writer_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      type(row_prefix_type), intent(inout) :: prefix
      integer, intent(inout) :: rows
      type(error_type), allocatable, intent(out) :: error
      call write_reactions_rows(self%buffer, model, result, prefix)
      rows = rows + size(result%reactions, 2)
   end subroutine reactions_row

   !> The writer of energy.csv, with the columns `names` after `step,t,`.
   type(energy_writer_type) function energy_writer(names) result(writer)
      character(*), intent(in) :: names
      writer%prefixed = .true.
      writer%names = names
   end function energy_writer

   subroutine energy_header(self, model)
      class(energy_writer_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      call write_header(self%buffer, 'step,t,'//self%names)
   end subroutine energy_header

   subroutine energy_row(self, model, result, prefix, rows, error)
      class(energy_writer_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      type(row_prefix_type), intent(inout) :: prefix
      integer, intent(inout) :: rows
      type(error_type), allocatable, intent(out) :: error
      call write_energy_row(self%buffer, result, prefix)
      rows = rows + 1
   end subroutine energy_row

   !> The writer of deflection.csv.
   type(deflection_writer_type) function deflection_writer() result(writer)
      writer%prefixed = .true.
   end function deflection_writer

   subroutine deflection_header_(self, model)
      class(deflection_writer_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      call write_header(self%buffer, deflection_header)
   end subroutine deflection_header_

   subroutine deflection_row(self, model, result, prefix, rows, error)
      class(deflection_writer_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      type(row_prefix_type), intent(inout) :: prefix
      integer, intent(inout) :: rows
      type(error_type), allocatable, intent(out) :: error
      call write_deflection_rows(self%buffer, model, result, prefix)
      rows = rows + size(model%nodes)
   end subroutine deflection_row

end module fekap_output_table_writers
