!> The FEM's linear system: the residual and the band tangent of the free
!> equations with its free-driven block, assembled from the mesh, factored and
!> solved for Newton corrections, drive responses and the rates' right-hand
!> sides; each operation counted and, on the sampled steps, timed. All
!> storage is allocated once (new_linear_system): nothing here allocates in
!> the step loop.
module fekap_fem_linear_system
   use fekap_kinds, only: dp
   use fekap_model_work, only: work_counts_type
   use fekap_assembly_mesh, only: mesh_type
   use fekap_linalg_band, only: band_matrix_type, new_band_matrix
   use fekap_assembly_assemble, only: assemble_residual, assemble_tangent, &
      & assemble_drive_block, assemble_second_derivative
   use fekap_element_beam, only: max_gauss, section_values
   use fekap_stepping_stepper, only: clock_seconds
   implicit none
   private

   public :: linear_system_type, new_linear_system, assemble_system, assemble_system_residual, factor_system
   public :: assemble_system_drive_block
   public :: system_pivot, residual_norm, newton_correction, apply_correction, drive_response, drive_load_rhs
   public :: solve_system, apply_response, assemble_second_derivative_at, system_rcond, phase_start, phase_end

   !> Tangent, residual and right-hand side of the free equations.
   type :: linear_system_type
      !> Free-free block of the tangent (and its factor).
      type(band_matrix_type) :: kff
      !> Free-driven block of the tangent, (nfree, ndriven).
      real(dp), allocatable :: kfd(:, :)
      !> Residual over all dofs at the configuration of the last assembly.
      real(dp), allocatable :: r(:)
      !> Right-hand side over the free equations, (nfree, 1), and the solution in its place.
      real(dp), allocatable :: rhs(:, :)
      !> The largest element strain at the configuration of the last tangent
      !> assembly, and its element.
      real(dp) :: assembled_strain = 0
      integer :: assembled_element = 0
      !> (section_values, max_gauss, nelem): cos and sin of the elements'
      !> section angles, and the angles, at the configuration of the last
      !> tangent assembly, for the second derivative of the rates (see
      !> assemble_second_derivative) and the square-root form's B there.
      real(dp), allocatable :: section(:, :, :)
      !> The same at the configuration of the last residual assembly that
      !> asked for them (assemble_system_residual's `sections`), for the
      !> square-root form's B there.
      real(dp), allocatable :: residual_section(:, :, :)
      !> Pivot ratio of the factor in kff, once computed (see system_pivot).
      real(dp) :: pivot = 0
      logical :: pivot_known = .false.
      !> Condition estimate of the factor in kff, once computed (see system_rcond).
      real(dp) :: rcond = 0
      logical :: rcond_known = .false.
      !> Whether the phases of the current step are timed (a sample of the steps).
      logical :: timing = .true.
   end type linear_system_type

contains

   !> Storage for the linear system of a mesh (dense: the reference full-matrix solver).
   subroutine new_linear_system(self, mesh, dense)
      type(linear_system_type), intent(out) :: self
      type(mesh_type), intent(in) :: mesh
      logical, intent(in) :: dense
      call new_band_matrix(self%kff, mesh%nfree, mesh%kd, dense=dense, top=mesh%envelope)
      allocate (self%kfd(mesh%nfree, mesh%ndriven), self%rhs(mesh%nfree, 1), source=0.0_dp)
      allocate (self%r(mesh%ndof), source=0.0_dp)
      allocate (self%section(section_values, max_gauss, size(mesh%elements)), source=0.0_dp)
      allocate (self%residual_section(section_values, max_gauss, size(mesh%elements)), source=0.0_dp)
   end subroutine new_linear_system

   !> Residual and tangent at q (geometric stiffness where strained above
   !> geometric_above, see beam_residual) into r, kff and kfd, and the largest
   !> element strain at q, timed and counted.
   subroutine assemble_system(self, mesh, q, t, seg, geometric_above, counts)
      type(linear_system_type), intent(inout) :: self
      type(mesh_type), intent(in) :: mesh
      real(dp), intent(in) :: t, geometric_above
      real(dp), contiguous, intent(in) :: q(:)
      !> Master segment of each slideline.
      integer, intent(in) :: seg(:)
      type(work_counts_type), intent(inout) :: counts
      real(dp) :: clock
      clock = phase_start(self)
      call assemble_tangent(mesh, q, t, seg, self%r, self%kff, self%kfd, geometric_above, &
         & self%assembled_strain, self%assembled_element, self%section)
      call phase_end(self, clock, counts%seconds_assembly)
      counts%tangent_assemblies = counts%tangent_assemblies + 1
      counts%slideline_evaluations = counts%slideline_evaluations + size(mesh%slides)
   end subroutine assemble_system

   !> The residual and, of the tangent, the free-driven block kfd alone at q
   !> (assemble_drive_block), with the largest element strain and the
   !> sections at q, as assemble_system leaves them; kff is left as it was
   !> (not the tangent at q): the square-root form's need of K at a
   !> configuration whose B_f it factors. Timed, and counted as a residual assembly.
   subroutine assemble_system_drive_block(self, mesh, q, t, seg, geometric_above, counts)
      type(linear_system_type), intent(inout) :: self
      type(mesh_type), intent(in) :: mesh
      real(dp), intent(in) :: t, geometric_above
      real(dp), contiguous, intent(in) :: q(:)
      !> Master segment of each slideline.
      integer, intent(in) :: seg(:)
      type(work_counts_type), intent(inout) :: counts
      real(dp) :: clock
      clock = phase_start(self)
      call assemble_drive_block(mesh, q, t, seg, self%r, self%kfd, geometric_above, self%assembled_strain, &
         & self%assembled_element, self%section)
      call phase_end(self, clock, counts%seconds_assembly)
      counts%residual_assemblies = counts%residual_assemblies + 1
      counts%slideline_evaluations = counts%slideline_evaluations + size(mesh%slides)
   end subroutine assemble_system_drive_block

   !> The residual alone at q into r (with `sections`, the sections at q
   !> into residual_section), timed and counted.
   subroutine assemble_system_residual(self, mesh, q, t, seg, counts, sections)
      type(linear_system_type), intent(inout) :: self
      type(mesh_type), intent(in) :: mesh
      real(dp), intent(in) :: t
      real(dp), contiguous, intent(in) :: q(:)
      integer, intent(in) :: seg(:)
      type(work_counts_type), intent(inout) :: counts
      logical, intent(in), optional :: sections
      real(dp) :: clock
      logical :: keep
      clock = phase_start(self)
      keep = .false.
      if (present(sections)) keep = sections
      if (keep) then
         call assemble_residual(mesh, q, t, seg, self%r, self%residual_section)
      else
         call assemble_residual(mesh, q, t, seg, self%r)
      end if
      call phase_end(self, clock, counts%seconds_assembly)
      counts%residual_assemblies = counts%residual_assemblies + 1
      counts%slideline_evaluations = counts%slideline_evaluations + size(mesh%slides)
   end subroutine assemble_system_residual

   !> Factor the assembled tangent, counting Cholesky and LU fallbacks;
   !> info > 0 names the equation where it is singular.
   subroutine factor_system(self, info, counts)
      type(linear_system_type), intent(inout) :: self
      integer, intent(out) :: info
      type(work_counts_type), intent(inout) :: counts
      real(dp) :: clock
      clock = phase_start(self)
      call self%kff%factor(info)
      call phase_end(self, clock, counts%seconds_factorisation)
      self%pivot_known = .false.
      self%rcond_known = .false.
      if (self%kff%is_lu) then
         counts%lu_factorisations = counts%lu_factorisations + 1
      else
         counts%cholesky_factorisations = counts%cholesky_factorisations + 1
      end if
   end subroutine factor_system

   !> The pivot ratio of the factor in kff (band_pivot_ratio), computed once
   !> per factorisation: the branch-jump check, the drive response and the
   !> rates all ask for it.
   subroutine system_pivot(self, ratio)
      type(linear_system_type), intent(inout) :: self
      real(dp), intent(out) :: ratio
      if (.not. self%pivot_known) then
         self%pivot = self%kff%pivot_ratio()
         self%pivot_known = .true.
      end if
      ratio = self%pivot
   end subroutine system_pivot

   !> The reciprocal condition number of the factor in kff (band_rcond: 1-norm,
   !> a few solves), computed once per factorisation and timed with the
   !> solves: the change-point detection and the branch-jump check ask for it.
   !> The factor must be regular (factor_system's info = 0).
   subroutine system_rcond(self, rcond, counts)
      type(linear_system_type), intent(inout) :: self
      real(dp), intent(out) :: rcond
      type(work_counts_type), intent(inout) :: counts
      real(dp) :: clock
      if (.not. self%rcond_known) then
         clock = phase_start(self)
         call self%kff%rcond(self%rcond)
         call phase_end(self, clock, counts%seconds_solves)
         self%rcond_known = .true.
      end if
      rcond = self%rcond
   end subroutine system_rcond

   !> Solve for rhs with the current factor, in place, timed.
   subroutine solve_system(self, counts)
      type(linear_system_type), intent(inout) :: self
      type(work_counts_type), intent(inout) :: counts
      call timed_solve(self, counts)
   end subroutine solve_system

   !> solve_system, private so that the module's own callers inline it (the
   !> release build's -fPIC keeps public procedures out of line).
   subroutine timed_solve(self, counts)
      type(linear_system_type), intent(inout) :: self
      type(work_counts_type), intent(inout) :: counts
      real(dp) :: clock
      clock = phase_start(self)
      call self%kff%solve(self%rhs)
      call phase_end(self, clock, counts%seconds_solves)
   end subroutine timed_solve

   !> The second directional derivative d2P[v, v] at q into `second` (see
   !> assemble_second_derivative), with the section angles of the last
   !> tangent assembly, which must have been at q; timed and counted.
   subroutine assemble_second_derivative_at(self, mesh, q, v, seg, second, counts)
      type(linear_system_type), intent(inout) :: self
      type(mesh_type), intent(in) :: mesh
      real(dp), contiguous, intent(in) :: q(:), v(:)
      integer, intent(in) :: seg(:)
      real(dp), contiguous, intent(out) :: second(:)
      type(work_counts_type), intent(inout) :: counts
      real(dp) :: clock
      clock = phase_start(self)
      call assemble_second_derivative(mesh, q, v, seg, second, self%section)
      call phase_end(self, clock, counts%seconds_assembly)
      counts%slideline_evaluations = counts%slideline_evaluations + size(mesh%slides)
   end subroutine assemble_second_derivative_at

   !> The assembled residual over the free equations, negated, into rhs (the
   !> right-hand side of a Newton correction), and its Euclidean norm, scaled
   !> by its largest entry so that the squares cannot overflow.
   real(dp) function residual_norm(self, mesh) result(norm)
      type(linear_system_type), intent(inout) :: self
      type(mesh_type), intent(in) :: mesh
      real(dp) :: biggest, factor
      integer :: k
      associate (r => self%rhs(:, 1))
         biggest = 0
         do k = 1, mesh%nfree
            r(k) = -self%r(mesh%eq_dof(k))
            biggest = max(biggest, abs(r(k)))
         end do
         norm = 0
         if (.not. biggest > 0) return
         ! Subnormal entries: 1/biggest would overflow; the residual is zero to round-off.
         if (biggest < tiny(1.0_dp)) then
            norm = biggest
            return
         end if
         factor = 1/biggest
         do k = 1, mesh%nfree
            norm = norm + (r(k)*factor)**2
         end do
         norm = biggest*sqrt(norm)
      end associate
   end function residual_norm

   !> The Newton correction for the residual that residual_norm gathered into
   !> rhs, with the current factor, into rhs, and its length (each dof
   !> weighted by dof_length: rotations by the model size).
   subroutine newton_correction(self, mesh, dof_length, correction, counts)
      type(linear_system_type), intent(inout) :: self
      type(mesh_type), intent(in) :: mesh
      real(dp), contiguous, intent(in) :: dof_length(:)
      real(dp), intent(out) :: correction
      type(work_counts_type), intent(inout) :: counts
      integer :: k
      call timed_solve(self, counts)
      correction = 0
      do k = 1, mesh%nfree
         correction = max(correction, abs(self%rhs(k, 1))*dof_length(mesh%eq_dof(k)))
      end do
   end subroutine newton_correction

   !> Add the correction in rhs to the free dofs of q.
   subroutine apply_correction(self, mesh, q)
      type(linear_system_type), intent(in) :: self
      type(mesh_type), intent(in) :: mesh
      real(dp), contiguous, intent(inout) :: q(:)
      integer :: k
      do k = 1, mesh%nfree
         q(mesh%eq_dof(k)) = q(mesh%eq_dof(k)) + self%rhs(k, 1)
      end do
   end subroutine apply_correction

   !> rhs(:, 1) = -K_fd x + f over the free equations: the right-hand side of
   !> a drive change x (and a load change f over all dofs, when given), by
   !> columns of the free-driven block.
   subroutine drive_load_rhs(self, mesh, x, f)
      type(linear_system_type), intent(inout) :: self
      type(mesh_type), intent(in) :: mesh
      real(dp), contiguous, intent(in) :: x(:)
      real(dp), intent(in), optional :: f(:)
      integer :: j, k
      associate (rhs => self%rhs(:, 1), eqd => mesh%eq_dof)
         if (present(f)) then
            do k = 1, mesh%nfree
               rhs(k) = f(eqd(k))
            end do
         else
            rhs = 0
         end if
         do j = 1, mesh%ndriven
            rhs = rhs - x(j)*self%kfd(:, j)
         end do
      end associate
   end subroutine drive_load_rhs

   !> Linear response of every dof to unit changes of the drives, (ndof,
   !> ndriven): R_f = -K_ff^-1 K_fd with the current factor, 1 on the drive's
   !> own dof; the other driven and the fixed dofs keep their zeros (resp is
   !> one of the stepper's response arrays, zero there from the start).
   subroutine drive_response(self, mesh, resp, counts)
      type(linear_system_type), intent(inout) :: self
      type(mesh_type), intent(in) :: mesh
      real(dp), contiguous, intent(inout) :: resp(:, :)
      type(work_counts_type), intent(inout) :: counts
      integer :: j, k
      do j = 1, mesh%ndriven
         self%rhs(:, 1) = -self%kfd(:, j)
         call timed_solve(self, counts)
         do k = 1, mesh%nfree
            resp(mesh%eq_dof(k), j) = self%rhs(k, 1)
         end do
         resp(mesh%driven_dof(j), j) = 1
      end do
   end subroutine drive_response

   !> y = resp x: the dofs' change for the drives' change x, through a drive
   !> response resp (ndof, ndriven).
   pure subroutine apply_response(resp, x, y)
      real(dp), contiguous, intent(in) :: resp(:, :), x(:)
      real(dp), contiguous, intent(out) :: y(:)
      integer :: j
      if (size(x) == 0) then
         y = 0
         return
      end if
      y = x(1)*resp(:, 1)
      do j = 2, size(x)
         y = y + x(j)*resp(:, j)
      end do
   end subroutine apply_response

   !> The clock at the start of a phase, if this step's phases are timed (else 0).
   real(dp) function phase_start(self) result(clock)
      type(linear_system_type), intent(in) :: self
      clock = 0
      if (self%timing) clock = clock_seconds()
   end function phase_start

   !> Add the time since `clock` (from phase_start) to a phase's seconds.
   subroutine phase_end(self, clock, seconds)
      type(linear_system_type), intent(in) :: self
      real(dp), intent(in) :: clock
      real(dp), intent(inout) :: seconds
      if (self%timing) seconds = seconds + (clock_seconds() - clock)
   end subroutine phase_end

end module fekap_fem_linear_system
