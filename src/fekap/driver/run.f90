!> The time loop: start the method, advance step by step, and hand each
!> accepted step to the output writers as soon as it is accepted, so that a
!> run that stops early keeps every completed step. The writers gather their
!> rows in memory and the loop flushes them when flush_interval has passed
!> since the last flush (on a coarse, cheap clock), and at every stop:
!> flushing the files after every step cost more than the analysis of a step
!> of Example 1 (docs/performance.md). The loop's time is measured whole and
!> split into analysis and output as in a sample of its steps. The loop names
!> no file: the writers are registered by fekap_driver_outputs.
module fekap_driver_run
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, analysis_error, fatal_error
   use fekap_stepping_interrupt, only: interrupt_signal
   use fekap_model, only: model_type, loc_file
   use fekap_model_drive_law, only: law_beyond
   use fekap_model_results, only: step_result_type, new_step_result, not_finite, result_kinds
   use fekap_stepping_stepper, only: stepper_type, clock_seconds, coarse_clock_seconds, split_seconds, split_timed
   use fekap_output_writer, only: writer_list_type, run_summary_type
   use fekap_strings, only: es_text
   implicit none
   private

   public :: run_analysis, step_count, step_time

   !> Wall-clock seconds between flushes of the output files during a run:
   !> a run killed by SIGKILL loses at most the rows of about this last
   !> stretch (those not yet handed to the system); every other stop
   !> flushes all rows.
   real(dp), parameter, public :: flush_interval = 0.1_dp

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

   !> Run the analysis with `stepper`, handing its steps to `writers`. On an
   !> analysis failure the listing says where and why, and the error names
   !> the step.
   subroutine run_analysis(stepper, model, writers, error)
      class(stepper_type), intent(inout) :: stepper
      type(model_type), intent(in) :: model
      type(writer_list_type), intent(inout) :: writers
      type(error_type), allocatable, intent(out) :: error
      type(step_result_type) :: result
      type(error_type), allocatable :: step_error
      type(run_summary_type) :: summary
      integer :: n, nsteps, last_step
      real(dp) :: start(2), sampled(2), c0, c1, c2, c_start, c_loop, last_flush, now
      character(len=100) :: where_
      logical :: timed

      nsteps = step_count(model)
      call new_step_result(result, size(model%nodes), size(model%links))
      start = 0
      sampled = 0
      c0 = 0
      c1 = 0
      c_start = clock_seconds()
      last_flush = coarse_clock_seconds()
      call writers%header(model)
      ! The headers (and the listing's echo of the model) reach the disk
      ! before the first step: a disk that fills during the run leaves every
      ! file with its header. A disk already full runs no step.
      last_step = nsteps
      call writers%flush(error, checkpoint=.false.)
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
         if (.not. allocated(step_error) .and. result%written) then
            call check_finite(model, result, step_error)
         end if
         if (allocated(step_error) .and. interrupt_signal() /= 0) then
            ! A signal stopped the step in progress (between Newton iterations).
            write (where_, '(a,i0,a,i0,a,a,a)') 'interrupted by signal ', interrupt_signal(), ' during step ', n, &
               & ' (t = ', es_text(step_time(model, n, nsteps), 12, 5), ')'
            call fatal_error(error, trim(where_)//'; the step was stopped, the rows of the completed steps are kept')
            exit
         end if
         if (allocated(step_error)) then
            ! A message that names its own time (where the step was cut) gives the only time.
            if (allocated(step_error%time)) then
               write (where_, '(a,i0,a)') 'step ', n, ':'
            else
               write (where_, '(a,i0,a,a,a)') 'step ', n, ' (t = ', es_text(step_time(model, n, nsteps), 12, 5), '):'
            end if
            call analysis_error(error, trim(where_)//' '//step_error%message)
            exit
         end if
         call writers%step(model, result, summary%rows, error)
         if (allocated(error)) exit
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
            call writers%flush(error)
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
      summary%seconds(1:2) = start + split_seconds(sampled, c0 - c_loop)
      call writers%finish(error)
      c1 = clock_seconds()
      summary%seconds(2) = summary%seconds(2) + (c1 - c0)
      summary%seconds(3) = c1 - c_start
      summary%counts = stepper%counts
      summary%step_files = writers%step_files()
      ! Whatever stopped the run is told in the listing before its summary.
      call writers%close(summary, error)
   end subroutine run_analysis

   !> Say after which step an output file failed.
   !> A step whose results hold a value that is not finite fails: its rows
   !> are not written (they would hold NaN), those of the steps before stay.
   !> Where a drive's law is beyond the deck's numbers at t (its value, rate
   !> or second rate above 1e100 or not finite: a polynomial of high degree
   !> over a long span), the error names that drive: the method was given
   !> it. Else the method failed without noticing.
   subroutine check_finite(model, result, error)
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      type(error_type), allocatable, intent(inout) :: error
      character(:), allocatable :: drive
      integer :: kind
      kind = not_finite(result)
      if (kind == 0) return
      drive = overflowing_drive(model, result%t)
      if (len(drive) > 0) then
         call analysis_error(error, 'the '//trim(result_kinds(kind))//' are not finite numbers (NaN or infinity): '// &
            & drive//' gives a value, rate or second rate beyond 1e100 at t = '//es_text(result%t, 12, 5)// &
            & ': change its law, or end the run before this time')
         return
      end if
      call analysis_error(error, 'the method returned '//trim(result_kinds(kind))//' that are not finite numbers '// &
         & '(NaN or infinity) without noticing its failure; please report the deck. A smaller time step or '// &
         & 'another method may avoid it')
   end subroutine check_finite

   !> The first drive whose law at t is beyond 1e100 (value, rate or second
   !> rate) or not finite: its deck line (planar) or its joint (spatial);
   !> '' if none.
   function overflowing_drive(model, t) result(text)
      type(model_type), intent(in) :: model
      real(dp), intent(in) :: t
      character(:), allocatable :: text
      character(len=24) :: where_
      integer :: i
      text = ''
      if (allocated(model%drives)) then
         do i = 1, size(model%drives)
            if (.not. law_beyond(model%drives(i)%law, t)) cycle
            associate (loc => model%drives(i)%loc)
               write (where_, '(i0,a,i0)') loc%line, ':', loc%col
               text = 'the drive at '//loc_file(model, loc)//':'//trim(where_)
            end associate
            return
         end do
      end if
      if (allocated(model%spatial%drives)) then
         do i = 1, size(model%spatial%drives)
            if (.not. law_beyond(model%spatial%drives(i)%law, t)) cycle
            text = 'the drive of joint '//model%spatial%joints(model%spatial%drives(i)%joint)%name
            return
         end do
      end if
   end function overflowing_drive

   subroutine tell_step(error, n, t)
      type(error_type), intent(inout) :: error
      integer, intent(in) :: n
      real(dp), intent(in) :: t
      character(len=100) :: where_
      write (where_, '(a,i0,a,a,a)') ' (after step ', n, ', t = ', es_text(t, 12, 5), &
         & '); the files hold whole rows of the steps written before'
      error%message = error%message//trim(where_)
   end subroutine tell_step

end module fekap_driver_run
