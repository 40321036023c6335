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
      call write_rates_header(unit, 'step,t,point,x,y', ',vx,vy', ',ax,ay', velocities, accelerations)
   end subroutine write_points_header

   !> One row per tracked point.
   subroutine write_points_rows(unit, model, result, velocities, accelerations)
      integer, intent(in) :: unit
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      logical, intent(in) :: velocities, accelerations
      integer :: i, node
      do i = 1, size(model%output%points)
         node = model%output%points(i)
         call write_rates_row(unit, result, model%nodes(node)%name, result%pos(:, node), result%vel(:, node), &
            & result%acc(:, node), velocities, accelerations)
      end do
   end subroutine write_points_rows

   !> `step,t,link,angle[,omega[,alpha]]`.
   subroutine write_links_header(unit, velocities, accelerations)
      integer, intent(in) :: unit
      logical, intent(in) :: velocities, accelerations
      call write_rates_header(unit, 'step,t,link,angle', ',omega', ',alpha', velocities, accelerations)
   end subroutine write_links_header

   !> One row per reported link.
   subroutine write_links_rows(unit, model, result, velocities, accelerations)
      integer, intent(in) :: unit
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      logical, intent(in) :: velocities, accelerations
      integer :: i, link
      do i = 1, size(model%output%links)
         link = model%output%links(i)
         call write_rates_row(unit, result, model%links(link)%name, result%angle(link:link), &
            & result%omega(link:link), result%alpha(link:link), velocities, accelerations)
      end do
   end subroutine write_links_rows

   !> The header of a table of values and their rates: the rate columns only
   !> when computed.
   subroutine write_rates_header(unit, values, rates, second_rates, velocities, accelerations)
      integer, intent(in) :: unit
      character(*), intent(in) :: values, rates, second_rates
      logical, intent(in) :: velocities, accelerations
      if (velocities .and. accelerations) then
         call emit(unit, values//rates//second_rates)
      else if (velocities) then
         call emit(unit, values//rates)
      else
         call emit(unit, values)
      end if
   end subroutine write_rates_header

   !> `step,t,name,q[,dq[,ddq]]`: the rate columns as computed, left empty at a
   !> step where they are not known (a singular configuration).
   subroutine write_rates_row(unit, result, name, q, dq, ddq, velocities, accelerations)
      integer, intent(in) :: unit
      type(step_result_type), intent(in) :: result
      character(*), intent(in) :: name
      real(dp), intent(in) :: q(:), dq(:), ddq(:)
      logical, intent(in) :: velocities, accelerations
      if (velocities .and. .not. result%has_velocity) then
         call write_row(unit, result%step, name, [result%t, q], blanks=size(q)*merge(2, 1, accelerations))
      else if (velocities .and. accelerations) then
         call write_row(unit, result%step, name, [result%t, q, dq, ddq])
      else if (velocities) then
         call write_row(unit, result%step, name, [result%t, q, dq])
      else
         call write_row(unit, result%step, name, [result%t, q])
      end if
   end subroutine write_rates_row

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
