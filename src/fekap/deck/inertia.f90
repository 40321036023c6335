!> Reading the cards that give the mechanism's inertia and weight: MASSes
!> (point masses and rotary inertias at nodes) and GRAVity; and checking the
!> ANALysis type against the whole deck (see fekap_model_effects). The
!> sections' densities are read with the other section properties (SECTions).
module fekap_deck_inertia
   use fekap_kinds, only: dp
   use fekap_model, only: model_type, mass_type, effects_auto, effects_dynamics
   use fekap_model_effects, only: effects_plan_type, plan_effects, integrator_obstacle, effects_name
   use fekap_deck_context, only: context_type
   use fekap_deck_card, only: card_none, is_word_of
   use fekap_deck_geometry, only: has_end, welded, lookup_node, lookup_link
   implicit none
   private

   public :: read_masses, read_gravity, check_effects

   !> Largest magnitude of a mass, rotary inertia or gravity component.
   real(dp), parameter :: max_value = 1.0e100_dp

contains

   !> MASSes: `node m [J [LINK]]`: a point mass m at the node and a rotary
   !> inertia J on the end of LINK there (LINK may be left out when the links
   !> at the node are one rigid group: a single link, or links welded together).
   !> Several lines for one node add up.
   subroutine read_masses(ctx, model, lines)
      type(context_type), intent(inout) :: ctx
      type(model_type), intent(inout) :: model
      integer, intent(in) :: lines(:)
      character(*), parameter :: form = 'node m [J [LINK]]'
      type(mass_type), allocatable :: list(:)
      integer :: n, i, iline, node, link, j
      logical :: ok, fine
      allocate (list(size(lines)))
      n = 0
      do i = 1, size(lines)
         iline = lines(i)
         if (.not. ctx%require(iline, form, 'a MASSes line')) cycle
         if (ctx%nfields(iline) > 4) then
            call ctx%error(iline, 5, "unexpected field '"//ctx%field(iline, 5)//"'", label='a MASSes line is: '//form)
            cycle
         end if
         node = lookup_node(ctx, iline, 1)
         ok = node > 0
         n = n + 1
         list(n) = mass_type()   ! the slot may hold a dropped entry
         list(n)%loc = ctx%loc(iline, 1)
         list(n)%node = node
         call read_value(2, 'mass', list(n)%mass, fine)
         ok = ok .and. fine
         if (ctx%nfields(iline) >= 3) then
            call read_value(3, 'rotary inertia', list(n)%inertia, fine)
            ok = ok .and. fine
         end if
         if (ok .and. list(n)%mass == 0 .and. list(n)%inertia == 0) then
            call ctx%error(iline, 2, 'a mass of zero does nothing', label='give m > 0 or J > 0, or delete the line')
            ok = .false.
         end if
         if (node > 0) then
            if (.not. any([(has_end(model, j, node), j=1, size(model%links))])) then
               call ctx%error(iline, 1, 'node '//model%nodes(node)%name//' has no link to carry the mass', &
                  & label='a mass sits at a link end: connect the node with a link (LINKs)')
               ok = .false.
            end if
         end if
         if (ctx%nfields(iline) == 4) then
            link = lookup_link(ctx, iline, 4)
            if (link > 0 .and. node > 0) then
               if (.not. has_end(model, link, node)) then
                  call ctx%error(iline, 4, 'link '//model%links(link)%name//' has no end at node '// &
                     & model%nodes(node)%name, label='J turns with the end of LINK at the node')
                  link = 0
               end if
            end if
            ok = ok .and. link > 0
            list(n)%link = link
         else if (ok .and. list(n)%inertia > 0) then
            list(n)%link = only_group(node)
            if (list(n)%link == 0) then
               call ctx%error(iline, 3, 'which link end turns with the rotary inertia at node '// &
                  & model%nodes(node)%name//'?', label='links are hinged there: write node m J LINK')
               ok = .false.
            end if
         end if
         if (.not. ok) n = n - 1
      end do
      model%masses = list(:n)

   contains

      !> Field itok as a value >= 0 (and at most max_value).
      subroutine read_value(itok, what, value, good)
         integer, intent(in) :: itok
         character(*), intent(in) :: what
         real(dp), intent(out) :: value
         logical, intent(out) :: good
         call ctx%real_field(iline, itok, value, good)
         if (.not. good) return
         if (value < 0) then
            call ctx%error(iline, itok, 'negative '//what, label='a '//what//' is positive or zero')
            good = .false.
         else if (value > max_value) then
            call ctx%error(iline, itok, what//' too large', label='at most 1e100')
            good = .false.
         end if
      end subroutine read_value

      !> A link at node whose end there turns with every other link's end
      !> there (all welded to it), or 0 if the links there are hinged.
      integer function only_group(node_) result(link_)
         integer, intent(in) :: node_
         integer :: k
         link_ = 0
         do k = 1, size(model%links)
            if (.not. has_end(model, k, node_)) cycle
            if (link_ == 0) then
               link_ = k
            else if (.not. welded(model, link_, k)) then
               link_ = 0
               return
            end if
         end do
      end function only_group

   end subroutine read_masses

   !> GRAVity GX GY, on the card's own line (the acceleration of gravity).
   subroutine read_gravity(ctx, model, lines)
      type(context_type), intent(inout) :: ctx
      type(model_type), intent(inout) :: model
      !> The GRAVity card lines and any data lines after them.
      integer, intent(in) :: lines(:)
      integer :: i, iline, k, first
      real(dp) :: g(2)
      logical :: ok, fine
      first = 0
      do i = 1, size(lines)
         iline = lines(i)
         if (ctx%source%lines(iline)%card == card_none) then
            call ctx%error(iline, 1, 'data line after GRAVity', label='GRAVity takes its values on its own line: '// &
               & 'GRAVity GX GY')
            cycle
         end if
         if (first > 0) then
            call ctx%error_at(ctx%loc(iline, 1), 'gravity is given twice', label='keep one GRAVity card', &
               & note_loc=ctx%loc(first, 1), note='first given here')
            cycle
         end if
         first = iline
         if (ctx%nfields(iline) /= 3) then
            call ctx%error(iline, min(ctx%nfields(iline) + 1, 4), 'GRAVity takes two values', &
               & label='GRAVity GX GY, e.g. GRAVity 0 -9.81')
            cycle
         end if
         ok = .true.
         do k = 1, 2
            call ctx%real_field(iline, k + 1, g(k), fine)
            if (fine .and. abs(g(k)) > max_value) then
               call ctx%error(iline, k + 1, 'gravity too large', label='at most 1e100 in magnitude')
               fine = .false.
            end if
            ok = ok .and. fine
         end do
         if (.not. ok) cycle
         model%gravity = g
         model%gravity_loc = ctx%loc(iline, 1)
      end do
   end subroutine read_gravity

   !> The ANALysis type against the deck: a type that cannot run is an error
   !> at its line (the last type line of the ANALysis lines `lines`); a
   !> scene that auto finds asking for an analysis that cannot run is an
   !> error at its first mass.
   subroutine check_effects(ctx, model, lines)
      type(context_type), intent(inout) :: ctx
      type(model_type), intent(in) :: model
      integer, intent(in) :: lines(:)
      type(effects_plan_type) :: plan
      integer :: i, type_line
      type_line = 0
      do i = 1, size(lines)
         if (is_word_of(ctx%field(lines(i), 1), 'type', 4)) type_line = lines(i)
      end do
      plan = plan_effects(model)
      if (model%analysis%adaptive .and. len(plan%problem) == 0 .and. plan%effects /= effects_dynamics) then
         call ctx%error_at(model%analysis%adaptive_loc, 'adaptive steps are for dynamics: this deck runs '// &
            & effects_name(plan%effects), label='remove `adaptive TOL`, or give the links masses (ANALysis type dynamics)')
      end if
      if (len(plan%problem) == 0) return
      if (len(integrator_obstacle(model)) > 0 .and. model%analysis%integrator_loc%line > 0) then
         if (index(plan%problem, integrator_obstacle(model)) > 0) then
            call ctx%error_at(model%analysis%integrator_loc, integrator_obstacle(model), &
               & label='integrator generalized-alpha covers them')
            return
         end if
      end if
      if (type_line > 0 .and. model%analysis%effects /= effects_auto) then
         call ctx%error(type_line, 2, plan%problem, label='ANALysis type auto|kinematics|kinetostatics|statics|dynamics')
      else if (allocated(model%masses)) then
         if (size(model%masses) > 0) then
            call ctx%error_at(model%masses(1)%loc, plan%problem, label='or set ANALysis type')
            return
         end if
         call at_section()
      else
         call at_section()
      end if

   contains

      !> The problem at the first section with a density.
      subroutine at_section()
         integer :: k
         do k = 1, size(model%sections)
            if (model%sections(k)%rho_a > 0) then
               call ctx%error_at(model%sections(k)%loc, plan%problem, label='or set ANALysis type')
               return
            end if
         end do
      end subroutine at_section

   end subroutine check_effects

end module fekap_deck_inertia
