!> CSV tables of a run: points.csv, links.csv, steps.csv, nodes.csv, and
!> mesh.csv and mechanism.txt (written once).
!> The per-step rows are built with the exact number texts of
!> fekap_output_format (no format to interpret, no allocation) and appended
!> to the file's text buffer, which writes them in large pieces; mesh.csv,
!> written once, goes straight to a unit open for unformatted stream access.
!> Writers never open files themselves. Reals are written with 17
!> significant digits, enough to round-trip. The module is over 600 lines
!> because the tables' rows share its row prefix, its row lengths and the
!> cache of number texts that the prefix carries (real_text_cache_type, of
!> fekap_output_format, whose append_reals writes a row's reals in one
!> call), which keep the rows of a step in one place; splitting the
!> once-written mechanism.txt records off would be the way to shorten it.
module fekap_output_csv
   use fekap_kinds, only: dp
   use fekap_model, only: model_type, dof_x, dof_y, dof_rot, effects_dynamics, integrator_names
   use fekap_model_effects, only: planned_effects, effects_name
   use fekap_model_results, only: step_result_type
   use fekap_model_reactions, only: reaction_row_type, reaction_rows
   use fekap_output_format, only: append_real, append_integer, append_text, real_text, append_reals, &
      & real_text_cache_type, real_width
   use fekap_output_buffer, only: text_buffer_type, reserve_text
   implicit none
   private

   public :: write_points_header, write_points_rows, write_links_header, write_links_rows
   public :: write_header, write_steps_row, write_mesh_csv, new_row_prefix
   public :: write_nodes_header, write_nodes_row, write_mechanism_csv, write_reactions_rows
   public :: write_energy_row, write_deflection_rows
   !> For the tables of other modules (spatial runs): a header with rate columns, a row's
   !> longest text, a row of a name's values and rates.
   public :: write_rates_header, row_length, append_rates_row
   !> For mechanism.txt of a spatial run: one line to a unit, a CSV field
   !> quoted, a word of a list of names.
   public :: emit, quoted, word_at, write_mechanism_head, write_track_record
   !> The cache of real texts (fekap_output_format's), for the rows of other modules.
   public :: real_text_cache_type

   !> The fixed headers (write_header) of steps.csv, reactions.csv and
   !> deflection.csv; energy.csv's is `step,t,` and the effect's columns.
   !> (floor_steps_header: the steps.csv of a method whose Newton reports the
   !> round-off floor, with the `floor` column; dynamics_steps_header: a
   !> dynamics run's, with `floor` and, last, the `error_estimate` column.)
   character(*), parameter, public :: steps_header = 'step,t,iterations,residual,cuts', &
      & floor_steps_header = steps_header//',floor', &
      & dynamics_steps_header = floor_steps_header//',error_estimate', &
      & reactions_header = 'step,t,kind,link,node,fx,fy,m', deflection_header = 'step,t,node,ux,uy'

   !> Longest text of an integer and of the prefix `step,t,` of a row
   !> (real_width: of a real).
   integer, parameter :: integer_width = 11, prefix_length = integer_width + real_width + 2

   !> `step,t,`, the start of every row of a step in every table: its text
   !> is made once per step (new_row_prefix), not once per row. It goes to
   !> every table's rows, and with it the texts of the last reals written
   !> (`numbers`), which the tables share: a value written again, in the
   !> same table at a later step or in another table at the same step, is
   !> copied, not formatted again.
   type, public :: row_prefix_type
      character(len=prefix_length) :: text = ''
      integer :: n = 0
      type(real_text_cache_type) :: numbers
   end type row_prefix_type

contains

   !> `step,t,point,x,y[,vx,vy[,ax,ay]]`: rate columns only when computed.
   subroutine write_points_header(out, velocities, accelerations)
      type(text_buffer_type), intent(inout) :: out
      logical, intent(in) :: velocities, accelerations
      call write_rates_header(out, 'step,t,point,x,y', ',vx,vy', ',ax,ay', velocities, accelerations)
   end subroutine write_points_header

   !> One row per tracked point.
   subroutine write_points_rows(out, model, result, prefix, velocities, accelerations)
      type(text_buffer_type), intent(inout) :: out
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      !> new_row_prefix of the result.
      type(row_prefix_type), intent(inout) :: prefix
      logical, intent(in) :: velocities, accelerations
      real(dp) :: row(6)
      integer :: i, node, length, m
      length = 0
      do i = 1, size(model%output%points)
         length = length + row_chars(len(model%nodes(model%output%points(i))%name), 6)
      end do
      call reserve_text(out, length)
      do i = 1, size(model%output%points)
         node = model%output%points(i)
         if (velocities .and. .not. result%has_velocity) then
            call append_rates_row(out%text, out%n, prefix%text(1:prefix%n), model%nodes(node)%name, result%pos(:, node), &
               & result%vel(:, node), result%acc(:, node), result%has_velocity, velocities, accelerations, prefix%numbers)
            cycle
         end if
         ! The columns known: x, y and the rates asked for, gathered for one
         ! append_reals (no array descriptors per row).
         row(1:2) = result%pos(:, node)
         m = 2
         if (velocities) then
            row(3:4) = result%vel(:, node)
            m = 4
            if (accelerations) then
               row(5:6) = result%acc(:, node)
               m = 6
            end if
         end if
         call append_named_row(out, prefix, model%nodes(node)%name, row, m)
      end do
   end subroutine write_points_rows

   !> `step,t,link,angle[,omega[,alpha]]`.
   subroutine write_links_header(out, velocities, accelerations)
      type(text_buffer_type), intent(inout) :: out
      logical, intent(in) :: velocities, accelerations
      call write_rates_header(out, 'step,t,link,angle', ',omega', ',alpha', velocities, accelerations)
   end subroutine write_links_header

   !> One row per reported link.
   subroutine write_links_rows(out, model, result, prefix, velocities, accelerations)
      type(text_buffer_type), intent(inout) :: out
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      !> new_row_prefix of the result.
      type(row_prefix_type), intent(inout) :: prefix
      logical, intent(in) :: velocities, accelerations
      real(dp) :: row(3)
      integer :: i, link, length, m
      length = 0
      do i = 1, size(model%output%links)
         length = length + row_chars(len(model%links(model%output%links(i))%name), 3)
      end do
      call reserve_text(out, length)
      do i = 1, size(model%output%links)
         link = model%output%links(i)
         if (velocities .and. .not. result%has_velocity) then
            call append_rates_row(out%text, out%n, prefix%text(1:prefix%n), model%links(link)%name, &
               & result%angle(link:link), result%omega(link:link), result%alpha(link:link), result%has_velocity, &
               & velocities, accelerations, prefix%numbers)
            cycle
         end if
         ! As write_points_rows: the known columns through one append_reals.
         row(1) = result%angle(link)
         m = 1
         if (velocities) then
            row(2) = result%omega(link)
            m = 2
            if (accelerations) then
               row(3) = result%alpha(link)
               m = 3
            end if
         end if
         call append_named_row(out, prefix, model%links(link)%name, row, m)
      end do
   end subroutine write_links_rows

   !> The header of a table of values and their rates: the rate columns only
   !> when computed.
   subroutine write_rates_header(out, values, rates, second_rates, velocities, accelerations)
      type(text_buffer_type), intent(inout) :: out
      character(*), intent(in) :: values, rates, second_rates
      logical, intent(in) :: velocities, accelerations
      call reserve_text(out, len(values) + len(rates) + len(second_rates) + 1)
      call append_text(out%text, out%n, values)
      if (velocities) call append_text(out%text, out%n, rates)
      if (velocities .and. accelerations) call append_text(out%text, out%n, second_rates)
      call append_text(out%text, out%n, new_line('a'))
   end subroutine write_rates_header

   !> Longest row: the prefix, a name, `reals` reals after it and the newline.
   pure integer function row_length(name_length, reals)
      integer, intent(in) :: name_length, reals
      row_length = row_chars(name_length, reals)
   end function row_length

   !> row_length for this module's writers: a public procedure of a module
   !> compiled as position-independent code is called even from its own
   !> module (it could be interposed), a private one is inlined.
   pure integer function row_chars(name_length, reals)
      integer, intent(in) :: name_length, reals
      row_chars = prefix_length + name_length + reals*(real_width + 1) + 1
   end function row_chars

   !> The prefix `step,t,` of the rows of the step of `result`.
   pure subroutine new_row_prefix(self, result)
      !> Its cache of texts is kept from step to step.
      type(row_prefix_type), intent(inout) :: self
      type(step_result_type), intent(in) :: result
      self%n = 0
      call append_integer(self%text, self%n, result%step)
      call append_char(self%text, self%n, ',')
      call append_real(self%text, self%n, result%t)
      call append_char(self%text, self%n, ',')
   end subroutine new_row_prefix

   !> `step,t,name,q[,dq[,ddq]]` after its prefix `step,t,`: the rate columns
   !> as computed, left empty at a step where they are not known (a singular
   !> configuration). `cache`: the texts of the reals written before (see
   !> row_prefix_type).
   pure subroutine append_rates_row(text, n, prefix, name, q, dq, ddq, has_velocity, velocities, accelerations, cache)
      character(*), intent(inout) :: text
      integer, intent(inout) :: n
      character(*), intent(in) :: prefix, name
      real(dp), intent(in) :: q(:), dq(:), ddq(:)
      logical, intent(in) :: has_velocity, velocities, accelerations
      type(real_text_cache_type), intent(inout) :: cache
      !> The values of a row gathered for one call of append_values (a call
      !> each of q, dq and ddq cost as much as the cache saves).
      integer, parameter :: max_row = 16
      real(dp) :: row(max_row)
      integer :: i, m
      text(n + 1:n + len(prefix)) = prefix
      n = n + len(prefix)
      text(n + 1:n + len(name)) = name
      n = n + len(name)
      m = size(q) + size(dq) + size(ddq)
      if (velocities .and. has_velocity .and. m <= max_row) then
         row(1:size(q)) = q
         row(size(q) + 1:size(q) + size(dq)) = dq
         m = size(q) + size(dq)
         if (accelerations) then
            row(m + 1:m + size(ddq)) = ddq
            m = m + size(ddq)
         end if
         call append_values(text, n, row(1:m), cache)
         call append_char(text, n, new_line('a'))
         return
      end if
      call append_values(text, n, q, cache)
      if (velocities .and. .not. has_velocity) then
         do i = 1, size(dq) + merge(size(ddq), 0, accelerations)
            call append_char(text, n, ',')
         end do
      else if (velocities) then
         call append_values(text, n, dq, cache)
         if (accelerations) call append_values(text, n, ddq, cache)
      end if
      call append_char(text, n, new_line('a'))
   end subroutine append_rates_row

   !> `,v1,v2,...`: each value as append_real writes it, through `cache`
   !> (append_reals).
   pure subroutine append_values(text, n, values, cache)
      character(*), intent(inout) :: text
      integer, intent(inout) :: n
      real(dp), intent(in) :: values(:)
      type(real_text_cache_type), intent(inout) :: cache
      call append_reals(text, n, values, size(values), cache)
   end subroutine append_values

   !> The prefix `step,t,` of a row, copied as its whole prefix_length
   !> characters (a copy of fixed length is a few moves, one of the prefix's
   !> length a call of memmove), n advanced by its length: the characters
   !> beyond are overwritten by what follows. The caller has reserved a
   !> row_length.
   pure subroutine append_prefix(text, n, prefix)
      character(*), intent(inout) :: text
      integer, intent(inout) :: n
      type(row_prefix_type), intent(in) :: prefix
      text(n + 1:n + prefix_length) = prefix%text
      n = n + prefix%n
   end subroutine append_prefix

   !> A point's or link's row of known columns: `step,t,`, its name, the m
   !> values and the line's end (the buffer reserved by the caller).
   subroutine append_named_row(out, prefix, name, values, m)
      type(text_buffer_type), intent(inout) :: out
      type(row_prefix_type), intent(inout) :: prefix
      character(*), intent(in) :: name
      integer, intent(in) :: m
      real(dp), intent(in) :: values(m)
      call append_prefix(out%text, out%n, prefix)
      call append_name(out%text, out%n, name)
      call append_reals(out%text, out%n, values, m, prefix%numbers)
      call append_char(out%text, out%n, new_line('a'))
   end subroutine append_named_row

   !> A point's or link's name. Names are short: those of one to three
   !> characters are copied at their fixed length (a move or two), not
   !> through the call of memmove that a copy of variable length is (a loop
   !> over the characters the compiler makes into that call too).
   pure subroutine append_name(text, n, name)
      character(*), intent(inout) :: text
      integer, intent(inout) :: n
      character(*), intent(in) :: name
      select case (len(name))
      case (1)
         text(n + 1:n + 1) = name
      case (2)
         text(n + 1:n + 2) = name
      case (3)
         text(n + 1:n + 3) = name
      case default
         text(n + 1:n + len(name)) = name
      end select
      n = n + len(name)
   end subroutine append_name

   !> One character (inlined here, unlike append_text of another module).
   pure subroutine append_char(text, n, c)
      character(*), intent(inout) :: text
      integer, intent(inout) :: n
      character, intent(in) :: c
      text(n + 1:n + 1) = c
      n = n + 1
   end subroutine append_char

   !> A table's header line `header` (steps_header, ...).
   subroutine write_header(out, header)
      type(text_buffer_type), intent(inout) :: out
      character(*), intent(in) :: header
      call reserve_text(out, len(header) + 1)
      call append_text(out%text, out%n, header//new_line('a'))
   end subroutine write_header

   !> `step,t,iterations,residual,cuts` (and `,floor` when the result reports
   !> it: the FEM, the classical methods and dynamics; and `,error_estimate`
   !> when it reports that: dynamics).
   subroutine write_steps_row(out, result, prefix)
      type(text_buffer_type), intent(inout) :: out
      type(step_result_type), intent(in) :: result
      !> new_row_prefix of the result.
      type(row_prefix_type), intent(inout) :: prefix
      call reserve_text(out, prefix_length + 3*(integer_width + 1) + 2*(real_width + 1))
      call append_prefix(out%text, out%n, prefix)
      call append_integer(out%text, out%n, result%iterations)
      call append_char(out%text, out%n, ',')
      call append_real(out%text, out%n, result%residual)
      call append_char(out%text, out%n, ',')
      call append_integer(out%text, out%n, result%cuts)
      if (result%floor >= 0) then
         call append_char(out%text, out%n, ',')
         call append_integer(out%text, out%n, result%floor)
      end if
      if (result%estimate >= 0) then
         call append_char(out%text, out%n, ',')
         call append_real(out%text, out%n, result%estimate)
      end if
      call append_char(out%text, out%n, new_line('a'))
   end subroutine write_steps_row

   !> `step,t,A.x,A.y,B.x,...`: the header of nodes.csv, two columns per node
   !> of the model, in the deck's order; with output%mesh_nodes, then two per
   !> interior point of each meshed link, `L#1.x,L#1.y,...` from its first
   !> end (`#` is in no deck name).
   subroutine write_nodes_header(out, model)
      type(text_buffer_type), intent(inout) :: out
      type(model_type), intent(in) :: model
      integer :: i, k
      character(len=12) :: number
      call reserve_text(out, 7)
      call append_text(out%text, out%n, 'step,t')
      do i = 1, size(model%nodes)
         call reserve_text(out, 2*len(model%nodes(i)%name) + 7)
         call append_text(out%text, out%n, ','//model%nodes(i)%name//'.x,'//model%nodes(i)%name//'.y')
      end do
      if (model%output%mesh_nodes) then
         do i = 1, size(model%links)
            do k = 1, model%links(i)%nelem - 1
               write (number, '(i0)') k
               call reserve_text(out, 2*(len(model%links(i)%name) + len_trim(number)) + 9)
               call append_text(out%text, out%n, ','//model%links(i)%name//'#'//trim(number)//'.x,'// &
                  & model%links(i)%name//'#'//trim(number)//'.y')
            end do
         end do
      end if
      call append_text(out%text, out%n, new_line('a'))
   end subroutine write_nodes_header

   !> `step,t,x,y,x,y,...`: the positions of every node of the model at one
   !> step, so that the whole mechanism can be drawn whatever is tracked; with
   !> output%mesh_nodes, then those of the meshed links' interior points (a
   !> method without a mesh, whose links stay straight, places them evenly
   !> between the link's ends, as the mesh does).
   subroutine write_nodes_row(out, model, result, prefix)
      type(text_buffer_type), intent(inout) :: out
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      !> new_row_prefix of the result.
      type(row_prefix_type), intent(inout) :: prefix
      integer :: i, k, ip
      real(dp) :: xa(2), xb(2)
      call reserve_text(out, prefix_length + 2*size(result%pos, 2)*(real_width + 1) + 1)
      ! `step,t` without its last comma: each value brings its own.
      call append_prefix(out%text, out%n, prefix)
      out%n = out%n - 1
      ! Every node's x and y, in the order of result%pos (contiguous).
      call append_reals(out%text, out%n, result%pos, size(result%pos), prefix%numbers)
      if (model%output%mesh_nodes) then
         ip = 0
         do i = 1, size(model%links)
            associate (m => model%links(i)%nelem)
               call reserve_text(out, 2*(m - 1)*(real_width + 1))
               xa = result%pos(:, model%links(i)%node(1))
               xb = result%pos(:, model%links(i)%node(2))
               do k = 1, m - 1
                  ip = ip + 1
                  if (allocated(result%interior)) then
                     call append_values(out%text, out%n, result%interior(:, ip), prefix%numbers)
                  else
                     call append_values(out%text, out%n, xa + (xb - xa)*real(k, dp)/m, prefix%numbers)
                  end if
               end do
            end associate
         end do
      end if
      call append_char(out%text, out%n, new_line('a'))
   end subroutine write_nodes_row

   !> mechanism.txt's first records, planar and spatial alike: the header
   !> `record,fields`, the title, and the units when the deck has a units line.
   subroutine write_mechanism_head(unit, model)
      integer, intent(in) :: unit
      type(model_type), intent(in) :: model
      call emit(unit, 'record,fields')
      if (allocated(model%title)) call emit(unit, 'title,'//quoted(model%title))
      if (model%output%units_given) then
         call emit(unit, 'units,length,'//trim(model%output%length_unit))
         call emit(unit, 'units,time,'//trim(model%output%time_unit))
      end if
   end subroutine write_mechanism_head

   !> mechanism.txt's last record, planar and spatial alike: `track,NODE...`.
   subroutine write_track_record(unit, model)
      integer, intent(in) :: unit
      type(model_type), intent(in) :: model
      character(:), allocatable :: line
      integer :: i
      line = 'track'
      do i = 1, size(model%output%points)
         line = line//','//model%nodes(model%output%points(i))%name
      end do
      call emit(unit, line)
   end subroutine write_track_record

   !> mechanism.txt: what the plots need to draw the mechanism and label it,
   !> one record per line, the kind first: `title,TEXT`; `units,length,NAME`
   !> and `units,time,NAME`; `support,NODE,FIXED` (FIXED: the fixed
   !> freedoms among x, y, rotation, blank-separated); `guide,NAME,SLAVE,x1,y1,x2,y2`
   !> (a ground guide) or `slot,NAME,SLAVE,LINK...` (a slideline on links);
   !> `drive,x|y,NODE` or `drive,rotation,LINK,NODE`; `load,NODE,fx,fy,m`
   !> (at unit load factor, or the scale of its own law); `mass,NODE,m`;
   !> `track,NODE...`; `analysis,EFFECTS` (kinematics, kinetostatics, statics,
   !> dynamics, with the integrator's name and rho_inf for dynamics); `node,NAME,x,y`
   !> (its initial coordinates: the undeformed geometry). The units
   !> records only when the deck has a units line. To a unit open for
   !> unformatted stream access.
   subroutine write_mechanism_csv(unit, model)
      integer, intent(in) :: unit
      type(model_type), intent(in) :: model
      character(:), allocatable :: line
      integer :: i, j, effects
      call write_mechanism_head(unit, model)
      do i = 1, size(model%nodes)
         call emit(unit, 'node,'//model%nodes(i)%name//','//real_text(model%nodes(i)%x(1))//','// &
            & real_text(model%nodes(i)%x(2)))
      end do
      effects = planned_effects(model)
      if (effects == effects_dynamics) then
         call emit(unit, 'analysis,dynamics,'//trim(word_at(integrator_names, model%analysis%integrator))//','// &
            & real_text(model%analysis%rho_inf))
      else
         call emit(unit, 'analysis,'//effects_name(effects))
      end if
      if (allocated(model%supports)) then
         do i = 1, size(model%supports)
            associate (s => model%supports(i))
               line = trim(merge('x ', '  ', s%fix(dof_x)))//' '//trim(merge('y ', '  ', s%fix(dof_y)))//' '// &
                  & trim(merge('rotation', '        ', s%fix(dof_rot)))
               call emit(unit, 'support,'//model%nodes(s%node)%name//','//trim(adjustl(squeeze(line))))
            end associate
         end do
      end if
      if (allocated(model%slidelines)) then
         do i = 1, size(model%slidelines)
            associate (s => model%slidelines(i))
               if (s%ground) then
                  call emit(unit, 'guide,'//s%name//','//model%nodes(s%slave)%name//','//real_text(s%guide(1, 1))//','// &
                     & real_text(s%guide(2, 1))//','//real_text(s%guide(1, 2))//','//real_text(s%guide(2, 2)))
               else
                  line = 'slot,'//s%name//','//model%nodes(s%slave)%name
                  do j = 1, size(s%master_links)
                     line = line//','//model%links(s%master_links(j))%name
                  end do
                  call emit(unit, line)
               end if
            end associate
         end do
      end if
      if (allocated(model%drives)) then
         do i = 1, size(model%drives)
            associate (d => model%drives(i))
               select case (d%dof)
               case (dof_x)
                  call emit(unit, 'drive,x,'//model%nodes(d%node)%name)
               case (dof_y)
                  call emit(unit, 'drive,y,'//model%nodes(d%node)%name)
               case default
                  call emit(unit, 'drive,rotation,'//model%links(d%link)%name//','//model%nodes(d%node)%name)
               end select
            end associate
         end do
      end if
      if (allocated(model%loads)) then
         do i = 1, size(model%loads)
            associate (f => model%loads(i))
               call emit(unit, 'load,'//model%nodes(f%node)%name//','//real_text(f%force(1))//','// &
                  & real_text(f%force(2))//','//real_text(f%moment))
            end associate
         end do
      end if
      if (allocated(model%masses)) then
         do i = 1, size(model%masses)
            call emit(unit, 'mass,'//model%nodes(model%masses(i)%node)%name//','//real_text(model%masses(i)%mass))
         end do
      end if
      call write_track_record(unit, model)
   end subroutine write_mechanism_csv

   !> The k-th blank-separated word of a list of names (integrator_names, ...).
   pure function word_at(names, k) result(word)
      character(*), intent(in) :: names
      integer, intent(in) :: k
      character(:), allocatable :: word
      integer :: i, start, count
      start = 1
      count = 0
      word = ''
      do i = 1, len(names) + 1
         if (i > len(names)) then
            count = count + 1
            if (count == k) word = names(start:i - 1)
         else if (names(i:i) == ' ') then
            count = count + 1
            if (count == k) word = names(start:i - 1)
            start = i + 1
         end if
         if (count >= k) return
      end do
   end function word_at

   !> A CSV field in double quotes, its double quotes doubled.
   pure function quoted(text) result(field)
      character(*), intent(in) :: text
      character(:), allocatable :: field
      integer :: i, n
      ! Sized once: appending a character at a time copied the field each
      ! time, quadratic in the length of a long title.
      n = 0
      do i = 1, len(text)
         if (text(i:i) == '"') n = n + 1
      end do
      allocate (character(len=len(text) + n + 2) :: field)
      field(1:1) = '"'
      n = 1
      do i = 1, len(text)
         if (text(i:i) == '"') then
            field(n + 1:n + 2) = '""'
            n = n + 2
         else
            field(n + 1:n + 1) = text(i:i)
            n = n + 1
         end if
      end do
      field(n + 1:n + 1) = '"'
   end function quoted

   !> The text with runs of blanks made single blanks.
   pure function squeeze(text) result(out)
      character(*), intent(in) :: text
      character(:), allocatable :: out
      integer :: i
      out = ''
      do i = 1, len_trim(text)
         if (text(i:i) == ' ' .and. len(out) > 0) then
            if (out(len(out):len(out)) == ' ') cycle
         end if
         out = out//text(i:i)
      end do
   end function squeeze

   !> `step,t,kind,link,node,fx,fy,m` for every reaction row of a kinetostatics
   !> or statics step, in the order and with the labels of fekap_model_reactions:
   !> `drive` rows (the force or torque of each drive, in its component),
   !> `support` rows (each support's reactions, zero in a direction it leaves
   !> free), `slider` rows (the force, and the moment of a prismatic joint, that
   !> each sliding joint exerts on its slave), and `joint` rows, two per link
   !> (the force and moment the joint at each end exerts on the link). The force
   !> columns are empty at a step without reactions (a singular configuration).
   subroutine write_reactions_rows(out, model, result, prefix)
      type(text_buffer_type), intent(inout) :: out
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      type(row_prefix_type), intent(inout) :: prefix
      character(*), parameter :: kinds(4) = [character(len=7) :: 'drive', 'support', 'slider', 'joint']
      type(reaction_row_type), allocatable :: rows(:)
      integer :: row
      rows = reaction_rows(model)
      do row = 1, size(rows)
         associate (r => rows(row))
            if (r%link > 0) then
               call append_reaction(out, trim(kinds(r%kind)), model%links(r%link)%name, model%nodes(r%node)%name, row)
            else
               call append_reaction(out, trim(kinds(r%kind)), '', model%nodes(r%node)%name, row)
            end if
         end associate
      end do

   contains

      subroutine append_reaction(buffer, kind, link, node, irow)
         type(text_buffer_type), intent(inout) :: buffer
         character(*), intent(in) :: kind, link, node
         integer, intent(in) :: irow
         call reserve_text(buffer, row_chars(len(kind) + len(link) + len(node) + 2, 3))
         call append_text(buffer%text, buffer%n, prefix%text(1:prefix%n)//kind//','//link//','//node)
         if (result%has_reactions) then
            call append_values(buffer%text, buffer%n, result%reactions(:, irow), prefix%numbers)
         else
            call append_text(buffer%text, buffer%n, ',,,')
         end if
         call append_char(buffer%text, buffer%n, new_line('a'))
      end subroutine append_reaction

   end subroutine write_reactions_rows

   !> One row of energy.csv: the step's energies, work and momenta.
   subroutine write_energy_row(out, result, prefix)
      type(text_buffer_type), intent(inout) :: out
      type(step_result_type), intent(in) :: result
      type(row_prefix_type), intent(inout) :: prefix
      if (.not. result%has_energy) return
      call reserve_text(out, row_chars(0, size(result%energy)))
      call append_text(out%text, out%n, prefix%text(1:prefix%n - 1))
      call append_values(out%text, out%n, result%energy, prefix%numbers)
      call append_char(out%text, out%n, new_line('a'))
   end subroutine write_energy_row

   !> `step,t,node,ux,uy` for every node of a kinetostatics step: the elastic
   !> deflection of the loaded configuration from the kinematic one (empty at
   !> a step without it, a singular configuration).
   subroutine write_deflection_rows(out, model, result, prefix)
      type(text_buffer_type), intent(inout) :: out
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      type(row_prefix_type), intent(inout) :: prefix
      integer :: i
      do i = 1, size(model%nodes)
         call reserve_text(out, row_chars(len(model%nodes(i)%name), 2))
         call append_text(out%text, out%n, prefix%text(1:prefix%n)//model%nodes(i)%name)
         if (result%has_deflection) then
            call append_values(out%text, out%n, result%deflection(:, i), prefix%numbers)
         else
            call append_text(out%text, out%n, ',,')
         end if
         call append_char(out%text, out%n, new_line('a'))
      end do
   end subroutine write_deflection_rows

   !> `link,node1,node2`: the end points of every link, for drawing the
   !> mechanism; to a unit open for unformatted stream access.
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

   !> One line of text and its newline.
   subroutine emit(unit, text)
      integer, intent(in) :: unit
      character(*), intent(in) :: text
      write (unit) text, new_line('a')
   end subroutine emit

end module fekap_output_csv
