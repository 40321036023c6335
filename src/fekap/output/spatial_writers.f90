!> The writers of a spatial run's tables: points.csv with z columns,
!> joints.csv, the relative motion of every revolute and prismatic joint,
!> and nodes.csv with z columns (their rows from fekap_output_spatial_csv).
!> Registered by the driver in place of the planar points.csv, links.csv and
!> nodes.csv writers.
module fekap_output_spatial_writers
   use fekap_error, only: error_type
   use fekap_model, only: model_type
   use fekap_model_results, only: step_result_type
   use fekap_output_csv, only: row_prefix_type
   use fekap_output_spatial_csv, only: write_spatial_points_header, write_spatial_points_rows, &
      & write_joints_header, write_joints_rows, write_spatial_nodes_header, write_spatial_nodes_row, &
      & write_spatial_links_header, write_spatial_links_rows
   use fekap_output_table_writers, only: table_writer_type
   implicit none
   private

   public :: spatial_points_writer, joints_writer, spatial_nodes_writer, spatial_links_writer

   !> points.csv of a spatial run: x, y, z (and rates).
   type, extends(table_writer_type) :: spatial_points_writer_type
      logical :: velocities = .false., accelerations = .false.
   contains
      procedure :: header => spatial_points_header
      procedure :: row => spatial_points_row
   end type spatial_points_writer_type

   !> joints.csv: each joint's angle or stroke (and rates).
   type, extends(table_writer_type) :: joints_writer_type
      logical :: velocities = .false., accelerations = .false.
   contains
      procedure :: header => joints_header
      procedure :: row => joints_row
   end type joints_writer_type

   !> links.csv of a spatial run: each link's rotation (and rates).
   type, extends(table_writer_type) :: spatial_links_writer_type
      logical :: velocities = .false., accelerations = .false.
   contains
      procedure :: header => spatial_links_header
      procedure :: row => spatial_links_row
   end type spatial_links_writer_type

   !> nodes.csv of a spatial run: every node's x, y, z.
   type, extends(table_writer_type) :: spatial_nodes_writer_type
   contains
      procedure :: header => spatial_nodes_header
      procedure :: row => spatial_nodes_row
   end type spatial_nodes_writer_type

contains

   !> The writer of a spatial run's points.csv, with the rate columns asked for.
   type(spatial_points_writer_type) function spatial_points_writer(velocities, accelerations) result(writer)
      logical, intent(in) :: velocities, accelerations
      writer%prefixed = .true.
      writer%velocities = velocities
      writer%accelerations = accelerations
   end function spatial_points_writer

   subroutine spatial_points_header(self, model)
      class(spatial_points_writer_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      call write_spatial_points_header(self%buffer, self%velocities, self%accelerations)
   end subroutine spatial_points_header

   subroutine spatial_points_row(self, model, result, prefix, rows, error)
      class(spatial_points_writer_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      type(row_prefix_type), intent(inout) :: prefix
      integer, intent(inout) :: rows
      type(error_type), allocatable, intent(out) :: error
      call write_spatial_points_rows(self%buffer, model, result, prefix%text(1:prefix%n), self%velocities, &
         & self%accelerations, prefix%numbers)
      rows = rows + size(model%output%points)
   end subroutine spatial_points_row

   !> The writer of joints.csv, with the rate columns asked for.
   type(joints_writer_type) function joints_writer(velocities, accelerations) result(writer)
      logical, intent(in) :: velocities, accelerations
      writer%prefixed = .true.
      writer%velocities = velocities
      writer%accelerations = accelerations
   end function joints_writer

   subroutine joints_header(self, model)
      class(joints_writer_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      call write_joints_header(self%buffer, self%velocities, self%accelerations)
   end subroutine joints_header

   subroutine joints_row(self, model, result, prefix, rows, error)
      class(joints_writer_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      type(row_prefix_type), intent(inout) :: prefix
      integer, intent(inout) :: rows
      type(error_type), allocatable, intent(out) :: error
      call write_joints_rows(self%buffer, model, result, prefix%text(1:prefix%n), self%velocities, self%accelerations, &
         & prefix%numbers)
      rows = rows + size(result%joint_motion, 2)
   end subroutine joints_row

   !> The writer of links.csv of a spatial run, with the rate columns asked for.
   type(spatial_links_writer_type) function spatial_links_writer(velocities, accelerations) result(writer)
      logical, intent(in) :: velocities, accelerations
      writer%prefixed = .true.
      writer%velocities = velocities
      writer%accelerations = accelerations
   end function spatial_links_writer

   subroutine spatial_links_header(self, model)
      class(spatial_links_writer_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      call write_spatial_links_header(self%buffer, self%velocities, self%accelerations)
   end subroutine spatial_links_header

   subroutine spatial_links_row(self, model, result, prefix, rows, error)
      class(spatial_links_writer_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      type(row_prefix_type), intent(inout) :: prefix
      integer, intent(inout) :: rows
      type(error_type), allocatable, intent(out) :: error
      call write_spatial_links_rows(self%buffer, model, result, prefix%text(1:prefix%n), self%velocities, &
         & self%accelerations, prefix%numbers)
      rows = rows + size(model%output%links)
   end subroutine spatial_links_row

   !> The writer of nodes.csv of a spatial run.
   type(spatial_nodes_writer_type) function spatial_nodes_writer() result(writer)
      writer%prefixed = .true.
   end function spatial_nodes_writer

   subroutine spatial_nodes_header(self, model)
      class(spatial_nodes_writer_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      call write_spatial_nodes_header(self%buffer, model)
   end subroutine spatial_nodes_header

   !> A row of every node: not counted among the table rows (as the planar nodes.csv's).
   subroutine spatial_nodes_row(self, model, result, prefix, rows, error)
      class(spatial_nodes_writer_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      type(row_prefix_type), intent(inout) :: prefix
      integer, intent(inout) :: rows
      type(error_type), allocatable, intent(out) :: error
      call write_spatial_nodes_row(self%buffer, result, prefix%text(1:prefix%n))
   end subroutine spatial_nodes_row

end module fekap_output_spatial_writers
