!> Velocities and accelerations of an accepted FEM configuration, (47) and
!> (48)-(53), with the factor of the tangent there, and what the factor's
!> pivot ratio says about the configuration: singular (no rates), near a
!> stationary configuration (ill-conditioned rates), or regular.
module fekap_solver_rates
   use fekap_kinds, only: dp
   use fekap_model_work, only: work_counts_type
   use fekap_model_results, only: note_length
   use fekap_assembly_mesh, only: mesh_type
   use fekap_solver_linear_system, only: linear_system_type, drive_load_rhs, solve_system, assemble_second_derivative_at
   implicit none
   private

   public :: pivot_note, solve_velocities, solve_accelerations

   !> Pivot ratios (see band_pivot_ratio) below which the tangent at a
   !> configuration counts as singular or as near-singular (a warning),
   !> relative to the largest ratio met so far in the run: the ratio itself
   !> also reflects the elements' bending-to-shear stiffness (4 EI / (kGA
   !> L^2), see docs/performance.md for its range), so only its drop means a
   !> stationary configuration. Below singular_floor the factor is singular to
   !> round-off whatever the reference.
   real(dp), parameter, public :: singular_drop = 1.0e-10_dp, near_singular_drop = 1.0e-3_dp, &
      & singular_floor = 1.0e-16_dp

contains

   !> The listing's note on a configuration at time t whose tangent has the
   !> pivot ratio `ratio` against the run's largest, `reference` ('' if
   !> regular), and whether rates can be solved there (not singular).
   !> velocities: the run asks for rates (the note says what happens to them).
   subroutine pivot_note(t, ratio, reference, velocities, note, regular)
      real(dp), intent(in) :: t, ratio, reference
      logical, intent(in) :: velocities
      character(len=note_length), intent(inout) :: note
      logical, intent(out) :: regular
      character(len=160) :: text
      character(:), allocatable :: consequence
      regular = .true.
      if (ratio < singular_drop*reference .or. ratio < singular_floor) then
         consequence = ''
         if (velocities) consequence = ': velocities and accelerations are left out of this step'
         write (text, '(a,es12.5,a)') 't = ', t, ': singular configuration (the tangent has no inverse)'
         note = trim(text)//consequence
         regular = .false.
      else if (ratio < near_singular_drop*reference) then
         consequence = ')'
         if (velocities) consequence = '): velocities and accelerations are ill-conditioned'
         write (text, '(a,es12.5,a,es9.2)') 't = ', t, ': near a stationary configuration (pivot ratio ', ratio
         note = trim(text)//consequence
      end if
   end subroutine pivot_note

   !> Velocities K v_f = -K_fd v_d + f' (47) with the factor in the system;
   !> f' the loads' rate over all dofs, when loaded (f_ext for the load factor t).
   subroutine solve_velocities(system, mesh, vd, v, counts, load_rate)
      type(linear_system_type), intent(inout) :: system
      type(mesh_type), intent(in) :: mesh
      !> The drives' rates.
      real(dp), contiguous, intent(in) :: vd(:)
      real(dp), contiguous, intent(out) :: v(:)
      type(work_counts_type), intent(inout) :: counts
      real(dp), intent(in), optional :: load_rate(:)
      integer :: i, k
      v = 0
      do i = 1, mesh%ndriven
         v(mesh%driven_dof(i)) = vd(i)
      end do
      call drive_load_rhs(system, mesh, vd, load_rate)
      call solve_system(system, counts)
      do k = 1, mesh%nfree
         v(mesh%eq_dof(k)) = system%rhs(k, 1)
      end do
   end subroutine solve_velocities

   !> Accelerations K a_f = -K_fd a_d - d2P[v, v] + f'' (48)-(53) at q with
   !> velocities v, with the factor in the system, which must be that of the
   !> tangent at q: its last tangent assembly, whose section angles it keeps,
   !> was at q. work is scratch over the dofs; f'' the loads' second rate over
   !> all dofs, when a load has a law (0 for the load factor t).
   subroutine solve_accelerations(system, mesh, q, v, seg, ad, a, work, counts, load_rate2)
      type(linear_system_type), intent(inout) :: system
      type(mesh_type), intent(in) :: mesh
      real(dp), contiguous, intent(in) :: q(:), v(:)
      !> Master segment of each slideline at q.
      integer, intent(in) :: seg(:)
      !> The drives' second rates.
      real(dp), contiguous, intent(in) :: ad(:)
      real(dp), contiguous, intent(out) :: a(:)
      real(dp), contiguous, intent(inout) :: work(:)
      type(work_counts_type), intent(inout) :: counts
      real(dp), intent(in), optional :: load_rate2(:)
      integer :: i, k
      call assemble_second_derivative_at(system, mesh, q, v, seg, work, counts)
      a = 0
      do i = 1, mesh%ndriven
         a(mesh%driven_dof(i)) = ad(i)
      end do
      call drive_load_rhs(system, mesh, ad, load_rate2)
      do k = 1, mesh%nfree
         system%rhs(k, 1) = system%rhs(k, 1) - work(mesh%eq_dof(k))
      end do
      call solve_system(system, counts)
      do k = 1, mesh%nfree
         a(mesh%eq_dof(k)) = system%rhs(k, 1)
      end do
   end subroutine solve_accelerations

end module fekap_solver_rates
