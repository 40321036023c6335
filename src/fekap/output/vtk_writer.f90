!> The writer of the VTK output: each written step to
!> `<outdir>/vtk/<stem>_<step>.vtu` (the directory must exist), and the
!> collection `<outdir>/<stem>.pvd` rewritten at the flushes when it has
!> grown enough (fekap_output_pvd) and at the end, however the run ended.
module fekap_output_vtk_writer
   use, intrinsic :: iso_fortran_env, only: int64
   use fekap_kinds, only: dp
   use fekap_error, only: error_type
   use fekap_model, only: model_type
   use fekap_model_results, only: step_result_type, fill_fields_from_nodes
   use fekap_posix, only: os_unlink
   use fekap_output_csv, only: row_prefix_type
   use fekap_output_vtk, only: write_vtu
   use fekap_output_pvd, only: pvd_type, add_pvd_entry, pvd_due, write_pvd_text
   use fekap_output_checked_file, only: open_replace, close_checked, replace_checked
   use fekap_output_directory, only: temporary_suffix
   use fekap_output_writer, only: writer_type
   implicit none
   private

   public :: vtk_writer

   type, extends(writer_type) :: vtk_writer_type
      !> The output directory and the deck's stem, for the file names.
      character(:), allocatable :: outdir, stem
      !> The fields come from the model's nodes and links (a method without a mesh).
      logical :: from_nodes = .false.
      !> (2, nlink): end nodes of each link, for from_nodes.
      integer, allocatable :: links_nodes(:, :)
      !> A written step with the fields made from its nodes (from_nodes).
      type(step_result_type) :: filled
      !> (2, npoint), or (3, npoint) in a spatial run: point positions at the first step.
      real(dp), allocatable :: initial_pos(:, :)
      !> The collection of the files written so far.
      type(pvd_type) :: pvd
   contains
      procedure :: header => vtk_header
      procedure :: row => vtk_row
      procedure :: flush => vtk_flush
      procedure :: checkpoint => vtk_checkpoint
      procedure :: finish => vtk_finish
      procedure :: step_files => vtk_step_files
   end type vtk_writer_type

contains

   !> The writer of the VTK files of the deck `stem` in `outdir` (whose
   !> `vtk` directory the registry makes).
   type(vtk_writer_type) function vtk_writer(outdir, stem) result(writer)
      character(*), intent(in) :: outdir, stem
      writer%outdir = outdir
      writer%stem = stem
   end function vtk_writer

   subroutine vtk_header(self, model)
      class(vtk_writer_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      integer :: l
      allocate (self%links_nodes(2, size(model%links)))
      do l = 1, size(model%links)
         self%links_nodes(:, l) = model%links(l)%node
      end do
   end subroutine vtk_header

   !> Write the step's .vtu file and add it to the collection (written at
   !> the checkpoints when it has grown enough, and at the end). A method
   !> that fills no mesh fields at its start fills none later: its fields
   !> are made from the nodes.
   subroutine vtk_row(self, model, result, prefix, rows, error)
      class(vtk_writer_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      type(row_prefix_type), intent(inout) :: prefix
      integer, intent(inout) :: rows
      type(error_type), allocatable, intent(out) :: error
      integer :: unit
      if (result%step == 0) self%from_nodes = .not. allocated(result%mesh_pos)
      if (self%from_nodes) then
         self%filled = result
         call fill_fields_from_nodes(self%filled, self%links_nodes)
         if (allocated(result%pos_z)) then
            ! A spatial run: its nodes in 3D.
            self%filled%mesh_pos = with_z(result%pos, result%pos_z)
            self%filled%mesh_vel = with_z(result%vel, result%vel_z)
            self%filled%mesh_acc = with_z(result%acc, result%acc_z)
         end if
         if (result%step == 0) self%initial_pos = self%filled%mesh_pos
      else if (result%step == 0) then
         self%initial_pos = result%mesh_pos
      end if
      call open_replace(self%outdir//'/'//vtu_name(self%stem, result%step), unit, error, stream=.true., &
         & formatted=.true.)
      if (allocated(error)) return
      if (self%from_nodes) then
         call write_vtu(unit, model, self%filled, self%initial_pos)
      else
         call write_vtu(unit, model, result, self%initial_pos)
      end if
      ! A .vtu that did not fit is removed, not left cut.
      call close_checked(unit, -1_int64, error)
      if (allocated(error)) return
      call add_pvd_entry(self%pvd, result%t, vtu_name(self%stem, result%step))
   end subroutine vtk_row

   !> (3, n) points from their (2, n) x, y and their z.
   pure function with_z(xy, z) result(xyz)
      real(dp), intent(in) :: xy(:, :), z(:)
      real(dp) :: xyz(3, size(z))
      xyz(1:2, :) = xy
      xyz(3, :) = z
   end function with_z

   !> Each .vtu file is checked as it is closed: nothing is held.
   subroutine vtk_flush(self, error)
      class(vtk_writer_type), intent(inout) :: self
      type(error_type), allocatable, intent(out) :: error
   end subroutine vtk_flush

   !> The collection, when it has grown enough since it was last written.
   subroutine vtk_checkpoint(self, error)
      class(vtk_writer_type), intent(inout) :: self
      type(error_type), allocatable, intent(out) :: error
      if (pvd_due(self%pvd)) call write_pvd(self, error)
   end subroutine vtk_checkpoint

   !> The whole collection, however the run ended. On a full disk the newest
   !> step files make room for the collection of the others, so that no .vtu
   !> is left without its .pvd.
   subroutine vtk_finish(self, error)
      class(vtk_writer_type), intent(inout) :: self
      type(error_type), allocatable, intent(out) :: error
      type(error_type), allocatable :: retry_error
      integer :: dropped
      character(len=100) :: text
      if (self%pvd%entries <= self%pvd%written) return
      call write_pvd(self, error)
      if (.not. allocated(error)) return
      dropped = 0
      do while (self%pvd%entries > 0)
         call drop_last_step_file(self)
         dropped = dropped + 1
         call write_pvd(self, retry_error)
         if (.not. allocated(retry_error)) exit
         deallocate (retry_error)
      end do
      if (.not. allocated(retry_error)) then
         write (text, '(a,i0,a)') ' (the newest ', dropped, ' .vtu files were removed to make room for it)'
         error%message = error%message//trim(text)
      end if
   end subroutine vtk_finish

   integer function vtk_step_files(self) result(files)
      class(vtk_writer_type), intent(in) :: self
      files = self%pvd%entries
   end function vtk_step_files

   !> Write the .pvd collection as it is: whole, to a temporary name, then
   !> renamed over the old one (a reader never sees part of it).
   subroutine write_pvd(self, error)
      class(vtk_writer_type), intent(inout) :: self
      type(error_type), allocatable, intent(out) :: error
      integer :: unit
      call open_replace(self%outdir//'/'//self%stem//'.pvd'//temporary_suffix, unit, error, stream=.true., &
         & formatted=.true.)
      if (allocated(error)) return
      call write_pvd_text(unit, self%pvd)
      call replace_checked(unit, self%outdir//'/'//self%stem//'.pvd'//temporary_suffix, &
         & self%outdir//'/'//self%stem//'.pvd', error)
      if (.not. allocated(error)) self%pvd%written = self%pvd%entries
   end subroutine write_pvd

   !> Remove the newest step file of the collection and its entry (to make
   !> room for the .pvd on a full disk).
   subroutine drop_last_step_file(self)
      class(vtk_writer_type), intent(inout) :: self
      integer :: start, first, last, code
      associate (p => self%pvd)
         start = index(p%text(1:p%n - 1), new_line('a'), back=.true.) + 1
         first = index(p%text(start:p%n), 'file="') + start + 5
         last = first + index(p%text(first:p%n), '"') - 2
         code = os_unlink(self%outdir//'/'//p%text(first:last))
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

end module fekap_output_vtk_writer
