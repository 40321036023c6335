!> Reading VELOcities: the links' velocities at the start of dynamics, each
!> a rigid motion `LINK vx vy omega` (its first node's velocity and its
!> angular velocity). Links that share a node must agree on its velocity.
module fekap_deck_velocities
   use fekap_kinds, only: dp
   use fekap_model, only: model_type, start_velocity_type
   use fekap_deck_context, only: context_type
   use fekap_deck_geometry, only: lookup_link
   implicit none
   private

   public :: read_velocities

   !> Largest magnitude of a velocity value.
   real(dp), parameter :: max_value = 1.0e15_dp

contains

   subroutine read_velocities(ctx, model, lines)
      type(context_type), intent(inout) :: ctx
      type(model_type), intent(inout) :: model
      integer, intent(in) :: lines(:)
      character(*), parameter :: form = 'LINK vx vy omega'
      type(start_velocity_type), allocatable :: list(:)
      integer :: n, i, j, k, iline, link, a, b, node
      real(dp) :: values(3), va(2), vb(2)
      logical :: ok, fine
      allocate (list(size(lines)))
      n = 0
      do i = 1, size(lines)
         iline = lines(i)
         if (.not. ctx%require(iline, form, 'a VELOcities line')) cycle
         if (ctx%nfields(iline) /= 4) then
            call ctx%error(iline, min(ctx%nfields(iline) + 1, 5), 'a VELOcities line has 4 fields', &
               & label='a VELOcities line is: '//form//' (the first node''s velocity and the angular velocity)')
            cycle
         end if
         link = lookup_link(ctx, iline, 1)
         ok = link > 0
         do k = 1, 3
            call ctx%real_field(iline, k + 1, values(k), fine)
            if (fine .and. abs(values(k)) > max_value) then
               call ctx%error(iline, k + 1, 'velocity too large', label='at most 1e15 in magnitude')
               fine = .false.
            end if
            ok = ok .and. fine
         end do
         if (.not. ok) cycle
         do j = 1, n
            if (list(j)%link == link) then
               call ctx%error(iline, 1, 'link '//model%links(link)%name//' has a velocity already', &
                  & label='one VELOcities line per link')
               ok = .false.
            end if
         end do
         if (.not. ok) cycle
         n = n + 1
         list(n) = start_velocity_type(link=link, v=values(1:2), omega=values(3), loc=ctx%loc(iline, 1))
         ! A node of this link shared with a link given before: the same velocity.
         do j = 1, n - 1
            do a = 1, 2
               node = model%links(link)%node(a)
               do b = 1, 2
                  if (model%links(list(j)%link)%node(b) /= node) cycle
                  va = list(n)%velocity_at(model%nodes(model%links(link)%node(1))%x, model%nodes(node)%x)
                  vb = list(j)%velocity_at(model%nodes(model%links(list(j)%link)%node(1))%x, &
                     & model%nodes(node)%x)
                  if (norm2(va - vb) > 1.0e-9_dp*max(1.0_dp, norm2(va), norm2(vb))) then
                     call ctx%error(iline, 1, 'links '//model%links(list(j)%link)%name//' and '// &
                        & model%links(link)%name//' give node '//model%nodes(node)%name//' different velocities', &
                        & label='links that share a node must agree on its velocity')
                  end if
               end do
            end do
         end do
      end do
      model%start_velocities = list(:n)
   end subroutine read_velocities

end module fekap_deck_velocities
