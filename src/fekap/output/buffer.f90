!> The text of an output file gathered in memory and written in large
!> pieces. A Fortran write statement costs as much however short its text as
!> the text of several numbers (docs/performance.md), so the per-step rows are
!> appended here (whole lines) and written when the buffer is full and when
!> the run flushes its files. A flush checks that the file on disk holds all
!> that was written (fekap_output_checked_file); after a failed write the
!> file is cut back to its length at the last good flush, which ends with a
!> whole line.
module fekap_output_buffer
   use, intrinsic :: iso_fortran_env, only: int64
   use fekap_error, only: error_type
   use fekap_output_checked_file, only: unit_path, verified_length, write_failure
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

   !> Write the held text to the unit and empty the buffer (the unit's own
   !> buffer is not flushed).
   subroutine write_buffered(self)
      type(text_buffer_type), intent(inout) :: self
      integer :: ios
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
      if (ios /= 0) self%failed = .true.
      self%n = 0
   end subroutine write_buffered

   !> Write the held text, flush the unit and check that the file on disk
   !> holds everything written to it. If not, the unit is closed, the file
   !> cut back to its length at the last good flush, and the error names the
   !> file and the reason.
   subroutine flush_text_buffer(self, error)
      type(text_buffer_type), intent(inout) :: self
      type(error_type), allocatable, intent(out) :: error
      integer(int64) :: length
      integer :: ios
      if (self%closed) return
      call write_buffered(self)
      length = -1
      if (.not. self%failed) length = verified_length(self%unit, self%path)
      if (length >= 0) then
         self%verified = length
         return
      end if
      self%failed = .true.
      self%closed = .true.
      ! The failed write is the error; a failing close (its library buffer
      ! cannot be written either) adds nothing to it.
      close (self%unit, iostat=ios)
      if (ios /= 0) self%failed = .true.
      call write_failure(self%path, self%verified, error)
   end subroutine flush_text_buffer

end module fekap_output_buffer
