!> Splitting deck text into lines and lines into fields.
!>
!> A `*` in column 1 makes the line a comment; `!` anywhere starts a comment to
!> the end of the line. Fields are separated by blanks or commas; a comma inside
!> parentheses does not separate (`atan2(-1,3)` is one field). Tabs count as one
!> blank column each, a carriage return (CRLF files) is dropped.
module fekap_deck_lexer
   implicit none
   private

   public :: token_type, split_lines, lex_line, find_control

   !> One field of a line and the column where it starts.
   type :: token_type
      character(:), allocatable :: text
      integer :: col = 0
   end type token_type

   !> A piece of text (an array of these holds strings of different lengths).
   type, public :: text_type
      character(:), allocatable :: s
   end type text_type

contains

   !> The lines of `buffer`, split at line feeds; tabs and carriage returns become blanks
   !> and a final carriage return is dropped. A final line feed ends the last line.
   pure subroutine split_lines(buffer, lines)
      character(*), intent(in) :: buffer
      type(text_type), allocatable, intent(out) :: lines(:)
      integer :: n, start, i, k, stop_
      character(*), parameter :: lf = achar(10)
      n = 0
      do i = 1, len(buffer)
         if (buffer(i:i) == lf) n = n + 1
      end do
      if (len(buffer) > 0) then
         if (buffer(len(buffer):len(buffer)) /= lf) n = n + 1
      end if
      allocate (lines(n))
      start = 1
      do k = 1, n
         stop_ = index(buffer(start:), lf)
         if (stop_ == 0) then
            stop_ = len(buffer)
         else
            stop_ = start + stop_ - 2
         end if
         lines(k)%s = buffer(start:stop_)
         if (len(lines(k)%s) > 0) then
            if (lines(k)%s(len(lines(k)%s):) == achar(13)) lines(k)%s = lines(k)%s(:len(lines(k)%s) - 1)
         end if
         do i = 1, len(lines(k)%s)
            if (lines(k)%s(i:i) == achar(9) .or. lines(k)%s(i:i) == achar(13)) lines(k)%s(i:i) = ' '
         end do
         start = stop_ + 2
      end do
   end subroutine split_lines

   !> Position of the first control character (other than tab, line feed and
   !> carriage return) in `buffer`, 0 if there is none: such a file is not a deck.
   pure integer function find_control(buffer) result(pos)
      character(*), intent(in) :: buffer
      integer :: i, c
      pos = 0
      do i = 1, len(buffer)
         c = iachar(buffer(i:i))
         if ((c < 32 .and. c /= 9 .and. c /= 10 .and. c /= 13) .or. c == 127) then
            pos = i
            return
         end if
      end do
   end function find_control

   !> Fields of one line, and the line without its comment (`code`, for cards that
   !> take the rest of the line). `empty_col` is the column of the first empty field
   !> (a comma right after a separator), 0 if there is none.
   pure subroutine lex_line(text, code, tokens, empty_col)
      character(*), intent(in) :: text
      character(:), allocatable, intent(out) :: code
      type(token_type), allocatable, intent(out) :: tokens(:)
      integer, intent(out) :: empty_col
      integer :: i, start, depth, n, pass, bang
      logical :: after_comma
      character :: c
      empty_col = 0
      code = ''
      allocate (tokens(0))
      if (len(text) == 0) return
      if (text(1:1) == '*') return
      bang = index(text, '!')
      if (bang > 0) then
         code = text(:bang - 1)
      else
         code = text
      end if
      ! Pass 1 counts the fields, pass 2 stores them.
      do pass = 1, 2
         n = 0
         start = 0
         depth = 0
         after_comma = .true.   ! a comma first on the line is an empty field
         do i = 1, len(code) + 1
            c = ' '
            if (i <= len(code)) c = code(i:i)
            if (start == 0) then
               if (c == ',') then
                  if (after_comma .and. empty_col == 0) empty_col = i
                  after_comma = .true.
               else if (c /= ' ') then
                  start = i
                  depth = 0
               end if
            end if
            if (start > 0) then
               if (c == '(') depth = depth + 1
               if (c == ')') depth = depth - 1
               if (c == ' ' .or. (c == ',' .and. depth <= 0)) then
                  n = n + 1
                  if (pass == 2) then
                     tokens(n)%text = code(start:i - 1)
                     tokens(n)%col = start
                  end if
                  start = 0
                  after_comma = c == ','
               end if
            end if
         end do
         if (pass == 1) then
            deallocate (tokens)
            allocate (tokens(n))
         end if
      end do
   end subroutine lex_line

end module fekap_deck_lexer
