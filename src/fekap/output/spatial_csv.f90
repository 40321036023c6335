!> The CSV tables of a spatial run: points.csv with z columns
!> (`step,t,point,x,y,z[,vx,vy,vz[,ax,ay,az]]`) and joints.csv
!> (`step,t,joint,angle[,rate[,acceleration]]`: each revolute joint's angle
!> and each prismatic joint's stroke relative to the deck's configuration,
!> fekap_model_spatial's reported_joints). Rows are appended to the file's
!> text buffer as csv.f90's are; a planar run never calls these.
module fekap_output_spatial_csv
   use fekap_model, only: model_type
   use fekap_model_results, only: step_result_type
   use fekap_model_spatial, only: reported_joints
   use fekap_output_buffer, only: text_buffer_type, reserve_text
   use fekap_output_csv, only: write_rates_header, row_length, append_rates_row
   implicit none
   private

   public :: write_spatial_points_header, write_spatial_points_rows, write_joints_header, write_joints_rows

contains

   !> The header of points.csv of a spatial run.
   subroutine write_spatial_points_header(out, velocities, accelerations)
      type(text_buffer_type), intent(inout) :: out
      logical, intent(in) :: velocities, accelerations
      call write_rates_header(out, 'step,t,point,x,y,z', ',vx,vy,vz', ',ax,ay,az', velocities, accelerations)
   end subroutine write_spatial_points_header

   !> One row per tracked point, with z.
   subroutine write_spatial_points_rows(out, model, result, prefix, velocities, accelerations)
      type(text_buffer_type), intent(inout) :: out
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      !> `step,t,` of the step's rows.
      character(*), intent(in) :: prefix
      logical, intent(in) :: velocities, accelerations
      integer :: i, node
      do i = 1, size(model%output%points)
         node = model%output%points(i)
         call reserve_text(out, row_length(len(model%nodes(node)%name), 9))
         call append_rates_row(out%text, out%n, prefix, model%nodes(node)%name, [result%pos(:, node), result%pos_z(node)], &
            & [result%vel(:, node), result%vel_z(node)], [result%acc(:, node), result%acc_z(node)], &
            & result%has_velocity, velocities, accelerations)
      end do
   end subroutine write_spatial_points_rows

   !> The header of joints.csv.
   subroutine write_joints_header(out, velocities, accelerations)
      type(text_buffer_type), intent(inout) :: out
      logical, intent(in) :: velocities, accelerations
      call write_rates_header(out, 'step,t,joint,angle', ',rate', ',acceleration', velocities, accelerations)
   end subroutine write_joints_header

   !> One row per reported joint.
   subroutine write_joints_rows(out, model, result, prefix, velocities, accelerations)
      type(text_buffer_type), intent(inout) :: out
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      character(*), intent(in) :: prefix
      logical, intent(in) :: velocities, accelerations
      integer, allocatable :: joints(:)
      integer :: i
      joints = reported_joints(model%spatial)
      do i = 1, size(joints)
         associate (name => model%spatial%joints(joints(i))%name)
            call reserve_text(out, row_length(len(name), 3))
            call append_rates_row(out%text, out%n, prefix, name, result%joint_motion(1:1, i), result%joint_motion(2:2, i), &
               & result%joint_motion(3:3, i), result%has_velocity, velocities, accelerations)
         end associate
      end do
   end subroutine write_joints_rows

end module fekap_output_spatial_csv
