!> The deck as read: every non-blank line of the deck file and of the files it
!> INCLUDEs, spliced in place, each with its fields and the card it starts.
!>
!> INCLude is textual: the included lines continue the block that is open at the
!> INCLude line, and the block open at the end of the included file continues
!> after it. A relative name is resolved against the directory of the including
!> file (the current directory for a deck given as a string). END ends the file
!> it is in; it is required in the main deck and optional in an included one;
!> text after END is an error.
module fekap_deck_source
   use fekap_deck_card, only: card_of, card_none, card_include, card_end
   use fekap_deck_diagnostic, only: diagnostics_type, mark_type
   use fekap_deck_lexer, only: token_type, text_type, split_lines, lex_line, find_control
   use fekap_posix, only: os_read_all, os_error_text, os_file_kind, kind_regular, kind_directory, kind_fifo, &
      & kind_socket
   implicit none
   private

   public :: source_type, line_type, load_file, load_string, line_mark

   !> Deepest nesting of INCLude.
   integer, parameter :: max_depth = 16

   !> One non-blank line of the deck.
   type :: line_type
      !> Index into source%files, and the line number in that file.
      integer :: file = 0
      integer :: number = 0
      !> The line as displayed in diagnostics.
      character(:), allocatable :: text
      !> The line without its comment.
      character(:), allocatable :: code
      type(token_type), allocatable :: tokens(:)
      !> The card this line starts (card_none for a data line).
      integer :: card = card_none
      !> The first non-blank line of an INCLuded file, when it starts no card:
      !> an error there is told without the line (mark_type's withheld).
      logical :: first_of_include = .false.
   end type line_type

   !> All lines of a deck.
   type :: source_type
      !> Names of the files read (the main deck first).
      type(text_type), allocatable :: files(:)
      integer :: nfiles = 0
      type(line_type), allocatable :: lines(:)
      integer :: nlines = 0
      !> The main deck ends with END.
      logical :: terminated = .false.
      !> The main deck could be read (it exists and is text).
      logical :: readable = .false.
      !> Line number of the last non-blank line of the main deck (0: none).
      integer :: last_line = 0
   end type source_type

contains

   !> Read the deck file `path` and everything it includes.
   subroutine load_file(source, diagnostics, path)
      type(source_type), intent(out) :: source
      type(diagnostics_type), intent(inout) :: diagnostics
      character(*), intent(in) :: path
      type(text_type) :: stack(0)
      character(:), allocatable :: buffer, message
      logical :: ok
      call read_whole_file(path, buffer, ok, message, main=.true.)
      if (.not. ok) then
         call diagnostics%add(mark_type(file=path, text=''), message)
         return
      end if
      call load_text(source, diagnostics, buffer, path, directory_of(path), stack)
   end subroutine load_file

   !> Read a deck given as text (lines separated by new_line characters); `name`
   !> stands for the file name in diagnostics, INCLude is relative to the current directory.
   subroutine load_string(source, diagnostics, text, name)
      type(source_type), intent(out) :: source
      type(diagnostics_type), intent(inout) :: diagnostics
      character(*), intent(in) :: text, name
      type(text_type) :: stack(0)
      call load_text(source, diagnostics, text, name, '', stack)
   end subroutine load_string

   recursive subroutine load_text(source, diagnostics, buffer, name, directory, stack)
      type(source_type), intent(inout) :: source
      type(diagnostics_type), intent(inout) :: diagnostics
      character(*), intent(in) :: buffer, name, directory
      !> Files being included, outermost first (empty for the main deck).
      type(text_type), intent(in) :: stack(:)
      type(text_type), allocatable :: lines(:)
      type(line_type) :: line
      type(mark_type) :: mark
      integer :: k, bad, lnum, col, empty_col, ifile, at_include
      character(:), allocatable :: target, included, message, included_text
      character(len=40) :: where
      logical :: main, ok, ended, first
      character(*), parameter :: bom = achar(239)//achar(187)//achar(191), cr = achar(13), lf = achar(10)
      main = size(stack) == 0
      ! A UTF-8 byte order mark (some Windows editors write one) is not part of the text.
      if (len(buffer) >= 3) then
         if (buffer(1:3) == bom) then
            call load_text(source, diagnostics, buffer(4:), name, directory, stack)
            return
         end if
      end if
      ! Line ends of carriage returns alone (classic Mac OS files) are line ends.
      if (index(buffer, cr) > 0 .and. index(buffer, lf) == 0) then
         call load_text(source, diagnostics, replace_cr(buffer), name, directory, stack)
         return
      end if
      call add_file(source, name, ifile)
      bad = find_control(buffer)
      if (bad > 0) then
         lnum = 1 + count_lf(buffer(:bad - 1))
         col = bad - index(buffer(:bad - 1), achar(10), back=.true.)
         write (where, '(a,i0)') 'character code ', iachar(buffer(bad:bad))
         call diagnostics%add(mark_type(file=name, line=lnum, col=col, text='', order=source%nlines + 1), &
            & 'binary file: '//trim(where)//' is not text; a deck is a plain text file')
         return
      end if
      if (main) source%readable = .true.
      call split_lines(buffer, lines)
      ended = .false.
      first = .not. main
      do k = 1, size(lines)
         line%file = ifile
         line%number = k
         ! Each split line is freed as it is taken.
         call move_alloc(lines(k)%s, line%text)
         call lex_line(line%text, line%code, line%tokens, empty_col)
         if (size(line%tokens) == 0 .and. empty_col == 0) cycle
         if (main) source%last_line = k
         ! Only a data line, not a card, is withheld: a file that is no deck
         ! starts with no card.
         line%first_of_include = first
         if (size(line%tokens) > 0) line%first_of_include = first .and. card_of(line%tokens(1)%text) == card_none
         first = .false.
         if (ended) then
            call diagnostics%add(mark_of(source, line, 1), 'text after END', &
               & label='END ends the deck; move this before END or delete it')
            exit
         end if
         line%card = card_none
         if (size(line%tokens) > 0) line%card = card_of(line%tokens(1)%text)
         call append_line(source, line)
         if (empty_col > 0) then
            mark = mark_of(source, line, 0)
            mark%col = empty_col
            call diagnostics%add(mark, 'empty field', label='two commas with nothing between them')
         end if
         if (line%card == card_end .and. size(line%tokens) == 1) then
            ended = .true.
            if (main) source%terminated = .true.
         else if (line%card == card_include) then
            at_include = source%nlines
            target = trim(adjustl(line%code(line%tokens(1)%col + len(line%tokens(1)%text):)))
            if (len(target) == 0) then
               call diagnostics%add(mark_of(source, line, 1), 'INCLude needs a file name', &
                  & label='write INCLude FILE (relative to this deck''s directory)')
               cycle
            end if
            if (target(1:1) == '/') then
               included = target
            else
               included = directory//target
            end if
            if (on_stack(included, stack, name)) then
               call diagnostics%add(mark_of(source, line, 2), 'INCLude cycle: '//included// &
                  & ' is already being read', label='a deck cannot include itself')
               cycle
            end if
            if (size(stack) + 1 >= max_depth) then
               call diagnostics%add(mark_of(source, line, 2), 'INCLude nested too deeply')
               cycle
            end if
            call read_whole_file(included, included_text, ok, message, main=.false.)
            if (.not. ok) then
               call diagnostics%add(mark_of(source, line, 2), message)
               cycle
            end if
            call load_text(source, diagnostics, included_text, included, directory_of(included), &
               & [stack, text_type(name)])
            deallocate (included_text)
            if (source%nlines == at_include) then
               call diagnostics%add(mark_of(source, source%lines(at_include), 2), 'the included file '// &
                  & included//' has no cards or data', label='an empty INCLude is probably a mistake')
            end if
         end if
      end do
   end subroutine load_text

   !> The place of field `itok` of the last appended line (past the end of
   !> its code if it has no such field).
   pure function mark_of(source, line, itok) result(mark)
      type(source_type), intent(in) :: source
      type(line_type), intent(in) :: line
      integer, intent(in) :: itok
      type(mark_type) :: mark
      mark = line_mark(source, line, source%nlines, itok, 1)
   end function mark_of

   !> The place of field `itok` of `line`, the order-th line of the deck
   !> (for sorting diagnostics); without such a field, `gap` columns past the
   !> end of the line's code (a missing field).
   pure function line_mark(source, line, order, itok, gap) result(mark)
      type(source_type), intent(in) :: source
      type(line_type), intent(in) :: line
      integer, intent(in) :: order, itok, gap
      type(mark_type) :: mark
      mark%file = source%files(line%file)%s
      mark%line = line%number
      mark%text = line%text
      mark%order = order
      mark%withheld = line%first_of_include
      if (itok >= 1 .and. itok <= size(line%tokens)) then
         mark%col = line%tokens(itok)%col
         mark%length = len(line%tokens(itok)%text)
      else
         mark%col = len_trim(line%code) + gap
         mark%length = 1
      end if
   end function line_mark

   pure logical function on_stack(path, stack, current)
      character(*), intent(in) :: path, current
      type(text_type), intent(in) :: stack(:)
      integer :: i
      on_stack = path == current
      do i = 1, size(stack)
         on_stack = on_stack .or. path == stack(i)%s
      end do
   end function on_stack

   !> The directory part of a path, with its trailing '/', or '' for a bare name.
   pure function directory_of(path) result(directory)
      character(*), intent(in) :: path
      character(:), allocatable :: directory
      directory = path(:index(path, '/', back=.true.))
   end function directory_of

   !> `text` with every carriage return made a line feed.
   pure function replace_cr(text) result(out)
      character(*), intent(in) :: text
      character(len=len(text)) :: out
      integer :: i
      out = text
      do i = 1, len(out)
         if (out(i:i) == achar(13)) out(i:i) = achar(10)
      end do
   end function replace_cr

   pure integer function count_lf(text) result(n)
      character(*), intent(in) :: text
      integer :: i
      n = 0
      do i = 1, len(text)
         if (text(i:i) == achar(10)) n = n + 1
      end do
   end function count_lf

   pure subroutine add_file(source, name, ifile)
      type(source_type), intent(inout) :: source
      character(*), intent(in) :: name
      integer, intent(out) :: ifile
      type(text_type), allocatable :: grown(:)
      if (.not. allocated(source%files)) allocate (source%files(8))
      if (source%nfiles == size(source%files)) then
         allocate (grown(2*size(source%files)))
         grown(1:source%nfiles) = source%files(1:source%nfiles)
         call move_alloc(grown, source%files)
      end if
      source%nfiles = source%nfiles + 1
      source%files(source%nfiles)%s = name
      ifile = source%nfiles
   end subroutine add_file

   pure subroutine append_line(source, line)
      type(source_type), intent(inout) :: source
      type(line_type), intent(in) :: line
      type(line_type), allocatable :: grown(:)
      integer :: i
      if (.not. allocated(source%lines)) allocate (source%lines(64))
      if (source%nlines == size(source%lines)) then
         allocate (grown(2*size(source%lines)))
         ! Moved, not copied: a copy of every line's texts doubled the
         ! memory of a large deck at each growth.
         do i = 1, source%nlines
            grown(i)%file = source%lines(i)%file
            grown(i)%number = source%lines(i)%number
            grown(i)%card = source%lines(i)%card
            grown(i)%first_of_include = source%lines(i)%first_of_include
            call move_alloc(source%lines(i)%text, grown(i)%text)
            call move_alloc(source%lines(i)%code, grown(i)%code)
            call move_alloc(source%lines(i)%tokens, grown(i)%tokens)
         end do
         call move_alloc(grown, source%lines)
      end if
      source%nlines = source%nlines + 1
      source%lines(source%nlines) = line
   end subroutine append_line

   !> The whole content of a file, or ok = .false. and a message naming the file.
   !> Only a regular file is opened, and for the main deck its standard
   !> input (`... | fekap /dev/stdin`): opening a FIFO would wait for a
   !> writer for ever, and a device (/dev/zero, /dev/urandom) is no deck.
   subroutine read_whole_file(path, buffer, ok, message, main)
      character(*), intent(in) :: path
      character(:), allocatable, intent(out) :: buffer
      logical, intent(out) :: ok
      character(:), allocatable, intent(out) :: message
      !> The main deck (which may be the standard input), not an INCLude.
      logical, intent(in) :: main
      logical :: exists, is_stdin
      integer :: unit, ios, n, kind
      character(len=256) :: iomsg
      ok = .false.
      buffer = ''
      inquire (file=path, exist=exists)
      if (.not. exists) then
         message = "cannot open '"//path//"': no such file"
         return
      end if
      ios = os_file_kind(path, kind, is_stdin)
      if (ios /= 0) then
         message = "cannot open '"//path//"': "//os_error_text(ios)
         return
      end if
      if (kind == kind_directory) then
         message = "cannot read '"//path//"': it is a directory, not a deck"
         return
      end if
      if (kind /= kind_regular .and. .not. (main .and. is_stdin)) then
         select case (kind)
         case (kind_fifo)
            message = "cannot read '"//path//"': a FIFO (named pipe), not a regular file"
         case (kind_socket)
            message = "cannot read '"//path//"': a socket, not a regular file"
         case default
            message = "cannot read '"//path//"': a device, not a regular file"
         end select
         if (main) then
            message = message//'; a deck is a plain text file (a pipe is read as fekap /dev/stdin)'
         else
            message = message//'; an INCLude names a plain text file'
         end if
         return
      end if
      open (newunit=unit, file=path, access='stream', form='unformatted', action='read', status='old', &
         & iostat=ios, iomsg=iomsg)
      if (ios /= 0) then
         message = "cannot open '"//path//"': "//trim(iomsg)
         return
      end if
      inquire (unit=unit, size=n)
      if (n <= 0) then
         ! Not a regular file with text in it: a pipe (`... | fekap /dev/stdin`),
         ! a terminal, an empty file or a directory, read to its end.
         close (unit)
         ios = os_read_all(path, buffer)
         if (ios /= 0) then
            message = "cannot read '"//path//"': "//os_error_text(ios)
            return
         end if
         ok = .true.
         return
      end if
      deallocate (buffer)
      allocate (character(len=n) :: buffer)
      if (n > 0) read (unit, iostat=ios, iomsg=iomsg) buffer
      close (unit)
      if (ios /= 0) then
         message = "cannot read '"//path//"': "//trim(iomsg)
         return
      end if
      ok = .true.
   end subroutine read_whole_file

end module fekap_deck_source
