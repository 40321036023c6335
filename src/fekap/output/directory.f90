!> The output directory of a run: made without a shell (the path taken
!> literally, parents included), locked for the run, and cleared of the files
!> an earlier run of FEKAP and its scripts wrote there.
!>
!> The lock is an flock(2) on the directory itself (no lock file is left in
!> it). The kernel releases the lock when the run's process ends, however it
!> ends (SIGKILL included), so a lock is never stale. A second run into a
!> locked directory stops at once with an input error.
module fekap_output_directory
   use fekap_error, only: error_type, input_error, output_error
   use fekap_posix, only: os_make_path, os_open_lock, os_error_text, os_unlink, os_rmdir, os_list_directory, &
      & name_list_type
   implicit none
   private

   public :: prepare_output_directory, is_fekap_file, make_directory

   !> errno of flock(2) when another process holds the lock.
   integer, parameter :: ewouldblock = 11

   !> Files of FEKAP and its scripts removed from the output directory at the
   !> start of a run (docs/deck-format.md, "What a run writes"): a name, or a
   !> pattern with one `*`. The VTK step files are `vtk/*.vtu`.
   character(*), parameter :: own_files(*) = [character(len=17) :: 'points.csv', 'links.csv', 'steps.csv', &
      & 'mesh.csv', 'nodes.csv', 'reactions.csv', 'energy.csv', 'deflection.csv', 'mechanism.txt', '*.lis', '*.pvd', &
      & '*.fekap-tmp', 'paths.png', &
      & 'angles.png', 'iterations.png', 'history_*.png', 'shapes.png', 'energy.png', 'reactions.png', &
      & 'deflection.png', 'motion.gif', 'motion.mp4', 'motion-frame.png']

contains

   !> Make `path` and its missing parents without a shell. An error names the
   !> part of the path that could not be made and the system's reason.
   subroutine make_directory(path, error)
      character(*), intent(in) :: path
      type(error_type), allocatable, intent(out) :: error
      character(:), allocatable :: failed
      integer :: code
      code = os_make_path(path, failed)
      if (code /= 0) call output_error(error, failed//': cannot create the directory: '//os_error_text(code))
   end subroutine make_directory

   !> Make the output directory, lock it for this run (the lock is held until
   !> the process ends) and remove FEKAP's files of an earlier run from it
   !> (and from its vtk/ subdirectory).
   subroutine prepare_output_directory(outdir, error)
      character(*), intent(in) :: outdir
      type(error_type), allocatable, intent(out) :: error
      integer :: code, fd
      call make_directory(outdir, error)
      if (allocated(error)) return
      code = os_open_lock(outdir, fd)
      if (code == ewouldblock) then
         call input_error(error, 'fekap: '//outdir//'/: another fekap run is writing its results here; '// &
            & 'wait for it to end or give another directory with -o')
         return
      else if (code /= 0) then
         call output_error(error, outdir//': cannot lock the output directory: '//os_error_text(code))
         return
      end if
      call remove_own_files(outdir, error)
      if (allocated(error)) return
      call remove_own_files(outdir//'/vtk', error, vtu=.true.)
      if (allocated(error)) return
      ! An empty vtk/ left by an earlier run goes too (a run with VTK output makes it again).
      code = os_rmdir(outdir//'/vtk')
   end subroutine prepare_output_directory

   !> Remove the files of `dir` that FEKAP writes (with `vtu`, the .vtu files).
   subroutine remove_own_files(dir, error, vtu)
      character(*), intent(in) :: dir
      type(error_type), allocatable, intent(out) :: error
      logical, intent(in), optional :: vtu
      type(name_list_type) :: list
      logical :: step_files
      integer :: i, code
      step_files = .false.
      if (present(vtu)) step_files = vtu
      ! A missing directory has nothing to remove.
      if (os_list_directory(dir, list) /= 0) return
      do i = 1, list%count
         associate (name => list%names(i)%text)
            if (step_files) then
               if (.not. matches(name, '*.vtu')) cycle
            else
               if (.not. is_fekap_file(name)) cycle
            end if
            code = os_unlink(dir//'/'//name)
            if (code /= 0) then
               call output_error(error, dir//'/'//name//': cannot remove this file of an earlier run: '// &
                  & os_error_text(code))
               return
            end if
         end associate
      end do
   end subroutine remove_own_files

   !> The name is one of the files FEKAP or its scripts write into an output
   !> directory (own_files).
   pure logical function is_fekap_file(name)
      character(*), intent(in) :: name
      integer :: k
      is_fekap_file = .false.
      do k = 1, size(own_files)
         if (matches(name, trim(own_files(k)))) then
            is_fekap_file = .true.
            return
         end if
      end do
   end function is_fekap_file

   !> `name` matches `pattern`, which holds at most one `*` (any text).
   pure logical function matches(name, pattern)
      character(*), intent(in) :: name, pattern
      integer :: star, tail
      star = index(pattern, '*')
      if (star == 0) then
         matches = name == pattern .and. len(name) == len(pattern)
         return
      end if
      tail = len(pattern) - star
      matches = len(name) >= len(pattern) - 1
      if (.not. matches) return
      matches = name(:star - 1) == pattern(:star - 1) .and. name(len(name) - tail + 1:) == pattern(star + 1:)
   end function matches

end module fekap_output_directory
