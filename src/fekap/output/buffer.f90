!> The text of an output file gathered in memory and written in large
!> pieces. A Fortran write statement costs as much however short its text as
!> the text of several numbers (docs/performance.md), so the per-step rows are
!> appended here (whole lines) and written when the buffer is full and when
!> the run flushes its files. Each such write, and each flush, checks that
!> the file on disk holds all that was written (fekap_output_checked_file);
!> after a failed write the file is cut back to the last whole line on disk:
!> checked at once, before any other file can free space, the file is then
!> what was written up to the point where the disk filled, so every row
!> that fitted whole is kept, the header included.
module fekap_output_buffer
   use, intrinsic :: iso_fortran_env, only: int64
   use fekap_error, only: error_type
   use fekap_output_checked_file, only: unit_path, verified_length, write_failure, whole_lines_length
   implicit none
   private

   public :: text_buffer_type, new_text_buffer, reserve_text, write_buffered, flush_text_buffer

   !> Starting capacity in characters: a write holds hundreds of rows, and
   !> pieces over 64 KiB skip gfortran's own unit buffer (128 KiB for
   !> unformatted units: a piece more than half its size is written directly,
   !> not copied into it first).
   integer, parameter :: default_capacity = 131072

   type :: text_buffer_type
      !> The file's unit, open for stream access: unformatted, or formatted
      !> when `formatted` (a newline in its text then ends a record).
      integer :: unit = 0
      logical :: formatted = .false.
      !> text(1:n) is held: whole lines, each ending in new_line('a').
      character(:), allocatable :: text
      integer :: n = 0
      !> The file's name, for messages and to cut it back after a failed write.
      character(:), allocatable :: path
      !> Length of the file at the last flush that found all of it on disk.
      integer(int64) :: verified = 0
      !> A write statement failed: nothing more is written (the next flush
      !> reports it).
      logical :: failed = .false.
      !> The failure was reported and the unit closed.
      logical :: closed = .false.
      !> The failure found by a write, reported by the next flush.
      type(error_type), allocatable :: failure
   end type text_buffer_type

contains

   !> An empty buffer for `unit`.
   subroutine new_text_buffer(self, unit, formatted)
      type(text_buffer_type), intent(out) :: self
      !> A unit open for stream access.
      integer, intent(in) :: unit
      !> The unit is open for formatted stream access.
      logical, intent(in) :: formatted
      self%unit = unit
      self%formatted = formatted
      allocate (character(len=default_capacity) :: self%text)
      self%n = 0
      self%path = unit_path(unit)
   end subroutine new_text_buffer

   !> Make room for `length` more characters after text(1:n): write what is
   !> held if they do not fit, and grow the buffer (once) for a longer piece.
   subroutine reserve_text(self, length)
      type(text_buffer_type), intent(inout) :: self
      integer, intent(in) :: length
      if (self%n + length <= len(self%text)) return
      call write_buffered(self)
      if (length > len(self%text)) then
         deallocate (self%text)
         allocate (character(len=2*length) :: self%text)
      end if
   end subroutine reserve_text

   !> Write the held text to the unit, check that it reached the disk (unless
   !> `check` is false: the caller checks next), and empty the buffer.
   subroutine write_buffered(self, check)
      type(text_buffer_type), intent(inout) :: self
      logical, intent(in), optional :: check
      integer :: ios
      integer(int64) :: length
      if (self%n == 0) return
      ios = 0
      if (self%failed) then
         continue
      else if (self%formatted) then
         ! The record end of the write is the last newline.
         write (self%unit, '(a)', iostat=ios) self%text(1:self%n - 1)
      else
         write (self%unit, iostat=ios) self%text(1:self%n)
      end if
      self%n = 0
      if (self%failed) return
      if (ios == 0 .and. present(check)) then
         if (.not. check) return
      end if
      length = -1
      if (ios == 0) length = verified_length(self%unit, self%path)
      if (length >= 0) then
         self%verified = length
      else
         call fail(self)
      end if
   end subroutine write_buffered

   !> Write the held text, flush the unit and check that the file on disk
   !> holds everything written to it. If not, the unit is closed, the file
   !> cut back to its last whole line, and the error names the file and the
   !> reason (once; a failure found by an earlier write is reported here).
   subroutine flush_text_buffer(self, error)
      type(text_buffer_type), intent(inout) :: self
      type(error_type), allocatable, intent(out) :: error
      integer(int64) :: length
      if (self%closed) then
         if (allocated(self%failure)) call move_alloc(self%failure, error)
         return
      end if
      call write_buffered(self, check=.false.)
      length = -1
      if (.not. self%failed) length = verified_length(self%unit, self%path)
      if (length >= 0) then
         self%verified = length
         return
      end if
      if (.not. self%closed) call fail(self)
      if (allocated(self%failure)) call move_alloc(self%failure, error)
   end subroutine flush_text_buffer

   !> The file came out short: close the unit, cut the file back to its last
   !> whole line (beyond the last verified length: what fitted of the rows
   !> written since) and keep the error for the next flush.
   subroutine fail(self)
      type(text_buffer_type), intent(inout) :: self
      integer :: ios
      self%failed = .true.
      self%closed = .true.
      ! The failed write is the error; a failing close (its library buffer
      ! cannot be written either) adds nothing to it.
      close (self%unit, iostat=ios)
      if (ios /= 0) self%failed = .true.
      call write_failure(self%path, whole_lines_length(self%path, self%verified), self%failure)
   end subroutine fail

end module fekap_output_buffer
