!> Velocities and accelerations of an accepted FEM configuration, (47) and
!> (48)-(53), with the factor of the tangent there, and what the factor's
!> pivot ratio says about the configuration: singular (no rates), near a
!> stationary configuration (ill-conditioned rates), or regular. An exactly
!> constrained mechanism solves them in the square-root form instead, with
!> the band LU of its stress-free strain-rate operator B_f and one step of
!> refinement (root_velocities, root_accelerations; docs/theory.md, "Rates
!> at scale"). A redundant mechanism's rates from K's factor are refined
!> with residuals from its element strain rates (refine_rates).
module fekap_fem_rates
   use fekap_kinds, only: dp
   use fekap_model_work, only: work_counts_type
   use fekap_model_results, only: note_length
   use fekap_assembly_mesh, only: mesh_type
   use fekap_fem_linear_system, only: linear_system_type, drive_load_rhs, solve_system, assemble_second_derivative_at
   use fekap_assembly_strain_rate, only: strain_rate_type, solve_strain_rate, strain_rates, strain_accelerations, &
      & strain_forces
   implicit none
   private

   public :: pivot_note, singular_pivot, solve_velocities, solve_accelerations
   public :: root_velocities, root_accelerations, root_drive_response, root_refined_response, root_drive_block, &
      & refine_rates

   !> Solves of a rate in the square-root form: the plain solve and one
   !> refinement whose residual is the element strain rates (one more gains
   !> nothing: the error is then at the floor of the positions' round-off).
   integer, parameter :: root_passes = 2

   !> B_f's condition on the tangent's scale (strain_rate_rcond's
   !> 1/kappa_1(B_f)^2) at or above which the square-root form's rates take
   !> the plain solve alone (see root_velocities' `refine`): the LU solve's
   !> error is of order u kappa(B_f) |x| (u the unit round-off; Higham,
   !> Accuracy and Stability of Numerical Algorithms, 2002, sec. 9), so with
   !> kappa_1(B_f) <= 100 the refinement's correction is within about 100
   !> units of the rates' last place, at the round-off of the positions it
   !> starts from. The ill-conditioned (the scissor lift at scale, a
   !> mechanism near a change point, stiff sections spread over decades)
   !> keep their refinement.
   real(dp), parameter, public :: plain_rates_rcond = 1.0e-4_dp

   !> Most refinements of a redundant mechanism's rates (refine_rates): each
   !> gains about -log10(eps kappa(K)) digits, and they stop sooner when the
   !> correction stops shrinking or is at round-off of the rates.
   integer, parameter :: refine_passes = 4

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

   !> Whether a tangent with pivot ratio `ratio` against the run's largest,
   !> `reference`, is singular (see singular_drop).
   pure logical function singular_pivot(ratio, reference) result(singular)
      real(dp), intent(in) :: ratio, reference
      singular = ratio < singular_drop*reference .or. ratio < singular_floor
   end function singular_pivot

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
      if (singular_pivot(ratio, reference)) then
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
      integer :: k
      v = 0
      call put_driven(mesh, vd, v)
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
      integer :: k
      call assemble_second_derivative_at(system, mesh, q, v, seg, work, counts)
      a = 0
      call put_driven(mesh, ad, a)
      call drive_load_rhs(system, mesh, ad, load_rate2)
      do k = 1, mesh%nfree
         system%rhs(k, 1) = system%rhs(k, 1) - work(mesh%eq_dof(k))
      end do
      call solve_system(system, counts)
      do k = 1, mesh%nfree
         a(mesh%eq_dof(k)) = system%rhs(k, 1)
      end do
   end subroutine solve_accelerations

   !> Refinement of the velocities x (without v) or the accelerations x (with
   !> the velocities v) of a redundant mechanism, solved with the factor of K
   !> = B^T W B in the system (46): its error is eps kappa(K), the square of
   !> B's condition times the spread of the stiffnesses W. Each pass solves K
   !> dx_f = -B_f^T W r with that factor, r the strain and gap rates B x (or
   !> second rates B x + eps2(v)) computed element by element from nodal
   !> differences (strain_rates, strain_accelerations) and weighted element by
   !> element (strain_forces): they vanish for the exact rates, and are free
   !> of the cancellation of K x's global sum. A correction is taken while it
   !> shrinks, and the passes stop at one at round-off of x. root holds B's
   !> geometry at the configuration (rate_geometry_at); rows is scratch over
   !> B's rows.
   subroutine refine_rates(root, mesh, system, x, rows, counts, v)
      type(strain_rate_type), intent(in) :: root
      type(mesh_type), intent(in) :: mesh
      type(linear_system_type), intent(inout) :: system
      real(dp), contiguous, intent(inout) :: x(:)
      real(dp), contiguous, intent(inout) :: rows(:)
      type(work_counts_type), intent(inout) :: counts
      real(dp), contiguous, intent(in), optional :: v(:)
      real(dp) :: last, size_of, scale
      integer :: pass, k
      last = huge(1.0_dp)
      scale = maxval(abs(x))
      do pass = 1, refine_passes
         if (present(v)) then
            call strain_accelerations(root, mesh, v, x, rows)
         else
            call strain_rates(root, mesh, x, rows)
         end if
         call strain_forces(root, mesh, rows, system%rhs(:, 1))
         system%rhs(:, 1) = -system%rhs(:, 1)
         call solve_system(system, counts)
         size_of = maxval(abs(system%rhs(:, 1)))
         if (.not. size_of < last) exit
         do k = 1, mesh%nfree
            x(mesh%eq_dof(k)) = x(mesh%eq_dof(k)) + system%rhs(k, 1)
         end do
         if (size_of <= epsilon(1.0_dp)*scale) exit
         last = size_of
      end do
   end subroutine refine_rates

   !> Velocities of an exactly constrained mechanism: B_f v_f = -B_d v_d with
   !> the factor of the stress-free B in `root`, then one refinement
   !> B_f dv = -B v with the strain rates B v computed element by element
   !> from nodal differences (unless `refine` is false: the plain solve
   !> alone, where B_f is well conditioned, plain_rates_rcond). work is
   !> scratch over the equations.
   subroutine root_velocities(root, mesh, vd, v, work, refine)
      type(strain_rate_type), intent(in) :: root
      type(mesh_type), intent(in) :: mesh
      !> The drives' rates.
      real(dp), contiguous, intent(in) :: vd(:)
      real(dp), contiguous, intent(out) :: v(:)
      real(dp), contiguous, intent(inout) :: work(:)
      logical, intent(in), optional :: refine
      integer :: pass
      v = 0
      call put_driven(mesh, vd, v)
      do pass = 1, passes(refine)
         call strain_rates(root, mesh, v, work)
         call add_root_correction(root, mesh, work, v)
      end do
   end subroutine root_velocities

   !> Accelerations of an exactly constrained mechanism: B_f a_f = -B_d a_d -
   !> eps2(v) (the strains' second rates vanish) with the factor of the
   !> stress-free B in `root`, then one refinement with the residual
   !> B a + eps2(v) element by element (strain_accelerations); `refine` as
   !> root_velocities'.
   subroutine root_accelerations(root, mesh, v, ad, a, work, refine)
      type(strain_rate_type), intent(in) :: root
      type(mesh_type), intent(in) :: mesh
      real(dp), contiguous, intent(in) :: v(:)
      !> The drives' second rates.
      real(dp), contiguous, intent(in) :: ad(:)
      real(dp), contiguous, intent(out) :: a(:)
      real(dp), contiguous, intent(inout) :: work(:)
      logical, intent(in), optional :: refine
      integer :: pass
      a = 0
      call put_driven(mesh, ad, a)
      do pass = 1, passes(refine)
         call strain_accelerations(root, mesh, v, a, work)
         call add_root_correction(root, mesh, work, a)
      end do
   end subroutine root_accelerations

   !> The solves of a rate in the square-root form: root_passes, or the
   !> plain solve alone when `refine` is given false.
   pure integer function passes(refine)
      logical, intent(in), optional :: refine
      passes = root_passes
      if (present(refine)) then
         if (.not. refine) passes = 1
      end if
   end function passes

   !> Linear response of every dof to unit changes of the drives (as
   !> drive_response): R_f = -B_f^-1 B_d with the factor in `root`, 1 on the
   !> drive's own dof; the other entries of resp are left as they are (zero).
   subroutine root_drive_response(root, mesh, resp, work)
      type(strain_rate_type), intent(in) :: root
      type(mesh_type), intent(in) :: mesh
      real(dp), contiguous, intent(inout) :: resp(:, :)
      real(dp), contiguous, intent(inout) :: work(:)
      integer :: j, k
      do j = 1, mesh%ndriven
         work = -root%bd(:, j)
         call solve_strain_rate(root, work)
         do k = 1, mesh%nfree
            resp(mesh%eq_dof(k), j) = work(k)
         end do
         resp(mesh%driven_dof(j), j) = 1
      end do
   end subroutine root_drive_response

   !> root_drive_response refined once as root_velocities refines v (the
   !> response's strain rates at root's geometry, add_root_correction), and
   !> the largest correction of a column against that column's largest entry
   !> before it (against 1 where that is smaller): the factor's contraction
   !> along the response (fekap_fem_factor's carry_factor).
   subroutine root_refined_response(root, mesh, resp, work, rho)
      type(strain_rate_type), intent(in) :: root
      type(mesh_type), intent(in) :: mesh
      real(dp), contiguous, intent(inout) :: resp(:, :)
      real(dp), contiguous, intent(inout) :: work(:)
      real(dp), intent(out) :: rho
      real(dp) :: size_resp, change
      integer :: j, k
      call root_drive_response(root, mesh, resp, work)
      rho = 0
      do j = 1, mesh%ndriven
         size_resp = 0
         do k = 1, mesh%nfree
            size_resp = max(size_resp, abs(resp(mesh%eq_dof(k), j)))
         end do
         call strain_rates(root, mesh, resp(:, j), work)
         call add_root_correction(root, mesh, work, resp(:, j))
         change = 0
         do k = 1, mesh%nfree
            change = max(change, abs(work(k)))
         end do
         rho = max(rho, change/max(size_resp, 1.0_dp))
      end do
   end subroutine root_refined_response

   !> K's free-driven block from B, K_fd = B_f^T W B_d (46), column by
   !> column: B_d's column (root%bd, by B's rows) weighted and gathered onto
   !> the free equations by strain_forces, with the section angles and gap
   !> gradients root holds. The material tangent's block without assembling
   !> K: in exact arithmetic K's at a stress-free configuration, to the
   !> strains' size (round-off at a converged one) otherwise. rows is
   !> scratch over B's rows.
   subroutine root_drive_block(root, mesh, kfd, rows)
      type(strain_rate_type), intent(in) :: root
      type(mesh_type), intent(in) :: mesh
      real(dp), contiguous, intent(out) :: kfd(:, :)
      real(dp), contiguous, intent(inout) :: rows(:)
      integer :: j
      do j = 1, mesh%ndriven
         rows = root%bd(:, j)
         call strain_forces(root, mesh, rows, kfd(:, j), driven=.true.)
      end do
   end subroutine root_drive_block

   !> x(mesh%driven_dof) = values, in a loop: the assignment through the
   !> vector subscript copied the index list to a heap temporary (a malloc
   !> and a free) at every call.
   pure subroutine put_driven(mesh, values, x)
      type(mesh_type), intent(in) :: mesh
      real(dp), contiguous, intent(in) :: values(:)
      real(dp), contiguous, intent(inout) :: x(:)
      integer :: j
      do j = 1, size(mesh%driven_dof)
         x(mesh%driven_dof(j)) = values(j)
      end do
   end subroutine put_driven

   !> x_f += -B_f^-1 r: the correction of the free dofs of x for the residual
   !> r (over B_f's rows, overwritten), with the factor in root.
   subroutine add_root_correction(root, mesh, r, x)
      type(strain_rate_type), intent(in) :: root
      type(mesh_type), intent(in) :: mesh
      real(dp), contiguous, intent(inout) :: r(:), x(:)
      integer :: k
      r = -r
      call solve_strain_rate(root, r)
      do k = 1, mesh%nfree
         x(mesh%eq_dof(k)) = x(mesh%eq_dof(k)) + r(k)
      end do
   end subroutine add_root_correction

end module fekap_fem_rates
