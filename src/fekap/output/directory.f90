!> The output directory of a run: made without a shell (the path taken
!> literally, parents included), locked for the run, and cleared of the files
!> that an earlier run of FEKAP and its scripts wrote there, and of those only.
!>
!> The lock is an flock(2) on the directory itself (no lock file is left in
!> it). The kernel releases the lock when the run's process ends, however it
!> ends (SIGKILL included), so a lock is never stale. A second run into a
!> locked directory stops at once with an input error.
!>
!> What a run wrote is recorded in the directory's manifest (manifest_name):
!> one name a line, written before the files are, and appended to by
!> scripts/plot.py for the pictures it draws. The next run removes the files
!> the manifest lists and nothing else; a file of a name this run would write
!> that no manifest lists (someone else's points.csv, paths.png) stops the
!> run (an input error naming the files) unless the run is forced, and the
!> deck itself is never among the files removed or written over.
module fekap_output_directory
   use, intrinsic :: iso_fortran_env, only: int64
   use fekap_error, only: error_type, input_error, output_error
   use fekap_posix, only: os_make_path, os_open_lock, os_error_text, os_unlink, os_rmdir, os_list_directory, &
      & name_list_type, os_read_all, os_file_kind, kind_regular, os_same_file, os_rename, os_close
   use fekap_output_checked_file, only: close_checked
   implicit none
   private

   public :: prepare_output_directory, is_fekap_file, make_directory, output_plan_type, add_run_file

   !> errno of flock(2) when another process holds the lock, and of a missing file.
   integer, parameter :: ewouldblock = 11, enoent = 2

   !> The manifest of the files of the last run, in the output directory.
   character(*), parameter, public :: manifest_name = '.fekap-manifest'
   !> Suffix of a file written whole under a temporary name and renamed.
   character(*), parameter, public :: temporary_suffix = '.fekap-tmp'

   !> Files FEKAP and its scripts may write into an output directory: a name,
   !> or a pattern with one `*` (docs: README, "What a run writes"). Only
   !> names of these forms are ever removed, whatever a manifest says. The
   !> VTK step files are `vtk/*.vtu`.
   character(*), parameter :: own_files(*) = [character(len=17) :: 'points.csv', 'links.csv', 'steps.csv', &
      & 'mesh.csv', 'nodes.csv', 'reactions.csv', 'energy.csv', 'deflection.csv', 'mechanism.txt', '*.lis', '*.pvd', &
      & 'joints.csv', &
      & '*.fekap-tmp', 'paths.png', &
      & 'angles.png', 'iterations.png', 'history_*.png', 'shapes.png', 'energy.png', 'reactions.png', &
      & 'deflection.png', 'motion.gif', 'motion.mp4', 'motion-frame.png', 'views.png', 'joints.png']

   !> The files of a run of one deck whatever it computes (its CSV files,
   !> mechanism.txt, the plots of scripts/plot.py) besides `<stem>.lis`,
   !> `<stem>.pvd` and `vtk/<stem>_*.vtu`: one of these found in the directory
   !> and not in its manifest is someone else's.
   character(*), parameter :: run_files(*) = [character(len=17) :: 'points.csv', 'links.csv', 'steps.csv', &
      & 'mesh.csv', 'nodes.csv', 'reactions.csv', 'energy.csv', 'deflection.csv', 'mechanism.txt', 'paths.png', 'joints.csv', &
      & 'angles.png', 'iterations.png', 'history_*.png', 'shapes.png', 'energy.png', 'reactions.png', &
      & 'deflection.png', 'motion.gif', 'motion.mp4', 'motion-frame.png', 'views.png', 'joints.png']

   !> Most foreign files named in the error.
   integer, parameter :: max_named = 8

   !> What a run will write into its output directory.
   type :: output_plan_type
      !> The deck's path (never removed nor written over).
      character(:), allocatable :: deck
      !> The deck's stem: the listing is `<stem>.lis`, the VTK files `<stem>.pvd`, `vtk/<stem>_*.vtu`.
      character(:), allocatable :: stem
      !> Write over (and remove) files of FEKAP's names that no manifest lists (`fekap --force`).
      logical :: force = .false.
      !> The files the run writes, relative to the directory (add_run_file).
      type(name_list_type) :: files
   end type output_plan_type

contains

   !> Add `name` (relative to the output directory; `vtk/<stem>_*.vtu` stands
   !> for the VTK step files) to the files a run writes.
   pure subroutine add_run_file(plan, name)
      type(output_plan_type), intent(inout) :: plan
      character(*), intent(in) :: name
      call append_name(plan%files, name)
   end subroutine add_run_file

   pure subroutine append_name(list, name)
      type(name_list_type), intent(inout) :: list
      character(*), intent(in) :: name
      type(name_list_type) :: grown
      if (.not. allocated(list%names)) allocate (list%names(16))
      if (list%count == size(list%names)) then
         allocate (grown%names(2*size(list%names)))
         grown%names(1:list%count) = list%names(1:list%count)
         call move_alloc(grown%names, list%names)
      end if
      list%count = list%count + 1
      list%names(list%count)%text = name
   end subroutine append_name


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
   !> the process ends), check it (the deck is not in it under a name the run
   !> writes; no file of such a name but those of the manifest, unless
   !> forced), remove the files its manifest lists, and write the manifest of
   !> this run. On an error the lock is let go.
   subroutine prepare_output_directory(outdir, plan, error)
      character(*), intent(in) :: outdir
      type(output_plan_type), intent(in) :: plan
      type(error_type), allocatable, intent(out) :: error
      integer :: fd
      call lock_directory(outdir, fd, error)
      if (allocated(error)) return
      call clear_directory(outdir, plan, error)
      if (allocated(error)) call os_close(fd)
   end subroutine prepare_output_directory

   !> Make the directory and take its lock (fd, open for the life of the run).
   subroutine lock_directory(outdir, fd, error)
      character(*), intent(in) :: outdir
      integer, intent(out) :: fd
      type(error_type), allocatable, intent(out) :: error
      integer :: code
      fd = -1
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
   end subroutine lock_directory

   !> The checks, removals and manifest of prepare_output_directory.
   subroutine clear_directory(outdir, plan, error)
      character(*), intent(in) :: outdir
      type(output_plan_type), intent(in) :: plan
      type(error_type), allocatable, intent(out) :: error
      type(name_list_type) :: old, top, vtk, foreign
      integer :: code, i
      call read_manifest(outdir, old, error)
      if (allocated(error)) return
      code = os_list_directory(outdir, top)
      if (code /= 0) then
         call output_error(error, outdir//': cannot list the output directory: '//os_error_text(code))
         return
      end if
      ! A missing vtk/ has nothing in it.
      if (os_list_directory(outdir//'/vtk', vtk) /= 0) vtk%count = 0

      ! The deck under a name this run writes or removes: refused, forced or not.
      do i = 1, top%count
         associate (name => top%names(i)%text)
            if (.not. (is_run_name(name, plan%stem) .or. listed(old, name))) cycle
            if (os_same_file(outdir//'/'//name, plan%deck)) then
               call input_error(error, 'fekap: the deck '//plan%deck//' is the file '//outdir//'/'//name// &
                  & ', which this run would replace: give another output directory with -o, '// &
                  & 'or move or rename the deck')
               return
            end if
         end associate
      end do

      ! Files of FEKAP's output names that no earlier run recorded.
      do i = 1, top%count
         associate (name => top%names(i)%text)
            if (is_run_name(name, plan%stem) .and. .not. listed(old, name)) call append_name(foreign, name)
         end associate
      end do
      do i = 1, vtk%count
         associate (name => vtk%names(i)%text)
            if (is_step_file(name, plan%stem) .and. .not. listed(old, 'vtk/'//name)) then
               call append_name(foreign, 'vtk/'//name)
            end if
         end associate
      end do
      if (foreign%count > 0 .and. .not. plan%force) then
         call input_error(error, 'fekap: '//outdir//'/ holds '//named(foreign)//', of the names FEKAP''s '// &
            & 'runs and plots write (the plots would read them as this run''s), which no earlier run recorded in '// &
            & manifest_name//' (they are not FEKAP''s, or were written before FEKAP kept a manifest): move them '// &
            & 'away, give another directory with -o, or give --force to remove them')
         return
      end if

      ! The files of the earlier run, and with --force the foreign ones.
      call remove_listed(outdir, old, vtk, error)
      if (allocated(error)) return
      if (plan%force) then
         call remove_listed(outdir, foreign, vtk, error)
         if (allocated(error)) return
      end if
      ! The vtk/ of an earlier run goes too when that leaves it empty (a run
      ! with VTK output makes it again).
      do i = 1, old%count
         if (index(old%names(i)%text, 'vtk/') /= 1) cycle
         code = os_rmdir(outdir//'/vtk')
         exit
      end do

      call write_manifest(outdir, plan, error)
   end subroutine clear_directory

   !> The names of `list` for a message: the first max_named, and how many more.
   pure function named(list) result(text)
      type(name_list_type), intent(in) :: list
      character(:), allocatable :: text
      character(len=12) :: more
      integer :: i
      text = ''
      do i = 1, min(list%count, max_named)
         if (i > 1) text = text//', '
         text = text//list%names(i)%text
      end do
      if (list%count > max_named) then
         write (more, '(i0)') list%count - max_named
         text = text//' and '//trim(more)//' more'
      end if
   end function named

   !> The entries of the manifest of `outdir` that name files FEKAP may
   !> remove (see removable); none when there is no manifest.
   subroutine read_manifest(outdir, list, error)
      character(*), intent(in) :: outdir
      type(name_list_type), intent(out) :: list
      type(error_type), allocatable, intent(out) :: error
      character(:), allocatable :: text
      logical :: is_stdin
      integer :: code, kind, start, stop_
      code = os_file_kind(outdir//'/'//manifest_name, kind, is_stdin)
      if (code == enoent) return
      if (code == 0 .and. kind /= kind_regular) then
         call input_error(error, 'fekap: '//outdir//'/'//manifest_name//' is not a regular file: '// &
            & 'remove it or give another directory with -o')
         return
      end if
      if (code == 0) code = os_read_all(outdir//'/'//manifest_name, text)
      if (code /= 0) then
         call output_error(error, outdir//'/'//manifest_name//': cannot read: '//os_error_text(code))
         return
      end if
      start = 1
      do while (start <= len(text))
         stop_ = index(text(start:), new_line('a'))
         if (stop_ == 0) then
            stop_ = len(text) + 1
         else
            stop_ = start + stop_ - 1
         end if
         if (removable(text(start:stop_ - 1))) call append_name(list, text(start:stop_ - 1))
         start = stop_ + 1
      end do
   end subroutine read_manifest

   !> Write the manifest of the run (under a temporary name, then renamed).
   subroutine write_manifest(outdir, plan, error)
      character(*), intent(in) :: outdir
      type(output_plan_type), intent(in) :: plan
      type(error_type), allocatable, intent(out) :: error
      character(:), allocatable :: path
      integer :: unit, ios, i, code
      character(len=512) :: message
      path = outdir//'/'//manifest_name//temporary_suffix
      open (newunit=unit, file=path, status='replace', action='write', access='stream', form='unformatted', &
         & iostat=ios, iomsg=message)
      if (ios /= 0) then
         call output_error(error, path//': cannot write this file: '//trim(message))
         return
      end if
      write (unit) '# The files fekap and scripts/plot.py wrote here in the last run, one a line: '// &
         & 'the next fekap run into this directory removes these, and no other file.'//new_line('a')
      do i = 1, plan%files%count
         write (unit) plan%files%names(i)%text//new_line('a')
      end do
      call close_checked(unit, -1_int64, error)
      if (allocated(error)) return
      code = os_rename(path, outdir//'/'//manifest_name)
      if (code /= 0) then
         call output_error(error, outdir//'/'//manifest_name//': cannot write: '//os_error_text(code))
         code = os_unlink(path)
      end if
   end subroutine write_manifest

   !> Remove the files `list` names from `outdir` (`vtk` lists its vtk/, for
   !> the entries `vtk/<stem>_*.vtu`). A file already gone is no error.
   subroutine remove_listed(outdir, list, vtk, error)
      character(*), intent(in) :: outdir
      type(name_list_type), intent(in) :: list, vtk
      type(error_type), allocatable, intent(out) :: error
      integer :: i, j
      do i = 1, list%count
         associate (entry => list%names(i)%text)
            if (index(entry, '*') == 0) then
               call remove(entry)
            else
               do j = 1, vtk%count
                  if (step_matches('vtk/'//vtk%names(j)%text, entry)) call remove('vtk/'//vtk%names(j)%text)
               end do
            end if
         end associate
         if (allocated(error)) return
      end do
   contains
      subroutine remove(name)
         character(*), intent(in) :: name
         integer :: code
         code = os_unlink(outdir//'/'//name)
         if (code /= 0 .and. code /= enoent) call output_error(error, outdir//'/'//name// &
            & ': cannot remove this file of an earlier run: '//os_error_text(code))
      end subroutine remove
   end subroutine remove_listed

   !> A manifest entry FEKAP may act on: a plain name of FEKAP's forms
   !> (own_files), or `vtk/` and a .vtu name; never a path that leaves the
   !> directory, a hidden file, or any other name (a manifest edited by hand
   !> cannot make a run remove a user's file of another kind).
   pure logical function removable(entry)
      character(*), intent(in) :: entry
      character(:), allocatable :: base
      removable = .false.
      if (len(entry) == 0) return
      if (entry(1:1) == '.' .or. entry(1:1) == '/') return
      if (len(entry) > 4) then
         if (entry(1:4) == 'vtk/') then
            base = entry(5:)
            if (len(base) == 0 .or. index(base, '/') > 0) return
            if (base(1:1) == '.') return
            removable = matches(base, '*.vtu')
            return
         end if
      end if
      if (index(entry, '/') > 0 .or. index(entry, '*') > 0) return
      removable = is_fekap_file(entry)
   end function removable

   !> Whether `list` (manifest entries) holds `name`: the same name, or the
   !> pattern `vtk/<stem>_*.vtu` of a step file.
   pure logical function listed(list, name)
      type(name_list_type), intent(in) :: list
      character(*), intent(in) :: name
      integer :: i
      listed = .false.
      do i = 1, list%count
         associate (entry => list%names(i)%text)
            if (index(entry, '*') == 0) then
               listed = entry == name .and. len(entry) == len(name)
            else
               listed = step_matches(name, entry)
            end if
         end associate
         if (listed) return
      end do
   end function listed

   !> `name` matches the pattern `entry` with its `*` standing for digits only.
   pure logical function step_matches(name, entry)
      character(*), intent(in) :: name, entry
      integer :: star, tail, i
      step_matches = matches(name, entry)
      if (.not. step_matches) return
      star = index(entry, '*')
      tail = len(entry) - star
      do i = star, len(name) - tail
         if (name(i:i) < '0' .or. name(i:i) > '9') step_matches = .false.
      end do
      if (len(name) - tail < star) step_matches = .false.
   end function step_matches

   !> A name this run of the deck `stem` (or its plots) writes in the directory itself.
   pure logical function is_run_name(name, stem)
      character(*), intent(in) :: name, stem
      integer :: k
      is_run_name = same(name, stem//'.lis') .or. same(name, stem//'.pvd') .or. &
         & same(name, stem//'.pvd'//temporary_suffix)
      if (is_run_name) return
      do k = 1, size(run_files)
         if (matches(name, trim(run_files(k)))) then
            is_run_name = .true.
            return
         end if
      end do
   end function is_run_name

   !> The same text, trailing blanks included.
   pure logical function same(a, b)
      character(*), intent(in) :: a, b
      same = len(a) == len(b)
      if (same) same = a == b
   end function same

   !> A VTK step file of the deck `stem` (in vtk/).
   pure logical function is_step_file(name, stem)
      character(*), intent(in) :: name, stem
      is_step_file = step_matches(name, stem//'_*.vtu')
   end function is_step_file

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
