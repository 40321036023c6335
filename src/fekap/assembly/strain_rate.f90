!> The strain-rate operator B of an exactly constrained mechanism and its
!> band LU: the square-root form of the FEM's linear systems.
!>
!> The material tangent (46) is K = B^T W B, with B the gradients of the
!> elements' strains (Gamma1, Gamma2 and kappa L at the Gauss point, three
!> rows per element) and of the slidelines' gaps (one row each), W their
!> stiffnesses. When the mechanism is exactly constrained, B_f (its columns
!> on the free dofs) is square, and the Newton correction, the drive
!> response and the rates solve B_f x = r instead of K_ff x = B_f^T W r:
!> the same solution, with the condition number of B_f instead of its
!> square (docs/theory.md, "Rates at scale"). The rows are put in band
!> order (sorted by their least equation in the mesh's equation order), so
!> that B_f is a band matrix with kl sub- and ku superdiagonals; LAPACK's
!> dgbtrf factors it (its unblocked code dgbtf2 in loops for narrow bands);
!> its solves are dgbtrs's, with the factor's nonzeros (fekap_linalg_band_lu).
!>
!> Two forms of B: at the strains of an iterate (the exact Jacobian of the
!> strains, for Newton), and stress-free (the strains set to zero: it then
!> depends only on the section angles, for the rates at a converged
!> configuration). The strain rates B v and the second rates B a + eps2(v)
!> of the stress-free form are computed element by element from nodal
!> differences (strain_rates, strain_accelerations), which keeps them free
!> of the cancellation of a global product: they are the residuals of the
!> rates' refinement step. Of a redundant mechanism (more rows than free
!> dofs) only the rows and that geometry are kept: its rates, solved with
!> K, are refined with the same residuals weighted by W (strain_forces).
!>
!> The module is over 600 lines with one concept: B's assembly (its entries'
!> destinations found once), its band LU, solves and condition estimate,
!> and the rates' residuals all work on B's band row order and storage.
module fekap_assembly_strain_rate
   use, intrinsic :: iso_fortran_env, only: int64
   use fekap_kinds, only: dp
   use fekap_model, only: joint_prismatic
   use fekap_assembly_mesh, only: mesh_type
   use fekap_element_beam, only: beam_type
   use fekap_assembly_tracking, only: slide_position
   use fekap_linalg_lapack, only: band_lu_factor, band_lu_factor_loops, band_lu_blocked, norm_estimate_step
   use fekap_linalg_band_lu, only: band_lu_nonzeros_type, new_band_lu_nonzeros, gather_nonzeros, nonzeros_solve, &
      & nonzeros_solve_transposed, refactor_nonzeros
   implicit none
   private

   public :: strain_rate_type, new_strain_rate, assemble_strain_rate, factor_strain_rate, solve_strain_rate
   public :: strain_rates, strain_accelerations, strain_rate_rcond, strain_rate_rcond_bounds, rate_geometry_at
   public :: strain_forces, strain_rows, carry_geometry, solve_material_tangent

   !> The bounds from the last estimate hold while x = ||B_0^-1|| ||B_f - B_0||
   !> is below this (within ((1 + x)/(1 - x))**2 < 2.8 of each other).
   real(dp), parameter :: bound_reach = 0.25_dp

   !> A factorisation keeps the last one's pivot in a column while its
   !> magnitude is at least this fraction of the column's largest
   !> (refactor_nonzeros): 1 is partial pivoting's own choice.
   real(dp), parameter :: keep_pivot = 0.99_dp

   !> Entries of an element's rows of B: Gamma1 and Gamma2 on the six dofs
   !> (x1, y1, theta1, x2, y2, theta2), kappa L on theta1 and theta2.
   integer, parameter :: element_entries = 14
   !> Band storages of at most this many places are zeroed whole before an
   !> assembly (clear_assembled): 2 KiB, below which a block's zeroing costs
   !> about as much as a column's.
   integer, parameter :: small_band = 256
   !> The dof (1 to 6) and the row (1 to 3) of each of the element's entries.
   integer, parameter :: entry_dof(element_entries) = [1, 2, 3, 4, 5, 6, 1, 2, 3, 4, 5, 6, 3, 6]
   integer, parameter :: entry_row(element_entries) = [1, 1, 1, 1, 1, 1, 2, 2, 2, 2, 2, 2, 3, 3]

   !> B_f of a mesh, in band storage, and its factor.
   type :: strain_rate_type
      !> Whether the square-root form applies: B_f square (as many strain and
      !> gap rows as free dofs), one Gauss point per element, no prismatic joints.
      logical :: applies = .false.
      !> Whether the mechanism is redundant (more strain and gap rows than
      !> free dofs), with one Gauss point per element and no prismatic
      !> joints: its rates, solved with K = B^T W B, are refined with the
      !> strain rates (strain_rates, strain_accelerations, strain_forces) in
      !> the rows' own order; only the rows and the geometry are kept then.
      logical :: refines = .false.
      !> Equations (rows = columns), sub- and superdiagonals of B_f.
      integer :: n = 0, kl = 0, ku = 0
      !> Whether dgbtrf takes its blocked code for B_f's shape (band_lu_blocked).
      logical :: lu_blocked = .true.
      !> (3, nelem): band row of each element's strains Gamma1, Gamma2, kappa L.
      integer, allocatable :: element_row(:, :)
      !> (nslide): band row of each slideline's gap.
      integer, allocatable :: slide_row(:)
      !> (2, element_entries, nelem): where each element's entries of B go,
      !> as mesh_type%scatter_map for K: pairs (entry of element_values' list,
      !> place in ab taken as one array), element_count(1, e) of them, then
      !> element_count(2, e) pairs (entry, place in bd); fixed dofs have none.
      integer, allocatable :: element_map(:, :, :)
      !> (2, nelem): the lengths of the two lists of element_map.
      integer, allocatable :: element_count(:, :)
      !> (2 kl + ku + 1, n): B_f as dgbtrf stores it, then its LU factor if
      !> the band's loops made it (lu_blocked, or the pivots changed; B_f
      !> itself if refactor_nonzeros did: the factor is in nonzeros).
      real(dp), allocatable :: ab(:, :)
      integer, allocatable :: ipiv(:)
      !> The factor's nonzeros, which the solves take (gathered at each
      !> factorisation), and the places where B_f can have entries
      !> (entry_places; its entry_start and entry_at).
      type(band_lu_nonzeros_type) :: nonzeros
      !> (n, ndriven): the columns of B on the driven dofs (B_d), by rows.
      real(dp), allocatable :: bd(:, :)
      !> (2, nelem): cos and sin of each element's section angle at the last
      !> assembly; (6, nslide): each gap's gradient N_s (61) there, and (6,
      !> nslide) T_s (63), (3, nslide) the master's unit normal and length.
      real(dp), allocatable :: section(:, :), slide_ns(:, :), slide_ts(:, :), slide_nm(:, :)
      !> (6, nslide): the dofs of each gap at the last assembly (0: a ground point).
      integer, allocatable :: slide_dofs(:, :)
      !> (n): the largest magnitude in each column of the assembled B_f.
      real(dp), allocatable :: column_max(:)
      !> Whether ab holds a factor.
      logical :: factored = .false.
      !> Whether rows kl + 1 on of ab hold more than B_f's entries at their
      !> places: the factor of the band's loops or of dgbtrf, made in ab
      !> itself (whether or not it is regular: `factored`), which the next
      !> assembly zeroes first (clear_assembled). A factor made in the
      !> nonzeros' slots (refactor_nonzeros) leaves those rows as assembled,
      !> zero at every other place, and the next assembly writes each of its
      !> places over the last's (scatter_entries; scatter_row zeroes a
      !> slideline's row first). (Rows 1 to kl, the fill, may hold an older
      !> factor's; nothing reads them before the band's loops zero them.)
      logical :: band_factored = .false.
      !> Whether the factor is of B_f at another configuration than the
      !> geometry and B_d held (carry_geometry moved them on since the last
      !> assembly): its condition bounds are then not known.
      logical :: carried = .false.
      !> Pivot ratio of the factor on the scale of the tangent's
      !> (band_pivot_ratio): min over j of (|U(j, j)| / max_i |B(i, j)|)**2.
      !> K = B^T W B has the squares of B's pivots (exactly so for the R of
      !> a QR of B), so a configuration d away from a singular one has a
      !> ratio of order d**2 in both forms; 0 if B_f is singular.
      real(dp) :: pivot_ratio = 0
      !> 1-norm of B_f at its last factorisation, and dlacn2's scratch
      !> (allocated on first use), for strain_rate_rcond.
      real(dp) :: norm1 = 0
      real(dp), allocatable :: rcond_work(:)
      integer, allocatable :: rcond_iwork(:)
      !> The column where the last estimate ended (0: none yet), where the
      !> next one starts (norm_estimate_step's `start`): from step to step
      !> B_f moves little, and its inverse's largest column with it.
      integer :: estimate_column = 0
      !> B_f as assembled (before its factorisation), at its places only
      !> (nonzeros' entry_at, in their order: B_f is zero elsewhere), at the
      !> last factorisation and at the last condition estimate (allocated on
      !> the first estimate), and the estimate of ||B_f^-1||_1 made there (0:
      !> none yet), for strain_rate_rcond_bounds.
      real(dp), allocatable :: unfactored(:), estimated(:)
      real(dp) :: inverse_norm = 0
      !> ||B_f - B_0||_1 of the current factor's matrix B_f from that of the
      !> last estimate, B_0, found at its factorisation (while unfactored_kept).
      real(dp) :: distance = 0
      !> Whether unfactored, or estimated, holds the current factor's matrix.
      logical :: unfactored_kept = .false., estimate_current = .false.
   end type strain_rate_type

contains

   !> The band order of B_f's rows for a mesh, and its storage, if the
   !> square-root form applies (self%applies); nothing is allocated otherwise
   !> but the row maps.
   subroutine new_strain_rate(self, mesh)
      type(strain_rate_type), intent(out) :: self
      type(mesh_type), intent(in) :: mesh
      integer, allocatable :: least(:), most(:), order(:), count_at(:)
      integer :: nelem, nslide, nrow, e, i, k, r, row, d, eq, dofs(6)
      nelem = size(mesh%elements)
      nslide = size(mesh%slides)
      nrow = strain_rows(mesh)
      self%n = mesh%nfree
      allocate (self%element_row(3, nelem), self%slide_row(nslide), source=0)
      if (mesh%nfree == 0) return
      if (any(mesh%elements%ngauss /= 1)) return
      do i = 1, nslide
         if (mesh%slides(i)%kind == joint_prismatic) return
      end do
      if (nrow > mesh%nfree) then
         ! Redundant: the rows in their own order, and the geometry of B.
         self%element_row = reshape([(row, row=1, 3*nelem)], [3, nelem])
         self%slide_row = [(3*nelem + i, i=1, nslide)]
         call allocate_geometry(self, nelem, nslide)
         self%refines = .true.
         return
      end if
      if (nrow /= mesh%nfree) return
      ! Each row's least and largest equation: rows 3 (e - 1) + 1:3 are
      ! element e's (Gamma1 and Gamma2 on all six dofs, kappa L on the
      ! rotations), then one per slideline over the dofs of all its segments.
      allocate (least(nrow), source=huge(1))
      allocate (most(nrow), source=0)
      do e = 1, nelem
         do k = 1, 6
            eq = mesh%eq(mesh%edof(k, e))
            if (eq == 0) cycle
            do r = 1, 3
               if (r == 3 .and. k /= 3 .and. k /= 6) cycle
               row = 3*(e - 1) + r
               least(row) = min(least(row), eq)
               most(row) = max(most(row), eq)
            end do
         end do
      end do
      do i = 1, nslide
         row = 3*nelem + i
         do k = 1, size(mesh%slides(i)%seg, 2)
            call slide_dofs_of(mesh, i, k, dofs)
            do d = 1, 6
               if (dofs(d) == 0) cycle
               eq = mesh%eq(dofs(d))
               if (eq == 0) cycle
               least(row) = min(least(row), eq)
               most(row) = max(most(row), eq)
            end do
         end do
      end do
      if (any(most == 0)) return
      ! Stable counting sort of the rows by their least equation.
      allocate (count_at(nrow + 1), source=0)
      do row = 1, nrow
         count_at(least(row) + 1) = count_at(least(row) + 1) + 1
      end do
      count_at(1) = 1
      do k = 2, nrow + 1
         count_at(k) = count_at(k) + count_at(k - 1)
      end do
      allocate (order(nrow))
      do row = 1, nrow
         order(row) = count_at(least(row))
         count_at(least(row)) = count_at(least(row)) + 1
      end do
      self%kl = 0
      self%ku = 0
      do row = 1, nrow
         self%kl = max(self%kl, order(row) - least(row))
         self%ku = max(self%ku, most(row) - order(row))
      end do
      self%element_row = reshape(order(1:3*nelem), [3, nelem])
      self%slide_row = order(3*nelem + 1:)
      allocate (self%ab(2*self%kl + self%ku + 1, nrow), self%bd(nrow, mesh%ndriven), source=0.0_dp)
      allocate (self%ipiv(nrow), source=0)
      self%lu_blocked = band_lu_blocked(nrow, self%kl, self%ku)
      allocate (self%column_max(nrow), source=0.0_dp)
      call allocate_geometry(self, nelem, nslide)
      call build_element_map(self, mesh)
      ! B_f's places, for its factor's nonzeros and its column sizes (the
      ! nonzeros' record keeps them: entry_start, entry_at).
      call new_band_lu_nonzeros(self%nonzeros, self%kl, self%ku, entry_places(self))
      self%applies = .true.
   end subroutine new_strain_rate

   !> Storage for the geometry of the stress-free B (section, slide_*).
   pure subroutine allocate_geometry(self, nelem, nslide)
      type(strain_rate_type), intent(inout) :: self
      integer, intent(in) :: nelem, nslide
      allocate (self%section(2, nelem), self%slide_ns(6, nslide), self%slide_ts(6, nslide), &
         & self%slide_nm(3, nslide), source=0.0_dp)
      allocate (self%slide_dofs(6, nslide), source=0)
   end subroutine allocate_geometry

   !> Where B_f can have entries in its band storage: the elements' places
   !> (element_map) and every place of a slideline's row in the band (its
   !> dofs change with its segment). dgbtrf's blocked code, for wide bands,
   !> is not the loops that fekap_linalg_band_lu's symbolic factorisation
   !> follows: every place of the band there.
   pure function entry_places(self) result(possible)
      type(strain_rate_type), intent(in) :: self
      logical, allocatable :: possible(:, :)
      integer :: e, m, i, row, eq
      allocate (possible(size(self%ab, 1), self%n), source=self%lu_blocked)
      do e = 1, size(self%element_count, 2)
         do m = 1, self%element_count(1, e)
            call mark(possible, size(possible), self%element_map(2, m, e))
         end do
      end do
      do i = 1, size(self%slide_row)
         row = self%slide_row(i)
         do eq = max(1, row - self%kl), min(self%n, row + self%ku)
            possible(self%kl + self%ku + 1 + row - eq, eq) = .true.
         end do
      end do
   contains
      !> possible taken as one array: its place `at` marked.
      pure subroutine mark(possible, size_of, at)
         integer, intent(in) :: size_of, at
         logical, intent(inout) :: possible(size_of)
         possible(at) = .true.
      end subroutine mark
   end function entry_places

   !> The destinations of the elements' entries of B (element_map), from the
   !> band rows of their strains and the dofs' equations, once: the
   !> assembly of each iteration then adds each entry with one index.
   pure subroutine build_element_map(self, mesh)
      type(strain_rate_type), intent(inout) :: self
      type(mesh_type), intent(in) :: mesh
      integer :: band(2, element_entries), driven(2, element_entries), nb, nd, e, m, dof, eq, row, ldab
      ldab = size(self%ab, 1)
      allocate (self%element_map(2, element_entries, size(mesh%elements)), source=0)
      allocate (self%element_count(2, size(mesh%elements)), source=0)
      do e = 1, size(mesh%elements)
         nb = 0
         nd = 0
         do m = 1, element_entries
            dof = mesh%edof(entry_dof(m), e)
            if (dof == 0) cycle
            row = self%element_row(entry_row(m), e)
            eq = mesh%eq(dof)
            if (eq > 0) then
               ! ab(kl + ku + 1 + row - eq, eq), as scatter_row puts it.
               nb = nb + 1
               band(:, nb) = [m, self%kl + self%ku + 1 + row - eq + (eq - 1)*ldab]
            else if (mesh%drive_col(dof) > 0) then
               nd = nd + 1
               driven(:, nd) = [m, row + (mesh%drive_col(dof) - 1)*self%n]
            end if
         end do
         self%element_map(:, 1:nb, e) = band(:, 1:nb)
         self%element_map(:, nb + 1:nb + nd, e) = driven(:, 1:nd)
         self%element_count(:, e) = [nb, nd]
      end do
   end subroutine build_element_map

   !> The dofs of slideline i on its segment k (0 for a ground guide's points).
   pure subroutine slide_dofs_of(mesh, i, k, dofs)
      type(mesh_type), intent(in) :: mesh
      integer, intent(in) :: i, k
      integer, intent(out) :: dofs(6)
      associate (sl => mesh%slides(i))
         dofs(1:2) = mesh%tdof(:, sl%slave)
         dofs(3:6) = 0
         if (.not. sl%ground) then
            dofs(3:4) = mesh%tdof(:, sl%seg(1, k))
            dofs(5:6) = mesh%tdof(:, sl%seg(2, k))
         end if
      end associate
   end subroutine slide_dofs_of

   !> B at q (slidelines on their segments seg) into the band storage and
   !> B_d; stress_free: with the strains set to zero (the rates' form), else
   !> the exact gradients of the strains (Newton's). With `strain`, the
   !> strains and gaps themselves by band rows (Newton's residual); with
   !> `largest`, the largest element strain (as beam_max_strain) and its element.
   !> `section`: the sections that the beams' assembly found at q
   !> (assemble_residual's or assemble_tangent's), whose cosines and sines
   !> serve where their angle is this one to the bit (section_of).
   subroutine assemble_strain_rate(self, mesh, q, seg, stress_free, strain, largest, element, section)
      type(strain_rate_type), intent(inout) :: self
      type(mesh_type), intent(in) :: mesh
      real(dp), contiguous, intent(in) :: q(:)
      integer, intent(in) :: seg(:)
      logical, intent(in) :: stress_free
      real(dp), contiguous, intent(out), optional :: strain(:)
      real(dp), intent(out), optional :: largest
      integer, intent(out), optional :: element
      !> (section_values, max_gauss, nelem): see above.
      real(dp), contiguous, intent(in), optional :: section(:, :, :)
      real(dp) :: xe(6), rl, phi, c, s, a1, a2, g1, g2, xs(2), x1(2)
      real(dp) :: worst, values(element_entries)
      integer :: e, i, k
      call clear_assembled(self, mesh)
      self%factored = .false.
      self%carried = .false.
      if (present(largest)) largest = 0
      if (present(element)) element = 0
      do e = 1, size(mesh%elements)
         associate (el => mesh%elements(e), dofs => mesh%edof(:, e), rows => self%element_row(:, e))
            do k = 1, 6
               xe(k) = q(dofs(k))
            end do
            rl = 1/el%length
            phi = el%angle + (xe(3) + xe(6))/2
            call section_of(phi, e, c, s, section)
            self%section(:, e) = [c, s]
            a1 = (xe(4) - xe(1))*rl
            a2 = (xe(5) - xe(2))*rl
            g1 = c*a1 + s*a2 - 1                               ! (27)
            g2 = -s*a1 + c*a2
            if (present(strain)) then
               strain(rows(1)) = g1
               strain(rows(2)) = g2
               strain(rows(3)) = xe(6) - xe(3)
            end if
            if (present(largest) .and. present(element)) then
               worst = max(abs(g1), abs(g2), abs(xe(6) - xe(3)))
               if (worst > largest .or. element == 0) then
                  largest = worst
                  element = e
               end if
            end if
            if (stress_free) then
               g1 = 0
               g2 = 0
            end if
            ! Gradients of Gamma1, Gamma2 in (x1, y1, theta1, x2, y2, theta2),
            ! and of kappa L on the rotations only (its band bounds were found so).
            values = [-c*rl, -s*rl, g2/2, c*rl, s*rl, g2/2, &
               & s*rl, -c*rl, -(1 + g1)/2, -s*rl, c*rl, -(1 + g1)/2, -1.0_dp, 1.0_dp]
            call scatter_entries(self%element_map(:, :, e), self%element_count(1, e), self%element_count(2, e), &
               & values, size(self%ab), self%ab, size(self%bd), self%bd)
         end associate
      end do
      do i = 1, size(mesh%slides)
         call slide_geometry(self, mesh, i, seg(i), q, xs, x1)
         if (present(strain)) strain(self%slide_row(i)) = dot_product(xs - x1, self%slide_nm(1:2, i))
         call scatter_row(self, mesh, self%slide_row(i), self%slide_dofs(:, i), self%slide_ns(:, i))
      end do
   end subroutine assemble_strain_rate

   !> The geometry of the stress-free B at q that strain_rates and
   !> strain_accelerations read (the section angles, the gaps' gradients),
   !> as assemble_strain_rate leaves it, without assembling B or touching
   !> its factor: their residuals at q with a factor made at a configuration
   !> round-off away (a Newton iterate that converged at its first correction).
   !> `section` as assemble_strain_rate's.
   subroutine rate_geometry_at(self, mesh, q, seg, section)
      type(strain_rate_type), intent(inout) :: self
      type(mesh_type), intent(in) :: mesh
      real(dp), contiguous, intent(in) :: q(:)
      integer, intent(in) :: seg(:)
      real(dp), contiguous, intent(in), optional :: section(:, :, :)
      real(dp) :: phi, xs(2), x1(2)
      integer :: e, i
      do e = 1, size(mesh%elements)
         associate (dofs => mesh%edof(:, e))
            phi = mesh%elements(e)%angle + (q(dofs(3)) + q(dofs(6)))/2
            call section_of(phi, e, self%section(1, e), self%section(2, e), section)
         end associate
      end do
      do i = 1, size(mesh%slides)
         call slide_geometry(self, mesh, i, seg(i), q, xs, x1)
      end do
   end subroutine rate_geometry_at

   !> The strains and gaps at q (into strain, by B's rows, as
   !> assemble_strain_rate's), B's geometry there (rate_geometry_at's) and
   !> the stress-free B_d there, leaving the factor as it is: a factor made
   !> at a Newton iterate one correction from q then solves at q, its
   !> residuals (strain_rates, strain_accelerations) and B_d q's (carried).
   !> Slidelines on the segments seg, which must be the factor's. `section`
   !> as assemble_strain_rate's, so that the geometry is its to the bit.
   !> The element's frame (its xe, phi, cosine and sine, strains) is written
   !> out as assemble_strain_rate writes it: a procedure shared by the two
   !> loops was not inlined, and Example 1's step took 278 instructions more
   !> (13,285 -> 13,563, docs/performance.md, the seventeenth session).
   subroutine carry_geometry(self, mesh, q, seg, strain, section)
      type(strain_rate_type), intent(inout) :: self
      type(mesh_type), intent(in) :: mesh
      real(dp), contiguous, intent(in) :: q(:)
      integer, intent(in) :: seg(:)
      real(dp), contiguous, intent(out) :: strain(:)
      real(dp), contiguous, intent(in), optional :: section(:, :, :)
      real(dp) :: xe(6), rl, phi, c, s, a1, a2, values(element_entries), xs(2), x1(2)
      integer :: e, i, k, nb
      do e = 1, size(mesh%elements)
         associate (el => mesh%elements(e), dofs => mesh%edof(:, e), rows => self%element_row(:, e))
            do k = 1, 6
               xe(k) = q(dofs(k))
            end do
            rl = 1/el%length
            phi = el%angle + (xe(3) + xe(6))/2
            call section_of(phi, e, c, s, section)
            self%section(1, e) = c
            self%section(2, e) = s
            a1 = (xe(4) - xe(1))*rl
            a2 = (xe(5) - xe(2))*rl
            ! (27), as assemble_strain_rate.
            strain(rows(1)) = c*a1 + s*a2 - 1
            strain(rows(2)) = -s*a1 + c*a2
            strain(rows(3)) = xe(6) - xe(3)
            nb = self%element_count(1, e)
            if (self%element_count(2, e) == 0) cycle
            ! The element's driven columns, stress-free (assemble_strain_rate's values with Gamma = 0).
            values = [-c*rl, -s*rl, 0.0_dp, c*rl, s*rl, 0.0_dp, &
               & s*rl, -c*rl, -0.5_dp, -s*rl, c*rl, -0.5_dp, -1.0_dp, 1.0_dp]
            call driven_entries(self%element_map(:, :, e), nb, self%element_count(2, e), values, size(self%bd), &
               & self%bd)
         end associate
      end do
      do i = 1, size(mesh%slides)
         call slide_geometry(self, mesh, i, seg(i), q, xs, x1)
         strain(self%slide_row(i)) = dot_product(xs - x1, self%slide_nm(1:2, i))
         ! The gap's driven columns (scatter_row's B_d part).
         self%bd(self%slide_row(i), :) = 0
         call scatter_driven(self, mesh, self%slide_row(i), self%slide_dofs(:, i), self%slide_ns(:, i))
      end do
      self%carried = .true.
   end subroutine carry_geometry

   !> An element's entries on the driven dofs into bd (taken as one array),
   !> replacing what was there: map, nb and nd as scatter_entries'.
   pure subroutine driven_entries(map, nb, nd, values, nbd, bd)
      integer, intent(in) :: map(2, element_entries), nb, nd, nbd
      real(dp), intent(in) :: values(element_entries)
      real(dp), intent(inout) :: bd(nbd)
      integer :: m
      do m = nb + 1, nb + nd
         bd(map(2, m)) = 0
      end do
      do m = nb + 1, nb + nd
         bd(map(2, m)) = bd(map(2, m)) + values(map(1, m))
      end do
   end subroutine driven_entries

   !> cos(phi) and sin(phi) of element e's section angle phi: those of
   !> `section` (section_values, max_gauss, nelem; the beams' assembly at
   !> the same configuration) where its angle is phi to the bit, else
   !> computed. The beam takes the angle at its Gauss point as theta0 + theta1/2
   !> + theta2/2, rounded otherwise than (theta1 + theta2)/2 here in some
   !> cases: those compute their own, so that B is the same to the bit.
   pure subroutine section_of(phi, e, c, s, section)
      real(dp), intent(in) :: phi
      integer, intent(in) :: e
      real(dp), intent(out) :: c, s
      real(dp), contiguous, intent(in), optional :: section(:, :, :)
      if (present(section)) then
         ! The same bits (a signed zero included): the same cosine and sine.
         if (transfer(section(3, 1, e), 1_int64) == transfer(phi, 1_int64)) then
            c = section(1, 1, e)
            s = section(2, 1, e)
            return
         end if
      end if
      c = cos(phi)
      s = sin(phi)
   end subroutine section_of

   !> Slideline i's gap geometry at q on its segment iseg: its dofs, its
   !> gradient N_s (61), T_s (63) and the master's unit normal and length, and
   !> the slave's and the segment's first point.
   pure subroutine slide_geometry(self, mesh, i, iseg, q, xs, x1)
      type(strain_rate_type), intent(inout) :: self
      type(mesh_type), intent(in) :: mesh
      integer, intent(in) :: i, iseg
      real(dp), contiguous, intent(in) :: q(:)
      real(dp), intent(out) :: xs(2), x1(2)
      real(dp) :: x2(2), s1, t(2), nrm(2), alpha
      call slide_position(mesh, mesh%slides(i), iseg, q, xs, x1, x2, self%slide_dofs(:, i))
      s1 = norm2(x2 - x1)
      t = (x2 - x1)/s1
      nrm = [-t(2), t(1)]
      alpha = dot_product(xs - x1, t)/s1
      ! The gap's gradient N_s (61) and T_s (63) on (xs, ys, x1, y1, x2, y2).
      self%slide_ns(:, i) = [nrm, -(1 - alpha)*nrm, -alpha*nrm]
      self%slide_ts(:, i) = [t, -(1 - alpha)*t, -alpha*t]
      self%slide_nm(:, i) = [nrm, s1]
   end subroutine slide_geometry

   !> a(1:n) = 0 as one block (an assignment to a two-dimensional component
   !> sets each column apart, a call each).
   pure subroutine zero(a, n)
      integer, intent(in) :: n
      real(dp), intent(out) :: a(n)
      a = 0
   end subroutine zero

   !> Zero what the last assembly and factorisation can have left nonzero in
   !> ab and bd, before an assembly (not the whole storage: at 10^4 cells it
   !> is megabytes a step, two assemblies a step).
   !> - ab, after the band's loops or dgbtrf factored in it (band_factored):
   !>   with the band LU's loops (not lu_blocked), rows kl + 1 to
   !>   2 kl + ku + 1 of each column only. Rows 1 to kl are the factor's fill,
   !>   which the factorisation itself sets to zero before it adds into them
   !>   (dgbtf2's order, as band_lu_factor_loops: columns ku + 2 to kv at its
   !>   start, column j + kv at column j), and which nothing reads before: the
   !>   entries' places (entry_places) are below them. dgbtrf's blocked code
   !>   reads no fill either, but every place of the band is an entry place
   !>   there (column_sizes reads them all): the whole band then. A band of
   !>   at most small_band places is zeroed whole: one short block costs
   !>   fewer instructions than a loop over the columns.
   !> - ab, after a factorisation in the nonzeros' slots (not band_factored):
   !>   nothing. Rows kl + 1 on hold the last assembly's entries alone, and
   !>   the next writes each of its places: the elements' are written over
   !>   (scatter_entries), a slideline's row is zeroed at every place of the
   !>   band before its entries are added (scatter_row: its dofs change with
   !>   the segment; docs/performance.md, the twenty-second session).
   !> - bd: the places the elements' entries go (element_map's second
   !>   lists), or the whole block with a whole band (scatter_row zeroes a
   !>   slideline's row); bd is zero elsewhere from its allocation.
   pure subroutine clear_assembled(self, mesh)
      type(strain_rate_type), intent(inout) :: self
      type(mesh_type), intent(in) :: mesh
      logical :: whole
      whole = self%lu_blocked .or. size(self%ab) <= small_band
      if (self%band_factored) then
         if (whole) then
            call zero(self%ab, size(self%ab))
         else
            call zero_rows(size(self%ab, 1), self%n, self%kl + 1, self%ab)
         end if
         self%band_factored = .false.
      end if
      if (whole) then
         call zero(self%bd, size(self%bd))
         return
      end if
      if (size(self%bd) == 0) return
      call zero_driven(size(mesh%elements), self%element_map, self%element_count, size(self%bd), self%bd)
   end subroutine clear_assembled

   !> Row `row` of B_f zero at every place of the band (entry_places' of a
   !> slideline's row).
   pure subroutine zero_band_row(self, row)
      type(strain_rate_type), intent(inout) :: self
      integer, intent(in) :: row
      integer :: eq
      do eq = max(1, row - self%kl), min(self%n, row + self%ku)
         self%ab(self%kl + self%ku + 1 + row - eq, eq) = 0
      end do
   end subroutine zero_band_row

   !> a(first:, :) = 0 of an (m, n) array, column by column.
   pure subroutine zero_rows(m, n, first, a)
      integer, intent(in) :: m, n, first
      real(dp), intent(inout) :: a(m, n)
      integer :: i, j
      do j = 1, n
         do i = first, m
            a(i, j) = 0
         end do
      end do
   end subroutine zero_rows

   !> bd (taken as one array) zero at the places of the elements' entries
   !> on driven dofs (element_map's second lists).
   pure subroutine zero_driven(nelem, map, count, nbd, bd)
      integer, intent(in) :: nelem, map(2, element_entries, nelem), count(2, nelem), nbd
      real(dp), intent(inout) :: bd(nbd)
      integer :: e, m
      do e = 1, nelem
         do m = count(1, e) + 1, count(1, e) + count(2, e)
            bd(map(2, m, e)) = 0
         end do
      end do
   end subroutine zero_driven

   !> The largest magnitude in each column of the band matrix ab (n
   !> columns, taken as one array) and its 1-norm: each column's magnitudes
   !> at its places (place_start, place: entry_places') summed from zero in
   !> row order (the rest of the column is zero: the whole column's maxval
   !> and sum to the bit); with b, B_0 at the same places, also ||ab -
   !> B_0||_1 the same way (B_0 zero elsewhere too) and ab's values at the
   !> places into `kept` (b, distance and kept come together). Each value
   !> also goes to values(slot(k)): the factor's slot of the place
   !> (fekap_linalg_band_lu's entry_slot, for refactor_nonzeros).
   pure subroutine column_sizes(n, place_start, place, nab, ab, slot, nvalues, values, column_max, norm1, b, distance, kept)
      integer, intent(in) :: n, place_start(n + 1), place(place_start(n + 1) - 1), nab, slot(place_start(n + 1) - 1)
      integer, intent(in) :: nvalues
      real(dp), intent(in) :: ab(nab)
      real(dp), intent(inout) :: values(nvalues)
      real(dp), intent(out) :: column_max(n), norm1
      real(dp), intent(in), optional :: b(place_start(n + 1) - 1)
      real(dp), intent(out), optional :: distance
      real(dp), intent(out), optional :: kept(place_start(n + 1) - 1)
      real(dp) :: largest, total, a, column, value
      integer :: j, k
      norm1 = 0
      if (present(distance)) distance = 0
      do j = 1, n
         largest = 0
         total = 0
         column = 0
         if (present(b)) then
            do k = place_start(j), place_start(j + 1) - 1
               value = ab(place(k))
               kept(k) = value
               values(slot(k)) = value
               a = abs(value)
               if (a > largest) largest = a
               total = total + a
               column = column + abs(value - b(k))
            end do
            if (column > distance) distance = column
         else
            do k = place_start(j), place_start(j + 1) - 1
               value = ab(place(k))
               values(slot(k)) = value
               a = abs(value)
               if (a > largest) largest = a
               total = total + a
            end do
         end if
         column_max(j) = largest
         if (total > norm1) norm1 = total
      end do
   end subroutine column_sizes

   !> An element's entries of B through its lists of destinations
   !> (element_map): nb into the band storage ab (written), then nd added
   !> into B_d, each array taken in memory order.
   pure subroutine scatter_entries(map, nb, nd, values, nab, ab, nbd, bd)
      integer, intent(in) :: map(2, element_entries), nb, nd, nab, nbd
      real(dp), intent(in) :: values(element_entries)
      !> ab and bd as arrays of their sizes (one index per entry).
      real(dp), intent(inout) :: ab(nab), bd(nbd)
      integer :: m
      ! Each place of ab takes one entry: an element's rows are its own, and
      ! its six dofs are distinct (its two nodes are; the test
      ! assembly_over_the_last_is_a_fresh_one checks the places of the
      ! example decks). So an entry is written over the last assembly's, and
      ! ab is not zeroed first (clear_assembled). + 0 gives what adding to a
      ! zeroed place gave: a -0 becomes +0, every other value stays (IEEE
      ! addition, which the compiler keeps while signed zeros are honoured,
      ! as without -ffast-math).
      if (nb == element_entries) then
         ! An element on free dofs only (most of a large mesh): its entries
         ! in their own order (map(1, m) = m), in a loop of fixed length.
         do m = 1, element_entries
            ab(map(2, m)) = values(m) + 0
         end do
         return
      end if
      do m = 1, nb
         ab(map(2, m)) = values(map(1, m)) + 0
      end do
      do m = nb + 1, nb + nd
         bd(map(2, m)) = bd(map(2, m)) + values(map(1, m))
      end do
   end subroutine scatter_entries

   !> Row `row` of B on the dofs `dofs` (0: none), a slideline's: free
   !> columns into the band, driven ones into B_d (scatter_driven), after
   !> the row is zeroed at every place of the band and of B_d (its dofs
   !> change with the segment, and the band is not zeroed before every
   !> assembly: clear_assembled).
   pure subroutine scatter_row(self, mesh, row, dofs, values)
      type(strain_rate_type), intent(inout) :: self
      type(mesh_type), intent(in) :: mesh
      integer, intent(in) :: row, dofs(:)
      real(dp), intent(in) :: values(:)
      integer :: k, eq, band_row
      call zero_band_row(self, row)
      self%bd(row, :) = 0
      band_row = self%kl + self%ku + 1 + row
      do k = 1, size(dofs)
         if (dofs(k) == 0) cycle
         eq = mesh%eq(dofs(k))
         if (eq > 0) self%ab(band_row - eq, eq) = self%ab(band_row - eq, eq) + values(k)
      end do
      call scatter_driven(self, mesh, row, dofs, values)
   end subroutine scatter_row

   !> Row `row` of B's entries on driven dofs into B_d (added, in the order
   !> of dofs; a fixed dof, or 0, has none).
   pure subroutine scatter_driven(self, mesh, row, dofs, values)
      type(strain_rate_type), intent(inout) :: self
      type(mesh_type), intent(in) :: mesh
      integer, intent(in) :: row, dofs(:)
      real(dp), intent(in) :: values(:)
      integer :: k, col
      do k = 1, size(dofs)
         if (dofs(k) == 0) cycle
         if (mesh%eq(dofs(k)) > 0) cycle
         col = mesh%drive_col(dofs(k))
         if (col > 0) self%bd(row, col) = self%bd(row, col) + values(k)
      end do
   end subroutine scatter_driven

   !> Band LU of the assembled B_f (dgbtrf), in place, and its nonzeros
   !> for the solves (gather_nonzeros); info > 0: the band row where U has
   !> a zero pivot (B_f singular). A narrow band is factored on the places
   !> and with the pivots of the last factor while they serve
   !> (refactor_nonzeros), by the band's loops from the first column where
   !> they do not.
   subroutine factor_strain_rate(self, info)
      type(strain_rate_type), intent(inout) :: self
      integer, intent(out) :: info
      real(dp) :: ratio
      integer :: j, stopped
      ! The matrix kept for strain_rate_rcond_bounds and the next estimate
      ! (read at B_f's places, below rows 1 to kl, the factor's fill).
      self%estimate_current = .false.
      self%unfactored_kept = allocated(self%unfactored)
      ! The same pass puts B_f's entries at their slots in the factor
      ! (refactor_nonzeros' first step, `loaded`).
      associate (nz => self%nonzeros)
         if (self%unfactored_kept) then
            call column_sizes(self%n, nz%entry_start, nz%entry_at, size(self%ab), self%ab, nz%entry_slot, size(nz%values), &
               & nz%values, self%column_max, self%norm1, self%estimated, self%distance, self%unfactored)
         else
            call column_sizes(self%n, nz%entry_start, nz%entry_at, size(self%ab), self%ab, nz%entry_slot, size(nz%values), &
               & nz%values, self%column_max, self%norm1)
         end if
      end associate
      info = 0
      stopped = 1
      if (self%lu_blocked) then
         call band_lu_factor(self%ab, self%kl, self%ku, self%ipiv, info)
      else
         call refactor_nonzeros(self%nonzeros, self%ab, self%ipiv, keep_pivot, stopped, loaded=.true.)
         if (stopped > 0) call band_lu_factor_loops(self%ab, self%kl, self%ku, self%ipiv, info, stopped)
      end if
      self%band_factored = self%lu_blocked .or. stopped > 0
      self%factored = info == 0
      self%pivot_ratio = 0
      if (.not. self%factored) return
      if (stopped > 0) call gather_nonzeros(self%nonzeros, self%ab, self%ipiv)
      ! The least ratio, then its square: the least of the squares to the
      ! bit (a rounded square does not decrease as its argument grows).
      ratio = huge(1.0_dp)
      do j = 1, self%n
         if (.not. self%column_max(j) > 0) return
         ratio = min(ratio, abs(self%nonzeros%values(j))/self%column_max(j))
      end do
      self%pivot_ratio = min(huge(1.0_dp), ratio**2)
   end subroutine factor_strain_rate

   !> The condition estimate of the factor of B_f (1-norm, Higham's estimator
   !> LAPACK dlacn2, in loops (norm_estimate_step), with the factor's solves), squared to be on the tangent's
   !> scale like pivot_ratio (K = B^T W B); 0 without a factor. After the
   !> first, each estimate starts at the column where the last one ended
   !> (estimate_column): three solves where that column still serves,
   !> where dlacn2 makes four or five (five at the scissor lift's every
   !> step). Change points
   !> compare it with the run's best. Not dgbcon: its careful triangular
   !> solves (dlatbs) rescan the whole vector per column when B_f is
   !> ill-conditioned, quadratic in the size (minutes for a link of 10^5
   !> elements).
   subroutine strain_rate_rcond(self, rcond)
      type(strain_rate_type), intent(inout) :: self
      real(dp), intent(out) :: rcond
      real(dp) :: est
      integer :: kase, isave(3)
      rcond = 0
      if (.not. self%factored .or. .not. self%norm1 > 0) return
      if (.not. allocated(self%rcond_work)) allocate (self%rcond_work(2*self%n), self%rcond_iwork(self%n))
      est = 0
      kase = 0
      associate (x => self%rcond_work(1:self%n))
         do
            call norm_estimate_step(self%n, x, self%rcond_iwork, est, kase, isave, self%estimate_column)
            if (kase == 0) exit
            if (kase == 1) then
               call nonzeros_solve(self%nonzeros, x)
            else
               call nonzeros_solve_transposed(self%nonzeros, x)
            end if
         end do
      end associate
      self%estimate_column = isave(2)
      if (est > 0) rcond = ((1/self%norm1)/est)**2
      ! The matrix of this estimate, for strain_rate_rcond_bounds at later
      ! factors: kept by its factorisation (unfactored), or estimated already.
      if (.not. self%estimate_current) then
         self%inverse_norm = 0
         if (.not. self%unfactored_kept) then
            ! The first estimate: later factorisations keep their matrices.
            if (.not. allocated(self%unfactored)) then
               allocate (self%estimated(size(self%nonzeros%entry_at)), &
                  & self%unfactored(size(self%nonzeros%entry_at)), source=0.0_dp)
            end if
            return
         end if
         call swap(self%estimated, self%unfactored)
         self%unfactored_kept = .false.
         self%estimate_current = .true.
      end if
      self%inverse_norm = est
      if (.not. est > 0) self%inverse_norm = 0
   end subroutine strain_rate_rcond

   !> Bounds low <= rcond <= high of the condition estimate that
   !> strain_rate_rcond would make of the current factor (on the tangent's
   !> scale, as it), from the last estimate made, e0 of ||B_0^-1||_1, and the
   !> distance d = ||B_f - B_0||_1 from its matrix: with E = B_f - B_0,
   !> B_f^-1 = (I + B_0^-1 E)^-1 B_0^-1, so ||B_f^-1|| lies between e0/(1 +
   !> e0 d) and e0/(1 - e0 d) (Golub and Van Loan, Theorem 2.3.4) when e0 d <
   !> 1; they are taken with e0 as the estimate of ||B_0^-1||, as the
   !> estimate's own use takes it. low = 0 and high = huge when not known
   !> (no estimate yet, no factor, or e0 d above bound_reach).
   pure subroutine strain_rate_rcond_bounds(self, low, high)
      type(strain_rate_type), intent(in) :: self
      real(dp), intent(out) :: low, high
      real(dp) :: reach, distance, limit
      low = 0
      high = huge(1.0_dp)
      if (.not. self%factored .or. self%carried .or. .not. self%inverse_norm > 0 .or. .not. self%norm1 > 0) return
      limit = bound_reach/self%inverse_norm
      distance = 0
      if (.not. self%estimate_current) then
         if (.not. self%unfactored_kept) return
         ! Its distance, found at the factorisation; too far: not known.
         distance = self%distance
         if (distance >= limit) return
      end if
      reach = self%inverse_norm*distance
      low = ((1 - reach)/(self%norm1*self%inverse_norm))**2
      high = ((1 + reach)/(self%norm1*self%inverse_norm))**2
   end subroutine strain_rate_rcond_bounds

   pure subroutine swap(a, b)
      real(dp), allocatable, intent(inout) :: a(:), b(:)
      real(dp), allocatable :: c(:)
      call move_alloc(a, c)
      call move_alloc(b, a)
      call move_alloc(c, b)
   end subroutine swap

   !> Solve B_f x = b with the factor's nonzeros (b by band rows in, x by
   !> equations out): dgbtrs's operations in its order (fekap_linalg_band_lu).
   pure subroutine solve_strain_rate(self, x)
      type(strain_rate_type), intent(in) :: self
      real(dp), contiguous, intent(inout) :: x(:)
      call nonzeros_solve(self%nonzeros, x)
   end subroutine solve_strain_rate

   !> Solve K_ff x = b, K = B^T W B the material tangent (46) at zero
   !> strain (W: row_weights, kp for a gap), with B_f's factor: x = B_f^-1
   !> W^-1 B_f^-T b (b and x by equations; W^-1 by band rows). The error is
   !> then of the condition of B_f, not of its square as with K's own
   !> factor: kinetostatics' deflection under the loads of its masses.
   pure subroutine solve_material_tangent(self, mesh, x)
      type(strain_rate_type), intent(in) :: self
      type(mesh_type), intent(in) :: mesh
      real(dp), contiguous, intent(inout) :: x(:)
      integer :: e, i
      call nonzeros_solve_transposed(self%nonzeros, x)
      do e = 1, size(mesh%elements)
         associate (rows => self%element_row(:, e))
            x(rows) = x(rows)/row_weights(mesh%elements(e))
         end associate
      end do
      do i = 1, size(mesh%slides)
         x(self%slide_row(i)) = x(self%slide_row(i))/mesh%slides(i)%kp
      end do
      call nonzeros_solve(self%nonzeros, x)
   end subroutine solve_material_tangent

   !> r = B v by band rows, the strain and gap rates of the velocities v over
   !> all dofs (zero on fixed dofs), with the stress-free B at the section
   !> angles of the last assembly, element by element from nodal differences.
   pure subroutine strain_rates(self, mesh, v, r)
      type(strain_rate_type), intent(in) :: self
      type(mesh_type), intent(in) :: mesh
      real(dp), contiguous, intent(in) :: v(:)
      real(dp), contiguous, intent(out) :: r(:)
      real(dp) :: rl, c, s, d1, d2, ve(6)
      integer :: e, i, k, rows(3)
      ! Not unrolled: a mechanism's few elements ran the unrolled loop's set-up for nothing.
      !GCC$ unroll 1
      do e = 1, size(mesh%elements)
         ! The element's velocities and rows first: the stores into r cannot
         ! then make the compiler read the index arrays again.
         do k = 1, 6
            ve(k) = v(mesh%edof(k, e))
         end do
         rows = self%element_row(:, e)
         rl = 1/mesh%elements(e)%length
         c = self%section(1, e)
         s = self%section(2, e)
         d1 = (ve(4) - ve(1))*rl
         d2 = (ve(5) - ve(2))*rl
         r(rows(1)) = c*d1 + s*d2
         r(rows(2)) = -s*d1 + c*d2 - (ve(3) + ve(6))/2
         r(rows(3)) = ve(6) - ve(3)
      end do
      do i = 1, size(mesh%slides)
         ! Into a local array: gather's result of run-time size is a heap
         ! temporary (a malloc and a free per slideline and call).
         call gather_six(v, self%slide_dofs(:, i), ve)
         r(self%slide_row(i)) = dot_product(self%slide_ns(:, i), ve)
      end do
   end subroutine strain_rates

   !> ve = v(dofs), 0 where dofs is 0 (a fixed guide's point), as gather's.
   pure subroutine gather_six(v, dofs, ve)
      real(dp), contiguous, intent(in) :: v(:)
      integer, intent(in) :: dofs(6)
      real(dp), intent(out) :: ve(6)
      integer :: k
      do k = 1, 6
         ve(k) = 0
         if (dofs(k) > 0) ve(k) = v(dofs(k))
      end do
   end subroutine gather_six

   !> r = B a + eps2(v) by band rows: the second rates of the strains and gaps
   !> for accelerations a and velocities v over all dofs, of the stress-free
   !> B of the last assembly. With the first rates zero, the second rates of
   !> (Gamma1, Gamma2, kappa L) are B a + (psi'^2, 0, 0), psi' the section's
   !> angular velocity (docs/theory.md); of a gap, N_s a - 2 (T_s v)(N_m v)/s1
   !> (the Hessian of slide_force's header at g = 0).
   pure subroutine strain_accelerations(self, mesh, v, a, r)
      type(strain_rate_type), intent(in) :: self
      type(mesh_type), intent(in) :: mesh
      real(dp), contiguous, intent(in) :: v(:), a(:)
      real(dp), contiguous, intent(out) :: r(:)
      real(dp) :: vs(6), psi, vm
      integer :: e, i
      call strain_rates(self, mesh, a, r)
      do e = 1, size(mesh%elements)
         associate (dofs => mesh%edof(:, e))
            psi = (v(dofs(3)) + v(dofs(6)))/2
            r(self%element_row(1, e)) = r(self%element_row(1, e)) + psi*psi
         end associate
      end do
      do i = 1, size(mesh%slides)
         call gather_six(v, self%slide_dofs(:, i), vs)
         ! N_m v: the normal's component of the master's relative velocity.
         vm = dot_product(self%slide_nm(1:2, i), vs(5:6) - vs(3:4))
         r(self%slide_row(i)) = r(self%slide_row(i)) - 2*dot_product(self%slide_ts(:, i), vs)*vm/self%slide_nm(3, i)
      end do
   end subroutine strain_accelerations

   !> The material tangent's (46) weights W of an element's rows: EA L, kGA
   !> L and EI / L for Gamma1, Gamma2 and kappa L at the one Gauss point
   !> (weight 2, Jacobian L/2); a gap's is kp (65). So K = B^T W B at zero
   !> strain.
   pure function row_weights(el) result(w)
      type(beam_type), intent(in) :: el
      real(dp) :: w(3)
      w = [el%ea*el%length, el%kga*el%length, el%ei*(1/el%length)]
   end function row_weights

   !> f = B_f^T W r over the free equations: the nodal forces of the
   !> stresses W r of strain and gap rates r (by rows, as strain_rates gives
   !> them), element by element with the stress-free B of the last assembly
   !> (rate_geometry_at); W as row_weights', kp for a gap.
   !> `driven` (r a column of B_d): the elements with entries on driven
   !> dofs only, r being zero on the others' rows, whose forces are zeros
   !> that would add nothing (the same f to the bit).
   pure subroutine strain_forces(self, mesh, r, f, driven)
      type(strain_rate_type), intent(in) :: self
      type(mesh_type), intent(in) :: mesh
      real(dp), contiguous, intent(in) :: r(:)
      real(dp), contiguous, intent(out) :: f(:)
      logical, intent(in), optional :: driven
      real(dp) :: rl, c, s, p1, p2, p3, fe(6), w(3)
      integer :: e, i, k, eq
      logical :: driven_only
      driven_only = .false.
      if (present(driven)) driven_only = driven
      f = 0
      do e = 1, size(mesh%elements)
         if (driven_only) then
            if (self%element_count(2, e) == 0) cycle
         end if
         associate (el => mesh%elements(e), rows => self%element_row(:, e))
            rl = 1/el%length
            c = self%section(1, e)
            s = self%section(2, e)
            w = row_weights(el)
            p1 = w(1)*r(rows(1))
            p2 = w(2)*r(rows(2))
            p3 = w(3)*r(rows(3))
            ! The rows of B (see assemble_strain_rate's values at zero strain).
            fe(1) = (-c*p1 + s*p2)*rl
            fe(2) = (-s*p1 - c*p2)*rl
            fe(3) = -p2/2 - p3
            fe(4) = -fe(1)
            fe(5) = -fe(2)
            fe(6) = -p2/2 + p3
         end associate
         do k = 1, 6
            eq = mesh%eq(mesh%edof(k, e))
            if (eq > 0) f(eq) = f(eq) + fe(k)
         end do
      end do
      do i = 1, size(mesh%slides)
         p1 = mesh%slides(i)%kp*r(self%slide_row(i))
         do k = 1, 6
            if (self%slide_dofs(k, i) == 0) cycle
            eq = mesh%eq(self%slide_dofs(k, i))
            if (eq > 0) f(eq) = f(eq) + p1*self%slide_ns(k, i)
         end do
      end do
   end subroutine strain_forces

   !> The number of rows of B for a mesh (3 per element, 1 per slideline):
   !> B_f is square when it equals the number of free dofs.
   pure integer function strain_rows(mesh) result(rows)
      type(mesh_type), intent(in) :: mesh
      rows = 3*size(mesh%elements) + size(mesh%slides)
   end function strain_rows

end module fekap_assembly_strain_rate
