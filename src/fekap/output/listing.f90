!> The human-readable listing (<stem>.lis): the model echoed, the plan of
!> the run, one line per step, and a closing summary of the work done.
module fekap_output_listing
   use fekap_kinds, only: dp
   use fekap_model, only: model_type, dof_x, dof_y, dof_rot, method_fem, method_cartesian, &
      & predictor_previous, predictor_extrapolate, convergence_paper, joint_prismatic
   use fekap_model_results, only: step_result_type
   use fekap_model_spatial, only: joint_names, joint_revolute, joint_universal, spatial_prismatic => joint_prismatic, &
      & joint_cylindrical
   use fekap_model_drive_law, only: law_type, law_rate, law_harmonic, law_polynomial, law_table
   use fekap_model_effects, only: effects_plan_type, plan_effects, effects_name
   use fekap_model_work, only: work_counts_type, phase_seconds
   use fekap_output_format, only: append_es, append_i, append_integer, append_text
   use fekap_output_buffer, only: text_buffer_type, reserve_text
   use fekap_strings, only: es_text, int_text
   implicit none
   private

   public :: write_listing_model, write_listing_plan, write_listing_step_header, write_listing_step
   public :: write_listing_note
   public :: write_listing_summary, write_listing_stop, plan_text

   real(dp), parameter :: rad2deg = 180/acos(-1.0_dp)

contains

   !> Title and the model: nodes, sections, links, joints, supports, drives, loads, slidelines.
   subroutine write_listing_model(unit, model, version)
      integer, intent(in) :: unit
      type(model_type), intent(in) :: model
      character(*), intent(in) :: version
      integer :: i, j
      real(dp) :: d(2)
      write (unit, '(a)') 'FEKAP '//version//' - Finite Element Kinematic Analysis Program'
      write (unit, '(a)') 'deck:  '//model%file
      if (allocated(model%title)) write (unit, '(a)') 'title: '//model%title
      if (model%output%units_given) then
         write (unit, '(a)') 'units: length '//trim(model%output%length_unit)//', time '//trim(model%output%time_unit)
      else
         write (unit, '(a)') 'units: none given (OUTPut units length=NAME time=NAME): the numbers are used as '// &
            & 'given, the plots label lengths "length" and times "time"'
      end if
      if (allocated(model%parameters)) call write_parameters(unit, model)
      if (model%analysis%spatial) then
         call write_spatial_model(unit, model)
         return
      end if
      write (unit, '(/,a)') 'NODES'
      write (unit, '(2x,a12,2a24)') 'name', 'x', 'y'
      do i = 1, size(model%nodes)
         write (unit, '(2x,a12,2a)') model%nodes(i)%name, fast_es_text(model%nodes(i)%x(1), 24, 15), &
            & fast_es_text(model%nodes(i)%x(2), 24, 15)
      end do
      write (unit, '(/,a)') 'SECTIONS'
      write (unit, '(2x,a12,3a16)') 'name', 'EA', 'kGA', 'EI'
      do i = 1, size(model%sections)
         write (unit, '(2x,a12,3a)') model%sections(i)%name, fast_es_text(model%sections(i)%ea, 16, 7), &
            & fast_es_text(model%sections(i)%kga, 16, 7), fast_es_text(model%sections(i)%ei, 16, 7)
      end do
      write (unit, '(/,a)') 'LINKS'
      write (unit, '(2x,a12,2a8,a12,a9,2a20)') 'name', 'first', 'second', 'section', 'elements', 'length', &
         & 'angle (deg)'
      do i = 1, size(model%links)
         associate (l => model%links(i))
            d = model%nodes(l%node(2))%x - model%nodes(l%node(1))%x
            write (unit, '(2x,a12,2a8,a12,i9,2a)') l%name, model%nodes(l%node(1))%name, &
               & model%nodes(l%node(2))%name, model%sections(l%section)%name, l%nelem, fast_es_text(norm2(d), 20, 11), &
               & fast_es_text(atan2(d(2), d(1))*rad2deg, 20, 11)
         end associate
      end do
      if (allocated(model%welds)) then
         if (size(model%welds) > 0) write (unit, '(/,a)') 'WELDS (links rigidly joined; elsewhere links are hinged)'
         do i = 1, size(model%welds)
            write (unit, '(2x,a)', advance='no') 'at '//model%nodes(model%welds(i)%node)%name//':'
            do j = 1, size(model%welds(i)%links)
               write (unit, '(1x,a)', advance='no') model%links(model%welds(i)%links(j))%name
            end do
            write (unit, '(a)') ''
         end do
      end if
      if (allocated(model%supports)) then
         write (unit, '(/,a)') 'SUPPORTS'
         do i = 1, size(model%supports)
            associate (s => model%supports(i))
               write (unit, '(2x,a12,a)') model%nodes(s%node)%name, trim(merge(' x  ', '    ', s%fix(dof_x)))// &
                  & trim(merge(' y  ', '    ', s%fix(dof_y)))//merge(' rotation', '         ', s%fix(dof_rot))
            end associate
         end do
      end if
      if (allocated(model%drives)) then
         write (unit, '(/,a)') 'DRIVES'
         do i = 1, size(model%drives)
            associate (dr => model%drives(i))
               select case (dr%dof)
               case (dof_x)
                  write (unit, '(2x,a)') 'x of node '//model%nodes(dr%node)%name//': '//law_text(dr%law, 'x')
               case (dof_y)
                  write (unit, '(2x,a)') 'y of node '//model%nodes(dr%node)%name//': '//law_text(dr%law, 'y')
               case default
                  write (unit, '(2x,a)') 'angle of link '//model%links(dr%link)%name//' at node '// &
                     & model%nodes(dr%node)%name//': '//law_text(dr%law, 'angle')
               end select
            end associate
         end do
      end if
      if (allocated(model%loads)) then
         if (size(model%loads) > 0) write (unit, '(/,a)') 'LOADS (times the load factor t)'
         do i = 1, size(model%loads)
            write (unit, '(2x,a12,3a)') model%nodes(model%loads(i)%node)%name, fast_es_text(model%loads(i)%force(1), 16, 7), &
               & fast_es_text(model%loads(i)%force(2), 16, 7), fast_es_text(model%loads(i)%moment, 16, 7)
         end do
      end if
      if (allocated(model%slidelines)) then
         if (size(model%slidelines) > 0) write (unit, '(/,a)') 'SLIDELINES'
         do i = 1, size(model%slidelines)
            associate (s => model%slidelines(i))
               if (s%ground) then
                  write (unit, '(2x,a)') s%name//': node '//model%nodes(s%slave)%name//' on the ground guide from ('// &
                     & short_text(s%guide(1, 1))//', '//short_text(s%guide(2, 1))//') to ('//short_text(s%guide(1, 2))// &
                     & ', '//short_text(s%guide(2, 2))//'), '//trim(merge('prismatic  ', 'pin-in-slot', &
                     & s%kind == joint_prismatic))
               else
                  write (unit, '(2x,a)') s%name//': node '//model%nodes(s%slave)%name//' on '// &
                     & trim(master_text(model, s%master_links))//', '// &
                     & trim(merge('prismatic  ', 'pin-in-slot', s%kind == joint_prismatic))
               end if
            end associate
         end do
      end if
      call write_listing_inertia(unit, model)
   end subroutine write_listing_model

   !> A spatial model (ANALysis `type kinematics spatial`, or a planar deck
   !> run with --spatial): nodes with z, the 3D sections with their
   !> orientation vectors, links as beams or trusses with their 3D lengths,
   !> the joints with their kinds, nodes and axes, and the drives.
   subroutine write_spatial_model(unit, model)
      integer, intent(in) :: unit
      type(model_type), intent(in) :: model
      character(*), parameter :: c_names(6) = [character(len=3) :: 'EA', 'GA2', 'GA3', 'GJ', 'EI2', 'EI3']
      real(dp) :: d(3)
      integer :: i, k
      character(:), allocatable :: line, second
      associate (sp => model%spatial)
         write (unit, '(/,a)') 'NODES'
         write (unit, '(2x,a12,3a24)') 'name', 'x', 'y', 'z'
         do i = 1, size(model%nodes)
            write (unit, '(2x,a12,3a)') model%nodes(i)%name, fast_es_text(model%nodes(i)%x(1), 24, 15), &
               & fast_es_text(model%nodes(i)%x(2), 24, 15), fast_es_text(sp%z(i), 24, 15)
         end do
         write (unit, '(/,a)') 'SECTIONS (the orientation vector v gives axis 2; 0 0 0: not given)'
         write (unit, '(2x,a12,6a16,2x,a)') 'name', (trim(c_names(k)), k=1, 6), 'v'
         do i = 1, size(model%sections)
            line = ''
            do k = 1, 6
               if (sp%sections(i)%given(k) .or. .not. any(sp%sections(i)%given)) then
                  line = line//fast_es_text(sp%sections(i)%c(k), 16, 7)
               else
                  line = line//repeat(' ', 15)//'-'
               end if
            end do
            write (unit, '(2x,a12,a,2x,a)') model%sections(i)%name, line, short_text(sp%sections(i)%orientation(1))// &
               & ' '//short_text(sp%sections(i)%orientation(2))//' '//short_text(sp%sections(i)%orientation(3))
         end do
         write (unit, '(/,a)') 'LINKS'
         write (unit, '(2x,a12,2a8,a12,a9,a7,a20)') 'name', 'first', 'second', 'section', 'elements', 'kind', 'length'
         do i = 1, size(model%links)
            associate (l => model%links(i))
               d = [model%nodes(l%node(2))%x - model%nodes(l%node(1))%x, sp%z(l%node(2)) - sp%z(l%node(1))]
               write (unit, '(2x,a12,2a8,a12,i9,a7,a)') l%name, model%nodes(l%node(1))%name, &
                  & model%nodes(l%node(2))%name, model%sections(l%section)%name, l%nelem, &
                  & trim(merge('truss', ' beam', sp%truss(i))), fast_es_text(norm2(d), 20, 11)
            end associate
         end do
         if (allocated(sp%joints)) then
            write (unit, '(/,a)') 'JOINTS (axes in global coordinates)'
            write (unit, '(2x,a12,a12,2a8,2x,a)') 'name', 'kind', 'first', 'second', 'axes'
            do i = 1, size(sp%joints)
               associate (j => sp%joints(i))
                  second = 'ground'
                  if (j%node(2) > 0) second = model%nodes(j%node(2))%name
                  line = ''
                  select case (j%kind)
                  case (joint_revolute, spatial_prismatic, joint_cylindrical)
                     line = vector_text(j%axis)
                  case (joint_universal)
                     line = vector_text(j%axis)//', '//vector_text(j%axis2)
                  end select
                  if (len(line) > 0) line = '  '//line
                  if (j%ground_first) then
                     write (unit, '(2x,a12,a12,2a8,a)') j%name, kind_name(j%kind), second, &
                        & model%nodes(j%node(1))%name, line
                  else
                     write (unit, '(2x,a12,a12,2a8,a)') j%name, kind_name(j%kind), model%nodes(j%node(1))%name, &
                        & second, line
                  end if
               end associate
            end do
         end if
         if (allocated(sp%drives)) then
            write (unit, '(/,a)') 'DRIVES'
            do i = 1, size(sp%drives)
               associate (dr => sp%drives(i))
                  if (dr%stroke) then
                     write (unit, '(2x,a)') 'stroke of joint '//sp%joints(dr%joint)%name//': '//law_text(dr%law, 'stroke')
                  else
                     write (unit, '(2x,a)') 'angle of joint '//sp%joints(dr%joint)%name//': '//law_text(dr%law, 'angle')
                  end if
               end associate
            end do
         end if
      end associate
   contains
      !> The deck's name of a joint kind (joint_names, the kind-th word).
      function kind_name(kind) result(name)
         integer, intent(in) :: kind
         character(:), allocatable :: name
         integer :: first, k
         first = 1
         do k = 1, kind - 1
            first = first + index(joint_names(first:), ' ')
         end do
         name = joint_names(first:)
         if (index(name, ' ') > 0) name = name(:index(name, ' ') - 1)
      end function kind_name

      function vector_text(v) result(text)
         real(dp), intent(in) :: v(3)
         character(:), allocatable :: text
         text = short_text(v(1))//' '//short_text(v(2))//' '//short_text(v(3))
      end function vector_text
   end subroutine write_spatial_model

   !> es_text(x, width, decimals), the same characters: esW.D from
   !> fekap_output_format's exact digits (append_es) where that writes an E
   !> (an exponent of two digits), es_text itself otherwise (a third exponent
   !> digit, asterisks, not a number). The model's echo writes numbers per
   !> node and link, and es_text's formatted internal writes made it the
   !> largest part of setting up a large model.
   function fast_es_text(x, width, decimals) result(text)
      real(dp), intent(in) :: x
      integer, intent(in) :: width, decimals
      character(:), allocatable :: text
      character(len=64) :: line
      integer :: n
      n = 0
      call append_es(line, n, x, width, decimals, 0)
      text = line(1:n)
      if (index(text, 'E') == 0) text = es_text(x, width, decimals)
   end function fast_es_text

   !> The time law of a drive as a formula in t, e.g. `angle = angle0 + 6.28...*t`.
   function law_text(law, what) result(text)
      type(law_type), intent(in) :: law
      character(*), intent(in) :: what
      character(:), allocatable :: text
      integer :: k
      select case (law%kind)
      case (law_rate)
         if (law%absolute) then
            text = what//' = '//short_text(law%c(2))//' + '//short_text(law%c(1))//'*t'
         else
            text = what//' = (initial '//what//') + '//short_text(law%c(1))//'*t'
         end if
      case (law_harmonic)
         text = what//' = '//short_text(law%c(1))//' + '//short_text(law%c(2))//'*cos('//short_text(law%c(3))// &
            & '*t + '//short_text(law%c(4))//')'
      case (law_polynomial)
         text = what//' = '//short_text(law%c(1))
         do k = 2, size(law%c)
            if (k == 2) then
               text = text//' + '//short_text(law%c(k))//'*t'
            else
               text = text//' + '//short_text(law%c(k))//'*t^'//int_text(k - 1)
            end if
         end do
      case (law_table)
         text = what//' from a table of '//int_text(size(law%tt))//' points, t = '//short_text(law%tt(1))// &
            & ' to '//short_text(law%tt(size(law%tt)))//' (natural cubic spline)'
      case default
         text = what
      end select
   end function law_text

   !> The master links of a slideline: `link O4B` or `links L1 L2 ...`.
   function master_text(model, links) result(text)
      type(model_type), intent(in) :: model
      integer, intent(in) :: links(:)
      character(:), allocatable :: text
      integer :: j
      text = trim(merge('link ', 'links', size(links) == 1))
      do j = 1, size(links)
         text = text//' '//model%links(links(j))%name
      end do
   end function master_text

   !> A real in at most 9 significant digits, without blanks (listing text).
   pure function short_text(x) result(text)
      real(dp), intent(in) :: x
      character(:), allocatable :: text
      character(len=32) :: buf
      integer :: k
      write (buf, '(g0.9)') x
      text = trim(adjustl(buf))
      if (index(text, '.') == 0 .or. scan(text, 'Ee') > 0) return
      k = len(text)
      do while (text(k:k) == '0')
         k = k - 1
      end do
      if (text(k:k) == '.') k = k - 1
      text = text(:k)
   end function short_text

   !> The sections' densities, the point masses and gravity, when given.
   subroutine write_listing_inertia(unit, model)
      integer, intent(in) :: unit
      type(model_type), intent(in) :: model
      integer :: i
      if (any(model%sections%rho_a > 0)) then
         write (unit, '(/,a)') 'SECTION MASSES'
         write (unit, '(2x,a12,2a16)') 'name', 'rhoA', 'rhoI'
         do i = 1, size(model%sections)
            if (model%sections(i)%rho_a > 0) write (unit, '(2x,a12,2es16.7)') model%sections(i)%name, &
               & model%sections(i)%rho_a, model%sections(i)%rho_i
         end do
      end if
      if (allocated(model%masses)) then
         if (size(model%masses) > 0) then
            write (unit, '(/,a)') 'MASSES (m moves with the node, J turns with the link end)'
            write (unit, '(2x,a12,2a16,2x,a)') 'node', 'm', 'J', 'link'
         end if
         do i = 1, size(model%masses)
            associate (m => model%masses(i))
               if (m%link > 0) then
                  write (unit, '(2x,a12,2es16.7,2x,a)') model%nodes(m%node)%name, m%mass, m%inertia, &
                     & model%links(m%link)%name
               else
                  write (unit, '(2x,a12,2es16.7)') model%nodes(m%node)%name, m%mass, m%inertia
               end if
            end associate
         end do
      end if
      if (any(model%gravity /= 0)) write (unit, '(/,a,2es16.7)') 'GRAVITY', model%gravity
   end subroutine write_listing_inertia

   !> The deck parameters and the values this run used.
   subroutine write_parameters(unit, model)
      integer, intent(in) :: unit
      type(model_type), intent(in) :: model
      integer :: i, width
      character(len=32) :: form
      if (size(model%parameters) == 0) return
      width = max(12, maxval([(len(model%parameters(i)%name), i=1, size(model%parameters))]))
      write (form, '(a,i0,a)') '(2x,a', width, ',es24.15,a)'
      write (unit, '(/,a)') 'PARAMETERS'
      do i = 1, size(model%parameters)
         associate (p => model%parameters(i))
            write (unit, form) p%name, p%value, trim(merge('  (--set)', '         ', p%set_on_command_line))
         end associate
      end do
   end subroutine write_parameters

   !> One line saying what the run computes, e.g. "computing positions and
   !> velocities; 40 steps; output every 10th step".
   function plan_text(model, nsteps) result(text)
      type(model_type), intent(in) :: model
      integer, intent(in) :: nsteps
      character(:), allocatable :: text
      character(len=32) :: num
      text = 'method '//trim(merge('fem      ', 'cartesian', model%analysis%method == method_fem))
      if (model%analysis%method /= method_fem .and. model%analysis%method /= method_cartesian) text = 'method angles'
      if (model%analysis%spatial) text = 'method fem, spatial'
      if (model%analysis%velocities .and. model%analysis%accelerations) then
         text = text//'; computing positions, velocities and accelerations'
      else if (model%analysis%velocities) then
         text = text//'; computing positions and velocities'
      else
         text = text//'; computing positions'
      end if
      if (allocated(model%slidelines)) then
         write (num, '(i0)') size(model%slidelines)
         if (size(model%slidelines) > 0) text = text//'; '//trim(num)//' slideline'// &
            & trim(merge('s', ' ', size(model%slidelines) > 1))
      end if
      write (num, '(i0)') nsteps
      text = text//'; '//trim(num)//' steps'
      if (model%output%every > 1) then
         write (num, '(i0)') model%output%every
         text = text//'; output every '//trim(num)//trim(ordinal(model%output%every))//' step'
      end if
   end function plan_text

   pure function ordinal(n) result(suffix)
      integer, intent(in) :: n
      character(len=2) :: suffix
      suffix = 'th'
      if (mod(n/10, 10) == 1) return
      select case (mod(n, 10))
      case (1)
         suffix = 'st'
      case (2)
         suffix = 'nd'
      case (3)
         suffix = 'rd'
      end select
   end function ordinal

   !> The plan and the settings of the analysis.
   subroutine write_listing_plan(unit, model, nsteps, mesh_text)
      integer, intent(in) :: unit
      type(model_type), intent(in) :: model
      integer, intent(in) :: nsteps
      character(*), intent(in) :: mesh_text
      character(len=16) :: pred
      type(effects_plan_type) :: effects
      write (unit, '(/,a)') 'PLAN'
      write (unit, '(2x,a)') plan_text(model, nsteps)
      effects = plan_effects(model)
      write (unit, '(2x,a)') 'effects: '//effects_name(effects%effects)//' ('//effects%why//')'
      if (len(effects%left_out) > 0) write (unit, '(2x,a)') effects%left_out
      if (len(mesh_text) > 0) write (unit, '(2x,a)') mesh_text
      select case (model%analysis%predictor)
      case (predictor_previous)
         pred = 'previous'
      case (predictor_extrapolate)
         pred = 'extrapolate'
      case default
         pred = 'taylor'
      end select
      ! es_text: 1e300 keeps its E (es12.5 writes 1.00000+300).
      write (unit, '(2x,a)') 'time from '//es_text(model%analysis%t_start, 12, 5)//' to '// &
         & es_text(model%analysis%t_end, 12, 5)//' step '//es_text(model%analysis%dt, 12, 5)
      if (model%analysis%spatial) then
         ! The spatial stepper's own settings (fekap_spatial_stepper).
         write (unit, '(2x,a,a,a,i0,a)') 'Newton: length ', es_text(model%analysis%length_tol, 9, 2), &
            & ' x longest element (the rates from an iterate within 1e-14 of it), at most ', &
            & model%analysis%max_iter, ' iterations'
         write (unit, '(2x,a)') 'predictor: Taylor series with the rates of the last three accelerations'
         return
      end if
      write (unit, '(2x,a,a,a,i0,a)') 'Newton: tolerance '//es_text(model%analysis%tol, 9, 2)//', length ', &
         & es_text(model%analysis%length_tol, 9, 2), ' x model size, at most ', model%analysis%max_iter, ' iterations'
      write (unit, '(2x,a)') 'predictor '//trim(pred)//', convergence test '// &
         & trim(merge('paper  ', 'default', model%analysis%convergence == convergence_paper))
   end subroutine write_listing_plan

   subroutine write_listing_step_header(unit)
      integer, intent(in) :: unit
      write (unit, '(/,a)') 'STEPS'
      write (unit, '(a8,a20,a12,a16,a6)') 'step', 't', 'iterations', 'residual', 'cuts'
   end subroutine write_listing_step_header

   !> The step's line, to the listing's text buffer.
   subroutine write_listing_step(out, result)
      type(text_buffer_type), intent(inout) :: out
      type(step_result_type), intent(in) :: result
      ! As the format (i8,es20.11,i12,es16.6,i6), without its cost.
      call reserve_text(out, 63)
      call append_i(out%text, out%n, result%step, 8)
      call append_es(out%text, out%n, result%t, 20, 11, 0)
      call append_i(out%text, out%n, result%iterations, 12)
      call append_es(out%text, out%n, result%residual, 16, 6, 0)
      call append_i(out%text, out%n, result%cuts, 6)
      ! The line's end stored here: append_text's copy of a length known
      ! only at run time is a call of memcpy.
      out%text(out%n + 1:out%n + 1) = new_line('a')
      out%n = out%n + 1
   end subroutine write_listing_step

   !> A note on step `step` (a near-singular configuration, step cuts), after
   !> its line, to the listing's text buffer.
   subroutine write_listing_note(out, step, note)
      type(text_buffer_type), intent(inout) :: out
      integer, intent(in) :: step
      character(*), intent(in) :: note
      call reserve_text(out, len(note) + 36)
      call append_text(out%text, out%n, repeat(' ', 10)//'note: step ')
      call append_integer(out%text, out%n, step)
      call append_text(out%text, out%n, ', ')
      call append_text(out%text, out%n, note)
      call append_text(out%text, out%n, new_line('a'))
   end subroutine write_listing_note

   !> Closing summary: counts of the work done and time per phase (the
   !> phases timed on a sample of the steps, scaled to the analysis time).
   subroutine write_listing_summary(unit, counts, rows, seconds, vtk_files)
      integer, intent(in) :: unit
      type(work_counts_type), intent(in) :: counts
      integer, intent(in) :: rows
      !> Time in analysis, output and total.
      real(dp), intent(in) :: seconds(3)
      !> Number of VTK step files written, when VTK output was asked for.
      integer, intent(in), optional :: vtk_files
      real(dp) :: phases(3)
      write (unit, '(/,a)') 'SUMMARY'
      write (unit, '(2x,a30,i12)') 'configurations solved', counts%steps
      write (unit, '(2x,a30,i12)') 'Newton iterations', counts%iterations
      if (counts%steps > 0) write (unit, '(2x,a30,f12.3)') 'iterations per configuration', &
         & real(counts%iterations, dp)/counts%steps
      ! Every method's steps whose residual stayed above the tolerance at round-off (steps.csv's floor column).
      if (counts%floor_steps > 0) write (unit, '(2x,a30,i12)') 'accepted at round-off floor', counts%floor_steps
      ! Dynamics: the largest local error estimate (steps.csv's error_estimate column) and where.
      if (counts%largest_estimate >= 0) write (unit, '(2x,a30,a,a,a,a,a)') 'largest local error estimate', &
         & es_text(counts%largest_estimate, 12, 3), ' at t = ', trim(adjustl(es_text(counts%largest_estimate_t, 12, 5))), ', ', &
         & trim(counts%largest_estimate_where)
      if (counts%rejected_steps > 0) write (unit, '(2x,a30,i12)') 'adaptive steps rejected', counts%rejected_steps
      write (unit, '(2x,a30,i12)') 'residual assemblies', counts%residual_assemblies
      write (unit, '(2x,a30,i12)') 'tangent assemblies', counts%tangent_assemblies
      write (unit, '(2x,a30,i12)') 'Cholesky factorisations', counts%cholesky_factorisations
      write (unit, '(2x,a30,i12)') 'LU factorisations (fallback)', counts%lu_factorisations
      ! The square-root form's (FEM): B_f's LU, and its condition estimates at the predictors.
      if (counts%root_factorisations > 0) then
         write (unit, '(2x,a30,i12)') 'LU factorisations of B_f', counts%root_factorisations
         write (unit, '(2x,a30,i12)') 'predictor condition estimates', counts%condition_estimates
      end if
      write (unit, '(2x,a30,i12)') 'velocity solves', counts%velocity_solves
      write (unit, '(2x,a30,i12)') 'acceleration solves', counts%acceleration_solves
      write (unit, '(2x,a30,i12)') 'slideline evaluations', counts%slideline_evaluations
      write (unit, '(2x,a30,a)') 'smallest pivot ratio', es_text(counts%min_pivot_ratio, 12, 3)
      write (unit, '(2x,a30,i12)') 'rows written', rows
      if (present(vtk_files)) write (unit, '(2x,a30,i12)') 'VTK files written', vtk_files
      phases = phase_seconds(counts, seconds(1))
      write (unit, '(2x,a30,f12.4)') 'time in analysis (s)', seconds(1)
      write (unit, '(2x,a30,f12.4)') '  of which assembly (s)', phases(1)
      write (unit, '(2x,a30,f12.4)') '  of which factorisation (s)', phases(2)
      write (unit, '(2x,a30,f12.4)') '  of which solves (s)', phases(3)
      write (unit, '(2x,a30,f12.4)') 'time in output (s)', seconds(2)
      write (unit, '(2x,a30,f12.4)') 'total time (s)', seconds(3)
   end subroutine write_listing_summary

   !> Why the run stopped early.
   subroutine write_listing_stop(unit, message)
      integer, intent(in) :: unit
      character(*), intent(in) :: message
      write (unit, '(/,a)') 'RUN STOPPED'
      write (unit, '(2x,a)') message
      write (unit, '(2x,a)') 'The rows written so far are valid results of the completed steps.'
   end subroutine write_listing_stop

end module fekap_output_listing
