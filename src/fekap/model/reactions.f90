!> The rows of reactions.csv, stated once: what each row is (a drive, a
!> support, a sliding joint, or one end of a link) and its labels. The
!> effects that compute reactions (kinetostatics, statics) fill the rows in
!> this order; the CSV writer prints their labels. The order: one row per
!> drive (model%drives), one per support (model%supports), one per slideline
!> (model%slidelines), then two per link (model%links: its first end, then
!> its second).
module fekap_model_reactions
   use fekap_model, only: model_type, dof_rot
   implicit none
   private

   public :: reaction_row_type, reaction_rows, reaction_count

   !> Kinds of reaction rows.
   integer, parameter, public :: reaction_drive = 1, reaction_support = 2, reaction_slider = 3, reaction_joint = 4

   !> One row: its kind, the index of its drive, support, slideline or link,
   !> the link end (1, 2) of a joint row, and its labels' link and node
   !> (indices into model%links and model%nodes, 0 for an empty label).
   type :: reaction_row_type
      integer :: kind = 0
      integer :: item = 0
      integer :: end = 0
      integer :: link = 0
      integer :: node = 0
   end type reaction_row_type

contains

   !> Number of reaction rows of a model.
   pure integer function reaction_count(model) result(n)
      type(model_type), intent(in) :: model
      n = 2*size(model%links)
      if (allocated(model%drives)) n = n + size(model%drives)
      if (allocated(model%supports)) n = n + size(model%supports)
      if (allocated(model%slidelines)) n = n + size(model%slidelines)
   end function reaction_count

   !> The rows of `model`, in order. Labels: a rotation drive names its link
   !> and the driven end's node, an x or y drive its node; a support its node
   !> (and the clamped link of a `rot` support); a slider its slave node (and
   !> the slave's link of a prismatic joint); a joint row its link and the
   !> node at that end.
   pure function reaction_rows(model) result(rows)
      type(model_type), intent(in) :: model
      type(reaction_row_type), allocatable :: rows(:)
      integer :: row, i, l, end_
      allocate (rows(reaction_count(model)))
      row = 0
      if (allocated(model%drives)) then
         do i = 1, size(model%drives)
            row = row + 1
            rows(row) = reaction_row_type(reaction_drive, i, 0, 0, model%drives(i)%node)
            if (model%drives(i)%dof == dof_rot) rows(row)%link = model%drives(i)%link
         end do
      end if
      if (allocated(model%supports)) then
         do i = 1, size(model%supports)
            row = row + 1
            rows(row) = reaction_row_type(reaction_support, i, 0, 0, model%supports(i)%node)
            if (model%supports(i)%fix(dof_rot)) rows(row)%link = model%supports(i)%link
         end do
      end if
      if (allocated(model%slidelines)) then
         do i = 1, size(model%slidelines)
            row = row + 1
            rows(row) = reaction_row_type(reaction_slider, i, 0, model%slidelines(i)%slave_link, &
               & model%slidelines(i)%slave)
         end do
      end if
      do l = 1, size(model%links)
         do end_ = 1, 2
            row = row + 1
            rows(row) = reaction_row_type(reaction_joint, l, end_, l, model%links(l)%node(end_))
         end do
      end do
   end function reaction_rows

end module fekap_model_reactions
