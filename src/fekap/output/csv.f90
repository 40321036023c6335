!> CSV tables of a run: points.csv, links.csv, steps.csv and mesh.csv.
!> Writers take a unit open for unformatted stream access (lines are written
!> as bytes with their newline: no format to interpret per row) and never
!> open files themselves. Reals are written with 17 significant digits,
!> enough to round-trip.
module fekap_output_csv
   use fekap_kinds, only: dp
   use fekap_model, only: model_type
   use fekap_model_results, only: step_result_type
   use fekap_output_format, only: real_text, integer_text, append_real, append_integer
   implicit none
   private

   public :: write_points_header, write_points_rows, write_links_header, write_links_rows
   public :: write_steps_header, write_steps_row, write_mesh_csv

   !> Width of one real field before blanks are squeezed out.
   integer, parameter :: real_width = 25

contains

   !> `step,t,point,x,y[,vx,vy[,ax,ay]]`: rate columns only when computed.
   subroutine write_points_header(unit, velocities, accelerations)
      integer, intent(in) :: unit
      logical, intent(in) :: velocities, accelerations
      character(:), allocatable :: header
      header = 'step,t,point,x,y'
      if (velocities) header = header//',vx,vy'
      if (velocities .and. accelerations) header = header//',ax,ay'
      call emit(unit, header)
   end subroutine write_points_header

   !> One row per tracked point.
   subroutine write_points_rows(unit, model, result, velocities, accelerations)
      integer, intent(in) :: unit
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      logical, intent(in) :: velocities, accelerations
      integer :: i, node, nval
      real(dp) :: values(7)
      do i = 1, size(model%output%points)
         node = model%output%points(i)
         values(1:3) = [result%t, result%pos(:, node)]
         nval = 3
         if (velocities .and. .not. result%has_velocity) then
            ! Not computed at this step (a singular configuration): empty fields.
            call write_row(unit, result%step, model%nodes(node)%name, values(1:nval), &
               & blanks=merge(4, 2, accelerations))
            cycle
         end if
         if (velocities) then
            values(4:5) = result%vel(:, node)
            nval = 5
            if (accelerations) then
               values(6:7) = result%acc(:, node)
               nval = 7
            end if
         end if
         call write_row(unit, result%step, model%nodes(node)%name, values(1:nval))
      end do
   end subroutine write_points_rows

   !> `step,t,link,angle[,omega[,alpha]]`.
   subroutine write_links_header(unit, velocities, accelerations)
      integer, intent(in) :: unit
      logical, intent(in) :: velocities, accelerations
      character(:), allocatable :: header
      header = 'step,t,link,angle'
      if (velocities) header = header//',omega'
      if (velocities .and. accelerations) header = header//',alpha'
      call emit(unit, header)
   end subroutine write_links_header

   !> One row per reported link.
   subroutine write_links_rows(unit, model, result, velocities, accelerations)
      integer, intent(in) :: unit
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      logical, intent(in) :: velocities, accelerations
      integer :: i, link, nval
      real(dp) :: values(4)
      do i = 1, size(model%output%links)
         link = model%output%links(i)
         values(1:2) = [result%t, result%angle(link)]
         nval = 2
         if (velocities .and. .not. result%has_velocity) then
            call write_row(unit, result%step, model%links(link)%name, values(1:nval), &
               & blanks=merge(2, 1, accelerations))
            cycle
         end if
         if (velocities) then
            values(3) = result%omega(link)
            nval = 3
            if (accelerations) then
               values(4) = result%alpha(link)
               nval = 4
            end if
         end if
         call write_row(unit, result%step, model%links(link)%name, values(1:nval))
      end do
   end subroutine write_links_rows

   subroutine write_steps_header(unit)
      integer, intent(in) :: unit
      call emit(unit, 'step,t,iterations,residual,cuts')
   end subroutine write_steps_header

   subroutine write_steps_row(unit, result)
      integer, intent(in) :: unit
      type(step_result_type), intent(in) :: result
      call emit(unit, integer_text(result%step)//','//real_text(result%t)//','// &
         & integer_text(result%iterations)//','//real_text(result%residual)//','//integer_text(result%cuts))
   end subroutine write_steps_row

   !> `link,node1,node2`: the end points of every link, for drawing the mechanism.
   subroutine write_mesh_csv(unit, model)
      integer, intent(in) :: unit
      type(model_type), intent(in) :: model
      integer :: l
      call emit(unit, 'link,node1,node2')
      do l = 1, size(model%links)
         call emit(unit, model%links(l)%name//','//model%nodes(model%links(l)%node(1))%name//','// &
            & model%nodes(model%links(l)%node(2))%name)
      end do
   end subroutine write_mesh_csv

   !> `step,t,name,v2,...`: values(1) is t; `blanks` empty fields follow.
   subroutine write_row(unit, step, name, values, blanks)
      integer, intent(in) :: unit, step
      character(*), intent(in) :: name
      real(dp), intent(in) :: values(:)
      integer, intent(in), optional :: blanks
      character(len=40 + len(name) + real_width*size(values)) :: line
      integer :: i, n
      n = 0
      call append_integer(line, n, step)
      line(n + 1:n + 1) = ','
      n = n + 1
      call append_real(line, n, values(1))
      line(n + 1:n + 1 + len(name)) = ','//name
      n = n + 1 + len(name)
      do i = 2, size(values)
         line(n + 1:n + 1) = ','
         n = n + 1
         call append_real(line, n, values(i))
      end do
      if (present(blanks)) then
         line(n + 1:n + blanks) = repeat(',', blanks)
         n = n + blanks
      end if
      call emit(unit, line(1:n))
   end subroutine write_row

   !> One line of text and its newline.
   subroutine emit(unit, text)
      integer, intent(in) :: unit
      character(*), intent(in) :: text
      write (unit) text, new_line('a')
   end subroutine emit

end module fekap_output_csv
