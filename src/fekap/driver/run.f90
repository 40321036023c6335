!> The time loop: start the method, advance step by step, and write each
!> step's rows as soon as it is accepted, so that a run that stops early
!> keeps every completed step. The rows are gathered in memory and the files
!> flushed when flush_interval has passed since the last flush (on a coarse,
!> cheap clock), and at every stop: flushing the four files after every step
!> cost about 2.3 us a step (docs/performance.md), more than the 2 us the
!> analysis of a step aims at. The loop's time is measured whole and split
!> into analysis and output as in a sample of its steps.
module fekap_driver_run
   use fekap_kinds, only: dp
   use, intrinsic :: iso_fortran_env, only: int64
   use fekap_error, only: error_type, analysis_error, fatal_error, output_error
   use fekap_stepping_interrupt, only: interrupt_signal
   use fekap_model, only: model_type
   use fekap_model_results, only: step_result_type, new_step_result, fill_fields_from_nodes, has_note
   use fekap_stepping_stepper, only: stepper_type, clock_seconds, coarse_clock_seconds, split_seconds, split_timed
   use fekap_output_csv, only: write_points_header, write_points_rows, write_links_header, write_links_rows, &
      & write_header, steps_header, dynamics_steps_header, reactions_header, deflection_header, write_steps_row, &
      & row_prefix_type, &
      & new_row_prefix, write_nodes_header, write_nodes_row, write_reactions_rows, write_energy_row, write_deflection_rows
   use fekap_output_spatial_csv, only: write_spatial_points_header, write_spatial_points_rows, &
      & write_joints_header, write_joints_rows
   use fekap_output_listing, only: write_listing_step_header, write_listing_step, write_listing_summary, &
      & write_listing_stop, write_listing_note
   use fekap_output_vtk, only: write_vtu
   use fekap_output_pvd, only: pvd_type, add_pvd_entry, pvd_due, write_pvd_text
   use fekap_output_buffer, only: text_buffer_type, new_text_buffer, flush_text_buffer
   use fekap_strings, only: es_text
   use fekap_output_checked_file, only: close_checked, replace_checked
   use fekap_posix, only: os_unlink
   implicit none
   private

   public :: run_units_type, run_analysis, step_count, step_time, open_replace

   !> A unit that is not written (newunit numbers are negative, so not -1).
   integer, parameter, public :: no_unit = -huge(1)

   !> Wall-clock seconds between flushes of the output files during a run:
   !> a run killed by SIGKILL loses at most the rows of about this last
   !> stretch (those not yet handed to the system); every other stop
   !> flushes all rows.
   real(dp), parameter, public :: flush_interval = 0.1_dp

   !> Added to a file's name while it is written whole before replacing the
   !> file (removed at the start of a run with the other files of FEKAP).
   character(*), parameter, public :: temporary_suffix = '.fekap-tmp'

   !> Open units of the output files; no_unit for a file that is not written.
   !> The CSV files are open for unformatted stream access, the listing for
   !> formatted stream access (see open_replace).
   !> VTK output is many files, opened by the loop: with `vtk`, each written
   !> step goes to `<outdir>/vtk/<stem>_<step>.vtu` (the directory must exist)
   !> and the collection `<outdir>/<stem>.pvd` is rewritten at the flushes
   !> when it has grown enough (fekap_output_pvd) and at the end.
   type :: run_units_type
      integer :: points = no_unit
      integer :: links = no_unit
      integer :: steps = no_unit
      !> nodes.csv: every node's position at the written steps.
      integer :: nodes = no_unit
      integer :: listing = no_unit
      !> reactions.csv, written by kinetostatics and dynamics runs only.
      integer :: reactions = no_unit
      !> energy.csv, written by dynamics runs only, with its columns after step,t.
      integer :: energy = no_unit
      character(:), allocatable :: energy_names
      !> deflection.csv, written by kinetostatics runs with OUTPut deflection on.
      integer :: deflection = no_unit
      !> joints.csv, written by spatial runs only.
      integer :: joints = no_unit
      logical :: vtk = .false.
      !> The output directory and the deck's stem, for the VTK file names.
      character(:), allocatable :: outdir, stem
   end type run_units_type

   !> What the loop keeps between VTK steps.
   type :: vtk_state_type
      !> The fields come from the model's nodes and links (a method without a mesh).
      logical :: from_nodes = .false.
      !> (2, nlink): end nodes of each link, for from_nodes.
      integer, allocatable :: links_nodes(:, :)
      !> (2, npoint): point positions at the first step.
      real(dp), allocatable :: initial_pos(:, :)
      !> The collection of the files written so far.
      type(pvd_type) :: pvd
   end type vtk_state_type

   !> The text of the files written step by step, held between flushes.
   type :: run_buffers_type
      type(text_buffer_type) :: points, links, steps, nodes, listing, reactions, energy, deflection, joints
   end type run_buffers_type

contains

   !> Number of steps from t_start to t_end: dt divides the interval, or the
   !> last step is shortened to end exactly at t_end.
   pure integer function step_count(model) result(n)
      type(model_type), intent(in) :: model
      real(dp) :: span
      span = model%analysis%t_end - model%analysis%t_start
      n = nint(span/model%analysis%dt)
      if (abs(n*model%analysis%dt - span) > 1.0e-9_dp*model%analysis%dt) n = ceiling(span/model%analysis%dt)
      n = max(n, 1)
   end function step_count

   !> Time of step n (not accumulated, so no drift over long runs).
   pure real(dp) function step_time(model, n, nsteps) result(t)
      type(model_type), intent(in) :: model
      integer, intent(in) :: n, nsteps
      if (n >= nsteps) then
         t = model%analysis%t_end
      else
         t = model%analysis%t_start + n*model%analysis%dt
      end if
   end function step_time

   !> Run the analysis with `stepper`, writing to `units`. On an analysis
   !> failure the listing says where and why, and the error names the step.
   subroutine run_analysis(stepper, model, units, error)
      class(stepper_type), intent(inout) :: stepper
      type(model_type), intent(in) :: model
      type(run_units_type), intent(in) :: units
      type(error_type), allocatable, intent(out) :: error
      type(step_result_type) :: result
      type(error_type), allocatable :: step_error, write_error, retry_error
      type(vtk_state_type) :: vtk
      type(run_buffers_type) :: out
      type(row_prefix_type) :: prefix
      integer :: n, nsteps, rows, l, last_step, dropped
      real(dp) :: seconds(3), start(2), sampled(2), c0, c1, c2, c_start, c_loop, last_flush, now
      character(len=100) :: where_
      logical :: vel, acc, timed

      vel = model%analysis%velocities
      acc = vel .and. model%analysis%accelerations
      nsteps = step_count(model)
      call new_step_result(result, size(model%nodes), size(model%links))
      seconds = 0
      start = 0
      sampled = 0
      c0 = 0
      c1 = 0
      rows = 0
      c_start = clock_seconds()
      last_flush = coarse_clock_seconds()
      call new_run_buffers(units, out)
      if (units%points /= no_unit .and. model%analysis%spatial) then
         call write_spatial_points_header(out%points, vel, acc)
      else if (units%points /= no_unit) then
         call write_points_header(out%points, vel, acc)
      end if
      if (units%joints /= no_unit) call write_joints_header(out%joints, vel, acc)
      if (units%links /= no_unit) call write_links_header(out%links, vel, acc)
      if (units%steps /= no_unit .and. units%energy /= no_unit) then
         call write_header(out%steps, dynamics_steps_header)
      else if (units%steps /= no_unit) then
         call write_header(out%steps, steps_header)
      end if
      if (units%nodes /= no_unit) call write_nodes_header(out%nodes, model)
      if (units%reactions /= no_unit) call write_header(out%reactions, reactions_header)
      if (units%energy /= no_unit) call write_header(out%energy, 'step,t,'//units%energy_names)
      if (units%deflection /= no_unit) call write_header(out%deflection, deflection_header)
      if (units%listing /= no_unit) call write_listing_step_header(units%listing)
      if (units%vtk) then
         allocate (vtk%links_nodes(2, size(model%links)))
         do l = 1, size(model%links)
            vtk%links_nodes(:, l) = model%links(l)%node
         end do
      end if
      ! The headers (and the listing's echo of the model) reach the disk
      ! before the first step: a disk that fills during the run leaves every
      ! file with its header. A disk already full runs no step.
      last_step = nsteps
      call flush_all(units, out, error)
      if (allocated(error)) last_step = -1

      ! The start is timed whole; the time of the steps after it is split into
      ! analysis and output as on a sample of them (see split_timed). The
      ! sample is uniform: the first steps, with their short predictors, are
      ! no more typical of a run than the start.
      c_loop = clock_seconds()
      do n = 0, last_step
         timed = n == 0 .or. split_timed(n, nsteps)
         if (timed) c0 = clock_seconds()
         result%step = n
         result%cuts = 0
         result%written = n == 0 .or. n == nsteps .or. mod(n, model%output%every) == 0
         if (n == 0) then
            call stepper%start(result, step_error)
         else
            call stepper%advance(step_time(model, n, nsteps), result, step_error)
         end if
         if (timed) c1 = clock_seconds()
         if (allocated(step_error) .and. interrupt_signal() /= 0) then
            ! A signal stopped the step in progress (between Newton iterations).
            write (where_, '(a,i0,a,i0,a,a,a)') 'interrupted by signal ', interrupt_signal(), ' during step ', n, &
               & ' (t = ', es_text(step_time(model, n, nsteps), 12, 5), ')'
            call fatal_error(error, trim(where_)//'; the step was stopped, the rows of the completed steps are kept')
            exit
         end if
         if (allocated(step_error)) then
            ! A message that names its own time (where the step was cut) gives the only time.
            if (index(step_error%message, 't = ') == 1) then
               write (where_, '(a,i0,a)') 'step ', n, ':'
            else
               write (where_, '(a,i0,a,a,a)') 'step ', n, ' (t = ', es_text(step_time(model, n, nsteps), 12, 5), '):'
            end if
            call analysis_error(error, trim(where_)//' '//step_error%message)
            exit
         end if
         if (units%vtk) then
            ! A method that fills no mesh fields at its start fills none later.
            if (n == 0) vtk%from_nodes = .not. allocated(result%mesh_pos)
            if (vtk%from_nodes) call fill_fields_from_nodes(result, vtk%links_nodes)
            if (n == 0) vtk%initial_pos = result%mesh_pos
         end if
         if (result%written) then
            if (units%points /= no_unit .or. units%links /= no_unit .or. units%steps /= no_unit .or. &
               & units%nodes /= no_unit .or. units%reactions /= no_unit .or. units%energy /= no_unit .or. &
               & units%deflection /= no_unit .or. units%joints /= no_unit) then
               call new_row_prefix(prefix, result)
            end if
            if (units%points /= no_unit .and. model%analysis%spatial) then
               call write_spatial_points_rows(out%points, model, result, prefix%text(1:prefix%n), vel, acc)
               rows = rows + size(model%output%points)
            else if (units%points /= no_unit) then
               call write_points_rows(out%points, model, result, prefix, vel, acc)
               rows = rows + size(model%output%points)
            end if
            if (units%joints /= no_unit) then
               call write_joints_rows(out%joints, model, result, prefix%text(1:prefix%n), vel, acc)
               rows = rows + size(result%joint_motion, 2)
            end if
            if (units%links /= no_unit) then
               call write_links_rows(out%links, model, result, prefix, vel, acc)
               rows = rows + size(model%output%links)
            end if
            if (units%steps /= no_unit) then
               call write_steps_row(out%steps, result, prefix)
               rows = rows + 1
            end if
            if (units%nodes /= no_unit) call write_nodes_row(out%nodes, model, result, prefix)
            if (units%reactions /= no_unit) then
               call write_reactions_rows(out%reactions, model, result, prefix)
               rows = rows + size(result%reactions, 2)
            end if
            if (units%energy /= no_unit) then
               call write_energy_row(out%energy, result, prefix)
               rows = rows + 1
            end if
            if (units%deflection /= no_unit) then
               call write_deflection_rows(out%deflection, model, result, prefix)
               rows = rows + size(model%nodes)
            end if
            if (units%listing /= no_unit) call write_listing_step(out%listing, result)
            if (units%vtk) then
               call write_vtk_step(units, model, result, vtk, error)
               if (allocated(error)) exit
            end if
         end if
         if (units%listing /= no_unit) then
            if (has_note(result%note)) call write_listing_note(out%listing, n, trim(result%note))
         end if
         ! Before the flush: a signal that comes once this step's rows are on
         ! disk stops the next step (or comes after it), never this one.
         if (interrupt_signal() /= 0 .and. n < nsteps) then
            write (where_, '(a,i0,a,i0,a,a,a)') 'interrupted by signal ', interrupt_signal(), ' after step ', n, &
               & ' (t = ', es_text(result%t, 12, 5), ')'
            call fatal_error(error, trim(where_)//'; the rows of the completed steps are kept')
            exit
         end if
         now = coarse_clock_seconds()
         if (now - last_flush >= flush_interval) then
            call flush_all(units, out, error)
            if (.not. allocated(error) .and. units%vtk) then
               if (pvd_due(vtk%pvd)) call write_pvd(units, vtk, error)
            end if
            if (allocated(error)) then
               call tell_step(error, n, result%t)
               exit
            end if
            last_flush = now
         end if
         if (timed) then
            c2 = clock_seconds()
            if (n == 0) then
               start = [c1 - c0, c2 - c1]
               c_loop = c2
            else
               sampled = sampled + [c1 - c0, c2 - c1]
            end if
         end if
      end do
      ! Every way out of the loop comes here (the last step, an analysis
      ! failure, a VTK file that cannot be written, a signal): the rows of
      ! every completed step reach the files, before the listing's summary.
      c0 = clock_seconds()
      seconds(1:2) = start + split_seconds(sampled, c0 - c_loop)
      call flush_all(units, out, write_error)
      if (allocated(write_error)) call add_error(error, write_error)
      if (units%vtk .and. vtk%pvd%entries > vtk%pvd%written) then
         ! The whole collection, however the run ended.
         call write_pvd(units, vtk, write_error)
         ! A full disk: the newest step files make room for the collection
         ! of the others, so that no .vtu is left without its .pvd.
         dropped = 0
         if (allocated(write_error)) then
            do while (vtk%pvd%entries > 0)
               call drop_last_step_file(units, vtk)
               dropped = dropped + 1
               call write_pvd(units, vtk, retry_error)
               if (.not. allocated(retry_error)) exit
               deallocate (retry_error)
            end do
            if (.not. allocated(retry_error)) then
               write (where_, '(a,i0,a)') ' (the newest ', dropped, ' .vtu files were removed to make room for it)'
               write_error%message = write_error%message//trim(where_)
            end if
            call add_error(error, write_error)
         end if
      end if
      c1 = clock_seconds()
      seconds(2) = seconds(2) + (c1 - c0)
      seconds(3) = c1 - c_start
      ! A listing that could not be written is left as cut back by its flush.
      if (units%listing /= no_unit .and. .not. out%listing%failed) then
         ! Whatever stopped the run (analysis failure, VTK file, signal, an
         ! output file that cannot be written) is told before the summary.
         if (allocated(error)) call write_listing_stop(units%listing, error%message)
         if (units%vtk) then
            call write_listing_summary(units%listing, stepper%counts, rows, seconds, vtk_files=vtk%pvd%entries)
         else
            call write_listing_summary(units%listing, stepper%counts, rows, seconds)
         end if
         call close_checked(units%listing, out%listing%verified, write_error)
         if (allocated(write_error)) call add_error(error, write_error)
      end if
   end subroutine run_analysis

   !> Say after which step an output file failed.
   subroutine tell_step(error, n, t)
      type(error_type), intent(inout) :: error
      integer, intent(in) :: n
      real(dp), intent(in) :: t
      character(len=100) :: where_
      write (where_, '(a,i0,a,a,a)') ' (after step ', n, ', t = ', es_text(t, 12, 5), &
         & '); the files hold whole rows of the steps written before'
      error%message = error%message//trim(where_)
   end subroutine tell_step

   !> Keep the first error of a run and add a later one's message to it; an
   !> output error after a completed run is the run's error.
   subroutine add_error(error, later)
      type(error_type), allocatable, intent(inout) :: error
      type(error_type), allocatable, intent(inout) :: later
      if (allocated(error)) then
         error%message = error%message//new_line('a')//later%message
      else
         call move_alloc(later, error)
      end if
   end subroutine add_error

   !> Write the step's .vtu file and add it to the collection (written by
   !> write_pvd at the flushes when it has grown enough, and at the end).
   subroutine write_vtk_step(units, model, result, vtk, error)
      type(run_units_type), intent(in) :: units
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      type(vtk_state_type), intent(inout) :: vtk
      type(error_type), allocatable, intent(out) :: error
      integer :: unit
      call open_replace(units%outdir//'/'//vtu_name(units%stem, result%step), unit, error, stream=.true., &
         & formatted=.true.)
      if (allocated(error)) return
      call write_vtu(unit, model, result, vtk%initial_pos)
      ! A .vtu that did not fit is removed, not left cut.
      call close_checked(unit, -1_int64, error)
      if (allocated(error)) return
      call add_pvd_entry(vtk%pvd, result%t, vtu_name(units%stem, result%step))
   end subroutine write_vtk_step

   !> Write the .pvd collection as it is: whole, to a temporary name, then
   !> renamed over the old one (a reader never sees part of it).
   subroutine write_pvd(units, vtk, error)
      type(run_units_type), intent(in) :: units
      type(vtk_state_type), intent(inout) :: vtk
      type(error_type), allocatable, intent(out) :: error
      integer :: unit
      call open_replace(units%outdir//'/'//units%stem//'.pvd'//temporary_suffix, unit, error, stream=.true., &
         & formatted=.true.)
      if (allocated(error)) return
      call write_pvd_text(unit, vtk%pvd)
      call replace_checked(unit, units%outdir//'/'//units%stem//'.pvd'//temporary_suffix, &
         & units%outdir//'/'//units%stem//'.pvd', error)
      if (.not. allocated(error)) vtk%pvd%written = vtk%pvd%entries
   end subroutine write_pvd

   !> Remove the newest step file of the collection and its entry (to make
   !> room for the .pvd on a full disk).
   subroutine drop_last_step_file(units, vtk)
      type(run_units_type), intent(in) :: units
      type(vtk_state_type), intent(inout) :: vtk
      integer :: start, first, last, code
      associate (p => vtk%pvd)
         start = index(p%text(1:p%n - 1), new_line('a'), back=.true.) + 1
         first = index(p%text(start:p%n), 'file="') + start + 5
         last = first + index(p%text(first:p%n), '"') - 2
         code = os_unlink(units%outdir//'/'//p%text(first:last))
         p%n = start - 1
         p%entries = p%entries - 1
         p%written = min(p%written, p%entries)
      end associate
   end subroutine drop_last_step_file

   !> `vtk/<stem>_<step, at least 6 digits>.vtu`, relative to the output directory.
   pure function vtu_name(stem, step) result(name)
      character(*), intent(in) :: stem
      integer, intent(in) :: step
      character(:), allocatable :: name
      character(len=12) :: number
      write (number, '(i0.6)') step
      name = 'vtk/'//stem//'_'//trim(number)//'.vtu'
   end function vtu_name

   !> Open a file for writing, replacing it (no_unit and an error if it cannot
   !> be written); formatted sequential, or with `stream` for stream access:
   !> unformatted (the CSV files, written as bytes), or formatted with
   !> `formatted` (the listing: formatted writes, and text of many lines
   !> written at once, each newline ending a record).
   subroutine open_replace(path, unit, error, stream, formatted)
      character(*), intent(in) :: path
      integer, intent(out) :: unit
      type(error_type), allocatable, intent(out) :: error
      logical, intent(in), optional :: stream, formatted
      integer :: ios
      character(len=512) :: message
      logical :: as_stream, as_formatted
      as_stream = .false.
      if (present(stream)) as_stream = stream
      as_formatted = .false.
      if (present(formatted)) as_formatted = formatted
      if (as_stream .and. as_formatted) then
         open (newunit=unit, file=path, status='replace', action='write', access='stream', &
            & form='formatted', iostat=ios, iomsg=message)
      else if (as_stream) then
         open (newunit=unit, file=path, status='replace', action='write', access='stream', &
            & form='unformatted', iostat=ios, iomsg=message)
      else
         open (newunit=unit, file=path, status='replace', action='write', iostat=ios, iomsg=message)
      end if
      if (ios /= 0) then
         unit = no_unit
         call output_error(error, path//': cannot write this file: '//trim(message))
      end if
   end subroutine open_replace

   !> Buffers for the files of `units` that are written.
   subroutine new_run_buffers(units, out)
      type(run_units_type), intent(in) :: units
      type(run_buffers_type), intent(out) :: out
      if (units%points /= no_unit) call new_text_buffer(out%points, units%points, formatted=.false.)
      if (units%links /= no_unit) call new_text_buffer(out%links, units%links, formatted=.false.)
      if (units%steps /= no_unit) call new_text_buffer(out%steps, units%steps, formatted=.false.)
      if (units%nodes /= no_unit) call new_text_buffer(out%nodes, units%nodes, formatted=.false.)
      if (units%reactions /= no_unit) call new_text_buffer(out%reactions, units%reactions, formatted=.false.)
      if (units%energy /= no_unit) call new_text_buffer(out%energy, units%energy, formatted=.false.)
      if (units%deflection /= no_unit) call new_text_buffer(out%deflection, units%deflection, formatted=.false.)
      if (units%joints /= no_unit) call new_text_buffer(out%joints, units%joints, formatted=.false.)
      if (units%listing /= no_unit) call new_text_buffer(out%listing, units%listing, formatted=.true.)
   end subroutine new_run_buffers

   !> Write the held rows and flush every file: what is written so far is on
   !> disk, checked. A file that cannot be written is cut back to whole rows
   !> and not written again; the others are still flushed (nothing is left in
   !> a unit's buffer for the exit to write unchecked). The error is the
   !> first file's.
   subroutine flush_all(units, out, error)
      type(run_units_type), intent(in) :: units
      type(run_buffers_type), intent(inout) :: out
      type(error_type), allocatable, intent(out) :: error
      if (units%points /= no_unit) call flush_one(out%points)
      if (units%links /= no_unit) call flush_one(out%links)
      if (units%steps /= no_unit) call flush_one(out%steps)
      if (units%nodes /= no_unit) call flush_one(out%nodes)
      if (units%reactions /= no_unit) call flush_one(out%reactions)
      if (units%energy /= no_unit) call flush_one(out%energy)
      if (units%deflection /= no_unit) call flush_one(out%deflection)
      if (units%joints /= no_unit) call flush_one(out%joints)
      if (units%listing /= no_unit) call flush_one(out%listing)
   contains
      subroutine flush_one(buffer)
         type(text_buffer_type), intent(inout) :: buffer
         type(error_type), allocatable :: failure
         call flush_text_buffer(buffer, failure)
         if (allocated(failure) .and. .not. allocated(error)) call move_alloc(failure, error)
      end subroutine flush_one
   end subroutine flush_all

end module fekap_driver_run
