!> Tests of fekap_output_buffer: text appended in many pieces, some longer
!> than the buffer, reaches a stream file byte for byte, in order with the
!> formatted writes made directly to the same (formatted stream) unit.
module test_output_buffer
   use fekap_testing, only: unittest_type, new_unittest, check, error_type
   use fekap_output_buffer, only: text_buffer_type, new_text_buffer, reserve_text, write_buffered
   use fekap_output_format, only: append_integer, append_text
   implicit none
   private
   public :: collect_output_buffer

   !> Scratch directory (the tests run from the repository root).
   character(*), parameter :: scratch = 'build/test-buffer/'

contains

   subroutine collect_output_buffer(tests)
      type(unittest_type), allocatable, intent(out) :: tests(:)
      tests = [ &
         & new_unittest('unformatted_stream', test_unformatted_stream), &
         & new_unittest('formatted_stream', test_formatted_stream) &
         & ]
   end subroutine collect_output_buffer

   !> Line i of the test text: its number and i mod 97 letters; line 5000 is
   !> longer than the buffer's starting capacity.
   function test_line(i) result(line)
      integer, intent(in) :: i
      character(:), allocatable :: line
      character(len=12) :: digits
      write (digits, '(i0)') i
      line = trim(digits)//','//repeat('x', mod(i, 97))
      if (i == 5000) line = line//repeat('y', 100000)
   end function test_line

   !> The bytes of a file.
   subroutine read_bytes(path, text)
      character(*), intent(in) :: path
      character(:), allocatable, intent(out) :: text
      integer :: unit, size_
      open (newunit=unit, file=path, status='old', action='read', access='stream', form='unformatted')
      inquire (unit=unit, size=size_)
      allocate (character(len=size_) :: text)
      if (size_ > 0) read (unit) text
      close (unit)
   end subroutine read_bytes

   !> Append lines first..last to the buffer, as the writers do.
   subroutine append_lines(buffer, first, last, want)
      type(text_buffer_type), intent(inout) :: buffer
      integer, intent(in) :: first, last
      character(:), allocatable, intent(inout) :: want
      character(:), allocatable :: line
      integer :: i
      do i = first, last
         line = test_line(i)
         call reserve_text(buffer, len(line) + 1)
         call append_text(buffer%text, buffer%n, line)
         call append_text(buffer%text, buffer%n, new_line('a'))
         want = want//line//new_line('a')
      end do
   end subroutine append_lines

   subroutine test_unformatted_stream(error)
      type(error_type), allocatable, intent(out) :: error
      type(text_buffer_type) :: buffer
      character(:), allocatable :: want, got
      integer :: unit
      call execute_command_line('mkdir -p '//scratch)
      open (newunit=unit, file=scratch//'unformatted.csv', status='replace', action='write', access='stream', &
         & form='unformatted')
      call new_text_buffer(buffer, unit, formatted=.false.)
      want = ''
      call append_lines(buffer, 1, 6000, want)
      call write_buffered(buffer)
      call check(error, buffer%n == 0, 'the buffer is empty after write_buffered')
      if (allocated(error)) return
      ! Nothing held: nothing written.
      call write_buffered(buffer)
      call reserve_text(buffer, 20)
      call append_integer(buffer%text, buffer%n, -42)
      call append_text(buffer%text, buffer%n, new_line('a'))
      want = want//'-42'//new_line('a')
      call write_buffered(buffer)
      close (unit)
      call read_bytes(scratch//'unformatted.csv', got)
      call check(error, len(got) == len(want), 'file length')
      if (allocated(error)) return
      call check(error, got == want, 'the file holds the appended text byte for byte')
   end subroutine test_unformatted_stream

   !> As the listing: formatted writes before, between and after buffered lines.
   subroutine test_formatted_stream(error)
      type(error_type), allocatable, intent(out) :: error
      type(text_buffer_type) :: buffer
      character(:), allocatable :: want, got
      character(len=1), parameter :: nl = new_line('a')
      integer :: unit
      call execute_command_line('mkdir -p '//scratch)
      open (newunit=unit, file=scratch//'formatted.lis', status='replace', action='write', access='stream', &
         & form='formatted')
      call new_text_buffer(buffer, unit, formatted=.true.)
      write (unit, '(a)') 'HEAD'
      write (unit, '(/,a)') 'STEPS'
      want = 'HEAD'//nl//nl//'STEPS'//nl
      call append_lines(buffer, 1, 6000, want)
      call write_buffered(buffer)
      write (unit, '(2x,a,i4)') 'middle', 12
      want = want//'  middle  12'//nl
      call append_lines(buffer, 6001, 6003, want)
      call write_buffered(buffer)
      write (unit, '(/,a)') 'SUMMARY'
      want = want//nl//'SUMMARY'//nl
      close (unit)
      call read_bytes(scratch//'formatted.lis', got)
      call check(error, len(got) == len(want), 'file length')
      if (allocated(error)) return
      call check(error, got == want, 'the file holds the formatted and the buffered text in order')
   end subroutine test_formatted_stream

end module test_output_buffer
