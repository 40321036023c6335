!> Writes that are checked: a file counts as written when its length on disk
!> equals the position its unit reached. gfortran's I/O library loses a
!> failed write(2) without a word (on a full file system a write statement, a
!> flush and a close all report success, and the file simply ends short, as
!> test/app/test_full_disk_rows.py shows on a full file system). A file that came
!> out short is cut back to the length last verified (whole lines: the
!> writers hand over whole lines only), and the error names the file and
!> the operating system's reason, found by appending one byte with write(2).
module fekap_output_checked_file
   use, intrinsic :: iso_fortran_env, only: int64
   use fekap_error, only: error_type, output_error
   use fekap_posix, only: os_append_probe, os_truncate, os_unlink, os_error_text, os_rename, os_file_size
   implicit none
   private

   public :: unit_path, verified_length, write_failure, close_checked, replace_checked, whole_lines_length
   public :: open_replace

   !> A unit that is not open (newunit numbers are negative, so not -1).
   integer, parameter, public :: no_unit = -huge(1)

contains

   !> The file name a unit was opened with.
   function unit_path(unit) result(path)
      integer, intent(in) :: unit
      character(:), allocatable :: path
      character(len=4096) :: name
      inquire (unit=unit, name=name)
      path = trim(name)
   end function unit_path

   !> Flush `unit` and return the length of its file if every byte written to
   !> it is on disk, else -1.
   integer(int64) function verified_length(unit, path) result(length)
      integer, intent(in) :: unit
      character(*), intent(in) :: path
      integer :: ios
      integer(int64) :: pos, size_
      length = -1
      flush (unit, iostat=ios)
      if (ios /= 0) return
      inquire (unit=unit, pos=pos, iostat=ios)
      if (ios /= 0) return
      ! From the file itself: INQUIRE (file=..., size=) answers from the unit.
      size_ = os_file_size(path)
      if (size_ == pos - 1) length = size_
   end function verified_length

   !> The length of `path` up to its last whole line at or after `from`
   !> bytes (`from`, which ends a line or the file's start, when no newline
   !> follows it): the bytes past `from` are read back from the disk.
   integer(int64) function whole_lines_length(path, from) result(length)
      character(*), intent(in) :: path
      integer(int64), intent(in) :: from
      character(:), allocatable :: tail
      integer(int64) :: size_
      integer :: unit, ios, last
      length = max(from, 0_int64)
      size_ = os_file_size(path)
      if (size_ <= length) return
      ! What a short write left: at most a buffer's worth past the last check.
      if (size_ - length > huge(1)) return
      allocate (character(len=int(size_ - length)) :: tail)
      open (newunit=unit, file=path, access='stream', form='unformatted', action='read', status='old', &
         & iostat=ios)
      if (ios /= 0) return
      read (unit, pos=length + 1, iostat=ios) tail
      close (unit)
      if (ios /= 0) return
      last = index(tail, new_line('a'), back=.true.)
      length = length + last
   end function whole_lines_length

   !> After a failed write to `path`: why it failed (the OS error), with the
   !> file cut back to `keep` bytes, or removed when keep < 0. The file's unit
   !> must be closed first (its library buffer would land after the cut).
   subroutine write_failure(path, keep, error)
      character(*), intent(in) :: path
      integer(int64), intent(in) :: keep
      type(error_type), allocatable, intent(out) :: error
      integer :: code, status
      code = os_append_probe(path)
      if (keep >= 0) then
         status = os_truncate(path, keep)
      else
         status = os_unlink(path)
      end if
      if (code /= 0) then
         call output_error(error, path//': cannot write: '//os_error_text(code))
      else
         call output_error(error, path//': cannot write: the file system took fewer bytes than were written')
      end if
   end subroutine write_failure

   !> Close a unit whose whole file has just been written and check that all
   !> of it is on disk. On failure the file is cut back to `keep` bytes
   !> (removed when keep < 0) and the error says why.
   subroutine close_checked(unit, keep, error)
      integer, intent(in) :: unit
      integer(int64), intent(in) :: keep
      type(error_type), allocatable, intent(out) :: error
      character(:), allocatable :: path
      integer(int64) :: length
      integer :: ios
      path = unit_path(unit)
      length = verified_length(unit, path)
      close (unit, iostat=ios)
      if (length < 0 .or. ios /= 0) call write_failure(path, keep, error)
   end subroutine close_checked

   !> Close a unit open on `temporary`, check it, and rename it to `path`
   !> (replacing an earlier `path` in one step, so a reader sees the old file
   !> or the new one, never a part). On failure the temporary is removed.
   subroutine replace_checked(unit, temporary, path, error)
      integer, intent(in) :: unit
      character(*), intent(in) :: temporary, path
      type(error_type), allocatable, intent(out) :: error
      integer :: code
      call close_checked(unit, -1_int64, error)
      if (allocated(error)) return
      code = os_rename(temporary, path)
      if (code /= 0) then
         call output_error(error, path//': cannot write: '//os_error_text(code))
         code = os_unlink(temporary)
      end if
   end subroutine replace_checked

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

end module fekap_output_checked_file
