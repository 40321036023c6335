!> The deck reader: reads a FEKAP input deck (see docs/deck-format.md) into a
!> model_type, checks it, and reports every problem of the deck at once as one
!> input error with compiler-like diagnostics.
module fekap_deck
   use fekap_error, only: error_type, input_error
   use fekap_model, only: model_type
   use fekap_deck_card, only: card_none, card_title, card_sections, card_nodes, card_links, card_welds, &
      & card_supports, card_drives, card_loads, card_slidelines, card_analysis, card_output, card_include, &
      & card_end, card_parameters, ncards, card_name, card_list, card_of, card_masses, card_gravity, &
      & card_velocities, card_joints
   use fekap_deck_spatial, only: read_spatial_sections, read_spatial_nodes, read_spatial_links, read_joints, &
      & read_spatial_drives
   use fekap_deck_context, only: context_type
   use fekap_deck_diagnostic, only: mark_type
   use fekap_deck_source, only: load_file, load_string
   use fekap_deck_geometry, only: read_sections, read_nodes, read_links, read_welds, read_supports
   use fekap_deck_motion, only: read_drives, read_loads, read_slidelines
   use fekap_deck_settings, only: read_title, read_analysis, read_output
   use fekap_deck_inertia, only: read_masses, read_gravity, check_effects
   use fekap_deck_parameters, only: override_type, read_parameters
   use fekap_model_effects, only: has_masses
   use fekap_deck_velocities, only: read_velocities
   implicit none
   private

   public :: read_deck, read_deck_string, override_type

   !> A block whose lines are skipped (after an unknown card or stray data).
   integer, parameter :: card_skip = -1

contains

   !> Read the deck file `filename` (and the files it INCLUDEs) into `model`.
   subroutine read_deck(model, filename, error, overrides)
      type(model_type), intent(out) :: model
      !> Path of the deck, also its name in diagnostics.
      character(*), intent(in) :: filename
      !> An input error whose message lists every problem of the deck.
      type(error_type), allocatable, intent(out) :: error
      !> Values of deck parameters that replace the deck's (`fekap --set name=value`).
      type(override_type), intent(in), optional :: overrides(:)
      type(context_type) :: ctx
      call load_file(ctx%source, ctx%diagnostics, filename)
      call finish(ctx, model, filename, error, overrides)
   end subroutine read_deck

   !> Read a deck given as text, lines separated by new_line('a'); `name` stands
   !> for the file name in diagnostics and INCLude is relative to the current directory.
   subroutine read_deck_string(model, text, name, error, overrides)
      type(model_type), intent(out) :: model
      character(*), intent(in) :: text
      character(*), intent(in) :: name
      type(error_type), allocatable, intent(out) :: error
      type(override_type), intent(in), optional :: overrides(:)
      type(context_type) :: ctx
      call load_string(ctx%source, ctx%diagnostics, text, name)
      call finish(ctx, model, name, error, overrides)
   end subroutine read_deck_string

   subroutine finish(ctx, model, name, error, overrides)
      type(context_type), intent(inout) :: ctx
      type(model_type), intent(inout) :: model
      character(*), intent(in) :: name
      type(error_type), allocatable, intent(out) :: error
      type(override_type), intent(in), optional :: overrides(:)
      integer :: i
      model%file = name
      ! A loop, not an array constructor: gfortran 12 sizes the constructor's
      ! allocatable strings wrongly (heap overrun at a long file name).
      if (allocated(model%files)) deallocate (model%files)
      allocate (model%files(ctx%source%nfiles))
      do i = 1, ctx%source%nfiles
         model%files(i)%name = ctx%source%files(i)%s
      end do
      model%title = ''
      if (ctx%source%readable) then
         if (ctx%source%nlines == 0) then
            call ctx%diagnostics%add(mark_type(file=name, line=1, text=''), &
               & 'empty deck: there are no cards in it; a deck has NODEs, SECTions, LINKs, DRIVes or LOADs, and END')
         else
            if (present(overrides)) then
               call interpret(ctx, model, overrides)
            else
               call interpret(ctx, model, [override_type ::])
            end if
         end if
      end if
      if (ctx%diagnostics%count > 0) call input_error(error, ctx%diagnostics%render())
   end subroutine finish

   !> Sort the lines into the cards' blocks, read the cards in dependency order, check the whole.
   subroutine interpret(ctx, model, overrides)
      type(context_type), intent(inout) :: ctx
      type(model_type), intent(inout) :: model
      type(override_type), intent(in) :: overrides(:)
      integer, allocatable :: block(:)
      integer :: i, card, current, nfields, last
      logical :: seen(ncards)
      allocate (block(ctx%source%nlines), source=card_none)
      seen = .false.
      current = card_none
      do i = 1, ctx%source%nlines
         associate (line => ctx%source%lines(i))
            card = line%card
            nfields = size(line%tokens)
            if (card == card_include) cycle   ! the included lines follow, in the open block
            if (card /= card_none .and. card /= card_title .and. card /= card_gravity .and. nfields > 1) then
               call ctx%error(i, 1, "'"//line%tokens(1)%text//"' reads as the card "//card_name(card)// &
                  & ', but more fields follow', label='a card keyword stands alone on its line, '// &
                  & 'and a name cannot be a card keyword (4 or more letters that begin one)')
               cycle
            end if
            if (card == card_end) cycle
            if (card == card_title) then
               block(i) = card_title
               current = card_skip
               cycle
            end if
            if (card == card_gravity) then
               ! Its values are on its line; data lines after it are errors (read_gravity).
               block(i) = card_gravity
               current = card_gravity
               seen(card) = .true.
               cycle
            end if
            if (card /= card_none) then
               current = card
               seen(card) = .true.
               cycle
            end if
            if (nfields == 0) cycle
            ! A data line.
            if (nfields == 1 .and. looks_like_keyword(line%tokens(1)%text)) then
               call ctx%error(i, 1, "unknown card '"//line%tokens(1)%text//"'", label='cards: '//card_list())
               current = card_skip
            else if (current == card_none) then
               call ctx%error(i, 1, 'data line before the first card', &
                  & label='start a block with a card such as NODEs or LINKs')
               current = card_skip
            else if (current /= card_skip) then
               block(i) = current
            end if
         end associate
      end do

      ! Parameters first: every numeric field after them may use them.
      call read_parameters(ctx, lines_of(card_parameters), overrides)
      if (allocated(ctx%parameters)) model%parameters = ctx%parameters
      call read_title(ctx, model, pack([(i, i=1, ctx%source%nlines)], block == card_title))
      call read_analysis(ctx, model, lines_of(card_analysis))
      if (model%analysis%spatial) then
         call read_spatial_deck()
      else
         call read_sections(ctx, model, lines_of(card_sections))
         call read_nodes(ctx, model, lines_of(card_nodes))
         call read_links(ctx, model, lines_of(card_links))
         call read_welds(ctx, model, lines_of(card_welds))
         call read_supports(ctx, model, lines_of(card_supports))
         call read_slidelines(ctx, model, lines_of(card_slidelines))
         call read_drives(ctx, model, lines_of(card_drives))
         call read_loads(ctx, model, lines_of(card_loads))
         call read_masses(ctx, model, lines_of(card_masses))
         call read_gravity(ctx, model, lines_of(card_gravity))
         call read_velocities(ctx, model, lines_of(card_velocities))
         call read_output(ctx, model, lines_of(card_output))
         call check_effects(ctx, model, lines_of(card_analysis))
         call refuse(card_joints, 'JOINts belong to a spatial deck', &
            & 'planar links meeting at a node are hinged there; '// &
            & 'for a spatial deck write ANALysis type kinematics spatial')
      end if

      ! The deck as a whole.
      last = ctx%source%nlines
      if (.not. ctx%source%terminated) then
         do i = 1, ctx%source%nlines
            if (ctx%source%lines(i)%file == 1 .and. ctx%source%lines(i)%number == ctx%source%last_line) last = i
         end do
         call ctx%error(last, size(ctx%source%lines(last)%tokens) + 1, 'unterminated deck: there is no END card', &
            & label='add END after the last block')
      end if
      if (model%analysis%spatial) then
         call require(card_nodes, 'NODEs', 'name x y z')
         call require(card_sections, 'SECTions', 'name EA=... GA2=... GA3=... GJ=... EI2=... EI3=...')
         call require(card_joints, 'JOINts', &
            & 'name kind first-node second-node|ground [axis x y z]')
      else
         call require(card_nodes, 'NODEs', 'name x y')
         call require(card_sections, 'SECTions', 'name E=... G=... A=... I=... k=...')
      end if
      call require(card_links, 'LINKs', 'name first-node second-node section')
      ! Masses move a mechanism by themselves (dynamics, under gravity).
      if (count(block == card_drives) + count(block == card_loads) == 0 .and. .not. has_masses(model)) then
         call ctx%error(last, 1, 'missing required block DRIVes or LOADs: nothing moves the mechanism', &
            & label='add DRIVes (e.g. rotation LINK rate 2*pi) or LOADs')
      end if
      if (size(model%links) > 0 .and. size(model%links) == count(block == card_links)) call check_nodes_used()

   contains

      !> The cards of a spatial deck (docs/deck-format.md, "Spatial decks");
      !> the planar-only cards are errors.
      subroutine read_spatial_deck()
         integer :: k
         integer, parameter :: planar_only(7) = [card_welds, card_supports, card_slidelines, card_loads, &
            & card_masses, card_gravity, card_velocities]
         call read_spatial_sections(ctx, model, lines_of(card_sections))
         call read_spatial_nodes(ctx, model, lines_of(card_nodes))
         call read_spatial_links(ctx, model, lines_of(card_links))
         call read_joints(ctx, model, lines_of(card_joints))
         call read_spatial_drives(ctx, model, lines_of(card_drives))
         call read_output(ctx, model, lines_of(card_output))
         do k = 1, size(planar_only)
            call refuse(planar_only(k), card_name(planar_only(k))//' is not a card of a spatial deck (yet)', &
               & 'a spatial deck has SECTions, NODEs, LINKs, JOINts, DRIVes, ANALysis, OUTPut: ground nodes by '// &
               & 'joints to ground, weld links by weld joints')
         end do
      end subroutine read_spatial_deck

      !> Every line of the card's blocks is an error: message, label.
      subroutine refuse(which, message, label)
         integer, intent(in) :: which
         character(*), intent(in) :: message, label
         integer :: k
         do k = 1, ctx%source%nlines
            if (block(k) == which) then
               call ctx%error(k, 1, message, label=label)
               exit
            end if
         end do
      end subroutine refuse

      function lines_of(which) result(lines)
         integer, intent(in) :: which
         integer, allocatable :: lines(:)
         lines = pack([(i, i=1, ctx%source%nlines)], block == which)
      end function lines_of

      subroutine require(which, name_, form)
         integer, intent(in) :: which
         character(*), intent(in) :: name_, form
         if (count(block == which) > 0) return
         if (seen(which)) then
            call ctx%error(last, 1, 'the '//name_//' block has no lines', label='add lines: '//form)
         else
            call ctx%error(last, 1, 'missing required block '//name_, label='add a '//name_//' block with lines: '//form)
         end if
      end subroutine require

      subroutine check_nodes_used()
         logical, allocatable :: used(:)
         integer :: k
         ! One pass over the links: a search of every link for each node would
         ! be quadratic in the deck's size.
         allocate (used(size(model%nodes)), source=.false.)
         do k = 1, size(model%links)
            used(model%links(k)%node) = .true.
         end do
         if (allocated(model%spatial%joints)) then
            ! A spatial node may be a joint's only (a slider block between a prismatic and a universal joint).
            do k = 1, size(model%spatial%joints)
               used(pack(model%spatial%joints(k)%node, model%spatial%joints(k)%node > 0)) = .true.
            end do
         end if
         do k = 1, size(model%nodes)
            if (used(k)) cycle
            call ctx%error_at(model%nodes(k)%loc, 'node '//model%nodes(k)%name//' is not on any link', &
               & label='connect it with a link (LINKs) or delete it')
         end do
      end subroutine check_nodes_used

   end subroutine interpret

   !> A lone word of 4 or more letters where data is expected: a misspelt card.
   pure logical function looks_like_keyword(field)
      character(*), intent(in) :: field
      integer :: i
      looks_like_keyword = len(field) >= 4 .and. card_of(field) == card_none
      do i = 1, len(field)
         looks_like_keyword = looks_like_keyword .and. &
            & ((field(i:i) >= 'a' .and. field(i:i) <= 'z') .or. (field(i:i) >= 'A' .and. field(i:i) <= 'Z'))
      end do
   end function looks_like_keyword

end module fekap_deck
