!> Compiler-like diagnostics of a deck: collected while reading, sorted by their
!> place in the deck, and rendered as one text:
!>
!>     decks/x.deck:12:7: error: expected a real number
!>        12 | C  3  sqrt(1S)
!>           |       ^~~~~~~~ unexpected 'S' after the number 1
!>
!> A diagnostic may carry a note pointing at a second place ("first defined here").
module fekap_deck_diagnostic
   implicit none
   private

   public :: mark_type, diagnostic_type, diagnostics_type

   !> Most diagnostics rendered; the rest are only counted.
   integer, parameter :: max_shown = 100
   !> Longest source line shown under a message, and longest message: a
   !> longer line is shown as a window around the caret, a longer message cut.
   integer, parameter :: max_line_shown = 160, max_message_shown = 400

   !> A place in the deck: file, line, columns, and the line's text for display.
   type :: mark_type
      character(:), allocatable :: file
      !> Line number in the file (0: the whole file).
      integer :: line = 0
      !> First column and number of columns to underline (0: no caret).
      integer :: col = 0
      integer :: length = 0
      !> The line as shown under the message ('' shows no source line).
      character(:), allocatable :: text
      !> Sort key: the position of the line in the deck as read (includes spliced).
      integer :: order = 0
      !> The first line of an INCLuded file: neither it nor any text of its
      !> file is shown (an INCLude of a file that is no deck, a key or a
      !> password file, must not print it).
      logical :: withheld = .false.
   end type mark_type

   !> One error, with an optional note at a second place.
   type :: diagnostic_type
      type(mark_type) :: at
      character(:), allocatable :: message
      !> Short text after the caret.
      character(:), allocatable :: label
      logical :: has_note = .false.
      type(mark_type) :: note_at
      character(:), allocatable :: note
   end type diagnostic_type

   !> The diagnostics of one deck.
   type :: diagnostics_type
      !> items(1:kept): the first diagnostics in deck order, at most max_shown.
      type(diagnostic_type), allocatable :: items(:)
      integer :: kept = 0
      !> Number of diagnostics reported, kept or not.
      integer :: count = 0
   contains
      !> Record an error at a place, with optional label and note.
      procedure :: add => diagnostics_add
      !> All diagnostics as one text, in deck order.
      procedure :: render => diagnostics_render
   end type diagnostics_type

contains

   pure subroutine diagnostics_add(self, at, message, label, note_at, note)
      class(diagnostics_type), intent(inout) :: self
      !> Where the error is.
      type(mark_type), intent(in) :: at
      !> What is wrong and, where it helps, what to do.
      character(*), intent(in) :: message
      character(*), intent(in), optional :: label
      !> A second place, e.g. the first definition of a duplicate name.
      type(mark_type), intent(in), optional :: note_at
      character(*), intent(in), optional :: note
      type(diagnostic_type), allocatable :: grown(:)
      integer :: slot, i
      if (.not. allocated(self%items)) allocate (self%items(16))
      self%count = self%count + 1
      if (self%kept < max_shown) then
         if (self%kept == size(self%items)) then
            allocate (grown(2*size(self%items)))
            grown(1:self%kept) = self%items(1:self%kept)
            call move_alloc(grown, self%items)
         end if
         self%kept = self%kept + 1
         slot = self%kept
      else
         ! Only the first max_shown in deck order are shown: a deck of a
         ! million bad lines keeps 100 diagnostics, not a million. The new one
         ! replaces the last kept if it comes before it.
         slot = 1
         do i = 2, self%kept
            if (before(self%items(slot)%at, self%items(i)%at)) slot = i
         end do
         if (.not. before(at, self%items(slot)%at)) return
      end if
      associate (d => self%items(slot))
         d%at = at
         d%message = message
         d%label = ''
         if (present(label)) d%label = label
         d%has_note = present(note_at) .and. present(note)
         if (d%has_note) then
            d%note_at = note_at
            d%note = note
         end if
      end associate
   end subroutine diagnostics_add

   pure function diagnostics_render(self) result(text)
      class(diagnostics_type), intent(in) :: self
      character(:), allocatable :: text
      integer, allocatable :: order(:)
      integer :: i, j, k
      character(len=16) :: count_text
      character(:), allocatable :: withheld_file
      text = ''
      if (self%count == 0) return
      ! Stable insertion sort by place in the deck.
      order = [(i, i=1, self%kept)]
      do i = 2, self%kept
         k = order(i)
         j = i - 1
         do while (j >= 1)
            if (.not. before(self%items(k)%at, self%items(order(j))%at)) exit
            order(j + 1) = order(j)
            j = j - 1
         end do
         order(j + 1) = k
      end do
      withheld_file = ''
      do i = 1, self%kept
         associate (d => self%items(order(i)))
            if (d%at%withheld) then
               text = text//render_withheld(d%at)
               withheld_file = d%at%file
               cycle
            end if
            ! After a withheld first line, the rest of that file's errors are not shown either.
            if (d%at%file == withheld_file .and. len(d%at%file) == len(withheld_file)) cycle
            text = text//render_one(d%at, 'error', d%message, d%label)
            if (d%has_note) text = text//render_one(d%note_at, 'note', d%note, '')
         end associate
      end do
      if (self%count > max_shown) then
         write (count_text, '(i0)') self%count - max_shown
         text = text//'... and '//trim(count_text)//' more errors not shown'//new_line('a')
      end if
      write (count_text, '(i0)') self%count
      if (self%count == 1) then
         text = text//'1 error in the deck'
      else
         text = text//trim(count_text)//' errors in the deck'
      end if
   end function diagnostics_render

   pure logical function before(a, b)
      type(mark_type), intent(in) :: a, b
      before = a%order < b%order .or. (a%order == b%order .and. a%col < b%col)
   end function before

   pure function render_one(at, severity, message, label) result(text)
      type(mark_type), intent(in) :: at
      character(*), intent(in) :: severity, message, label
      character(:), allocatable :: text
      character(len=16) :: num
      character(:), allocatable :: gutter, shown
      integer :: width, first, last, col, length
      character(*), parameter :: nl = new_line('a')
      text = place(at)//' '//severity//': '//cut_message(message)//nl
      if (.not. allocated(at%text) .or. at%line <= 0) return
      if (len(at%text) == 0) return
      write (num, '(i0)') at%line
      width = max(4, len_trim(num) + 1)
      gutter = repeat(' ', width)
      ! A long line is shown as a window of max_line_shown columns around the caret.
      first = 1
      last = len(at%text)
      col = at%col
      length = max(at%length, 1)
      if (last > max_line_shown) then
         first = max(1, min(at%col - max_line_shown/4, len(at%text) - max_line_shown + 1))
         last = first + max_line_shown - 1
         shown = at%text(first:last)
         if (first > 1) shown = '...'//shown
         if (last < len(at%text)) shown = shown//'...'
         col = at%col - first + 1 + merge(3, 0, first > 1)
         length = min(length, last - at%col + 1)
      else
         shown = at%text
      end if
      text = text//repeat(' ', width - len_trim(num))//trim(num)//' | '//shown//nl
      if (at%col > 0) then
         text = text//gutter//' | '//repeat(' ', col - 1)//'^'//repeat('~', max(length, 1) - 1)
         if (len(label) > 0) text = text//' '//cut_message(label)
         text = text//nl
      end if
   end function render_one

   !> `file:line:col:` of a mark (line and column when known).
   pure function place(at) result(text)
      type(mark_type), intent(in) :: at
      character(:), allocatable :: text
      character(len=16) :: num
      text = at%file//':'
      if (at%line > 0) then
         write (num, '(i0)') at%line
         text = text//trim(num)//':'
         if (at%col > 0) then
            write (num, '(i0)') at%col
            text = text//trim(num)//':'
         end if
      end if
   end function place

   !> An error at the first line of an INCLuded file, told without its text.
   pure function render_withheld(at) result(text)
      type(mark_type), intent(in) :: at
      character(:), allocatable :: text
      text = place(at)//' error: the first line of this INCLuded file is not valid deck text '// &
         & '(not shown, nor the other errors in this file: is it the file you meant to include?)'//new_line('a')
   end function render_withheld

   !> A message of at most max_message_shown characters (a message quoting a
   !> field of a 200 kB line is cut, saying how much was cut).
   pure function cut_message(message) result(text)
      character(*), intent(in) :: message
      character(:), allocatable :: text
      character(len=16) :: num
      if (len(message) <= max_message_shown) then
         text = message
         return
      end if
      write (num, '(i0)') len(message) - max_message_shown
      text = message(:max_message_shown)//'... ('//trim(num)//' more characters not shown)'
   end function cut_message

end module fekap_deck_diagnostic
