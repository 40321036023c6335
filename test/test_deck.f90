module test_deck
   use fekap_testing, only: unittest_type, new_unittest, check, test_failed, error_type
   use fekap_model, only: model_type
   use fekap_deck, only: read_deck, read_deck_string
   implicit none
   private
   public :: collect_deck
contains
   subroutine collect_deck(tests)
      type(unittest_type), allocatable, intent(out) :: tests(:)
      tests = [new_unittest('smoke', test_smoke)]
   end subroutine collect_deck
   subroutine test_smoke(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      call read_deck_string(model, 'NODES'//new_line('a')//' A 0 0'//new_line('a')//'END', 'x.deck', error)
      if (allocated(error)) print '(a)', error%message
   end subroutine test_smoke
end module test_deck
