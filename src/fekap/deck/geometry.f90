!> Reading the cards that define the mechanism's geometry: SECTions, NODEs,
!> LINKs, WELDs and SUPPorts. Each procedure reads all data lines of its card
!> (all blocks, in deck order), reports bad lines and keeps the good ones.
module fekap_deck_geometry
   use fekap_kinds, only: dp
   use fekap_model, only: model_type, section_type, node_type, link_type, weld_type, support_type, &
      & model_size, dof_x, dof_y, dof_rot
   use fekap_deck_card, only: is_word_of
   use fekap_strings, only: lower, same_name, int_text
   use fekap_deck_name_index, only: new_name_index
   use fekap_deck_context, only: context_type
   use fekap_deck_safe_arithmetic, only: safe_multiply
   implicit none
   private

   public :: read_sections, read_nodes, read_links, read_welds, read_supports
   public :: has_end, welded, lookup_node, lookup_link, too_many

   !> Links shorter than this times the model size have zero length.
   real(dp), parameter :: zero_length = 1.0e-12_dp
   !> Largest magnitude of a coordinate (keeps lengths and the model size finite).
   real(dp), parameter, public :: max_coordinate = 1.0e100_dp
   !> Range of section properties and of the stiffnesses EA, kGA, EI derived
   !> from them: beyond it the solver's arithmetic would overflow or underflow.
   real(dp), parameter :: min_property = 1.0e-100_dp, max_property = 1.0e100_dp
   !> Most elements per link.
   integer, parameter :: max_elements = 100000
   !> Most elements in a deck: a run takes about 3.2 KB of memory an element
   !> (947 MB for three links of 100,000), so this is about 3 GB; more ended
   !> in the runtime's own allocation error and a backtrace, or in the
   !> system's out-of-memory killer.
   integer, parameter :: max_total_elements = 1000000

contains

   !> SECTions: `name E= G= A= I= [k=]` (k defaults to 5/6) or `name EA= kGA= EI=`,
   !> and optionally a density: `rho=` (mass per length rho*A, rotary inertia
   !> per length rho*I), or `rhoA=` and optionally `rhoI=` directly.
   subroutine read_sections(ctx, model, lines)
      type(context_type), intent(inout) :: ctx
      type(model_type), intent(inout) :: model
      !> The card's data lines (indices into ctx%source%lines).
      integer, intent(in) :: lines(:)
      character(*), parameter :: keys(13) = [character(len=5) :: 'e', 'g', 'a', 'i', 'k', 'ea', 'kga', 'ei', &
         & 'rho', 'rhoa', 'rhoi', 'alpha', 'beta']
      character(*), parameter :: form = 'name E=... G=... A=... I=... [k=...]  or  name EA=... kGA=... EI=...'
      type(section_type), allocatable :: list(:)
      real(dp) :: value(13), v
      logical :: given(13), ok, good
      integer :: n, i, k, iline, eq, key, ikey(13), prev
      character(:), allocatable :: field
      allocate (list(size(lines)))
      n = 0
      do i = 1, size(lines)
         iline = lines(i)
         if (.not. ctx%name_field(iline, 1, 'section')) cycle
         if (.not. ctx%require(iline, 'name property=value', 'a SECTions line')) cycle
         given = .false.
         value = 0
         good = .true.
         ikey = 0
         do k = 2, ctx%nfields(iline)
            field = ctx%field(iline, k)
            eq = index(field, '=')
            if (eq <= 1) then
               call ctx%error(iline, k, "expected PROPERTY=VALUE, not '"//field//"'", &
                  & label='properties: E= G= A= I= k= EA= kGA= EI= rho= rhoA= rhoI= alpha= beta= (no blanks around =)')
               good = .false.
               cycle
            end if
            key = findloc(keys, lower(field(:eq - 1)), 1)
            if (key == 0) then
               call ctx%error(iline, k, "unknown section property '"//field(:eq - 1)//"'", &
                  & label='properties: E= G= A= I= k= EA= kGA= EI= rho= rhoA= rhoI= alpha= beta=')
               good = .false.
               cycle
            end if
            if (given(key)) then
               call ctx%error(iline, k, "property '"//field(:eq - 1)//"' given twice on this line")
               good = .false.
               cycle
            end if
            call ctx%real_field(iline, k, v, ok, text=field(eq + 1:))
            if (.not. ok) then
               good = .false.
               cycle
            end if
            if (key >= 12 .and. v < 0) then
               ! Rayleigh damping: zero is no damping.
               call ctx%error(iline, k, 'negative Rayleigh damping '//field(:eq - 1), &
                  & label='C = alpha M + beta K with alpha >= 0 and beta >= 0 (0: undamped)')
               good = .false.
               cycle
            else if (key >= 12 .and. v > max_property) then
               call ctx%error(iline, k, 'section property '//field(:eq - 1)//' out of range', &
                  & label='between 0 and 1e100')
               good = .false.
               cycle
            else if (key >= 12) then
               given(key) = .true.
               value(key) = v
               ikey(key) = k
               cycle
            end if
            if (key == 11 .and. v == 0) then
               ! rhoI=0: no rotary inertia (as rhoI= left out); needs rhoA= as any rhoI=.
               given(key) = .true.
               value(key) = 0
               ikey(key) = k
               cycle
            end if
            if (v <= 0) then
               call ctx%error(iline, k, 'non-positive section property '//field(:eq - 1), &
                  & label='section properties must be positive')
               good = .false.
               cycle
            end if
            if (v < min_property .or. v > max_property) then
               call ctx%error(iline, k, 'section property '//field(:eq - 1)//' out of range', &
                  & label='between 1e-100 and 1e100')
               good = .false.
               cycle
            end if
            given(key) = .true.
            value(key) = v
            ikey(key) = k
         end do
         ! A section with bad properties is kept (with zero stiffness) so that
         ! links naming it do not report it as undefined.
         n = n + 1
         list(n) = section_type()   ! the slot may hold a dropped entry
         list(n)%name = ctx%field(iline, 1)
         list(n)%loc = ctx%loc(iline, 1)
         if (good) then
            call derive(list(n)%ea, 6, [1, 3], 'EA', 'E= and A=')
            call derive(list(n)%kga, 7, [5, 2, 3], 'kGA', 'k=, G= and A= (k defaults to 5/6)')
            call derive(list(n)%ei, 8, [1, 4], 'EI', 'E= and I=')
            call derive_density()
            list(n)%alpha = value(12)
            list(n)%beta = value(13)
            if (any([list(n)%ea, list(n)%kga, list(n)%ei] > max_property) .or. &
               & any([list(n)%ea, list(n)%kga, list(n)%ei] < min_property .and. &
               & [list(n)%ea, list(n)%kga, list(n)%ei] > 0)) then
               call ctx%error(iline, 1, 'section stiffness out of range', &
                  & label='EA, kGA and EI must lie between 1e-100 and 1e100')
            end if
         end if
         prev = find_section_in(list(:n - 1), list(n)%name)
         if (prev > 0) then
            call ctx%error_at(list(n)%loc, "duplicate section name '"//list(n)%name//"'", &
               & note_loc=list(prev)%loc, note='first defined here')
            n = n - 1
         end if
      end do
      model%sections = list(:n)

   contains

      !> rho*A and rho*I from rho= (which needs A= and I=), or rhoA= [rhoI=].
      subroutine derive_density()
         logical :: fine
         if (given(9) .and. (given(10) .or. given(11))) then
            call ctx%error(iline, ikey(9), 'the density is given both as rho= and as rhoA=/rhoI=', &
               & label='give rho= (with A= and I=) or rhoA= [rhoI=]')
            good = .false.
         else if (given(9)) then
            if (.not. (given(3) .and. given(4))) then
               call ctx%error(iline, ikey(9), 'rho= needs A= and I= on the line (rhoA = rho*A, rhoI = rho*I)', &
                  & label='give A= and I=, or rhoA= [rhoI=] directly')
               good = .false.
               return
            end if
            call safe_multiply(value(9), value(3), list(n)%rho_a, fine)
            if (fine) call safe_multiply(value(9), value(4), list(n)%rho_i, fine)
            if (.not. fine .or. list(n)%rho_a > max_property .or. list(n)%rho_i > max_property .or. &
               & list(n)%rho_a < min_property .or. list(n)%rho_i < min_property) then
               call ctx%error(iline, ikey(9), 'section '//ctx%field(iline, 1)//': rho*A or rho*I out of range', &
                  & label='rhoA and rhoI must lie between 1e-100 and 1e100')
               good = .false.
            end if
         else if (given(11) .and. .not. given(10)) then
            call ctx%error(iline, ikey(11), 'rhoI= without rhoA=', label='give the mass per length rhoA= too')
            good = .false.
         else
            list(n)%rho_a = value(10)
            list(n)%rho_i = value(11)
         end if
      end subroutine derive_density

      !> A stiffness given directly (value(direct)) or as the product of others.
      subroutine derive(stiffness, direct, factors, what, how)
         real(dp), intent(out) :: stiffness
         integer, intent(in) :: direct, factors(:)
         character(*), intent(in) :: what, how
         integer :: j
         logical :: all_given, any_given, fine
         real(dp) :: factor, product
         stiffness = 0
         all_given = .true.
         any_given = .false.
         do j = 1, size(factors)
            if (factors(j) == 5) cycle   ! k has a default
            all_given = all_given .and. given(factors(j))
            any_given = any_given .or. given(factors(j))
         end do
         if (given(direct)) then
            if (all_given) then
               call ctx%error(iline, ikey(direct), what//' is given both directly and as '//how, &
                  & label='give one or the other')
               good = .false.
            end if
            stiffness = value(direct)
            return
         end if
         if (.not. all_given) then
            call ctx%error(iline, 1, 'section '//ctx%field(iline, 1)//' has no '//what, &
               & label='give '//what//'= or '//how)
            good = .false.
            return
         end if
         stiffness = 1
         do j = 1, size(factors)
            factor = value(factors(j))
            if (factors(j) == 5 .and. .not. given(5)) factor = 5.0_dp/6
            call safe_multiply(stiffness, factor, product, fine)
            stiffness = product
            if (.not. fine) then
               call ctx%error(iline, 1, 'section '//ctx%field(iline, 1)//': '//what//' is not a finite number', &
                  & label='the product '//how//' overflows')
               good = .false.
               return
            end if
         end do
      end subroutine derive

   end subroutine read_sections

   !> NODEs: `name x y`.
   subroutine read_nodes(ctx, model, lines)
      type(context_type), intent(inout) :: ctx
      type(model_type), intent(inout) :: model
      integer, intent(in) :: lines(:)
      type(node_type), allocatable :: list(:)
      integer :: n, i, iline, j
      logical :: okx, oky, malformed
      allocate (list(size(lines)))
      call new_name_index(ctx%nodes, size(lines))
      call new_name_index(ctx%dropped_nodes, size(lines))
      n = 0
      do i = 1, size(lines)
         iline = lines(i)
         if (.not. ctx%name_field(iline, 1, 'node')) cycle
         malformed = .not. ctx%require(iline, 'name x y', 'a NODEs line')
         if (.not. malformed) malformed = too_many(ctx, iline, 3, 'name x y', 'a NODEs line')
         if (malformed) then
            call ctx%dropped_nodes%insert(ctx%field(iline, 1), 1, j)
            cycle
         end if
         n = n + 1
         list(n) = node_type()   ! the slot may hold a dropped entry
         list(n)%name = ctx%field(iline, 1)
         list(n)%loc = ctx%loc(iline, 1)
         ! A node with a bad coordinate is kept so that links naming it do not
         ! report it as undefined.
         call ctx%real_field(iline, 2, list(n)%x(1), okx)
         call ctx%real_field(iline, 3, list(n)%x(2), oky)
         do j = 1, 2
            if (abs(list(n)%x(j)) > max_coordinate) then
               call ctx%error(iline, j + 1, 'coordinate too large', label='at most 1e100 in magnitude')
               list(n)%x(j) = 0
            end if
         end do
         call ctx%nodes%insert(list(n)%name, n, j)
         if (j > 0) then
            call ctx%error_at(list(n)%loc, "duplicate node name '"//list(n)%name//"'", &
               & label='each node needs its own name', note_loc=list(j)%loc, note='first defined here')
            n = n - 1
         end if
      end do
      model%nodes = list(:n)
   end subroutine read_nodes

   !> LINKs: `name first-node second-node section [number-of-elements]`.
   subroutine read_links(ctx, model, lines)
      type(context_type), intent(inout) :: ctx
      type(model_type), intent(inout) :: model
      integer, intent(in) :: lines(:)
      character(*), parameter :: form = 'name first-node second-node section [elements]'
      type(link_type), allocatable :: list(:)
      integer :: n, i, iline, j, k, total
      logical :: ok, keep, fine
      real(dp) :: length, size_
      allocate (list(size(lines)))
      call new_name_index(ctx%links, size(lines))
      call new_name_index(ctx%dropped_links, size(lines))
      size_ = model_size(model)
      n = 0
      total = 0
      do i = 1, size(lines)
         iline = lines(i)
         if (.not. ctx%name_field(iline, 1, 'link')) cycle
         fine = ctx%require(iline, form, 'a LINKs line')
         if (fine) fine = .not. too_many(ctx, iline, 5, form, 'a LINKs line')
         if (.not. fine) then
            call ctx%dropped_links%insert(ctx%field(iline, 1), 1, j)
            cycle
         end if
         n = n + 1
         list(n) = link_type()   ! the slot may hold a dropped entry
         list(n)%name = ctx%field(iline, 1)
         list(n)%loc = ctx%loc(iline, 1)
         ok = .true.
         do k = 1, 2
            list(n)%node(k) = lookup_node(ctx, iline, k + 1)
            ok = ok .and. list(n)%node(k) > 0
         end do
         ! Links with bad sections or element counts are kept (no cascade of
         ! undefined-link errors); links without both nodes are not.
         keep = ok
         list(n)%section = 0
         do j = 1, size(model%sections)
            if (same_name(model%sections(j)%name, ctx%field(iline, 4))) list(n)%section = j
         end do
         if (list(n)%section == 0) then
            call ctx%error(iline, 4, "undefined section '"//ctx%field(iline, 4)//"'", &
               & label='define it in SECTions')
         end if
         if (ctx%nfields(iline) >= 5) then
            call ctx%integer_field(iline, 5, list(n)%nelem, fine)
            if (fine .and. list(n)%nelem < 1) then
               call ctx%error(iline, 5, 'number of elements must be at least 1', &
                  & label='give a whole number from 1 to '//int_text(max_elements))
            else if (fine .and. list(n)%nelem > max_elements) then
               call ctx%error(iline, 5, 'too many elements: a link has at most '//int_text(max_elements), &
                  & label='give a whole number from 1 to '//int_text(max_elements))
            else if (fine .and. total <= max_total_elements) then
               total = total + list(n)%nelem
               if (total > max_total_elements) then
                  call ctx%error(iline, 5, 'too many elements in all: the links up to this one have '// &
                     & int_text(total)//', more than a deck''s '//int_text(max_total_elements)// &
                     & ' (about 3 KB of memory each)', label='mesh the links more coarsely')
               end if
            end if
         end if
         if (ok .and. list(n)%node(1) == list(n)%node(2)) then
            call ctx%error(iline, 3, 'link '//list(n)%name//' joins node '//ctx%field(iline, 2)//' to itself', &
               & label='a link joins two different nodes')
            keep = .false.
         else if (ok) then
            length = norm2(model%nodes(list(n)%node(2))%x - model%nodes(list(n)%node(1))%x)
            if (length < zero_length*size_) then
               call ctx%error(iline, 1, 'zero-length link '//list(n)%name//': nodes '//ctx%field(iline, 2)// &
                  & ' and '//ctx%field(iline, 3)//' are at the same place', &
                  & label='move one of the nodes (see NODEs)')
            end if
         end if
         if (keep) then
            call ctx%links%insert(list(n)%name, n, j)
            if (j > 0) then
               call ctx%error_at(list(n)%loc, "duplicate link name '"//list(n)%name//"'", &
                  & label='each link needs its own name', note_loc=list(j)%loc, note='first defined here')
               keep = .false.
            end if
         else
            call ctx%dropped_links%insert(list(n)%name, 1, j)
         end if
         if (.not. keep) n = n - 1
      end do
      model%links = list(:n)
   end subroutine read_links

   !> WELDs: `node link link ...` (these links' end rotations at node are one unknown).
   subroutine read_welds(ctx, model, lines)
      type(context_type), intent(inout) :: ctx
      type(model_type), intent(inout) :: model
      integer, intent(in) :: lines(:)
      character(*), parameter :: form = 'node link link [link ...]'
      type(weld_type), allocatable :: list(:)
      !> (2, nlink): the weld (index in list) that holds each link end, 0 if none,
      !> so that a link welded twice at one node is found in constant time.
      integer, allocatable :: weld_of_end(:, :)
      integer :: n, i, iline, k, j, link, node, e
      logical :: ok
      allocate (list(size(lines)))
      allocate (weld_of_end(2, size(model%links)), source=0)
      n = 0
      do i = 1, size(lines)
         iline = lines(i)
         if (.not. ctx%require(iline, form, 'a WELDs line')) cycle
         node = lookup_node(ctx, iline, 1)
         if (node == 0) cycle
         n = n + 1
         list(n) = weld_type()   ! the slot may hold a dropped entry
         list(n)%node = node
         list(n)%loc = ctx%loc(iline, 1)
         allocate (list(n)%links(0))
         ok = .true.
         do k = 2, ctx%nfields(iline)
            link = lookup_link(ctx, iline, k)
            if (link == 0) then
               ok = .false.
               cycle
            end if
            if (.not. has_end(model, link, node)) then
               call ctx%error(iline, k, 'link '//model%links(link)%name//' has no end at node '// &
                  & model%nodes(node)%name, label='a weld joins links that meet at its node')
               ok = .false.
               cycle
            end if
            if (any(list(n)%links == link)) then
               call ctx%error(iline, k, 'link '//model%links(link)%name//' is listed twice')
               ok = .false.
               cycle
            end if
            e = merge(1, 2, model%links(link)%node(1) == node)
            j = weld_of_end(e, link)
            if (j > 0) then
               call ctx%error_at(ctx%loc(iline, k), 'link '//model%links(link)%name//' is already welded at node '// &
                  & model%nodes(node)%name, label='list all links of one rigid joint on one WELDs line', &
                  & note_loc=list(j)%loc, note='welded here')
               ok = .false.
            end if
            list(n)%links = [list(n)%links, link]
         end do
         if (ok .and. size(list(n)%links) < 2) then
            call ctx%error(iline, 3, 'a weld joins at least two links', label=form)
            ok = .false.
         end if
         if (ok) then
            do k = 1, size(list(n)%links)
               link = list(n)%links(k)
               weld_of_end(merge(1, 2, model%links(link)%node(1) == node), link) = n
            end do
         else
            n = n - 1
         end if
      end do
      model%welds = list(:n)
   end subroutine read_welds

   !> SUPPorts: `node fixed ...` with fixed any of pin (= x y), x, y, rot [LINK].
   !> Several lines for one node are merged into one support; a node clamps at most one link.
   subroutine read_supports(ctx, model, lines)
      type(context_type), intent(inout) :: ctx
      type(model_type), intent(inout) :: model
      integer, intent(in) :: lines(:)
      type(support_type), allocatable :: list(:)
      integer :: n, i, iline, k, node, s, link, j, nlinks, last
      character(:), allocatable :: word
      allocate (list(size(lines)))
      n = 0
      do i = 1, size(lines)
         iline = lines(i)
         if (.not. ctx%require(iline, 'node what-is-fixed', 'a SUPPorts line')) cycle
         node = lookup_node(ctx, iline, 1)
         if (node == 0) cycle
         s = 0
         do j = 1, n
            if (list(j)%node == node) s = j
         end do
         if (s == 0) then
            n = n + 1
            list(n) = support_type()   ! the slot may hold a dropped entry
            s = n
            list(s)%node = node
            list(s)%loc = ctx%loc(iline, 1)
         end if
         k = 2
         do while (k <= ctx%nfields(iline))
            word = lower(ctx%field(iline, k))
            select case (word)
            case ('pin')
               list(s)%fix(dof_x:dof_y) = .true.
            case ('x')
               list(s)%fix(dof_x) = .true.
            case ('y')
               list(s)%fix(dof_y) = .true.
            case ('rot', 'rotation')
               link = 0
               if (k < ctx%nfields(iline)) then
                  select case (lower(ctx%field(iline, k + 1)))
                  case ('pin', 'x', 'y', 'rot', 'rotation')
                  case default
                     k = k + 1
                     link = lookup_link(ctx, iline, k)
                     if (link == 0) then
                        k = k + 1
                        cycle
                     end if
                  end select
               end if
               if (link == 0) then
                  ! Without a link name: the node's only link.
                  nlinks = 0
                  do j = 1, size(model%links)
                     if (has_end(model, j, node)) then
                        nlinks = nlinks + 1
                        last = j
                     end if
                  end do
                  if (nlinks /= 1) then
                     call ctx%error(iline, k, 'which link''s rotation does rot fix at node '//model%nodes(node)%name//'?', &
                        & label='write rot LINK')
                     k = k + 1
                     cycle
                  end if
                  link = last
               end if
               if (.not. has_end(model, link, node)) then
                  call ctx%error(iline, k, 'link '//model%links(link)%name//' has no end at node '// &
                     & model%nodes(node)%name, label='rot LINK clamps the end of LINK at the supported node')
               else if (list(s)%fix(dof_rot) .and. list(s)%link /= link) then
                  call ctx%error_at(ctx%loc(iline, k), 'node '//model%nodes(node)%name//' already clamps link '// &
                     & model%links(list(s)%link)%name, label='clamp one link and weld the others to it (WELDs)', &
                     & note_loc=list(s)%loc, note='support of '//model%nodes(node)%name//' defined here')
               else
                  list(s)%fix(dof_rot) = .true.
                  list(s)%link = link
               end if
            case default
               call ctx%error(iline, k, "unknown support '"//ctx%field(iline, k)//"'", &
                  & label='allowed: pin (= x y) | x | y | rot LINK')
            end select
            k = k + 1
         end do
      end do
      model%supports = list(:n)
   end subroutine read_supports

   !> The node named by field itok, or 0 after reporting an undefined one.
   integer function lookup_node(ctx, iline, itok) result(node)
      type(context_type), intent(inout) :: ctx
      integer, intent(in) :: iline, itok
      node = ctx%nodes%find(ctx%field(iline, itok))
      if (node /= 0) return
      ! A node whose own line was reported needs no second error here.
      if (ctx%dropped_nodes%find(ctx%field(iline, itok)) /= 0) return
      call ctx%error(iline, itok, "undefined node '"//ctx%field(iline, itok)//"'", label='define it in NODEs')
   end function lookup_node

   !> The link named by field itok, or 0 after reporting an undefined one.
   integer function lookup_link(ctx, iline, itok) result(link)
      type(context_type), intent(inout) :: ctx
      integer, intent(in) :: iline, itok
      link = ctx%links%find(ctx%field(iline, itok))
      if (link /= 0) return
      ! A link whose own line was reported (or a node of it) needs no second error here.
      if (ctx%dropped_links%find(ctx%field(iline, itok)) /= 0) return
      call ctx%error(iline, itok, "undefined link '"//ctx%field(iline, itok)//"'", label='define it in LINKs')
   end function lookup_link


   !> Whether link has an end at node.
   pure logical function has_end(model, link, node)
      type(model_type), intent(in) :: model
      integer, intent(in) :: link, node
      has_end = any(model%links(link)%node == node)
   end function has_end

   !> Whether links a and b are welded to each other at some node.
   pure logical function welded(model, a, b)
      type(model_type), intent(in) :: model
      integer, intent(in) :: a, b
      integer :: i
      welded = .false.
      if (.not. allocated(model%welds)) return
      do i = 1, size(model%welds)
         welded = welded .or. (any(model%welds(i)%links == a) .and. any(model%welds(i)%links == b))
      end do
   end function welded

   !> Whether a line has more than nmax fields (reports the first extra one).
   logical function too_many(ctx, iline, nmax, form, what)
      type(context_type), intent(inout) :: ctx
      integer, intent(in) :: iline, nmax
      character(*), intent(in) :: form, what
      too_many = ctx%nfields(iline) > nmax
      if (too_many) call ctx%error(iline, nmax + 1, "unexpected field '"//ctx%field(iline, nmax + 1)//"'", &
         & label=what//' is: '//form)
   end function too_many

   pure integer function find_section_in(list, name) result(idx)
      type(section_type), intent(in) :: list(:)
      character(*), intent(in) :: name
      integer :: i
      idx = 0
      do i = 1, size(list)
         if (same_name(list(i)%name, name)) then
            idx = i
            return
         end if
      end do
   end function find_section_in

end module fekap_deck_geometry
