!> The example decks of decks/, for the suites that run over all of them.
module test_example_decks
   use fekap_error, only: error_type, fatal_error
   use fekap_model, only: model_type
   use fekap_deck, only: read_deck
   use fekap_assembly_mesh, only: mesh_type, new_mesh
   implicit none
   private
   public :: example_decks, example_mesh

   !> Stems of the example decks (decks/<stem>.deck).
   character(len=32), parameter :: example_decks(9) = [character(len=32) :: 'fourbar', 'fourbar-quarter-turn', &
      & 'fourbar-half-turn', 'fourbar-appendage', 'double-crank', 'peaucellier', 'quick-return', &
      & 'slider-crank', 'cantilever-rollup']

contains

   !> The model and mesh of decks/<stem>.deck; a deck that does not read sets `error`
   !> (with the deck's name), which the suites assert is not set.
   subroutine example_mesh(stem, model, mesh, error)
      character(*), intent(in) :: stem
      type(model_type), intent(out) :: model
      type(mesh_type), intent(out) :: mesh
      type(error_type), allocatable, intent(out) :: error
      type(error_type), allocatable :: failure
      call read_deck(model, 'decks/'//trim(stem)//'.deck', failure)
      if (allocated(failure)) then
         call fatal_error(error, trim(stem)//': '//failure%message)
         return
      end if
      call new_mesh(mesh, model)
   end subroutine example_mesh

end module test_example_decks
