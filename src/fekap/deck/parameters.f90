!> The PARAmeters block, in the style of FEAP's PARAmeter command: lines
!> `name = expression`, read in deck order, each expression able to use the
!> names defined above it; every numeric field of the deck may then use them.
!> Values given on the command line (`fekap --set name=value`) replace the
!> deck's; a name the deck does not define, or a bad value, is reported like a
!> deck error at its place on the command line (`--set:K:COL`, the K-th --set).
module fekap_deck_parameters
   use fekap_error, only: error_type
   use fekap_model, only: parameter_type
   use fekap_strings, only: lower, same_name
   use fekap_deck_context, only: context_type
   use fekap_deck_diagnostic, only: mark_type
   use fekap_deck_expression, only: evaluate_expression, known_names
   use fekap_deck_name_index, only: new_name_index
   implicit none
   private

   public :: override_type, read_parameters

   !> One `--set name=value` of the command line, as given.
   type :: override_type
      character(:), allocatable :: text
   end type override_type

   !> Names an expression already gives a meaning: constants, functions, non-numbers.
   character(*), parameter :: reserved(16) = [character(len=8) :: 'pi', 'deg', 'nan', 'inf', 'infinity', &
      & 'sqrt', 'sin', 'cos', 'tan', 'asin', 'acos', 'atan', 'atan2', 'exp', 'log', 'abs']

contains

   !> Read the PARAmeters lines `lines` into ctx%parameters (left unallocated
   !> when there are none, so that a deck without the block reads as before)
   !> and apply `overrides`.
   subroutine read_parameters(ctx, lines, overrides)
      type(context_type), intent(inout) :: ctx
      !> The block's lines, in deck order.
      integer, intent(in) :: lines(:)
      !> The command line's values, in the order given (a later one for a name wins).
      type(override_type), intent(in) :: overrides(:)
      logical :: used(size(overrides)), valid(size(overrides))
      character(:), allocatable :: name, expr, known
      type(parameter_type) :: parameter
      type(error_type), allocatable :: error
      character(:), allocatable :: detail
      integer :: i, k, iexpr, eq, previous
      logical :: ok

      used = .false.
      do k = 1, size(overrides)
         valid(k) = check_override(ctx, overrides, k)
      end do
      ! Room for every line's parameter at once, and an index of their names:
      ! reading is linear in the number of lines.
      if (size(lines) > 0) allocate (ctx%parameters(size(lines)))
      ctx%nparameters = 0
      call new_name_index(ctx%parameter_index, size(lines))
      do i = 1, size(lines)
         call split_line(ctx, lines(i), name, iexpr, expr, ok)
         if (.not. ok) cycle
         previous = ctx%parameter_index%find(name)
         if (previous > 0) then
            call ctx%error_at(ctx%loc(lines(i), 1), "parameter '"//name//"' is defined twice", &
               & label='each parameter is defined once', note_loc=ctx%parameters(previous)%loc, &
               & note='first defined here')
            cycle
         end if
         parameter%name = name
         parameter%loc = ctx%loc(lines(i), 1)
         parameter%set_on_command_line = .false.
         k = 0
         do eq = size(overrides), 1, -1
            if (.not. valid(eq)) cycle
            if (same_name(override_name(overrides(eq)), name)) then
               k = eq
               exit
            end if
         end do
         if (k > 0) then
            used = used .or. [(same_name(override_name(overrides(eq)), name), eq=1, size(overrides))]
            eq = index(overrides(k)%text, '=')
            call evaluate_expression(overrides(k)%text(eq + 1:), parameter%value, error, detail, &
               & ctx%parameters(:ctx%nparameters), ctx%parameter_index)
            parameter%set_on_command_line = .not. allocated(error)
            if (allocated(error)) then
               ! Reported; the deck's value keeps the fields that use the name quiet.
               call ctx%diagnostics%add(override_mark(overrides, k, eq + 1, len(overrides(k)%text) - eq), &
                  & error%message, detail)
               call ctx%real_field(lines(i), iexpr, parameter%value, ok, text=expr)
            else
               ok = .true.
            end if
         else
            call ctx%real_field(lines(i), iexpr, parameter%value, ok, text=expr)
         end if
         ! A parameter without a value is left out: the fields that use it say so.
         if (ok) then
            ctx%nparameters = ctx%nparameters + 1
            ctx%parameters(ctx%nparameters) = parameter
            call ctx%parameter_index%insert(name, ctx%nparameters, previous)
         end if
      end do
      if (allocated(ctx%parameters)) then
         if (ctx%nparameters < size(ctx%parameters)) ctx%parameters = ctx%parameters(:ctx%nparameters)
         known = known_names(ctx%parameters)
         ! Without 'pi deg': the names the deck defines.
         known = known(7:)
      end if
      do k = 1, size(overrides)
         if (used(k) .or. .not. valid(k)) cycle
         if (size(lines) == 0) then
            call ctx%diagnostics%add(override_mark(overrides, k, 1, index(overrides(k)%text, '=') - 1), &
               & "unknown parameter '"//override_name(overrides(k))//"': the deck has no PARAmeters block", &
               & 'add it to the deck: PARAmeters, then lines name = value')
         else
            call ctx%diagnostics%add(override_mark(overrides, k, 1, index(overrides(k)%text, '=') - 1), &
               & "unknown parameter '"//override_name(overrides(k))//"'", 'the deck defines:'//known)
         end if
      end do
   end subroutine read_parameters

   !> A PARAmeters line: `name = expr`, `name=expr`, `name= expr` or `name =expr`,
   !> the expression one field. Gives the name, the field that holds the
   !> expression and its text; reports a malformed line.
   subroutine split_line(ctx, iline, name, iexpr, expr, ok)
      type(context_type), intent(inout) :: ctx
      integer, intent(in) :: iline
      character(:), allocatable, intent(out) :: name, expr
      integer, intent(out) :: iexpr
      logical, intent(out) :: ok
      character(*), parameter :: form = 'name = expression'
      character(:), allocatable :: first, second
      integer :: n, eq
      ok = .false.
      n = ctx%nfields(iline)
      first = ctx%field(iline, 1)
      second = ctx%field(iline, 2)
      eq = index(first, '=')
      name = first
      if (eq > 0) name = first(:eq - 1)
      iexpr = 0
      if (eq > 0 .and. eq < len(first)) then
         iexpr = 1
         expr = first(eq + 1:)
      else if (eq > 0 .and. n >= 2) then
         iexpr = 2
         expr = ctx%field(iline, 2)
      else if (eq == 0 .and. n >= 2) then
         if (second == '=' .and. n >= 3) then
            iexpr = 3
            expr = ctx%field(iline, 3)
         else if (second(1:1) == '=' .and. len(second) > 1) then
            iexpr = 2
            expr = second(2:)
         else if (second /= '=') then
            call ctx%error(iline, 2, "expected '=' after the parameter name", label='a PARAmeters line is: '//form)
            return
         end if
      end if
      if (iexpr == 0) then
         call ctx%error(iline, n + 1, 'missing expression', label='a PARAmeters line is: '//form)
         return
      end if
      if (iexpr < n) then
         call ctx%error(iline, iexpr + 1, 'more fields after the expression', &
            & label='an expression has no blanks; one parameter per line')
         return
      end if
      if (.not. is_identifier(name)) then
         call ctx%error(iline, 1, "invalid parameter name '"//name//"'", &
            & label='a parameter name is letters, digits and _, starting with a letter')
         return
      end if
      if (any(reserved == lower(name))) then
         call ctx%error(iline, 1, "'"//name//"' cannot be a parameter name", &
            & label='pi, deg and the function names keep their meaning')
         return
      end if
      ok = .true.
   end subroutine split_line

   !> Whether the K-th override is `name=value` with a usable name (reports one that is not).
   logical function check_override(ctx, overrides, k) result(ok)
      type(context_type), intent(inout) :: ctx
      type(override_type), intent(in) :: overrides(:)
      integer, intent(in) :: k
      integer :: eq
      eq = index(overrides(k)%text, '=')
      ok = eq > 1 .and. eq < len(overrides(k)%text)
      if (.not. ok) then
         call ctx%diagnostics%add(override_mark(overrides, k, max(eq, 1), max(len(overrides(k)%text), 1)), &
            & 'expected --set NAME=VALUE', 'for example --set crank=1.2 (a deck parameter and an expression)')
         return
      end if
      ok = is_identifier(overrides(k)%text(:eq - 1))
      if (.not. ok) call ctx%diagnostics%add(override_mark(overrides, k, 1, eq - 1), &
         & "invalid parameter name '"//overrides(k)%text(:eq - 1)//"'", &
         & 'a parameter name is letters, digits and _, starting with a letter')
   end function check_override

   !> The name part of an override.
   pure function override_name(override) result(name)
      type(override_type), intent(in) :: override
      character(:), allocatable :: name
      name = override%text(:max(index(override%text, '=') - 1, 0))
   end function override_name

   !> The place of columns col.. of the K-th override: "--set:K:col", sorted
   !> before every line of the deck.
   pure function override_mark(overrides, k, col, length) result(mark)
      type(override_type), intent(in) :: overrides(:)
      integer, intent(in) :: k, col, length
      type(mark_type) :: mark
      mark%file = '--set'
      mark%line = k
      mark%col = col
      mark%length = max(length, 1)
      mark%text = overrides(k)%text
      mark%order = k - size(overrides) - 1
   end function override_mark

   !> Letters, digits and _, starting with a letter: a name an expression can use.
   pure logical function is_identifier(text)
      character(*), intent(in) :: text
      integer :: i
      character :: c
      is_identifier = len(text) > 0
      do i = 1, len(text)
         c = lower(text(i:i))
         if (c >= 'a' .and. c <= 'z') cycle
         if (i > 1 .and. ((c >= '0' .and. c <= '9') .or. c == '_')) cycle
         is_identifier = .false.
      end do
   end function is_identifier

end module fekap_deck_parameters
