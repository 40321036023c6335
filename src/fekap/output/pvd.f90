!> The ParaView collection `<stem>.pvd` of a run's .vtu files, listing each
!> with its time. Its lines are formatted once, as each .vtu is written, and
!> held in memory; the run writes the file whole to a temporary name and
!> renames it over the collection (fekap_output_vtk_writer), so that it is never seen cut
!> short, not even after a SIGKILL. Rewriting it after every step would make a run quadratic in its steps
!> (docs/performance.md); it is rewritten only when
!> it has grown by an eighth since the last write (pvd_due) and at the end,
!> so that all the rewrites together write at most about nine times its
!> final size: linear in the steps.
module fekap_output_pvd
   use fekap_kinds, only: dp
   use fekap_output_format, only: real_text
   implicit none
   private

   public :: pvd_type, add_pvd_entry, pvd_due, write_pvd_text

   type :: pvd_type
      !> text(1:n): one DataSet line per .vtu file, each ending in a newline.
      character(:), allocatable :: text
      integer :: n = 0
      !> DataSet lines held, and how many of them the file on disk lists.
      integer :: entries = 0
      integer :: written = 0
   end type pvd_type


contains

   !> Add the .vtu file `file` (relative to the .pvd) at time t.
   pure subroutine add_pvd_entry(self, t, file)
      type(pvd_type), intent(inout) :: self
      real(dp), intent(in) :: t
      character(*), intent(in) :: file
      character(:), allocatable :: line, grown
      line = '    <DataSet timestep="'//real_text(t)//'" part="0" file="'//file//'"/>'//new_line('a')
      if (.not. allocated(self%text)) allocate (character(len=4096) :: self%text)
      if (self%n + len(line) > len(self%text)) then
         ! Doubling: appending stays linear in the number of lines.
         allocate (character(len=2*(len(self%text) + len(line))) :: grown)
         grown(1:self%n) = self%text(1:self%n)
         call move_alloc(grown, self%text)
      end if
      self%text(self%n + 1:self%n + len(line)) = line
      self%n = self%n + len(line)
      self%entries = self%entries + 1
   end subroutine add_pvd_entry

   !> Whether the collection has grown enough since it was last written to
   !> be written again (by an eighth, and by at least one file).
   pure logical function pvd_due(self)
      type(pvd_type), intent(in) :: self
      pvd_due = self%entries - self%written >= max(1, self%written/8)
   end function pvd_due

   !> The whole collection, to a unit open for formatted stream access.
   subroutine write_pvd_text(unit, self)
      integer, intent(in) :: unit
      type(pvd_type), intent(in) :: self
      write (unit, '(a)') '<?xml version="1.0"?>'
      write (unit, '(a)') '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">'
      write (unit, '(a)') '  <Collection>'
      ! Each newline of the held lines ends a record of the formatted stream.
      if (self%n > 0) write (unit, '(a)') self%text(1:self%n - 1)
      write (unit, '(a)') '  </Collection>'
      write (unit, '(a)') '</VTKFile>'
   end subroutine write_pvd_text

end module fekap_output_pvd
