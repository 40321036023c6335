!> The deck's card keywords and FEAP-style keyword matching: a card is the first
!> field of a line, at least 4 letters long, that is a prefix of a card keyword
!> (COOR, COORD and COORDINATES all match COORDINATES; COORX does not). END is
!> matched in full.
module fekap_deck_card
   use fekap_strings, only: lower, upper, is_word_of
   implicit none
   private

   public :: card_of, card_name, card_list, is_word_of

   integer, parameter, public :: card_none = 0, card_title = 1, card_sections = 2, card_nodes = 3, &
      & card_links = 4, card_welds = 5, card_supports = 6, card_drives = 7, card_loads = 8, &
      & card_slidelines = 9, card_analysis = 10, card_output = 11, card_include = 12, card_end = 13, &
      & card_parameters = 14, card_masses = 15, card_gravity = 16, card_velocities = 17, &
      & card_joints = 18
   !> Number of distinct cards.
   integer, parameter, public :: ncards = 18

   !> Keywords (upper case) and the card each selects; aliases share a card.
   character(*), parameter :: keywords(20) = [character(len=11) :: 'TITLE', 'SECTIONS', 'NODES', &
      & 'COORDINATES', 'LINKS', 'ELEMENTS', 'WELDS', 'SUPPORTS', 'BOUNDARY', 'DRIVES', 'LOADS', &
      & 'SLIDELINES', 'ANALYSIS', 'OUTPUT', 'INCLUDE', 'PARAMETERS', 'MASSES', 'GRAVITY', 'VELOCITIES', &
      & 'JOINTS']
   integer, parameter :: keyword_card(20) = [card_title, card_sections, card_nodes, card_nodes, &
      & card_links, card_links, card_welds, card_supports, card_supports, card_drives, card_loads, &
      & card_slidelines, card_analysis, card_output, card_include, card_parameters, card_masses, card_gravity, &
      & card_velocities, card_joints]
   !> Names for messages: the capital letters are the shortest accepted form.
   character(*), parameter :: display(ncards) = [character(len=10) :: 'TITLe', 'SECTions', 'NODEs', &
      & 'LINKs', 'WELDs', 'SUPPorts', 'DRIVes', 'LOADs', 'SLIDelines', 'ANALysis', 'OUTPut', &
      & 'INCLude', 'END', 'PARAmeters', 'MASSes', 'GRAVity', 'VELOcities', &
      & 'JOINts']

contains

   !> The card that `field` selects, or card_none.
   pure integer function card_of(field) result(card)
      character(*), intent(in) :: field
      integer :: i
      character(len(field)) :: up
      card = card_none
      up = upper(field)
      if (up == 'END') then
         card = card_end
         return
      end if
      if (len(field) < 4 .or. len(field) > len(keywords)) return
      do i = 1, len(field)
         if (.not. (up(i:i) >= 'A' .and. up(i:i) <= 'Z')) return
      end do
      do i = 1, size(keywords)
         if (keywords(i)(1:len(field)) == up) then
            card = keyword_card(i)
            return
         end if
      end do
   end function card_of

   !> The card's name for messages (TITLe, NODEs, ...).
   pure function card_name(card) result(name)
      integer, intent(in) :: card
      character(:), allocatable :: name
      if (card >= 1 .and. card <= ncards) then
         name = trim(display(card))
      else
         name = '(none)'
      end if
   end function card_name

   !> All card names, blank-separated, with their aliases.
   pure function card_list() result(list)
      character(:), allocatable :: list
      list = 'TITLe PARAmeters SECTions NODEs (COORdinates) LINKs (ELEMents) WELDs SUPPorts (BOUNdary) DRIVes ' &
         & //'LOADs MASSes GRAVity VELOcities SLIDelines JOINts ANALysis OUTPut INCLude END'
   end function card_list

end module fekap_deck_card
