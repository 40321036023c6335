!> Tests of fekap_assembly_mesh: the envelope of the free-free tangent that
!> the band solver skips above, over the example decks.
module test_assembly_mesh
   use fekap_kinds, only: dp
   use fekap_testing, only: unittest_type, new_unittest, check, error_type, next_random
   use test_example_decks, only: example_decks, example_mesh
   use fekap_model, only: model_type
   use fekap_assembly_mesh, only: mesh_type
   use fekap_assembly_band, only: band_matrix_type, new_band_matrix
   use fekap_assembly_assemble, only: assemble_tangent
   implicit none
   private
   public :: collect_assembly_mesh

contains

   subroutine collect_assembly_mesh(tests)
      type(unittest_type), allocatable, intent(out) :: tests(:)
      tests = [ &
         & new_unittest('new_mesh_envelope', test_envelope) &
         & ]
   end subroutine collect_assembly_mesh

   !> For every example deck, tangents assembled at perturbed configurations
   !> (with every slave on every master segment) have no nonzero entry above
   !> the envelope, the envelope lies inside the band, and it is tight: the
   !> first entry of each column's envelope is nonzero in one of them.
   subroutine test_envelope(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(mesh_type) :: mesh
      type(band_matrix_type) :: kff
      real(dp), allocatable :: q(:), r(:), kfd(:, :), reached(:, :)
      integer, allocatable :: seg(:)
      real(dp) :: strain
      integer :: d, i, j, k, state, element, kd, pass, narrower
      character(len=80) :: label
      state = 31
      narrower = 0
      do d = 1, size(example_decks)
         call example_mesh(example_decks(d), model, mesh, error)
         if (allocated(error)) return
         kd = mesh%kd
         call check(error, size(mesh%envelope), mesh%nfree, trim(example_decks(d))//': envelope size')
         if (allocated(error)) return
         do j = 1, mesh%nfree
            write (label, '(a,a,i0)') trim(example_decks(d)), ': envelope inside the band, column ', j
            call check(error, mesh%envelope(j) >= max(1, j - kd) .and. mesh%envelope(j) <= j, trim(label))
            if (allocated(error)) return
         end do
         ! The whole band, to see any entry that falls outside the envelope.
         call new_band_matrix(kff, mesh%nfree, kd)
         allocate (r(mesh%ndof), kfd(mesh%nfree, mesh%ndriven), seg(size(mesh%slides)))
         allocate (reached(kd + 1, mesh%nfree), source=0.0_dp)
         do pass = 1, 3
            q = mesh%q0
            do i = 1, size(q)
               q(i) = q(i) + 0.01_dp*(2*next_random(state) - 1)
            end do
            do k = 1, max_segments(mesh)
               do i = 1, size(seg)
                  seg(i) = min(k, size(mesh%slides(i)%seg, 2))
               end do
               call assemble_tangent(mesh, q, 0.0_dp, seg, r, kff, kfd, 0.0_dp, strain, element)
               reached = max(reached, abs(kff%a))
            end do
         end do
         do j = 1, mesh%nfree
            write (label, '(a,a,i0)') trim(example_decks(d)), ': zero above the envelope, column ', j
            call check(error, all(reached(1:kd + mesh%envelope(j) - j, j) == 0), trim(label))
            if (allocated(error)) return
            write (label, '(a,a,i0)') trim(example_decks(d)), ': the envelope''s first entry reached, column ', j
            call check(error, reached(kd + 1 + mesh%envelope(j) - j, j) > 0, trim(label))
            if (allocated(error)) return
            if (mesh%envelope(j) > max(1, j - kd)) narrower = narrower + 1
         end do
         deallocate (r, kfd, seg, reached)
      end do
      ! Not a vacuous check: the envelopes leave out part of the bands.
      call check(error, narrower > 0, 'some envelope narrower than its band')
   end subroutine test_envelope

   !> The most master segments of any slideline (1 without slidelines).
   pure integer function max_segments(mesh)
      type(mesh_type), intent(in) :: mesh
      integer :: i
      max_segments = 1
      do i = 1, size(mesh%slides)
         max_segments = max(max_segments, size(mesh%slides(i)%seg, 2))
      end do
   end function max_segments

end module test_assembly_mesh
