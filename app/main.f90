!> fekap: read a deck, run the analysis it asks for, write the results.
!> Printing and the exit code are fekap_app_report's; the rest is FEKAP's
!> (the module fekap).
program fekap_main
   use, intrinsic :: iso_c_binding, only: c_int
   use fekap, only: error_type, error_output, model_type, read_deck, stepper_type, settle_model, make_stepper, &
      & writer_list_type, open_outputs, run_analysis, step_count, plan_text, catch_interrupts, interrupt_reads, &
      & os_ignore_write_signals, spatial_from_planar
   use fekap_app_cli, only: cli_type, parse_command_line, apply_overrides, usage_text, fekap_version
   use fekap_app_report, only: say, finish, stop_if_interrupted, c_exit
   implicit none

   type(cli_type) :: cli
   type(model_type) :: model
   type(error_type), allocatable :: error
   class(stepper_type), allocatable :: stepper
   type(writer_list_type) :: writers

   ! A closed standard output (`fekap ... | head -1`) is not a failed
   ! analysis: its writes fail quietly instead of killing the run; a write
   ! past the file-size limit fails as on a full disk (exit 4).
   call os_ignore_write_signals()
   ! From the start: a signal while the deck is read or the model is set up
   ! ends the run with exit 1 and a message, before any file is written.
   call catch_interrupts()
   call parse_command_line(cli, error)
   if (allocated(error)) call finish(error)
   if (cli%help) call say_and_exit(usage_text())
   if (cli%version) call say_and_exit('fekap '//fekap_version)
   if (cli%print_outdir) call say_and_exit(cli%outdir)

   call interrupt_reads(.true.)
   call read_deck(model, cli%deck, error, cli%sets)
   call interrupt_reads(.false.)
   call stop_if_interrupted(cli%deck, 'while the deck was read')
   if (allocated(error)) call finish(error)
   call apply_overrides(cli, model, error)
   if (allocated(error)) call finish(error)
   if (allocated(cli%note) .and. .not. cli%quiet) call say(cli%note)
   call settle_model(model, error)
   if (allocated(error)) call finish(error)
   if (cli%spatial) then
      call spatial_from_planar(model, error)
      if (allocated(error)) call finish(error)
   end if

   call make_stepper(model, stepper, error)
   if (allocated(error)) call finish(error)
   call stop_if_interrupted(cli%deck, 'while the model was set up')
   call open_outputs(cli%outdir, cli%deck, cli%force, model, fekap_version, stepper%plan_text(), writers, error)
   if (allocated(error)) then
      if (error%kind == error_output) error%message = 'fekap: '//error%message
      call finish(error)
   end if
   if (.not. cli%quiet) call say('fekap: '//cli%deck//': '//plan_text(model, step_count(model)))

   call run_analysis(stepper, model, writers, error)
   if (allocated(error)) then
      error%message = cli%deck//': '//error%message
      if (.not. cli%quiet) call say('fekap: results of the completed steps are in '//cli%outdir//'/')
      call finish(error)
   end if
   if (.not. cli%quiet) call say('fekap: results in '//cli%outdir//'/')
   call c_exit(0_c_int)

contains

   !> Say `text` and exit 0 (--help, --version, --print-outdir).
   subroutine say_and_exit(text)
      character(*), intent(in) :: text
      call say(text)
      call c_exit(0_c_int)
   end subroutine say_and_exit

end program fekap_main
