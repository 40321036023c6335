!> The Cartesian-coordinate method (the paper's (13)-(26), Nikravesh's KAP):
!> every rigid body has coordinates (x, y, phi) (see fekap_classical_bodies),
!> the joints give the constraint equations Phi(q, t) = 0 of
!> fekap_classical_constraints, and Newton's method with the nonsymmetric
!> Jacobian Phi_q solves them at each time; velocities follow from
!> Phi_q q' = -Phi_t (23) and accelerations from Phi_q q'' = gamma (25).
!>
!> Redundant constraints (a Jacobian of deficient row rank, as in the double
!> parallel crank) are found by a QR factorisation with column pivoting of
!> Phi_q^T at the initial configuration: the equations left after the
!> numerical rank (|R(k,k)| <= 1e-10 |R(1,1)|) depend on the others. They are
!> an input error unless the analysis asks to remove them; then they are
!> dropped, and the choice is renewed at the start of every step from the
!> last converged configuration, so that the kept equations stay well
!> conditioned as the mechanism moves.
module fekap_classical_cartesian
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, input_error, analysis_error
   use fekap_model, only: model_type, model_size, convergence_paper
   use fekap_model_results, only: step_result_type, new_step_result
   use fekap_strings, only: int_text, short_real_text
   use fekap_fem_convergence, only: convergence_type, is_converged, divergence_length
   use fekap_classical_constraints, only: constraint_system_type, new_constraint_system, eq_angle
   use fekap_linalg_lapack, only: dense_lu_factor, dense_lu_solve, dense_pivoted_qr
   use fekap_classical_stepping, only: classical_stepper_type, new_classical_history, begin_result, drive_value, &
      & new_step_convergence, &
      & newton_positions, branch_state_type, branch_jump_text, magnitude_ratio, lu_determinant
   implicit none
   private

   public :: cartesian_stepper_type, new_cartesian_stepper

   !> Relative threshold of the numerical rank of Phi_q.
   real(dp), parameter :: rank_tol = 1.0e-10_dp
   !> Residual of the removed (redundant) equations, per model size, above
   !> which a converged configuration is not one of the mechanism.
   real(dp), parameter :: redundant_tol = 1.0e-6_dp
   !> Relative pivot below which an LU factor counts as singular.
   real(dp), parameter :: pivot_tol = 1.0e-13_dp

   !> Cartesian-coordinate stepper.
   type, extends(classical_stepper_type) :: cartesian_stepper_type
      private
      type(constraint_system_type) :: system
      integer :: nnode = 0, nlink = 0
      !> The equations solved (all of them unless redundant ones were removed).
      integer, allocatable :: active(:)
      logical :: redundant = .false.
      !> Coordinates and their rates.
      real(dp), allocatable :: q(:), qd(:), qdd(:)
      !> Work arrays: all residuals, the full Jacobian, the square Jacobian and a right-hand side.
      real(dp), allocatable :: phi(:), jac_all(:, :), jac(:, :), rhs(:)
      integer, allocatable :: ipiv(:)
      !> log10 of the product of the row norms of the factored Jacobian, its
      !> angle columns scaled by the model size (for the conditioning measure).
      real(dp) :: log_rows = 0
      !> 1 for the translation coordinates, the model size for the angles.
      real(dp), allocatable :: column_scale(:)
      !> Model size and the shortest link (the unit of translation drives in the jump check).
      real(dp) :: shortest_link = 1
      !> Whether the equations solved can change from step to step (redundant
      !> ones removed, slidelines on master chains): then the determinant of the
      !> last configuration is recomputed with the equations of the step.
      logical :: changing_equations = .false.
      !> Time of the accepted configuration at which the equations were last
      !> chosen (huge: not yet).
      real(dp) :: equations_time = huge(1.0_dp)
      !> Name of a link of each body, for messages.
      character(len=64), allocatable :: body_name(:)
      !> Jump check: the state of the accepted configuration and the largest
      !> conditioning measure met so far.
      type(branch_state_type) :: branch
      real(dp) :: reference = 0
   contains
      procedure :: start => cartesian_start
      procedure :: try_step
      procedure :: rates_at => solve_rates
      procedure :: finish_step
      procedure :: position_residual
      procedure :: position_correction
   end type cartesian_stepper_type

contains

   !> Bodies and constraint equations of `model`, checked at the initial
   !> configuration: not enough independent equations is an input error, and
   !> so are redundant ones unless analysis%remove_redundant.
   subroutine new_cartesian_stepper(self, model, error)
      type(cartesian_stepper_type), intent(out) :: self
      type(model_type), intent(in) :: model
      type(error_type), allocatable, intent(out) :: error
      integer :: n, m, l

      call new_constraint_system(self%system, model, error)
      if (allocated(error)) return
      self%analysis = model%analysis
      self%conv = new_step_convergence(model%analysis, model_size(model))
      self%nnode = size(model%nodes)
      self%nlink = size(model%links)
      n = self%system%n
      m = self%system%m
      allocate (self%q(n), self%qd(n), self%qdd(n), self%rhs(n), source=0.0_dp)
      allocate (self%phi(m), self%jac_all(m, n), self%jac(n, n), source=0.0_dp)
      allocate (self%ipiv(n))
      self%q = self%system%bodies%q0
      call new_classical_history(self, n)
      self%model_length = model_size(model)
      self%shortest_link = huge(1.0_dp)
      allocate (self%body_name(n/3))
      do l = size(model%links), 1, -1
         associate (x => model%nodes(model%links(l)%node(2))%x - model%nodes(model%links(l)%node(1))%x)
            if (norm2(x) > 0) self%shortest_link = min(self%shortest_link, norm2(x))
         end associate
         self%body_name(self%system%bodies%link_body(l)) = model%links(l)%name
      end do
      if (self%shortest_link == huge(1.0_dp)) self%shortest_link = self%model_length
      allocate (self%column_scale(n), source=1.0_dp)
      self%column_scale(3:n:3) = self%model_length
      call select_equations(self, self%q, .true., error)
      if (allocated(error)) return
      self%changing_equations = self%redundant .or. self%system%has_chains()
   end subroutine new_cartesian_stepper

   !> Choose the n equations to solve from the rank-revealing QR of Phi_q^T at q.
   !> At the start, a rank below n and redundant equations are diagnosed.
   subroutine select_equations(self, q, initial, error)
      type(cartesian_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: q(:)
      logical, intent(in) :: initial
      type(error_type), allocatable, intent(out) :: error
      real(dp), allocatable :: a(:, :)
      integer, allocatable :: jpvt(:)
      integer :: n, m, rank, k, info
      character(:), allocatable :: verb

      n = self%system%n
      m = self%system%m
      call self%system%jacobian(q, self%jac_all)
      self%counts%tangent_assemblies = self%counts%tangent_assemblies + 1
      a = transpose(self%jac_all)
      allocate (jpvt(m))
      rank = 0
      if (m > 0) then
         call dense_pivoted_qr(a, jpvt, info)
         if (info /= 0) then
            call analysis_error(error, 'the QR factorisation of the constraint Jacobian failed')
            return
         end if
         do k = 1, min(n, m)
            if (abs(a(k, k)) > rank_tol*abs(a(1, 1))) rank = k
         end do
      end if
      if (initial) then
         if (rank < n) then
            call input_error(error, 'the mechanism is not determined by its constraints: '//int_text(n)// &
               & ' body coordinates but '//int_text(rank)//' independent constraint equations; add drives or supports')
            return
         end if
         self%redundant = m > rank
         if (self%redundant .and. .not. self%analysis%remove_redundant) then
            if (count_labels(self, jpvt(rank + 1:m)) == 1) then
               verb = ' repeats'
            else
               verb = ' repeat'
            end if
            call input_error(error, 'the constraint equations are redundant: '//labels(self, jpvt(rank + 1:m))//verb// &
               & ' constraints of others; the finite element method (method fem) handles this mechanism,'// &
               & ' or set `redundant remove`')
            return
         end if
      end if
      self%active = sort(jpvt(1:n))
   end subroutine select_equations

   !> The distinct labels of the equations idx, separated by commas.
   function labels(self, idx) result(text)
      type(cartesian_stepper_type), intent(in) :: self
      integer, intent(in) :: idx(:)
      character(:), allocatable :: text
      integer :: k, j
      logical :: seen
      text = ''
      do k = 1, size(idx)
         seen = .false.
         do j = 1, k - 1
            if (self%system%eq(idx(j))%label == self%system%eq(idx(k))%label) seen = .true.
         end do
         if (seen) cycle
         if (len(text) > 0) text = text//', '
         text = text//self%system%eq(idx(k))%label
      end do
   end function labels

   integer function count_labels(self, idx) result(c)
      type(cartesian_stepper_type), intent(in) :: self
      integer, intent(in) :: idx(:)
      integer :: k, j
      c = 0
      do k = 1, size(idx)
         if (all([(self%system%eq(idx(j))%label /= self%system%eq(idx(k))%label, j=1, k - 1)])) c = c + 1
      end do
   end function count_labels

   pure function sort(v) result(s)
      integer, intent(in) :: v(:)
      integer :: s(size(v))
      integer :: i, j, x
      s = v
      do i = 2, size(s)
         x = s(i)
         j = i - 1
         do while (j >= 1)
            if (s(j) <= x) exit
            s(j + 1) = s(j)
            j = j - 1
         end do
         s(j + 1) = x
      end do
   end function sort

   !> The initial configuration at t_start (assembled by Newton's method if
   !> the given coordinates violate a constraint), with its rates.
   subroutine cartesian_start(self, result, error)
      class(cartesian_stepper_type), intent(inout) :: self
      type(step_result_type), intent(inout) :: result
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: t, increment_residual
      integer :: iterations
      self%step = 0
      t = self%analysis%t_start
      self%q = self%system%bodies%q0
      self%history%filled = 0
      self%equations_time = huge(1.0_dp)
      call self%system%residual(self%q, t, self%phi)
      increment_residual = active_norm(self)
      call newton_positions(self, t, increment_residual, iterations, error)
      if (allocated(error)) then
         error%message = 'the initial configuration cannot be assembled: '//error%message
         return
      end if
      call self%accept(self%q, t)
      call branch_state(self, self%q, .true., self%branch)
      self%reference = self%branch%measure
      call finish_step(self, t, iterations, result, error)
   end subroutine cartesian_start

   !> Newton's method at time t from the predictor, and the branch-jump
   !> check; the configuration is accepted (pushed on the history) only if both
   !> succeed.
   subroutine try_step(self, t, iterations, error)
      class(cartesian_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      integer, intent(out) :: iterations
      type(error_type), allocatable, intent(out) :: error
      type(branch_state_type) :: new
      real(dp) :: increment_residual, worst, step_floor
      real(dp) :: dd(size(self%system%laws)), dq_old(self%system%n/3), dq_new(self%system%n/3)
      logical :: rotation(size(self%system%laws))
      integer :: where_, b
      character(:), allocatable :: jump

      iterations = 0
      ! The equations (and master segments) to solve are chosen at the last
      ! accepted configuration, once: a retry after a step cut starts from
      ! the same configuration and would choose the same.
      if (self%equations_time /= self%history%t(self%history%newest)) then
         if (self%redundant) then
            call select_equations(self, self%history%q(:, self%history%newest), .false., error)
            if (allocated(error)) return
         end if
         call self%system%select_segments(self%history%q(:, self%history%newest))
         ! With other equations the determinant of the last configuration is another one.
         if (self%changing_equations) call branch_state(self, self%history%q(:, self%history%newest), .true., self%branch)
         self%equations_time = self%history%t(self%history%newest)
      end if
      ! The scale of the default test: the residual of the drive increment alone.
      self%q = self%history%q(:, self%history%newest)
      call set_driven_angles(self, t)
      call self%system%residual(self%q, t, self%phi)
      increment_residual = active_norm(self)
      ! Predictor, with the driven angles set to their values at t (the paper's (8)).
      call self%predict(t, self%q)
      call set_driven_angles(self, t)
      call newton_positions(self, t, increment_residual, iterations, error)
      if (allocated(error)) return
      if (self%system%has_chains()) then
         call follow_segments(self, t, increment_residual, iterations, error)
         if (allocated(error)) return
      end if
      ! Without its redundant equations the system may converge to a
      ! configuration of a mechanism with a joint missing: every equation must hold.
      if (self%redundant) then
         call self%system%residual(self%q, t, self%phi)
         if (maxval(abs(self%phi)) > redundant_tol*self%model_length) then
            call analysis_error(error, 't = '//short_real_text(t)// &
               & ': Newton converged to a configuration that violates the removed (redundant) equations (residual '// &
               & short_real_text(maxval(abs(self%phi)))//'), not a configuration of the mechanism', t=t)
            return
         end if
      end if

      ! Branch-jump check: every body angle against its linear response to the
      ! drive increment at both ends, and the sign of det Phi_q (from the last
      ! Newton factor, at the converged configuration within tolerance).
      call branch_state(self, self%q, iterations == 0, new)
      self%reference = max(self%reference, new%measure)
      call self%system%drive_increments(self%history%t(self%history%newest), t, dd, rotation)
      ! The drive increment: radians, or lengths of the shortest link.
      step_floor = 0
      do b = 1, size(dd)
         step_floor = max(step_floor, abs(dd(b))/merge(1.0_dp, self%shortest_link, rotation(b)))
      end do
      do b = 1, size(dq_old)
         dq_old(b) = dot_product(self%branch%response(3*b, :), dd)
         dq_new(b) = dot_product(new%response(3*b, :), dd)
      end do
      call magnitude_ratio(self%q(3:self%system%n:3) - self%history%q(3:self%system%n:3, self%history%newest), dq_old, dq_new, &
         & step_floor, self%analysis%length_tol, worst, where_)
      where_ = max(1, where_)
      jump = branch_jump_text(t, self%branch, new, self%reference, worst, &
         & self%q(3*where_) - self%history%q(3*where_, self%history%newest), 'the angle of link '//trim(self%body_name(where_)))
      if (len(jump) > 0) then
         call analysis_error(error, jump, t=t)
         return
      end if
      self%branch = new
      call self%accept(self%q, t)
   end subroutine try_step

   !> A slave that slid past the end of its master segment within the step
   !> is on the next one at the converged configuration: its equations
   !> follow it there and Newton goes on from that configuration (as the
   !> FEM moves a slave on to the next master element), at most
   !> max_segment_moves times. The last accepted configuration's branch
   !> state is taken again with the new equations (as at a change of
   !> equations between steps), and the equations are chosen again at the
   !> next try, which may be a retry from that configuration.
   subroutine follow_segments(self, t, increment_residual, iterations, error)
      class(cartesian_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t, increment_residual
      integer, intent(inout) :: iterations
      type(error_type), allocatable, intent(out) :: error
      integer, parameter :: max_segment_moves = 4
      integer :: move, its
      logical :: moved
      do move = 1, max_segment_moves
         call self%system%select_segments(self%q, moved)
         if (.not. moved) return
         self%equations_time = huge(1.0_dp)
         call branch_state(self, self%history%q(:, self%history%newest), .true., self%branch)
         call newton_positions(self, t, increment_residual, its, error)
         iterations = iterations + its
         if (allocated(error)) return
      end do
   end subroutine follow_segments

   !> The jump check's view of configuration q with the equations of the
   !> step: the sign of det Phi_q, the conditioning measure |det| over the
   !> product of the row norms (angle columns scaled by the model size, so that
   !> it is free of units), and the response to unit drive changes,
   !> Phi_q r_j = e_j (e_j selects the equation of drive j). With refactor,
   !> Phi_q is factored at q; otherwise the last Newton factor is used.
   subroutine branch_state(self, q, refactor, state)
      type(cartesian_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: q(:)
      logical, intent(in) :: refactor
      type(branch_state_type), intent(out) :: state
      type(error_type), allocatable :: singular
      real(dp) :: log_det
      integer :: j, k, info
      allocate (state%response(self%system%n, size(self%system%laws)), source=0.0_dp)
      if (refactor) then
         call self%system%jacobian(q, self%jac_all)
         self%counts%tangent_assemblies = self%counts%tangent_assemblies + 1
         self%rhs = 0
         call factor_and_solve(self, self%analysis%t_start, singular)
         if (allocated(singular)) then
            state%known = .true.
            return
         end if
      end if
      state%known = .true.
      call lu_determinant(self%jac, self%ipiv, state%sign, log_det)
      if (state%sign == 0) return
      state%measure = 10.0_dp**min(0.0_dp, log_det + (self%system%n/3)*log10(self%model_length) - self%log_rows)
      do k = 1, size(self%active)
         j = self%system%eq(self%active(k))%drive
         if (j == 0) cycle
         self%rhs = 0
         self%rhs(k) = 1
         call dense_lu_solve(self%jac, self%ipiv, self%rhs, info)
         state%response(:, j) = self%rhs
      end do
   end subroutine branch_state

   !> Angles of bodies driven directly by a rotation drive take their value at t.
   subroutine set_driven_angles(self, t)
      type(cartesian_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      integer :: k
      real(dp) :: f, df, ddf
      do k = 1, size(self%active)
         associate (e => self%system%eq(self%active(k)))
            if (e%kind /= eq_angle .or. e%drive == 0 .or. e%bj /= 0) cycle
            call drive_value(self%system%laws(e%drive), self%system%initial(e%drive), self%system%t_start, t, f, df, ddf)
            self%q(3*e%bi) = e%const + f
         end associate
      end do
   end subroutine set_driven_angles

   !> The residuals of the constraint equations at self%q and time t (in
   !> self%phi) and the norm of the active ones.
   subroutine position_residual(self, t, norm)
      class(cartesian_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      real(dp), intent(out) :: norm
      call self%system%residual(self%q, t, self%phi)
      self%counts%residual_assemblies = self%counts%residual_assemblies + 1
      norm = active_norm(self)
   end subroutine position_residual

   !> The Newton correction of self%q from the active residuals, and its
   !> length (the largest change of a body's position).
   subroutine position_correction(self, t, correction, error)
      class(cartesian_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      real(dp), intent(out) :: correction
      type(error_type), allocatable, intent(out) :: error
      integer :: k
      correction = 0
      call self%system%jacobian(self%q, self%jac_all)
      self%counts%tangent_assemblies = self%counts%tangent_assemblies + 1
      do k = 1, size(self%active)
         self%rhs(k) = -self%phi(self%active(k))
      end do
      call factor_and_solve(self, t, error)
      if (allocated(error)) return
      self%q = self%q + self%rhs
      do k = 1, self%system%n/3
         correction = max(correction, abs(self%rhs(3*k - 2)), abs(self%rhs(3*k - 1)))
      end do
   end subroutine position_correction

   !> Euclidean norm of the active residuals in self%phi.
   pure real(dp) function active_norm(self) result(r)
      type(cartesian_stepper_type), intent(in) :: self
      integer :: k
      r = 0
      do k = 1, size(self%active)
         r = r + self%phi(self%active(k))**2
      end do
      r = sqrt(r)
   end function active_norm

   !> Factor the active rows of self%jac_all and solve for self%rhs in place.
   subroutine factor_and_solve(self, t, error)
      type(cartesian_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      type(error_type), allocatable, intent(out) :: error
      integer :: info, k
      real(dp) :: big
      do k = 1, size(self%active)
         self%jac(k, :) = self%jac_all(self%active(k), :)
      end do
      big = maxval(abs(self%jac))
      self%log_rows = 0
      do k = 1, size(self%jac, 1)
         self%log_rows = self%log_rows + log10(max(tiny(1.0_dp), norm2(self%jac(k, :)*self%column_scale)))
      end do
      call dense_lu_factor(self%jac, self%ipiv, info)
      self%counts%lu_factorisations = self%counts%lu_factorisations + 1
      if (info == 0) then
         do k = 1, size(self%jac, 1)
            if (abs(self%jac(k, k)) <= pivot_tol*big) info = k
         end do
      end if
      if (info /= 0) then
         call analysis_error(error, 't = '//short_real_text(t)//': the constraint Jacobian is singular '// &
            & '(a singular configuration of the mechanism)', t=t)
         return
      end if
      call dense_lu_solve(self%jac, self%ipiv, self%rhs, info)
   end subroutine factor_and_solve

   !> Rates at the accepted configuration (when asked for) and the step's result.
   subroutine finish_step(self, t, iterations, result, error)
      class(cartesian_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      integer, intent(in) :: iterations
      type(step_result_type), intent(inout) :: result
      type(error_type), allocatable, intent(out) :: error
      integer :: k, b, l

      call begin_result(self, t, iterations, self%nnode, self%nlink, result)
      call self%system%residual(self%q, t, self%phi)
      self%counts%residual_assemblies = self%counts%residual_assemblies + 1
      result%residual = norm2(self%phi)
      result%has_velocity = self%analysis%velocities
      result%has_acceleration = self%analysis%velocities .and. self%analysis%accelerations
      call solve_rates(self, t, error)
      if (allocated(error)) return

      associate (bodies => self%system%bodies)
         do k = 1, self%nnode
            b = bodies%node_body(k)
            if (b == 0) then
               result%pos(:, k) = bodies%x0(:, k)
               result%vel(:, k) = 0
               result%acc(:, k) = 0
            else
               call bodies%position(b, bodies%node_local(:, k), self%q, self%qd, self%qdd, &
                  & result%pos(:, k), result%vel(:, k), result%acc(:, k))
            end if
         end do
         do l = 1, self%nlink
            b = bodies%link_body(l)
            result%angle(l) = self%q(3*b) + bodies%link_offset(l)
            result%omega(l) = self%qd(3*b)
            result%alpha(l) = self%qdd(3*b)
         end do
      end associate
   end subroutine finish_step

   !> Velocities and accelerations of the accepted configuration at time t,
   !> as the analysis asks for them (zero otherwise); both known feed the
   !> Taylor predictor.
   subroutine solve_rates(self, t, error)
      class(cartesian_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: gamma_rhs(self%system%m)
      integer :: info
      self%qd = 0
      self%qdd = 0
      if (.not. self%analysis%velocities) return
      ! Velocities (23): Phi_q q' = -Phi_t.
      call self%system%jacobian(self%q, self%jac_all)
      self%counts%tangent_assemblies = self%counts%tangent_assemblies + 1
      call self%system%velocity_rhs(t, self%phi)
      self%rhs = self%phi(self%active)
      call factor_and_solve(self, t, error)
      if (allocated(error)) return
      self%counts%velocity_solves = self%counts%velocity_solves + 1
      self%qd = self%rhs
      if (.not. self%analysis%accelerations) return
      ! Accelerations (25): Phi_q q'' = gamma, with the factors of the velocity solve.
      call self%system%acceleration_rhs(self%q, self%qd, t, gamma_rhs)
      self%qdd = gamma_rhs(self%active)
      call dense_lu_solve(self%jac, self%ipiv, self%qdd, info)
      self%counts%acceleration_solves = self%counts%acceleration_solves + 1
      call self%set_rates(self%qd, self%qdd)
   end subroutine solve_rates

end module fekap_classical_cartesian
