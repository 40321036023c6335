!> The state of reading one deck: its lines, the diagnostics found so far, and
!> helpers that read a field of a line as a number, an integer or a name, and
!> report a problem at the field's place.
module fekap_deck_context
   use fekap_kinds, only: dp
   use fekap_error, only: error_type
   use fekap_model, only: source_loc_type, parameter_type
   use fekap_deck_card, only: card_of, card_none, card_name
   use fekap_strings, only: lower
   use fekap_deck_name_index, only: name_index_type
   use fekap_deck_diagnostic, only: diagnostics_type, mark_type
   use fekap_deck_expression, only: evaluate_expression, evaluate_integer
   use fekap_deck_source, only: source_type, line_mark
   implicit none
   private

   public :: context_type

   !> A deck being read.
   type :: context_type
      type(source_type) :: source
      type(diagnostics_type) :: diagnostics
      !> Indexes of the model's node and link names, built as they are read.
      type(name_index_type) :: nodes, links
      !> Names of nodes and links whose lines were reported and dropped (a
      !> malformed line, a link to a dropped node): the lines naming them
      !> report nothing more, so one bad line gives one error, not a cascade.
      type(name_index_type) :: dropped_nodes, dropped_links
      !> The deck's parameters read so far, which numeric fields may use:
      !> the first nparameters of `parameters`, their names indexed.
      type(parameter_type), allocatable :: parameters(:)
      integer :: nparameters = 0
      type(name_index_type) :: parameter_index
   contains
      !> Report an error at field `itok` of line `iline` (past the end: at the end of the line).
      procedure :: error => context_error
      !> Report an error at a model entity's place, optionally with a note at another.
      procedure :: error_at => context_error_at
      !> The diagnostic mark of a field, or of an entity's place.
      procedure :: mark => context_mark
      procedure :: mark_loc => context_mark_loc
      !> An entity's place: the field's file, line and column.
      procedure :: loc => context_loc
      !> Number of fields of a line.
      procedure :: nfields => context_nfields
      !> The text of a field.
      procedure :: field => context_field
      !> Read a field as a real expression or an integer, reporting a bad one.
      procedure :: real_field => context_real_field
      procedure :: integer_field => context_integer_field
      !> Whether a field is a usable name (reports one that is not).
      procedure :: name_field => context_name_field
      !> Whether a line has at least n fields (reports the first missing one).
      procedure :: require => context_require
   end type context_type

contains

   pure subroutine context_error(self, iline, itok, message, label)
      class(context_type), intent(inout) :: self
      integer, intent(in) :: iline, itok
      character(*), intent(in) :: message
      character(*), intent(in), optional :: label
      call self%diagnostics%add(self%mark(iline, itok), message, label)
   end subroutine context_error

   pure subroutine context_error_at(self, loc, message, label, note_loc, note)
      class(context_type), intent(inout) :: self
      type(source_loc_type), intent(in) :: loc
      character(*), intent(in) :: message
      character(*), intent(in), optional :: label
      type(source_loc_type), intent(in), optional :: note_loc
      character(*), intent(in), optional :: note
      if (present(note_loc) .and. present(note)) then
         call self%diagnostics%add(self%mark_loc(loc), message, label, self%mark_loc(note_loc), note)
      else
         call self%diagnostics%add(self%mark_loc(loc), message, label)
      end if
   end subroutine context_error_at

   pure function context_mark(self, iline, itok) result(mark)
      class(context_type), intent(in) :: self
      integer, intent(in) :: iline, itok
      type(mark_type) :: mark
      ! A missing field is marked one blank past the end of the line.
      mark = line_mark(self%source, self%source%lines(iline), iline, itok, 2)
   end function context_mark

   pure function context_mark_loc(self, loc) result(mark)
      class(context_type), intent(in) :: self
      type(source_loc_type), intent(in) :: loc
      type(mark_type) :: mark
      integer :: i, k
      do i = 1, self%source%nlines
         associate (line => self%source%lines(i))
            if (line%number /= loc%line) cycle
            if (line%file /= loc%file) cycle
            do k = 1, size(line%tokens)
               if (line%tokens(k)%col == loc%col) then
                  mark = self%mark(i, k)
                  return
               end if
            end do
            mark = self%mark(i, 1)
            return
         end associate
      end do
      mark%file = ''
      if (loc%file >= 1 .and. loc%file <= self%source%nfiles) mark%file = self%source%files(loc%file)%s
      mark%line = loc%line
      mark%col = loc%col
      mark%text = ''
   end function context_mark_loc

   pure function context_loc(self, iline, itok) result(loc)
      class(context_type), intent(in) :: self
      integer, intent(in) :: iline, itok
      type(source_loc_type) :: loc
      type(mark_type) :: mark
      mark = self%mark(iline, itok)
      loc%file = self%source%lines(iline)%file
      loc%line = mark%line
      loc%col = mark%col
   end function context_loc

   pure integer function context_nfields(self, iline) result(n)
      class(context_type), intent(in) :: self
      integer, intent(in) :: iline
      n = size(self%source%lines(iline)%tokens)
   end function context_nfields

   pure function context_field(self, iline, itok) result(text)
      class(context_type), intent(in) :: self
      integer, intent(in) :: iline, itok
      character(:), allocatable :: text
      text = ''
      if (itok >= 1 .and. itok <= size(self%source%lines(iline)%tokens)) text = self%source%lines(iline)%tokens(itok)%text
   end function context_field

   pure subroutine context_real_field(self, iline, itok, value, ok, text)
      class(context_type), intent(inout) :: self
      integer, intent(in) :: iline, itok
      real(dp), intent(out) :: value
      logical, intent(out) :: ok
      !> The field's text when it is only part of the token (after `key=`).
      character(*), intent(in), optional :: text
      type(error_type), allocatable :: error
      character(:), allocatable :: detail
      if (.not. allocated(self%parameters)) then
         if (present(text)) then
            call evaluate_expression(text, value, error, detail)
         else
            call evaluate_expression(self%field(iline, itok), value, error, detail)
         end if
      else if (present(text)) then
         call evaluate_expression(text, value, error, detail, self%parameters(:self%nparameters), &
            & self%parameter_index)
      else
         call evaluate_expression(self%field(iline, itok), value, error, detail, &
            & self%parameters(:self%nparameters), self%parameter_index)
      end if
      ok = .not. allocated(error)
      if (.not. ok) call self%error(iline, itok, error%message, detail)
   end subroutine context_real_field

   pure subroutine context_integer_field(self, iline, itok, value, ok)
      class(context_type), intent(inout) :: self
      integer, intent(in) :: iline, itok
      integer, intent(out) :: value
      logical, intent(out) :: ok
      type(error_type), allocatable :: error
      character(:), allocatable :: detail
      if (allocated(self%parameters)) then
         call evaluate_integer(self%field(iline, itok), value, error, detail, &
            & self%parameters(:self%nparameters), self%parameter_index)
      else
         call evaluate_integer(self%field(iline, itok), value, error, detail)
      end if
      ok = .not. allocated(error)
      if (.not. ok) call self%error(iline, itok, error%message, detail)
   end subroutine context_integer_field

   !> A name is letters, digits and `_ - .`, starting with a letter or digit, and
   !> is not a card keyword (such a name at the start of a line would start a card).
   logical function context_name_field(self, iline, itok, what) result(ok)
      class(context_type), intent(inout) :: self
      integer, intent(in) :: iline, itok
      !> What the name is of: 'node', 'link', ...
      character(*), intent(in) :: what
      character(:), allocatable :: name
      integer :: i
      character :: c
      name = self%field(iline, itok)
      ok = len(name) > 0
      do i = 1, len(name)
         c = lower(name(i:i))
         if (.not. ((c >= 'a' .and. c <= 'z') .or. (c >= '0' .and. c <= '9') .or. &
            & (i > 1 .and. index('_-.', c) > 0))) ok = .false.
      end do
      if (.not. ok) then
         call self%error(iline, itok, 'invalid '//what//" name '"//name//"'", &
            & label='names are letters, digits, _ - . and start with a letter or digit')
         return
      end if
      if (card_of(name) /= card_none) then
         ok = .false.
         call self%error(iline, itok, what//" name '"//name//"' is a card keyword ("//card_name(card_of(name))//')', &
            & label='rename it: a name cannot begin a card keyword')
      end if
   end function context_name_field

   logical function context_require(self, iline, form, what) result(ok)
      class(context_type), intent(inout) :: self
      integer, intent(in) :: iline
      !> The line's fields, blank-separated, optional ones in brackets: 'name x y'.
      character(*), intent(in) :: form
      !> What kind of line it is, for the label: 'NODEs line', 'rate law'.
      character(*), intent(in) :: what
      integer :: i, n, start, have
      character(:), allocatable :: word
      have = self%nfields(iline)
      n = 0
      start = 0
      ok = .true.
      do i = 1, len(form) + 1
         if (i <= len(form)) then
            if (form(i:i) /= ' ') then
               if (start == 0) start = i
               cycle
            end if
         end if
         if (start == 0) cycle
         word = form(start:i - 1)
         start = 0
         if (word(1:1) == '[') exit
         n = n + 1
         if (n > have) then
            ok = .false.
            call self%error(iline, have + 1, "missing field '"//word//"'", label=what//' is: '//form)
            return
         end if
      end do
   end function context_require


end module fekap_deck_context
