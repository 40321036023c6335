!> Slideline tracking: which master segment each slave is on. The segment
!> each slave starts on, the move to a neighbouring segment when a converged
!> slave has slid past the end of its own, and the gap check that a converged
!> configuration keeps every slave on its master line; with the positions of
!> a slideline on a segment (slide_position) that assembly uses too.
module fekap_assembly_tracking
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, analysis_error
   use fekap_model, only: model_type
   use fekap_strings, only: short_real_text
   use fekap_assembly_mesh, only: mesh_type, slide_type
   use fekap_contact_slideline, only: slide_geometry, slide_locate, slide_on_element, slide_off_end
   implicit none
   private

   public :: slide_position, initial_segments, relocate, check_gaps

contains

   !> Positions of slideline `sl` on segment iseg: slave, master ends, and the
   !> dofs (slave x, y, master x1, y1, x2, y2; 0 for a fixed guide).
   pure subroutine slide_position(mesh, sl, iseg, q, xs, x1, x2, dofs)
      type(mesh_type), intent(in) :: mesh
      type(slide_type), intent(in) :: sl
      integer, intent(in) :: iseg
      real(dp), intent(in) :: q(:)
      real(dp), intent(out) :: xs(2), x1(2), x2(2)
      integer, intent(out) :: dofs(6)
      dofs(1:2) = mesh%tdof(:, sl%slave)
      xs = q(dofs(1:2))
      if (sl%ground) then
         dofs(3:6) = 0
         x1 = sl%guide(:, 1)
         x2 = sl%guide(:, 2)
      else
         dofs(3:4) = mesh%tdof(:, sl%seg(1, iseg))
         dofs(5:6) = mesh%tdof(:, sl%seg(2, iseg))
         x1 = q(dofs(3:4))
         x2 = q(dofs(5:6))
      end if
   end subroutine slide_position

   !> The master segment each slave starts on at q (seg): the one it projects
   !> into with the smallest gap, which must be within 1e-9 model sizes.
   subroutine initial_segments(mesh, model, q, model_length, seg, error)
      type(mesh_type), intent(in) :: mesh
      type(model_type), intent(in) :: model
      !> The model size (model_size).
      real(dp), intent(in) :: q(:), model_length
      integer, intent(out) :: seg(:)
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: xs(2), x1(2), x2(2), g, alpha, s1, best
      integer :: i, k, dofs(6)
      do i = 1, size(mesh%slides)
         best = huge(1.0_dp)
         seg(i) = 0
         do k = 1, size(mesh%slides(i)%seg, 2)
            call slide_position(mesh, mesh%slides(i), k, q, xs, x1, x2, dofs)
            call slide_geometry(xs, x1, x2, g, alpha, s1)
            if (alpha >= -1.0e-9_dp .and. alpha <= 1 + 1.0e-9_dp .and. abs(g) < best) then
               best = abs(g)
               seg(i) = k
            end if
         end do
         if (seg(i) == 0 .or. best > 1.0e-9_dp*model_length) then
            call analysis_error(error, 'slideline '//model%slidelines(i)%name//': the slave node '// &
               & model%nodes(mesh%slides(i)%slave)%name//' is not on its master line')
            return
         end if
      end do
   end subroutine initial_segments

   !> After convergence at time t: move each slave whose coordinate alpha left
   !> [0, 1] on to the neighbouring master segment (`moved`); past the end of
   !> a slideline the step fails with a message naming slave and slideline.
   subroutine relocate(mesh, model, t, q, seg, moved, error)
      type(mesh_type), intent(in) :: mesh
      type(model_type), intent(in) :: model
      real(dp), intent(in) :: t, q(:)
      integer, intent(inout) :: seg(:)
      logical, intent(out) :: moved
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: xs(2), x1(2), x2(2), g, alpha, s1
      integer :: i, next, status, dofs(6)
      character(len=120) :: msg
      moved = .false.
      do i = 1, size(mesh%slides)
         call slide_position(mesh, mesh%slides(i), seg(i), q, xs, x1, x2, dofs)
         call slide_geometry(xs, x1, x2, g, alpha, s1)
         call slide_locate(alpha, seg(i), size(mesh%slides(i)%seg, 2), next, status)
         if (status == slide_off_end) then
            ! alpha as short_real_text writes it: far past the end (a slave
            ! thrown off by a huge deflection) it overflowed f8.4.
            write (msg, '(a,es12.5,a)') 't = ', t, ': the slave left the slideline past its end (alpha = '// &
               & short_real_text(alpha)//') '
            call analysis_error(error, trim(msg)//': slave node '//model%nodes(mesh%slides(i)%slave)%name// &
               & ', slideline '//model%slidelines(i)%name//'; lengthen the master line or shorten the run', t=t)
            return
         end if
         if (status /= slide_on_element) then
            seg(i) = next
            moved = .true.
         end if
      end do
   end subroutine relocate

   !> A converged mechanism configuration at time t has every slave on its
   !> master line: a gap of at most `admissible` (a length).
   subroutine check_gaps(mesh, model, t, q, seg, admissible, error)
      type(mesh_type), intent(in) :: mesh
      type(model_type), intent(in) :: model
      real(dp), intent(in) :: t, q(:)
      integer, intent(in) :: seg(:)
      real(dp), intent(in) :: admissible
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: xs(2), x1(2), x2(2), g, alpha, s1
      integer :: i, dofs(6)
      character(len=120) :: msg
      do i = 1, size(mesh%slides)
         call slide_position(mesh, mesh%slides(i), seg(i), q, xs, x1, x2, dofs)
         call slide_geometry(xs, x1, x2, g, alpha, s1)
         if (abs(g) > admissible) then
            write (msg, '(a,es12.5,a,es9.2,a)') 't = ', t, ': Newton converged with a gap of ', g, ' at slideline '
            call analysis_error(error, trim(msg)//' '//model%slidelines(i)%name//', not a mechanism configuration', &
               & t=t)
            return
         end if
      end do
   end subroutine check_gaps

end module fekap_assembly_tracking
