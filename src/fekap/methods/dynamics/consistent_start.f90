!> The consistent start of dynamics (docs/dynamics.md, "The consistent
!> start"): at t0 the stiff modes start on the slow manifold. With K the
!> material tangent at the start configuration q_r (the kinematics' (47)), M
!> the mass matrix, c = K_fd a_d + d2P[v, v] (the drives' second rates and
!> the velocities' second derivative of the internal forces, as the
!> kinematics' accelerations (48)-(53)) and f = -R(q_r, v, a_f = 0) on the
!> free dofs (weights, loads, damping, the drives' inertia), the start solves
!>   K a = -c                (the strains' second rates vanish: rigid links)
!>   M a + K delta = f       (the deflection delta carries the rest of f)
!> with delta M-orthogonal to the mechanism's free motions (the null space of
!> K). In the stiff limit these are the rigid-body accelerations and the
!> elastic deflection under the rigid motion's internal forces. The two
!> singular-but-consistent systems K x = b are solved by the Richardson
!> iteration x += A^-1 mu (b - K x) preconditioned with A = M + mu K (one
!> Cholesky factor), from x0 = A^-1 (f - mu c) for a and A^-1 (mu F) for
!> delta: the null-space component N^T M x of every iterate then stays that of
!> x0 (N^T A = N^T M), N^T f for a and 0 for delta, which is the rigid-body
!> equations' and the orthogonality's; the rest contracts by 1/(1 + mu w^2)
!> an iteration (w an elastic mode's frequency). mu makes mu K about
!> `stiff_over_mass` times M (round-off of the rigid modes in A stays near
!> epsilon times that ratio). A second pass solves the same equations for the
!> residual the first left at q_r + delta (its terms of order delta^2).
module fekap_dynamics_consistent_start
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, analysis_error
   use fekap_model_work, only: work_counts_type
   use fekap_assembly_mesh, only: mesh_type
   use fekap_assembly_assemble, only: scatter_element
   use fekap_fem_linear_system, only: linear_system_type, assemble_system, factor_system, solve_system, &
      & assemble_second_derivative_at
   use fekap_dynamics_dynamic_system, only: dynamic_system_type, assemble_dynamics
   implicit none
   private

   public :: start_report_type, consistent_start

   !> mu K / M of the preconditioner A = M + mu K, on their largest diagonal entries.
   real(dp), parameter :: stiff_over_mass = 1.0e6_dp
   !> The iterations stop at this residual relative to the forces (or at round-off).
   real(dp), parameter :: relax_tolerance = 1.0e-13_dp
   integer, parameter :: relax_max_iterations = 1000
   !> Passes of the linear solution, each on the residual the last one left
   !> (its terms of order delta^2): one more reaches round-off with stiff links.
   integer, parameter :: max_passes = 4
   !> The start is used when its residual is below this fraction of the forces
   !> in play (weights, loads, inertia): its deflection is linear in the
   !> links' compliance, so a larger residual means links too flexible for it
   !> (their deflection is not small against their length), and the start
   !> falls back to the unstrained one.
   real(dp), parameter :: usable_residual = 1.0e-2_dp
   !> The residual's round-off: this many epsilons of the largest stiffness
   !> times the largest coordinate, times sqrt(n) (as the Newton's floor).
   real(dp), parameter :: round_off_factor = 10.0_dp

   !> What the start did: the iterations (relax) of the accelerations and of
   !> the deflection over its passes, whether all converged, the largest
   !> deflection, and the equations of motion's residual at the start (free
   !> dofs, relative to the largest force f).
   type :: start_report_type
      integer :: iterations_a = 0, iterations_delta = 0, passes = 0
      logical :: converged = .true.
      !> False when the residual is above usable_residual of the forces (and
      !> above its round-off): q and acc are then left as they came in.
      logical :: usable = .true.
      real(dp) :: deflection = 0, residual = 0
   end type start_report_type

contains

   !> The consistent start at (q, v, t): q's free dofs become q_r + delta, acc's
   !> the rigid-link accelerations a (acc holds the drives' second rates on
   !> theirs), system%r the residual at (q, v, acc) (the reactions). Each pass
   !> is kept only if it lowers the residual; a start left above
   !> usable_residual of the forces in play is not usable (report%usable):
   !> q's free dofs are then q_r again, for the unstrained start.
   subroutine consistent_start(dyn, system, mesh, q, v, acc, t, seg, counts, report, error)
      type(dynamic_system_type), intent(inout) :: dyn
      type(linear_system_type), intent(inout) :: system
      type(mesh_type), intent(in) :: mesh
      real(dp), contiguous, intent(inout) :: q(:), acc(:)
      real(dp), contiguous, intent(in) :: v(:)
      real(dp), intent(in) :: t
      integer, intent(in) :: seg(:)
      type(work_counts_type), intent(inout) :: counts
      type(start_report_type), intent(out) :: report
      type(error_type), allocatable, intent(out) :: error
      real(dp), allocatable :: kband(:, :), mband(:, :), f(:), c(:), a(:), delta(:), force(:), work(:), q0(:), &
         & da(:), ddelta(:)
      real(dp), allocatable :: best_a(:), best_delta(:)
      real(dp) :: mu, kmax, mmax, fscale, best, now, forces, round_off
      integer :: n, k, e, j, info, pass, iterations
      n = mesh%nfree
      if (n == 0) return
      allocate (f(n), c(n), a(n), delta(n), force(n), work(mesh%ndof), q0(n), da(n), ddelta(n))
      do k = 1, n
         q0(k) = q(mesh%eq_dof(k))
      end do
      ! f = -R at a_f = 0 (the drives' second rates on theirs).
      do k = 1, n
         acc(mesh%eq_dof(k)) = 0
      end do
      call assemble_dynamics(dyn, system, mesh, q, v, acc, t, seg, counts)
      do k = 1, n
         f(k) = -system%r(mesh%eq_dof(k))
      end do
      ! K (material) and c = K_fd a_d + d2P[v, v].
      call assemble_system(system, mesh, q, t, seg, huge(1.0_dp), counts)
      kband = system%kff%a
      call assemble_second_derivative_at(system, mesh, q, v, seg, work, counts)
      do k = 1, n
         c(k) = work(mesh%eq_dof(k))
      end do
      do j = 1, mesh%ndriven
         c = c + system%kfd(:, j)*acc(mesh%driven_dof(j))
      end do
      ! M over the free dofs, in the same band.
      call system%kff%zero()
      do e = 1, size(mesh%elements)
         call scatter_element(mesh%scatter_map(:, mesh%scatter_start(e):), mesh%scatter_count(1, e), 0, dyn%me(:, :, e), &
            & system%kff%a, system%kfd)
      end do
      do k = 1, n
         system%kff%a(mesh%kd + 1, k) = system%kff%a(mesh%kd + 1, k) + dyn%point_mass(mesh%eq_dof(k))
      end do
      mband = system%kff%a
      kmax = maxval(kband(mesh%kd + 1, :))
      mmax = maxval(mband(mesh%kd + 1, :))
      if (.not. (kmax > 0 .and. mmax > 0)) then
         call analysis_error(error, 'the start has no stiffness or no mass on its free dofs: '// &
            & 'consistent accelerations cannot be found')
         return
      end if
      mu = stiff_over_mass*mmax/kmax
      system%kff%a = mband + mu*kband
      call factor_system(system, info, counts)
      if (info /= 0) then
         call analysis_error(error, 'M + mu K is singular at the start: a free motion without mass '// &
            & '(give every moving dof a mass, or ANALysis start unstrained)')
         return
      end if
      fscale = max(maxval(abs(f)), mu*maxval(abs(c)))
      ! The forces in play: f (weights, loads, the drives' inertia) and M a (below).
      forces = maxval(abs(f))
      round_off = round_off_factor*epsilon(1.0_dp)*kmax*maxval(abs(q0))*sqrt(real(n, dp))
      a = 0
      delta = 0
      best = huge(1.0_dp)
      best_a = a
      best_delta = delta
      report%converged = .true.
      do pass = 1, max_passes
         ! The accelerations: K a = -c from A^-1 (f - mu c).
         da = precondition(f - mu*c)
         call relax(-c, da, fscale/mu, iterations)
         report%iterations_a = report%iterations_a + iterations
         report%converged = report%converged .and. iterations <= relax_max_iterations
         ! The deflection: K delta = F = f - M a from A^-1 (mu F).
         force = f - band_times(mband, mesh%kd, da)
         ddelta = precondition(mu*force)
         call relax(force, ddelta, max(fscale, maxval(abs(force))), iterations)
         report%iterations_delta = report%iterations_delta + iterations
         report%converged = report%converged .and. iterations <= relax_max_iterations
         a = a + da
         delta = delta + ddelta
         if (pass == 1) forces = max(forces, maxval(abs(band_times(mband, mesh%kd, a))))
         call place(a, delta)
         ! The residual at (q_r + delta, v, a): the terms of order delta^2 and
         ! the damping's change with delta, corrected by the next pass (c = 0:
         ! the strains' second rates stay those of the first).
         call assemble_dynamics(dyn, system, mesh, q, v, acc, t, seg, counts)
         do k = 1, n
            f(k) = -system%r(mesh%eq_dof(k))
         end do
         c = 0
         now = maxval(abs(f))
         ! A pass that does not lower the residual is not kept: the linear
         ! solution's round-off, or links too flexible for it (then the passes diverge).
         if (now >= best) then
            a = best_a
            delta = best_delta
            call place(a, delta)
            call assemble_dynamics(dyn, system, mesh, q, v, acc, t, seg, counts)
            exit
         end if
         report%passes = pass
         best = now
         best_a = a
         best_delta = delta
         ! Done at the tolerance, or at the residual's round-off (it stops falling fast).
         if (now <= relax_tolerance*10*max(forces, fscale)) exit
      end do
      report%deflection = maxval(abs(delta))
      report%residual = 0
      if (max(forces, round_off) > 0) report%residual = best/max(forces, round_off)
      report%usable = best <= max(usable_residual*forces, round_off)
      if (.not. report%usable) then
         do k = 1, n
            q(mesh%eq_dof(k)) = q0(k)
         end do
         return
      end if
      ! The residual left above round-off (the O(delta^2) terms the passes did
      ! not remove) is taken up by the accelerations of the dofs with mass,
      ! M da = f, so that the equations of motion hold at the start on them
      ! (the integrators' recursion starts from them); a dof without mass
      ! keeps its rigid-link acceleration (its equation is static). A residual
      ! at round-off is noise: divided by the masses it would only move a.
      if (best <= round_off) return
      system%kff%a = mband
      do k = 1, n
         if (mband(mesh%kd + 1, k) <= 0) system%kff%a(mesh%kd + 1, k) = 1
      end do
      call factor_system(system, info, counts)
      if (info /= 0) then
         call analysis_error(error, 'the mass matrix is singular at the start: consistent accelerations '// &
            & 'cannot be found (give every moving dof a mass)')
         return
      end if
      do k = 1, n
         f(k) = -system%r(mesh%eq_dof(k))
         if (mband(mesh%kd + 1, k) <= 0) f(k) = 0
      end do
      a = a + precondition(f)
      call place(a, delta)
      call assemble_dynamics(dyn, system, mesh, q, v, acc, t, seg, counts)
      ! system%r: the start's residual with its accelerations, the reactions there.

   contains

      !> q's free dofs q_r + delta, acc's the accelerations a.
      subroutine place(a, delta)
         real(dp), intent(in) :: a(:), delta(:)
         integer :: i
         do i = 1, n
            q(mesh%eq_dof(i)) = q0(i) + delta(i)
            acc(mesh%eq_dof(i)) = a(i)
         end do
      end subroutine place

      !> A^-1 b with the factor in the system.
      function precondition(b) result(x)
         real(dp), intent(in) :: b(:)
         real(dp) :: x(size(b))
         system%rhs = 0
         system%rhs(:, 1) = b
         call solve_system(system, counts)
         x = system%rhs(:, 1)
      end function precondition

      !> K x = b (K symmetric, positive semi-definite, b in its range) by the
      !> preconditioned Richardson iteration x += A^-1 mu (b - K x) from x: the
      !> error's part along K's range contracts by 1/(1 + mu w^2) an
      !> iteration, its null-space part stays (A^-1 M N = N), round-off
      !> included (conjugate gradients would amplify the round-off of K's
      !> null space, where p.K p vanishes). The residual b - K x to relax_tolerance
      !> of `scale` (a force: b's scale over mu for the accelerations), or
      !> until it stops falling (round-off). iterations is relax_max_iterations
      !> + 1 when it stopped short.
      subroutine relax(b, x, scale, iterations)
         real(dp), intent(in) :: b(:), scale
         real(dp), intent(inout) :: x(:)
         integer, intent(out) :: iterations
         real(dp) :: r(size(b)), size_r, last
         last = huge(1.0_dp)
         iterations = 0
         do
            r = b - band_times(kband, mesh%kd, x)
            size_r = maxval(abs(r))
            if (size_r <= relax_tolerance*scale .or. size_r == 0) return
            ! At round-off the residual stops falling (stiff modes converge at once).
            if (iterations > 0 .and. size_r > 0.5_dp*last .and. size_r <= 1.0e-8_dp*scale) return
            if (iterations == relax_max_iterations) exit
            x = x + precondition(mu*r)
            last = size_r
            iterations = iterations + 1
         end do
         iterations = relax_max_iterations + 1
      end subroutine relax

   end subroutine consistent_start

   !> y = A x for a symmetric matrix of half-bandwidth kd in the upper band
   !> storage A(i, j), i <= j, at a(kd + 1 + i - j, j).
   pure function band_times(a, kd, x) result(y)
      real(dp), intent(in) :: a(:, :), x(:)
      integer, intent(in) :: kd
      real(dp) :: y(size(x))
      integer :: i, j
      y = 0
      do j = 1, size(x)
         do i = max(1, j - kd), j - 1
            y(i) = y(i) + a(kd + 1 + i - j, j)*x(j)
            y(j) = y(j) + a(kd + 1 + i - j, j)*x(i)
         end do
         y(j) = y(j) + a(kd + 1, j)*x(j)
      end do
   end function band_times

end module fekap_dynamics_consistent_start
