!> The paper's orientation-angle method for the four-bar linkage, eqs. (1)-(12):
!> the crank angle theta1 is driven, the coupler and rocker angles
!> theta2, theta3 are found by Newton's method on the loop-closure equations.
!>
!> Internally the loop is A -> B -> C <- D with A the crank's ground pivot,
!> B the crank-coupler hinge, C the coupler-rocker hinge and D the rocker's
!> ground pivot; theta1, theta2, theta3 are the directions of A->B, B->C and
!> D->C. The ground vector D - A need not be horizontal.
module fekap_classical_angles
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, input_error, analysis_error, at_time
   use fekap_model, only: model_type, model_size, dof_x, dof_y, dof_rot, convergence_paper
   use fekap_model_drive_law, only: law_type
   use fekap_model_results, only: step_result_type, new_step_result
   use fekap_strings, only: int_text, short_real_text
   use fekap_fem_convergence, only: convergence_type, is_converged, divergence_length
   use fekap_classical_stepping, only: classical_stepper_type, new_classical_history, begin_result, drive_value, &
      & new_step_convergence, &
      & newton_positions, branch_state_type, branch_jump_text, magnitude_ratio
   implicit none
   private

   public :: angles_stepper_type, new_angles_stepper

   !> Orientation-angle stepper of a four-bar linkage.
   type, extends(classical_stepper_type) :: angles_stepper_type
      private
      integer :: nnode = 0, nlink = 0
      !> Nodes A, B, C, D of the loop (indices into model%nodes).
      integer :: node(4) = 0
      !> Crank, coupler and rocker (indices into model%links).
      integer :: link(3) = 0
      !> Reported direction angle of each of the three links minus its internal angle (0 or +-pi).
      real(dp) :: offset(3) = 0
      !> Link lengths l1, l2, l3 and the ground pivots A and D.
      real(dp) :: length(3) = 0
      real(dp) :: pivot_a(2) = 0, pivot_d(2) = 0
      !> The crank's drive law, its initial internal angle and the start time.
      type(law_type) :: law
      real(dp) :: theta1_initial = 0
      !> Current theta1 and its rates, and the unknowns d = (theta2, theta3) with theta2', theta3', theta2'', theta3''.
      real(dp) :: theta1(3) = 0
      real(dp) :: d(2) = 0, dd(2) = 0, ddd(2) = 0
      !> Names of the crank, coupler and rocker, for messages.
      character(len=64) :: link_name(3) = ''
      !> The loop-closure residual at d, for the Newton correction.
      real(dp) :: p(2) = 0
      !> Jump check: the state of the accepted configuration and the largest
      !> conditioning measure met so far.
      type(branch_state_type) :: branch
      real(dp) :: reference = 0
   contains
      procedure :: start => angles_start
      procedure :: try_step
      procedure :: rates_at
      procedure :: finish_step
      procedure :: position_residual
      procedure :: position_correction
   end type angles_stepper_type

contains

   !> Recognise the single four-bar loop of `model` and set up the method.
   !> Anything else is an input error that says what was found.
   subroutine new_angles_stepper(self, model, error)
      type(angles_stepper_type), intent(out) :: self
      type(model_type), intent(in) :: model
      type(error_type), allocatable, intent(out) :: error
      character(:), allocatable :: problems
      integer :: nnode, nlink, i, j, k, npivot, pivots(2), idrive, crank, coupler, rocker, na, nb, nc, nd
      real(dp) :: internal(2, 3)

      problems = ''
      nnode = 0
      nlink = 0
      if (allocated(model%nodes)) nnode = size(model%nodes)
      if (allocated(model%links)) nlink = size(model%links)
      if (nlink /= 3) call add(problems, count_text(nlink, 'link')//' (a four-bar has 3)')
      if (nnode /= 4) call add(problems, count_text(nnode, 'node')//' (a four-bar has 4)')
      if (allocated(model%welds)) then
         if (size(model%welds) > 0) call add(problems, count_text(size(model%welds), 'weld'))
      end if
      if (allocated(model%slidelines)) then
         if (size(model%slidelines) > 0) call add(problems, count_text(size(model%slidelines), 'slideline'))
      end if
      if (allocated(model%loads)) then
         if (size(model%loads) > 0) call add(problems, count_text(size(model%loads), 'load'))
      end if
      ! Ground pivots: nodes fixed in x and y; no other kind of support.
      npivot = 0
      pivots = 0
      if (allocated(model%supports)) then
         do i = 1, size(model%supports)
            associate (s => model%supports(i))
               if (s%fix(dof_rot)) then
                  call add(problems, 'a clamped rotation at node '//model%nodes(s%node)%name)
               else if (.not. (s%fix(dof_x) .and. s%fix(dof_y))) then
                  call add(problems, 'a support of only one coordinate at node '//model%nodes(s%node)%name)
               else if (all(pivots /= s%node)) then
                  npivot = npivot + 1
                  if (npivot <= 2) pivots(npivot) = s%node
               end if
            end associate
         end do
      end if
      if (npivot /= 2) call add(problems, count_text(npivot, 'ground pivot')//' (a four-bar has 2)')
      ! One rotation drive of a link.
      idrive = 0
      if (allocated(model%drives)) then
         if (size(model%drives) /= 1) then
            call add(problems, count_text(size(model%drives), 'drive')//' (a four-bar has 1, its crank)')
         else if (model%drives(1)%dof /= dof_rot .or. model%drives(1)%link == 0) then
            call add(problems, 'a drive that is not a link rotation')
         else
            idrive = 1
         end if
      else
         call add(problems, 'no drive')
      end if
      if (len(problems) > 0) then
         call refuse(error, problems)
         return
      end if

      ! Topology: crank A-B (A a pivot), coupler B-C, rocker C-D (D the other pivot).
      crank = model%drives(idrive)%link
      associate (ln => model%links(crank)%node)
         if (any(pivots == ln(1)) .and. .not. any(pivots == ln(2))) then
            na = ln(1)
            nb = ln(2)
         else if (any(pivots == ln(2)) .and. .not. any(pivots == ln(1))) then
            na = ln(2)
            nb = ln(1)
         else
            call refuse(error, 'the driven link '//model%links(crank)%name//' is not a crank with one end at a ground pivot')
            return
         end if
      end associate
      nd = merge(pivots(2), pivots(1), pivots(1) == na)
      coupler = 0
      rocker = 0
      do i = 1, 3
         if (i == crank) cycle
         if (any(model%links(i)%node == nb)) coupler = i
         if (any(model%links(i)%node == nd)) rocker = i
      end do
      if (coupler == 0 .or. rocker == 0 .or. coupler == rocker) then
         call refuse(error, 'the links do not form a single loop crank - coupler - rocker between the two ground pivots')
         return
      end if
      nc = sum(model%links(coupler)%node) - nb
      if (.not. any(model%links(rocker)%node == nc) .or. nc == na .or. nc == nd .or. nc == nb) then
         call refuse(error, 'the links do not form a single loop crank - coupler - rocker between the two ground pivots')
         return
      end if

      self%analysis = model%analysis
      self%conv = new_step_convergence(model%analysis, model_size(model))
      self%nnode = nnode
      self%nlink = nlink
      self%node = [na, nb, nc, nd]
      self%link = [crank, coupler, rocker]
      self%pivot_a = model%nodes(na)%x
      self%pivot_d = model%nodes(nd)%x
      internal(:, 1) = model%nodes(nb)%x - model%nodes(na)%x
      internal(:, 2) = model%nodes(nc)%x - model%nodes(nb)%x
      internal(:, 3) = model%nodes(nc)%x - model%nodes(nd)%x
      do k = 1, 3
         self%length(k) = norm2(internal(:, k))
         if (self%length(k) <= 1.0e-12_dp*model_size(model)) then
            call input_error(error, 'link '//model%links(self%link(k))%name//' has zero length')
            return
         end if
         j = self%link(k)
         associate (v => model%nodes(model%links(j)%node(2))%x - model%nodes(model%links(j)%node(1))%x)
            self%offset(k) = atan2(v(2), v(1)) - atan2(internal(2, k), internal(1, k))
         end associate
      end do
      self%model_length = model_size(model)
      do k = 1, 3
         self%link_name(k) = model%links(self%link(k))%name
      end do
      self%law = model%drives(idrive)%law
      self%theta1_initial = atan2(internal(2, 1), internal(1, 1))
      self%d = [atan2(internal(2, 2), internal(1, 2)), atan2(internal(2, 3), internal(1, 3))]
      call new_classical_history(self, 2)
   contains
      subroutine refuse(error, what)
         type(error_type), allocatable, intent(out) :: error
         character(*), intent(in) :: what
         call input_error(error, 'method angles covers four-bar linkages only: found '//what)
      end subroutine refuse
   end subroutine new_angles_stepper

   !> Append a problem to a list separated by commas.
   pure subroutine add(list, what)
      character(:), allocatable, intent(inout) :: list
      character(*), intent(in) :: what
      if (len(list) > 0) then
         list = list//', '//what
      else
         list = what
      end if
   end subroutine add

   pure function count_text(n, what) result(text)
      integer, intent(in) :: n
      character(*), intent(in) :: what
      character(:), allocatable :: text
      text = int_text(n)//' '//what
      if (n /= 1) text = text//'s'
   end function count_text

   !> The initial configuration at t_start, with its rates when asked for.
   subroutine angles_start(self, result, error)
      class(angles_stepper_type), intent(inout) :: self
      type(step_result_type), intent(inout) :: result
      type(error_type), allocatable, intent(out) :: error
      self%step = 0
      call drive_value(self%law, self%theta1_initial, self%analysis%t_start, self%analysis%t_start, &
         & self%theta1(1), self%theta1(2), self%theta1(3))
      call self%accept(self%d, self%analysis%t_start)
      call branch_state(self, self%d, self%branch)
      self%reference = self%branch%measure
      call finish_step(self, self%analysis%t_start, 0, result, error)
   end subroutine angles_start

   !> Newton's method (11)-(13) on the loop closure (1)-(2) at time t from the
   !> predictor, and the branch-jump check; the configuration is accepted
   !> (pushed on the history) only if both succeed.
   subroutine try_step(self, t, iterations, error)
      class(angles_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      integer, intent(out) :: iterations
      type(error_type), allocatable, intent(out) :: error
      type(branch_state_type) :: new
      real(dp) :: p(2), increment_residual, f0, df, ddf, increment, worst
      integer :: where_
      character(:), allocatable :: jump

      call drive_value(self%law, self%theta1_initial, self%analysis%t_start, t, &
         & self%theta1(1), self%theta1(2), self%theta1(3))
      ! The scale of the default test: the residual of the drive increment alone.
      call closure(self, self%history%q(:, self%history%newest), p)
      increment_residual = norm2(p)
      call self%predict(t, self%d)
      call newton_positions(self, t, increment_residual, iterations, error)
      if (allocated(error)) return

      ! Branch-jump check: the coupler and rocker angles against their linear
      ! response to the crank increment, and the sign of det K.
      call drive_value(self%law, self%theta1_initial, self%analysis%t_start, self%history%t(self%history%newest), f0, df, ddf)
      increment = self%theta1(1) - f0
      call branch_state(self, self%d, new)
      call magnitude_ratio(self%d - self%history%q(:, self%history%newest), increment*self%branch%response(:, 1), &
         & increment*new%response(:, 1), abs(increment), self%analysis%length_tol, worst, where_)
      self%reference = max(self%reference, new%measure)
      where_ = max(1, where_)
      jump = branch_jump_text(t, self%branch, new, self%reference, worst, &
         & self%d(where_) - self%history%q(where_, self%history%newest), 'the angle of link '//trim(self%link_name(where_ + 1)))
      if (len(jump) > 0) then
         call analysis_error(error, jump, t=t)
         return
      end if
      self%branch = new
      call self%accept(self%d, t)
   end subroutine try_step

   !> The loop-closure residual at the current d (kept in self%p) and its norm
   !> (theta1 at time t is already set: the closure needs no t).
   subroutine position_residual(self, t, norm)
      class(angles_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      real(dp), intent(out) :: norm
      call closure(self, self%d, self%p)
      self%counts%residual_assemblies = self%counts%residual_assemblies + 1
      norm = norm2(self%p)
   end subroutine position_residual

   !> The Newton correction of d from the kept residual, and its length
   !> (each angle times the length of its link).
   subroutine position_correction(self, t, correction, error)
      class(angles_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      real(dp), intent(out) :: correction
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: k(2, 2), delta(2)
      call tangent(self, self%d, k)
      self%counts%tangent_assemblies = self%counts%tangent_assemblies + 1
      call solve2(k, -self%p, delta, error)
      self%counts%lu_factorisations = self%counts%lu_factorisations + 1
      correction = 0
      if (allocated(error)) then
         error%message = 't = '//short_real_text(t)//': '//error%message
         call at_time(error, t)
         return
      end if
      self%d = self%d + delta
      correction = maxval(abs(delta)*self%length(2:3))
   end subroutine position_correction

   !> The jump check's view of the configuration d at the current crank angle:
   !> the sign of det K, |det K| / (|k1| |k2|) = |sin(theta3 - theta2)|, and the
   !> response of theta2, theta3 to a unit crank rotation, K r = -l1 n1.
   subroutine branch_state(self, d, state)
      type(angles_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: d(2)
      type(branch_state_type), intent(out) :: state
      type(error_type), allocatable :: singular
      real(dp) :: k(2, 2), det, e(2, 3), n(2, 3)
      call tangent(self, d, k)
      self%counts%tangent_assemblies = self%counts%tangent_assemblies + 1
      det = k(1, 1)*k(2, 2) - k(1, 2)*k(2, 1)
      state%known = .true.
      state%sign = nint(sign(1.0_dp, det))
      if (det == 0) state%sign = 0
      state%measure = abs(det)/(norm2(k(:, 1))*norm2(k(:, 2)))
      allocate (state%response(2, 1))
      call directions(self, d, e, n)
      ! A singular K has no response: zero, which lets the drive increment bound the change.
      call solve2(k, -self%length(1)*n(:, 1), state%response(:, 1), singular)
   end subroutine branch_state

   !> Rates of the accepted configuration at time t (the crank's own rates
   !> were set with its angle by try_step).
   subroutine rates_at(self, t, error)
      class(angles_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      type(error_type), allocatable, intent(out) :: error
      call solve_rates(self, error)
   end subroutine rates_at

   !> Rates at the accepted configuration (when asked for) and the step's result.
   subroutine finish_step(self, t, iterations, result, error)
      class(angles_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      integer, intent(in) :: iterations
      type(step_result_type), intent(inout) :: result
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: p(2), e(2, 3), n(2, 3), w(3), a(3)
      integer :: j

      call begin_result(self, t, iterations, self%nnode, self%nlink, result)
      call closure(self, self%d, p)
      result%residual = norm2(p)
      result%has_velocity = self%analysis%velocities
      result%has_acceleration = self%analysis%velocities .and. self%analysis%accelerations
      call solve_rates(self, error)
      if (allocated(error)) return
      w = 0
      a = 0
      if (result%has_velocity) w = [self%theta1(2), self%dd]
      if (result%has_acceleration) a = [self%theta1(3), self%ddd]
      call directions(self, self%d, e, n)

      ! Nodes: A and D fixed, B = A + l1 e1, C = B + l2 e2, and their rates.
      result%pos(:, self%node(1)) = self%pivot_a
      result%pos(:, self%node(4)) = self%pivot_d
      result%pos(:, self%node(2)) = self%pivot_a + self%length(1)*e(:, 1)
      result%pos(:, self%node(3)) = result%pos(:, self%node(2)) + self%length(2)*e(:, 2)
      result%vel = 0
      result%acc = 0
      result%vel(:, self%node(2)) = self%length(1)*w(1)*n(:, 1)
      result%vel(:, self%node(3)) = result%vel(:, self%node(2)) + self%length(2)*w(2)*n(:, 2)
      result%acc(:, self%node(2)) = self%length(1)*(a(1)*n(:, 1) - w(1)**2*e(:, 1))
      result%acc(:, self%node(3)) = result%acc(:, self%node(2)) + self%length(2)*(a(2)*n(:, 2) - w(2)**2*e(:, 2))
      do j = 1, 3
         result%angle(self%link(j)) = merge(self%theta1(1), self%d(max(1, j - 1)), j == 1) + self%offset(j)
         result%omega(self%link(j)) = w(j)
         result%alpha(self%link(j)) = a(j)
      end do
   end subroutine finish_step

   !> Velocities and accelerations of the accepted configuration, as the
   !> analysis asks for them (zero otherwise); both known feed the Taylor predictor.
   subroutine solve_rates(self, error)
      type(angles_stepper_type), intent(inout) :: self
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: k(2, 2), rhs(2), e(2, 3), n(2, 3), w(3)
      self%dd = 0
      self%ddd = 0
      if (.not. self%analysis%velocities) return
      call directions(self, self%d, e, n)
      call tangent(self, self%d, k)
      self%counts%tangent_assemblies = self%counts%tangent_assemblies + 1
      ! Velocities (8)-(10): K d' = P_a with P_a = -l1 theta1' n1.
      rhs = -self%length(1)*self%theta1(2)*n(:, 1)
      call solve2(k, rhs, self%dd, error)
      self%counts%lu_factorisations = self%counts%lu_factorisations + 1
      self%counts%velocity_solves = self%counts%velocity_solves + 1
      if (allocated(error)) return
      if (.not. self%analysis%accelerations) return
      w = [self%theta1(2), self%dd]
      ! Accelerations: the time derivative of l1 w1 n1 + l2 w2 n2 - l3 w3 n3 = 0 gives
      ! K d'' = -l1 theta1'' n1 + l1 theta1'**2 e1 + l2 theta2'**2 e2 - l3 theta3'**2 e3
      ! (the paper's (11)-(12), whose right-hand side is misprinted).
      rhs = -self%length(1)*self%theta1(3)*n(:, 1) + self%length(1)*w(1)**2*e(:, 1) &
         & + self%length(2)*w(2)**2*e(:, 2) - self%length(3)*w(3)**2*e(:, 3)
      call solve2(k, rhs, self%ddd, error)
      self%counts%acceleration_solves = self%counts%acceleration_solves + 1
      if (allocated(error)) return
      call self%set_rates(self%dd, self%ddd)
   end subroutine solve_rates

   !> Unit directions e = (cos, sin) and normals n = (-sin, cos) of theta1, theta2, theta3.
   pure subroutine directions(self, d, e, n)
      class(angles_stepper_type), intent(in) :: self
      real(dp), intent(in) :: d(2)
      real(dp), intent(out) :: e(2, 3), n(2, 3)
      real(dp) :: theta(3)
      theta = [self%theta1(1), d]
      e(1, :) = cos(theta)
      e(2, :) = sin(theta)
      n(1, :) = -e(2, :)
      n(2, :) = e(1, :)
   end subroutine directions

   !> Loop closure (1)-(2): P = l1 e1 + l2 e2 - l3 e3 - (D - A).
   pure subroutine closure(self, d, p)
      class(angles_stepper_type), intent(in) :: self
      real(dp), intent(in) :: d(2)
      real(dp), intent(out) :: p(2)
      real(dp) :: e(2, 3), n(2, 3)
      call directions(self, d, e, n)
      p = self%length(1)*e(:, 1) + self%length(2)*e(:, 2) - self%length(3)*e(:, 3) - (self%pivot_d - self%pivot_a)
   end subroutine closure

   !> The 2x2 nonsymmetric Jacobian K of (5): columns l2 n2 and -l3 n3.
   pure subroutine tangent(self, d, k)
      class(angles_stepper_type), intent(in) :: self
      real(dp), intent(in) :: d(2)
      real(dp), intent(out) :: k(2, 2)
      real(dp) :: e(2, 3), n(2, 3)
      call directions(self, d, e, n)
      k(:, 1) = self%length(2)*n(:, 2)
      k(:, 2) = -self%length(3)*n(:, 3)
   end subroutine tangent

   !> Solve the 2x2 system k x = b; a determinant below 1e-12 of the product
   !> of the column norms is a singular configuration (coupler and rocker in line).
   pure subroutine solve2(k, b, x, error)
      real(dp), intent(in) :: k(2, 2), b(2)
      real(dp), intent(out) :: x(2)
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: det
      det = k(1, 1)*k(2, 2) - k(1, 2)*k(2, 1)
      if (abs(det) <= 1.0e-12_dp*norm2(k(:, 1))*norm2(k(:, 2))) then
         x = 0
         call analysis_error(error, 'the Jacobian (5) is singular: coupler and rocker are in line')
         return
      end if
      x(1) = (b(1)*k(2, 2) - b(2)*k(1, 2))/det
      x(2) = (k(1, 1)*b(2) - k(2, 1)*b(1))/det
   end subroutine solve2

end module fekap_classical_angles
