!> fekap: read a deck, run the analysis it asks for, write the results.
!> The only place that prints errors and sets the exit code.
program fekap_main
   use, intrinsic :: iso_c_binding, only: c_int
   use, intrinsic :: iso_fortran_env, only: error_unit, output_unit, int64
   use fekap_error, only: error_type, error_input, error_analysis, error_output, fatal_error, input_error
   use fekap_model, only: model_type, method_fem, method_cartesian, effects_kinetostatics, effects_statics, &
      & effects_dynamics, effects_kinematics
   use fekap_deck, only: read_deck
   use fekap_model_effects, only: check_effects_request, planned_effects
   use fekap_reactions_reaction_stepper, only: reaction_stepper_type, new_reaction_stepper
   use fekap_dynamics_free_motion, only: check_free_motion
   use fekap_fem_determinacy, only: check_determined
   use fekap_dynamics_dynamic_stepper, only: dynamic_stepper_type, new_dynamic_stepper, energy_names
   use fekap_stepping_stepper, only: stepper_type
   use fekap_fem, only: fem_stepper_type, new_fem_stepper
   use fekap_spatial_stepper, only: spatial_stepper_type, new_spatial_stepper
   use fekap_classical, only: angles_stepper_type, new_angles_stepper, cartesian_stepper_type, &
      & new_cartesian_stepper
   use fekap_stepping_interrupt, only: catch_interrupts, interrupt_signal, interrupt_reads
   use fekap_driver_run, only: run_units_type, run_analysis, step_count, no_unit, open_replace
   use fekap_output_csv, only: write_mesh_csv, write_mechanism_csv
   use fekap_strings, only: es_text
   use fekap_output_directory, only: prepare_output_directory, make_directory, output_plan_type, add_run_file
   use fekap_output_checked_file, only: close_checked
   use fekap_posix, only: os_ignore_sigpipe
   use fekap_output_listing, only: write_listing_model, write_listing_plan, plan_text
   use fekap_app_cli, only: cli_type, parse_command_line, apply_overrides, usage_text, fekap_version
   implicit none

   interface
      !> C's exit: a status code that is a variable (F2008 `stop` takes constants only).
      subroutine c_exit(status) bind(C, name='exit')
         import :: c_int
         implicit none
         integer(c_int), value :: status
      end subroutine c_exit
   end interface

   type(cli_type) :: cli
   type(model_type) :: model
   type(error_type), allocatable :: error
   class(stepper_type), allocatable :: stepper
   type(run_units_type) :: units
   character(:), allocatable :: mesh_text

   ! A closed standard output (`fekap ... | head -1`) is not a failed
   ! analysis: its writes fail quietly instead of killing the run.
   call os_ignore_sigpipe()
   ! From the start: a signal while the deck is read or the model is set up
   ! ends the run with exit 1 and a message, before any file is written.
   call catch_interrupts()
   call parse_command_line(cli, error)
   if (allocated(error)) call finish(error)
   if (cli%help) then
      call say(usage_text())
      call c_exit(0_c_int)
   end if
   if (cli%version) then
      call say('fekap '//fekap_version)
      call c_exit(0_c_int)
   end if
   if (cli%print_outdir) then
      call say(cli%outdir)
      call c_exit(0_c_int)
   end if

   call interrupt_reads(.true.)
   call read_deck(model, cli%deck, error, cli%sets)
   call interrupt_reads(.false.)
   call stop_if_interrupted(cli%deck, 'while the deck was read')
   if (allocated(error)) call finish(error)
   call apply_overrides(cli, model, error)
   if (allocated(error)) call finish(error)
   if (allocated(cli%note) .and. .not. cli%quiet) call say(cli%note)
   call check_effects_request(model, error)
   if (allocated(error)) call finish(error)
   ! Without a mesh line, nodes.csv holds the meshed links' interior points
   ! where their bending is the result: statics and dynamics.
   if (.not. model%output%mesh_nodes_given) model%output%mesh_nodes = any(model%links%nelem > 1) .and. &
      & any(planned_effects(model) == [effects_statics, effects_dynamics])

   call make_stepper(model, stepper, error)
   if (allocated(error)) call finish(error)
   call stop_if_interrupted(cli%deck, 'while the model was set up')
   mesh_text = stepper%plan_text()
   call open_outputs(cli%outdir, cli%deck, cli%force, model, units, error)
   if (allocated(error)) then
      if (error%kind == error_output) error%message = 'fekap: '//error%message
      call finish(error)
   end if
   if (units%listing /= no_unit) then
      call write_listing_model(units%listing, model, fekap_version)
      call write_listing_plan(units%listing, model, step_count(model), mesh_text)
   end if
   if (.not. cli%quiet) call say('fekap: '//cli%deck//': '//plan_text(model, step_count(model)))

   call run_analysis(stepper, model, units, error)
   if (allocated(error)) then
      error%message = cli%deck//': '//without_drive_advice(model, error%message)
      if (.not. cli%quiet) call say('fekap: results of the completed steps are in '//cli%outdir//'/')
      call finish(error)
   end if
   if (.not. cli%quiet) call say('fekap: results in '//cli%outdir//'/')
   call c_exit(0_c_int)

contains

   !> A line to standard output; a closed output is ignored.
   subroutine say(text)
      character(*), intent(in) :: text
      integer :: ios
      ! Nothing more to say to a closed output: the run goes on.
      write (output_unit, '(a)', iostat=ios) text
      if (ios /= 0) return
      flush (output_unit, iostat=ios)
      if (ios /= 0) return
   end subroutine say

   !> The stepper of the deck's method.
   subroutine make_stepper(model, stepper, error)
      type(model_type), intent(in) :: model
      class(stepper_type), allocatable, intent(out) :: stepper
      type(error_type), allocatable, intent(out) :: error
      type(fem_stepper_type), allocatable :: fem
      type(reaction_stepper_type), allocatable :: reactions
      type(dynamic_stepper_type), allocatable :: dynamic
      type(cartesian_stepper_type), allocatable :: cartesian
      type(angles_stepper_type), allocatable :: angles
      type(spatial_stepper_type), allocatable :: spatial
      integer :: effects
      effects = planned_effects(model)
      if (model%analysis%spatial) then
         ! A spatial deck (kinematics only): joints as double nodes, SE(3) beams (docs/spatial.md).
         if (model%analysis%method /= method_fem) then
            call input_error(error, model%file//': a spatial deck runs with the finite element method only: '// &
               & 'leave out --method and the ANALysis method line')
            return
         end if
         allocate (spatial)
         call new_spatial_stepper(spatial, model, error)
         if (allocated(error)) return
         call move_alloc(spatial, stepper)
         return
      end if
      select case (model%analysis%method)
      case (method_fem)
         allocate (fem)
         call new_fem_stepper(fem, model)
         ! Dynamics moves a free part by its mass (check_free_motion below);
         ! the other analyses need every motion held.
         if (effects /= effects_dynamics) then
            call check_determined(fem%mesh, model, error)
            if (allocated(error)) return
         end if
         if (any(effects == [effects_kinetostatics, effects_statics])) then
            allocate (reactions)
            call new_reaction_stepper(reactions, fem, effects)
            call move_alloc(reactions, stepper)
         else if (effects == effects_dynamics) then
            ! Bad input first: a free motion with neither mass nor stiffness.
            call check_free_motion(fem%mesh, model, fem%mesh%q0, model%analysis%t_start, fem%seg, error)
            if (allocated(error)) return
            allocate (dynamic)
            call new_dynamic_stepper(dynamic, model)
            call move_alloc(dynamic, stepper)
         else
            call move_alloc(fem, stepper)
         end if
      case (method_cartesian)
         allocate (cartesian)
         call new_cartesian_stepper(cartesian, model, error)
         if (allocated(error)) then
            error%message = model%file//': '//error%message
            return
         end if
         call move_alloc(cartesian, stepper)
      case default
         allocate (angles)
         call new_angles_stepper(angles, model, error)
         if (allocated(error)) then
            error%message = model%file//': '//error%message
            return
         end if
         call move_alloc(angles, stepper)
      end select
   end subroutine make_stepper

   !> Create and lock the output directory, clear it of an earlier run's
   !> files, and open the files the deck asks for.
   subroutine open_outputs(outdir, deck, force, model, units, error)
      character(*), intent(in) :: outdir, deck
      !> Replace files of FEKAP's names that no earlier run recorded (--force).
      logical, intent(in) :: force
      type(model_type), intent(in) :: model
      type(run_units_type), intent(out) :: units
      type(error_type), allocatable, intent(out) :: error
      integer :: mesh_unit, effects
      character(:), allocatable :: stem
      type(output_plan_type) :: plan
      effects = planned_effects(model)
      stem = deck(index(deck, '/', back=.true.) + 1:)
      if (index(stem, '.', back=.true.) > 1) stem = stem(:index(stem, '.', back=.true.) - 1)
      ! The files opened below, for the directory's manifest.
      plan%deck = deck
      plan%stem = stem
      plan%force = force
      if (model%output%csv) then
         call add_run_file(plan, 'points.csv')
         ! A spatial run reports its joints' motion (joints.csv), not planar link angles.
         if (.not. model%analysis%spatial) call add_run_file(plan, 'links.csv')
         if (model%analysis%spatial) call add_run_file(plan, 'joints.csv')
         call add_run_file(plan, 'steps.csv')
         call add_run_file(plan, 'nodes.csv')
         call add_run_file(plan, 'mesh.csv')
         if (effects /= effects_kinematics) call add_run_file(plan, 'reactions.csv')
         if (effects == effects_kinetostatics .and. model%output%deflection) call add_run_file(plan, 'deflection.csv')
         if (effects == effects_dynamics) call add_run_file(plan, 'energy.csv')
         call add_run_file(plan, 'mechanism.txt')
      end if
      if (model%output%listing) call add_run_file(plan, stem//'.lis')
      if (model%output%vtk) then
         call add_run_file(plan, stem//'.pvd')
         call add_run_file(plan, stem//'.pvd.fekap-tmp')
         call add_run_file(plan, 'vtk/'//stem//'_*.vtu')
      end if
      call prepare_output_directory(outdir, plan, error)
      if (allocated(error)) return
      if (model%output%csv) then
         call open_replace(outdir//'/points.csv', units%points, error, stream=.true.)
         if (.not. allocated(error) .and. .not. model%analysis%spatial) then
            call open_replace(outdir//'/links.csv', units%links, error, stream=.true.)
         end if
         if (.not. allocated(error) .and. model%analysis%spatial) then
            call open_replace(outdir//'/joints.csv', units%joints, error, stream=.true.)
         end if
         if (.not. allocated(error)) call open_replace(outdir//'/steps.csv', units%steps, error, stream=.true.)
         if (.not. allocated(error)) call open_replace(outdir//'/nodes.csv', units%nodes, error, stream=.true.)
         if (.not. allocated(error)) call open_replace(outdir//'/mesh.csv', mesh_unit, error, stream=.true.)
         if (.not. allocated(error) .and. effects /= effects_kinematics) then
            call open_replace(outdir//'/reactions.csv', units%reactions, error, stream=.true.)
         end if
         if (.not. allocated(error) .and. effects == effects_kinetostatics .and. &
            & model%output%deflection) then
            call open_replace(outdir//'/deflection.csv', units%deflection, error, stream=.true.)
         end if
         if (.not. allocated(error) .and. effects == effects_dynamics) then
            call open_replace(outdir//'/energy.csv', units%energy, error, stream=.true.)
            units%energy_names = energy_names
         end if
         if (allocated(error)) return
         call write_mesh_csv(mesh_unit, model)
         call close_checked(mesh_unit, -1_int64, error)
         if (allocated(error)) return
         call open_replace(outdir//'/mechanism.txt', mesh_unit, error, stream=.true.)
         if (allocated(error)) return
         call write_mechanism_csv(mesh_unit, model)
         call close_checked(mesh_unit, -1_int64, error)
         if (allocated(error)) return
      end if
      ! Formatted stream: the run writes the listing's step lines many at a time.
      if (model%output%listing) call open_replace(outdir//'/'//stem//'.lis', units%listing, error, stream=.true., &
         & formatted=.true.)
      if (allocated(error)) return
      if (model%output%vtk) then
         call make_directory(outdir//'/vtk', error)
         if (allocated(error)) return
         units%vtk = .true.
         units%outdir = outdir
         units%stem = stem
      end if
   end subroutine open_outputs


   !> The step control's advice on a failure is about a drive's dead point;
   !> a run without drives (statics: the loads grow with time) has none, and
   !> its failure is a limit of the load.
   function without_drive_advice(model, message) result(text)
      type(model_type), intent(in) :: model
      character(*), intent(in) :: message
      character(:), allocatable :: text
      character(*), parameter :: drive_advice = ' of the time step: the mechanism cannot follow its drive'
      integer :: k, drives
      text = message
      drives = 0
      if (allocated(model%drives)) drives = size(model%drives)
      k = index(message, drive_advice)
      if (drives > 0 .or. k == 0) return
      text = message(:k - 1)//' of the time step: the structure cannot carry its loads past this point '// &
         & '(a limit load, where it buckles or snaps through, or a part left free to move); a smaller time '// &
         & 'step will not help: lower the loads, or support the structure where it gives way)'
   end function without_drive_advice

   !> Stop with exit 1 and a message when a signal came before the run's
   !> files were opened (`when` says during what).
   subroutine stop_if_interrupted(deck, when)
      character(*), intent(in) :: deck, when
      type(error_type), allocatable :: error
      character(len=12) :: number
      if (interrupt_signal() == 0) return
      write (number, '(i0)') interrupt_signal()
      call fatal_error(error, 'fekap: '//deck//': interrupted by signal '//trim(number)//' '//when// &
         & '; nothing was run or written')
      call finish(error)
   end subroutine stop_if_interrupted

   !> Print the error and exit with the code of its kind.
   subroutine finish(error)
      type(error_type), intent(in) :: error
      integer :: ios
      ! A closed standard error loses the message, not the exit code.
      write (error_unit, '(a)', iostat=ios) error%message
      if (ios /= 0) continue
      select case (error%kind)
      case (error_input)
         call c_exit(2_c_int)
      case (error_analysis)
         call c_exit(3_c_int)
      case (error_output)
         call c_exit(4_c_int)
      case default
         call c_exit(1_c_int)
      end select
   end subroutine finish

end program fekap_main
