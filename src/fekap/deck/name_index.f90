!> A hash index of names (case-insensitive) to their positions in a list, so
!> that a deck of tens of thousands of nodes and links reads in linear time:
!> every link names two nodes, and every name must be checked for duplicates.
module fekap_deck_name_index
   use, intrinsic :: iso_fortran_env, only: int64
   use fekap_strings, only: lower
   implicit none
   private

   public :: name_index_type, new_name_index

   type :: key_type
      character(:), allocatable :: text
   end type key_type

   !> Open addressing with linear probing; the table is kept at most half full.
   type :: name_index_type
      !> Position of the name in the caller's list, 0 for an empty slot.
      integer, allocatable :: value(:)
      type(key_type), allocatable :: key(:)
      integer :: count = 0
   contains
      !> Insert a name; `previous` is the position already stored under it (0 if none).
      procedure :: insert => index_insert
      !> The position stored under a name, 0 if none.
      procedure :: find => index_find
   end type name_index_type

contains

   !> An empty index for about `expected` names.
   pure subroutine new_name_index(self, expected)
      type(name_index_type), intent(out) :: self
      integer, intent(in) :: expected
      integer :: n
      n = 16
      do while (n < 2*expected + 1)
         n = 2*n
      end do
      allocate (self%value(n), source=0)
      allocate (self%key(n))
   end subroutine new_name_index

   !> FNV-1a hash of the lower-case name, as a slot number 1..n.
   pure integer function slot_of(text, n) result(slot)
      character(*), intent(in) :: text
      integer, intent(in) :: n
      integer(int64) :: h
      integer :: i
      h = 2166136261_int64
      do i = 1, len(text)
         h = ieor(h, int(iachar(text(i:i)), int64))
         h = modulo(h*16777619_int64, 4294967296_int64)
      end do
      slot = int(modulo(h, int(n, int64))) + 1
   end function slot_of

   pure subroutine index_insert(self, name, position, previous)
      class(name_index_type), intent(inout) :: self
      character(*), intent(in) :: name
      integer, intent(in) :: position
      integer, intent(out) :: previous
      character(len(name)) :: low
      integer :: slot
      low = lower(name)
      slot = slot_of(low, size(self%value))
      do while (self%value(slot) /= 0)
         if (self%key(slot)%text == low .and. len(self%key(slot)%text) == len(low)) then
            previous = self%value(slot)
            return
         end if
         slot = modulo(slot, size(self%value)) + 1
      end do
      previous = 0
      self%value(slot) = position
      self%key(slot)%text = low
      self%count = self%count + 1
   end subroutine index_insert

   pure integer function index_find(self, name) result(position)
      class(name_index_type), intent(in) :: self
      character(*), intent(in) :: name
      character(len(name)) :: low
      integer :: slot
      position = 0
      if (.not. allocated(self%value)) return
      low = lower(name)
      slot = slot_of(low, size(self%value))
      do while (self%value(slot) /= 0)
         if (self%key(slot)%text == low .and. len(self%key(slot)%text) == len(low)) then
            position = self%value(slot)
            return
         end if
         slot = modulo(slot, size(self%value)) + 1
      end do
   end function index_find

end module fekap_deck_name_index
