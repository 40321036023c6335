!> Tests of fekap_assembly_assemble: the assembled tangent (band and
!> free-driven block) against central differences of the assembled residual,
!> over the example decks.
module test_assembly_assemble
   use fekap_kinds, only: dp
   use fekap_testing, only: unittest_type, new_unittest, check, error_type, next_random
   use test_example_decks, only: example_decks, example_mesh
   use fekap_model, only: model_type, model_size
   use fekap_assembly_mesh, only: mesh_type
   use fekap_assembly_band, only: band_matrix_type, new_band_matrix
   use fekap_assembly_assemble, only: assemble_tangent, assemble_residual
   implicit none
   private
   public :: collect_assembly_assemble

contains

   subroutine collect_assembly_assemble(tests)
      type(unittest_type), allocatable, intent(out) :: tests(:)
      tests = [ &
         & new_unittest('assemble_tangent', test_tangent) &
         & ]
   end subroutine collect_assembly_assemble

   !> For every example deck, at a perturbed configuration (strained, so the
   !> geometric stiffness counts; every slave on its first master segment),
   !> each free and driven column of the tangent is the central difference of
   !> the residual over the free dofs, to 1e-6 of the tangent's largest entry.
   subroutine test_tangent(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(mesh_type) :: mesh
      type(band_matrix_type) :: kff
      real(dp), allocatable :: q(:), r(:), rp(:), rm(:), kfd(:, :), column(:)
      integer, allocatable :: seg(:)
      real(dp) :: strain, h, scale, worst
      integer :: d, i, j, k, state, element, col
      character(len=80) :: label
      state = 77
      do d = 1, size(example_decks)
         call example_mesh(example_decks(d), model, mesh, error)
         if (allocated(error)) return
         call new_band_matrix(kff, mesh%nfree, mesh%kd)
         allocate (r(mesh%ndof), rp(mesh%ndof), rm(mesh%ndof), kfd(mesh%nfree, mesh%ndriven), &
            & column(mesh%nfree), source=0.0_dp)
         allocate (seg(size(mesh%slides)), source=1)
         q = mesh%q0
         do i = 1, size(q)
            q(i) = q(i) + 0.01_dp*(2*next_random(state) - 1)
         end do
         call assemble_tangent(mesh, q, 0.5_dp, seg, r, kff, kfd, 0.0_dp, strain, element)
         scale = maxval(abs(kff%a))
         if (size(kfd) > 0) scale = max(scale, maxval(abs(kfd)))
         h = 1.0e-6_dp*model_size(model)
         worst = 0
         do j = 1, mesh%ndof
            ! The tangent's column of dof j: a free equation's column of the
            ! symmetric band, or a drive's column of the free-driven block.
            col = mesh%eq(j)
            if (col > 0) then
               do k = 1, mesh%nfree
                  if (abs(k - col) > mesh%kd) then
                     column(k) = 0
                  else
                     column(k) = kff%a(mesh%kd + 1 + min(k, col) - max(k, col), max(k, col))
                  end if
               end do
            else if (mesh%drive_col(j) > 0) then
               column = kfd(:, mesh%drive_col(j))
            else
               cycle
            end if
            q(j) = q(j) + h
            call assemble_residual(mesh, q, 0.5_dp, seg, rp)
            q(j) = q(j) - 2*h
            call assemble_residual(mesh, q, 0.5_dp, seg, rm)
            q(j) = q(j) + h
            do k = 1, mesh%nfree
               worst = max(worst, abs(column(k) - (rp(mesh%eq_dof(k)) - rm(mesh%eq_dof(k)))/(2*h)))
            end do
         end do
         write (label, '(a,a)') trim(example_decks(d)), ': tangent vs central differences'
         call check(error, worst/scale, 0.0_dp, trim(label), abs=1.0e-6_dp)
         if (allocated(error)) return
         call check(error, scale > 0, trim(example_decks(d))//': a tangent at all')
         if (allocated(error)) return
         deallocate (r, rp, rm, kfd, column, seg)
      end do
   end subroutine test_tangent

end module test_assembly_assemble
