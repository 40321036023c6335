!> The output files of a run: which ones the deck asks for (register_outputs,
!> the one list of them), the output directory prepared for them (its
!> manifest names them before any is written), each opened and its writer
!> registered, and mesh.csv and mechanism.txt, which are written whole at
!> the start. To add an output file: a writer (fekap_output_*_writer) and
!> one line in register_outputs.
module fekap_driver_outputs
   use, intrinsic :: iso_fortran_env, only: int64
   use fekap_error, only: error_type
   use fekap_model, only: model_type, effects_kinematics, effects_kinetostatics, effects_dynamics
   use fekap_model_effects, only: planned_effects
   use fekap_dynamics_dynamic_stepper, only: energy_names
   use fekap_output_writer, only: writer_type, writer_list_type, move_writers
   use fekap_output_spatial_writers, only: spatial_points_writer, joints_writer, spatial_nodes_writer
   use fekap_output_table_writers, only: table_writer_type, points_writer, links_writer, steps_writer, nodes_writer, &
      & reactions_writer, energy_writer, deflection_writer
   use fekap_output_listing_writer, only: listing_writer
   use fekap_output_vtk_writer, only: vtk_writer
   use fekap_output_csv, only: write_mesh_csv, write_mechanism_csv
   use fekap_output_spatial_csv, only: write_spatial_mechanism
   use fekap_output_directory, only: prepare_output_directory, make_directory, output_plan_type, add_run_file, &
      & temporary_suffix
   use fekap_output_checked_file, only: open_replace, close_checked
   use fekap_driver_run, only: step_count
   implicit none
   private

   public :: open_outputs

   !> Where register_outputs' lines go: on the first pass the files are only
   !> named, for the directory's manifest; on the second each is opened (in
   !> the order of the lines) and its writer added to the list. After an
   !> error the lines do nothing.
   type :: registry_type
      logical :: planning = .true.
      character(:), allocatable :: outdir
      type(output_plan_type) :: plan
      type(writer_list_type) :: writers
      type(error_type), allocatable :: error
   contains
      !> A file written row by row through a table writer's buffer.
      procedure :: table => registry_table
      !> A file written whole at the start by `emit`.
      procedure :: whole => registry_whole
      !> Files that a writer opens itself, one a step (`names`: the files and
      !> patterns of the manifest) in a directory of its own.
      procedure :: step_files => registry_step_files
   end type registry_type

   abstract interface
      !> Writes a whole file to a unit open for unformatted stream access.
      subroutine whole_interface(unit, model)
         import :: model_type
         implicit none
         integer, intent(in) :: unit
         type(model_type), intent(in) :: model
      end subroutine whole_interface
   end interface

contains

   !> Create and lock the output directory, clear it of an earlier run's
   !> files, open the files the deck asks for and register their writers.
   subroutine open_outputs(outdir, deck, force, model, version, plan_text, writers, error)
      character(*), intent(in) :: outdir, deck
      !> Replace files of FEKAP's names that no earlier run recorded (--force).
      logical, intent(in) :: force
      type(model_type), intent(in) :: model
      !> FEKAP's version and the stepper's plan_text, for the listing.
      character(*), intent(in) :: version, plan_text
      type(writer_list_type), intent(out) :: writers
      type(error_type), allocatable, intent(out) :: error
      type(registry_type) :: registry
      character(:), allocatable :: stem
      stem = deck(index(deck, '/', back=.true.) + 1:)
      if (index(stem, '.', back=.true.) > 1) stem = stem(:index(stem, '.', back=.true.) - 1)
      registry%plan%deck = deck
      registry%plan%stem = stem
      registry%plan%force = force
      registry%outdir = outdir
      call register_outputs(registry, model, stem, version, plan_text)
      call prepare_output_directory(outdir, registry%plan, error)
      if (allocated(error)) return
      registry%planning = .false.
      call register_outputs(registry, model, stem, version, plan_text)
      if (allocated(registry%error)) then
         call move_alloc(registry%error, error)
         return
      end if
      call move_writers(registry%writers, writers)
   end subroutine open_outputs

   !> The output files of a run, in the order their writers are called: the
   !> order of the rows within a step, and of the flushes (on a disk that
   !> fills, the first files keep the most).
   subroutine register_outputs(registry, model, stem, version, plan_text)
      type(registry_type), intent(inout) :: registry
      type(model_type), intent(in) :: model
      character(*), intent(in) :: stem, version, plan_text
      integer :: effects
      logical :: vel, acc
      ! (A local array: gfortran 12 sizes an array constructor with a
      ! character length expression wrongly.)
      character(len=len(stem) + len(temporary_suffix) + 10) :: vtk_files(3)
      effects = planned_effects(model)
      vel = model%analysis%velocities
      acc = vel .and. model%analysis%accelerations
      if (model%output%csv) then
         if (model%analysis%spatial) then
            ! A spatial run reports its joints' motion, not planar link angles.
            call registry%table('points.csv', spatial_points_writer(vel, acc))
            call registry%table('joints.csv', joints_writer(vel, acc))
         else
            call registry%table('points.csv', points_writer(vel, acc))
            call registry%table('links.csv', links_writer(vel, acc))
         end if
         call registry%table('steps.csv', steps_writer(dynamics=effects == effects_dynamics))
         if (model%analysis%spatial) then
            call registry%table('nodes.csv', spatial_nodes_writer())
         else
            call registry%table('nodes.csv', nodes_writer())
         end if
         call registry%whole('mesh.csv', write_mesh_csv, model)
         if (effects /= effects_kinematics) call registry%table('reactions.csv', reactions_writer())
         if (effects == effects_kinetostatics .and. model%output%deflection) then
            call registry%table('deflection.csv', deflection_writer())
         end if
         if (effects == effects_dynamics) call registry%table('energy.csv', energy_writer(energy_names))
         if (model%analysis%spatial) then
            call registry%whole('mechanism.txt', write_spatial_mechanism, model)
         else
            call registry%whole('mechanism.txt', write_mechanism_csv, model)
         end if
      end if
      if (model%output%listing) call registry%table(stem//'.lis', listing_writer(version, step_count(model), plan_text))
      if (model%output%vtk) then
         vtk_files(1) = stem//'.pvd'
         vtk_files(2) = stem//'.pvd'//temporary_suffix
         vtk_files(3) = 'vtk/'//stem//'_*.vtu'
         call registry%step_files(vtk_writer(registry%outdir, stem), 'vtk', vtk_files)
      end if
   end subroutine register_outputs

   subroutine registry_table(self, name, writer)
      class(registry_type), intent(inout) :: self
      !> The file's name in the output directory.
      character(*), intent(in) :: name
      class(table_writer_type), intent(in) :: writer
      class(table_writer_type), allocatable :: table
      class(writer_type), allocatable :: added
      integer :: unit
      if (allocated(self%error)) return
      if (self%planning) then
         call add_run_file(self%plan, name)
         return
      end if
      call open_replace(self%outdir//'/'//name, unit, self%error, stream=.true., formatted=writer%formatted)
      if (allocated(self%error)) return
      allocate (table, source=writer)
      call table%attach(unit)
      call move_alloc(table, added)
      call self%writers%add(added)
   end subroutine registry_table

   subroutine registry_whole(self, name, emit, model)
      class(registry_type), intent(inout) :: self
      character(*), intent(in) :: name
      procedure(whole_interface) :: emit
      type(model_type), intent(in) :: model
      integer :: unit
      if (allocated(self%error)) return
      if (self%planning) then
         call add_run_file(self%plan, name)
         return
      end if
      call open_replace(self%outdir//'/'//name, unit, self%error, stream=.true.)
      if (allocated(self%error)) return
      call emit(unit, model)
      call close_checked(unit, -1_int64, self%error)
   end subroutine registry_whole

   subroutine registry_step_files(self, writer, directory, names)
      class(registry_type), intent(inout) :: self
      class(writer_type), intent(in) :: writer
      !> The writer's directory in the output directory.
      character(*), intent(in) :: directory
      !> The files (`*` for the step) of the manifest.
      character(*), intent(in) :: names(:)
      class(writer_type), allocatable :: added
      integer :: i
      if (allocated(self%error)) return
      if (self%planning) then
         do i = 1, size(names)
            call add_run_file(self%plan, trim(names(i)))
         end do
         return
      end if
      call make_directory(self%outdir//'/'//directory, self%error)
      if (allocated(self%error)) return
      allocate (added, source=writer)
      call self%writers%add(added)
   end subroutine registry_step_files

end module fekap_driver_outputs
