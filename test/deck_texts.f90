!> Deck text shared by the deck suites: a minimal good deck and Example 1's
!> four-bar, around which bad-input tests vary one thing.
module test_deck_texts
   implicit none
   private

   public :: nl, base_head, with_base, fourbar

   character(*), parameter :: nl = new_line('a')

   !> Sections, nodes A and B, and the link AB (7 lines).
   character(*), parameter :: base_head = 'SECTions'//nl//' bar E=1 G=1 A=100 I=1 k=5/6'//nl// &
      & 'NODEs'//nl//' A 0 0'//nl//' B 2 0'//nl//'LINKs'//nl//' AB A B bar'//nl

   !> Example 1's geometry (after its section line), a crank drive.
   character(*), parameter :: nodes_links = 'NODEs'//nl//' A 0 0'//nl//' B 2 0'//nl//' C 3 sqrt(15)'//nl// &
      & ' D 4 0'//nl//'LINKs'//nl//' AB A B bar'//nl//' BC B C bar'//nl//' DC D C bar'//nl// &
      & 'SUPPorts'//nl//' A pin'//nl//' D pin'//nl//'DRIVes'//nl//' rotation AB rate 2*pi'//nl

contains

   !> Example 1's four-bar with one section `bar` whose properties follow
   !> `section` (line 2), then `rest` (cards, from line 17), and END.
   pure function fourbar(section, rest) result(text)
      character(*), intent(in) :: section, rest
      character(:), allocatable :: text
      text = 'SECTions'//nl//' bar '//section//nl//nodes_links//rest//'END'//nl
   end function fourbar

   !> The deck base_head plus `rest` plus END, with a drive.
   pure function with_base(rest) result(text)
      character(*), intent(in) :: rest
      character(:), allocatable :: text
      text = base_head//'SUPPorts'//nl//' A pin'//nl//rest//'DRIVes'//nl//' rotation AB rate 1'//nl//'END'//nl
   end function with_base

end module test_deck_texts
