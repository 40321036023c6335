!> The CSV tables of a spatial run: points.csv with z columns
!> (`step,t,point,x,y,z[,vx,vy,vz[,ax,ay,az]]`) and joints.csv
!> (`step,t,joint,angle[,rate[,acceleration]]`: each revolute joint's angle,
!> each prismatic joint's stroke and each cylindrical joint's angle and
!> stroke (row JOINT.stroke) relative to the deck's configuration,
!> fekap_model_spatial's reported_joints), nodes.csv with z columns
!> (`step,t,A.x,A.y,A.z,B.x,...`) and mechanism.txt with the nodes' z, the
!> joints and their drives. Rows are appended to the file's text buffer as
!> csv.f90's are; a planar run never calls these.
module fekap_output_spatial_csv
   use fekap_model, only: model_type
   use fekap_model_results, only: step_result_type
   use fekap_kinds, only: dp
   use fekap_model_spatial, only: reported_joints, joint_names, joint_revolute, joint_universal, joint_prismatic, &
      & joint_cylindrical
   use fekap_output_buffer, only: text_buffer_type, reserve_text
   use fekap_output_csv, only: write_rates_header, row_length, append_rates_row, emit, word_at, &
      & write_mechanism_head, write_track_record, real_text_cache_type
   use fekap_output_format, only: append_real, append_text, real_text
   implicit none
   private

   public :: write_spatial_points_header, write_spatial_points_rows, write_joints_header, write_joints_rows
   public :: write_spatial_nodes_header, write_spatial_nodes_row, write_spatial_mechanism
   public :: write_spatial_links_header, write_spatial_links_rows

contains

   !> The header of points.csv of a spatial run.
   subroutine write_spatial_points_header(out, velocities, accelerations)
      type(text_buffer_type), intent(inout) :: out
      logical, intent(in) :: velocities, accelerations
      call write_rates_header(out, 'step,t,point,x,y,z', ',vx,vy,vz', ',ax,ay,az', velocities, accelerations)
   end subroutine write_spatial_points_header

   !> One row per tracked point, with z.
   subroutine write_spatial_points_rows(out, model, result, prefix, velocities, accelerations, numbers)
      type(text_buffer_type), intent(inout) :: out
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      !> `step,t,` of the step's rows.
      character(*), intent(in) :: prefix
      logical, intent(in) :: velocities, accelerations
      !> The texts of the reals written before (row_prefix_type's).
      type(real_text_cache_type), intent(inout) :: numbers
      integer :: i, node
      do i = 1, size(model%output%points)
         node = model%output%points(i)
         call reserve_text(out, row_length(len(model%nodes(node)%name), 9))
         call append_rates_row(out%text, out%n, prefix, model%nodes(node)%name, [result%pos(:, node), result%pos_z(node)], &
            & [result%vel(:, node), result%vel_z(node)], [result%acc(:, node), result%acc_z(node)], &
            & result%has_velocity, velocities, accelerations, numbers)
      end do
   end subroutine write_spatial_points_rows

   !> The header of joints.csv.
   subroutine write_joints_header(out, velocities, accelerations)
      type(text_buffer_type), intent(inout) :: out
      logical, intent(in) :: velocities, accelerations
      call write_rates_header(out, 'step,t,joint,angle', ',rate', ',acceleration', velocities, accelerations)
   end subroutine write_joints_header

   !> One row per reported joint.
   subroutine write_joints_rows(out, model, result, prefix, velocities, accelerations, numbers)
      type(text_buffer_type), intent(inout) :: out
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      character(*), intent(in) :: prefix
      logical, intent(in) :: velocities, accelerations
      type(real_text_cache_type), intent(inout) :: numbers
      integer, allocatable :: joints(:)
      logical, allocatable :: stroke(:)
      character(:), allocatable :: name
      integer :: i
      call reported_joints(model%spatial, joints, stroke)
      do i = 1, size(joints)
         name = model%spatial%joints(joints(i))%name
         ! A cylindrical joint's second row: its stroke.
         if (stroke(i) .and. model%spatial%joints(joints(i))%kind == joint_cylindrical) name = name//'.stroke'
         call reserve_text(out, row_length(len(name), 3))
         call append_rates_row(out%text, out%n, prefix, name, result%joint_motion(1:1, i), result%joint_motion(2:2, i), &
            & result%joint_motion(3:3, i), result%has_velocity, velocities, accelerations, numbers)
      end do
   end subroutine write_joints_rows

   !> The header of links.csv of a spatial run:
   !> `step,t,link,q0,q1,q2,q3[,omega_x,omega_y,omega_z[,alpha_x,alpha_y,alpha_z]]`.
   subroutine write_spatial_links_header(out, velocities, accelerations)
      type(text_buffer_type), intent(inout) :: out
      logical, intent(in) :: velocities, accelerations
      call write_rates_header(out, 'step,t,link,q0,q1,q2,q3', ',omega_x,omega_y,omega_z', &
         & ',alpha_x,alpha_y,alpha_z', velocities, accelerations)
   end subroutine write_spatial_links_header

   !> One row per reported link (OUTPut `angles`): its rotation quaternion,
   !> angular velocity and acceleration (fekap_spatial_link_motion).
   subroutine write_spatial_links_rows(out, model, result, prefix, velocities, accelerations, numbers)
      type(text_buffer_type), intent(inout) :: out
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      character(*), intent(in) :: prefix
      logical, intent(in) :: velocities, accelerations
      type(real_text_cache_type), intent(inout) :: numbers
      integer :: i, link
      do i = 1, size(model%output%links)
         link = model%output%links(i)
         associate (name => model%links(link)%name)
            call reserve_text(out, row_length(len(name), 10))
            call append_rates_row(out%text, out%n, prefix, name, result%link_rotation(:, link), &
               & result%link_omega(:, link), result%link_alpha(:, link), result%has_velocity, velocities, accelerations, &
               & numbers)
         end associate
      end do
   end subroutine write_spatial_links_rows

   !> `step,t,A.x,A.y,A.z,B.x,...`: the header of nodes.csv of a spatial
   !> run, three columns per node of the model in the deck's order (a spatial
   !> link is one element: there are no interior points to add).
   subroutine write_spatial_nodes_header(out, model)
      type(text_buffer_type), intent(inout) :: out
      type(model_type), intent(in) :: model
      integer :: i
      call reserve_text(out, 7)
      call append_text(out%text, out%n, 'step,t')
      do i = 1, size(model%nodes)
         associate (name => model%nodes(i)%name)
            call reserve_text(out, 3*len(name) + 9)
            call append_text(out%text, out%n, ','//name//'.x,'//name//'.y,'//name//'.z')
         end associate
      end do
      call append_text(out%text, out%n, new_line('a'))
   end subroutine write_spatial_nodes_header

   !> `step,t,x,y,z,x,y,z,...`: every node's position at one step.
   subroutine write_spatial_nodes_row(out, result, prefix)
      type(text_buffer_type), intent(inout) :: out
      type(step_result_type), intent(in) :: result
      !> `step,t,` of the step's rows.
      character(*), intent(in) :: prefix
      integer :: i
      call reserve_text(out, row_length(0, 3*size(result%pos, 2)))
      call append_text(out%text, out%n, prefix(1:len(prefix) - 1))
      do i = 1, size(result%pos, 2)
         call append_value(result%pos(1, i))
         call append_value(result%pos(2, i))
         call append_value(result%pos_z(i))
      end do
      call append_text(out%text, out%n, new_line('a'))
   contains
      subroutine append_value(x)
         real(dp), intent(in) :: x
         call append_text(out%text, out%n, ',')
         call append_real(out%text, out%n, x)
      end subroutine append_value
   end subroutine write_spatial_nodes_row

   !> mechanism.txt of a spatial run, one record a line, the kind first:
   !> `record,fields`; `title,"TEXT"`; `units,length,NAME` and
   !> `units,time,NAME` (only from a units line); `node,NAME,x,y,z` (the
   !> deck's coordinates); `analysis,kinematics,spatial`;
   !> `joint,NAME,KIND,FIRST,SECOND[,ax,ay,az[,bx,by,bz]]` (FIRST or SECOND
   !> `ground`; the unit axes in global coordinates at the deck's
   !> configuration: one for revolute, prismatic and cylindrical joints, two
   !> for universal ones, none for spherical joints and welds);
   !> `drive,rotation|stroke,JOINT`; `track,NODE...`. To a unit open for
   !> unformatted stream access.
   subroutine write_spatial_mechanism(unit, model)
      integer, intent(in) :: unit
      type(model_type), intent(in) :: model
      character(:), allocatable :: line, first, second
      integer :: i
      call write_mechanism_head(unit, model)
      do i = 1, size(model%nodes)
         call emit(unit, 'node,'//model%nodes(i)%name//','//real_text(model%nodes(i)%x(1))//','// &
            & real_text(model%nodes(i)%x(2))//','//real_text(model%spatial%z(i)))
      end do
      call emit(unit, 'analysis,kinematics,spatial')
      if (allocated(model%spatial%joints)) then
         do i = 1, size(model%spatial%joints)
            associate (j => model%spatial%joints(i))
               first = model%nodes(j%node(1))%name
               second = 'ground'
               if (j%node(2) > 0) then
                  second = model%nodes(j%node(2))%name
               else if (j%ground_first) then
                  second = first
                  first = 'ground'
               end if
               line = 'joint,'//j%name//','//word_at(joint_names, j%kind)//','//first//','//second
               if (any(j%kind == [joint_revolute, joint_universal, joint_prismatic, joint_cylindrical])) then
                  line = line//axis_fields(j%axis)
               end if
               if (j%kind == joint_universal) line = line//axis_fields(j%axis2)
               call emit(unit, line)
            end associate
         end do
      end if
      if (allocated(model%spatial%drives)) then
         do i = 1, size(model%spatial%drives)
            associate (d => model%spatial%drives(i))
               call emit(unit, 'drive,'//trim(merge('stroke  ', 'rotation', d%stroke))//','// &
                  & model%spatial%joints(d%joint)%name)
            end associate
         end do
      end if
      call write_track_record(unit, model)
   end subroutine write_spatial_mechanism

   !> `,x,y,z` of the unit vector along axis (not zero: the deck checks).
   function axis_fields(axis) result(text)
      real(dp), intent(in) :: axis(3)
      character(:), allocatable :: text
      real(dp) :: unit_axis(3)
      unit_axis = axis/norm2(axis)
      text = ','//real_text(unit_axis(1))//','//real_text(unit_axis(2))//','//real_text(unit_axis(3))
   end function axis_fields

end module fekap_output_spatial_csv
