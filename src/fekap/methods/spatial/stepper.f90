!> The time stepper of a spatial deck's kinematics (fekap_spatial_kinematics
!> driven by the time loop): each step predicts the new configuration by
!> a Taylor series along the last rates, q (+) (h v + h^2/2 a + h^3/6 j +
!> h^4/24 k), j and k the third and fourth rates of the motion at the last
!> configuration (see curve_rates), then runs
!> Newton-Raphson on the free dofs with the material tangent (exact at the
!> stress-free solution). Every Newton iteration assembles and factors the
!> tangent at its iterate; the iteration whose correction is below the
!> length tolerance (lengths relative to the longest element), and below
!> rate_tol, ends Newton: its factored tangent, at the converged
!> configuration, gives the velocities and accelerations (Eischen, Sun &
!> Marler eqs. (47)-(53)), and its correction is applied without a further
!> assembly. A step's iterations count the corrections that needed another
!> assembly and factorisation after them, as the planar method counts its
!> check "with the tangent factored at the converged configuration" as no
!> iteration. A step whose Newton fails is cut in halves.
module fekap_spatial_stepper
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, analysis_error
   use fekap_model, only: model_type
   use fekap_model_results, only: step_result_type
   use fekap_stepping_stepper, only: stepper_type
   use fekap_spatial_mechanism, only: spatial_mechanism_type
   use fekap_spatial_kinematics, only: spatial_state_type, new_spatial_state, spatial_configuration_type, &
      & configure, assemble_spatial, set_drives, update_state, free_dofs, spatial_rates_factored, point_rate, &
      & tangent_for
   use fekap_spatial_tangent, only: spatial_tangent_type
   use fekap_spatial_build, only: spatial_map_type, build_spatial_mechanism
   use fekap_spatial_link_motion, only: link_motion_type, new_link_motion, fill_link_motion
   implicit none
   private

   public :: spatial_stepper_type, new_spatial_stepper

   !> Halvings of one step before it is given up (as the planar step control's).
   integer, parameter :: max_cuts = 8
   !> The last correction (relative to the longest element) below which the
   !> iterate's tangent gives the rates: the rates at an iterate differ from
   !> those at the solution by about d(rates)/dq times the correction (an
   !> acceleration omega^2 times it), so a correction at the length
   !> tolerance's 1e-12 would cost the accelerations two digits; one that
   !> the tolerance accepts above this is applied and the next iterate,
   !> whatever its correction below the tolerance, gives the rates.
   real(dp), parameter :: rate_tol = 1.0e-14_dp

   type, extends(stepper_type) :: spatial_stepper_type
      type(spatial_mechanism_type) :: m
      type(spatial_map_type) :: map
      !> The accepted state, its time and its rates.
      type(spatial_state_type) :: s
      real(dp) :: t = 0
      real(dp), allocatable :: v(:), a(:)
      !> The third and fourth rates of the motion there (the predictor's last terms).
      real(dp), allocatable :: jerk(:), snap(:)
      !> The third rates at the two configurations before, their times and how many there are.
      real(dp), allocatable :: jerk1(:), jerk2(:)
      real(dp) :: t1 = 0, t2 = 0
      integer :: jerks = 0
      !> The parameter step of the differences that give them (a quarter of the deck's step).
      real(dp) :: difference_step = 0
      !> Newton: length tolerance of the correction, most iterations.
      real(dp) :: tol = 1.0e-12_dp
      integer :: max_iter = 25
      integer, allocatable :: fdof(:)
      !> The tangent's band storage and its factor at the last iterate.
      type(spatial_tangent_type) :: kt
      !> The norm of the free dofs' residual at the last converged configuration.
      real(dp) :: residual = 0
      !> The links' rotations of the last step (links.csv).
      type(link_motion_type) :: links
   contains
      procedure :: start => spatial_start
      procedure :: advance => spatial_advance
      procedure :: plan_text => spatial_plan_text
   end type spatial_stepper_type

contains

   !> A stepper for the model of a spatial deck.
   subroutine new_spatial_stepper(self, model, error)
      type(spatial_stepper_type), intent(out) :: self
      type(model_type), intent(in) :: model
      type(error_type), allocatable, intent(out) :: error
      call build_spatial_mechanism(model, self%m, self%map, error)
      if (allocated(error)) return
      self%s = new_spatial_state(self%m)
      self%t = model%analysis%t_start
      self%tol = model%analysis%length_tol
      self%max_iter = model%analysis%max_iter
      self%fdof = free_dofs(self%m)
      call tangent_for(self%m, self%kt)
      self%difference_step = model%analysis%dt/4
      call new_link_motion(self%links, model, self%m, self%map%node_frame, self%map%node_point)
      allocate (self%v(self%m%ndof), self%a(self%m%ndof), self%jerk(self%m%ndof), self%snap(self%m%ndof), &
         & self%jerk1(self%m%ndof), self%jerk2(self%m%ndof), source=0.0_dp)
   end subroutine new_spatial_stepper

   !> The deck's configuration at the start time, solved (it is stress free:
   !> Newton's first correction is at round-off) with its rates.
   subroutine spatial_start(self, result, error)
      class(spatial_stepper_type), intent(inout) :: self
      type(step_result_type), intent(inout) :: result
      type(error_type), allocatable, intent(out) :: error
      integer :: iterations
      logical :: converged
      character(:), allocatable :: why
      call solve(self, self%t, iterations, converged, why)
      if (.not. converged) then
         call analysis_error(error, 'the start configuration does not assemble: '//why)
         return
      end if
      result%t = self%t
      result%iterations = iterations
      call fill_result(self, result)
   end subroutine spatial_start

   !> Advance to time t, cutting the step in halves while Newton fails.
   subroutine spatial_advance(self, t, result, error)
      class(spatial_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      type(step_result_type), intent(inout) :: result
      type(error_type), allocatable, intent(out) :: error
      type(spatial_state_type) :: saved
      real(dp), allocatable :: v0(:), a0(:), j0(:), k0(:)
      real(dp) :: h, t_try, t0
      integer :: cuts, iterations, total
      logical :: converged
      character(:), allocatable :: why
      character(len=160) :: text
      h = t - self%t
      cuts = 0
      total = 0
      do while (self%t < t)
         t_try = min(self%t + h, t)
         if (t - t_try < 1.0e-9_dp*h) t_try = t
         saved = self%s
         v0 = self%v
         a0 = self%a
         j0 = self%jerk
         k0 = self%snap
         t0 = self%t
         call predict(self, t_try - self%t)
         call solve(self, t_try, iterations, converged, why)
         total = total + iterations
         if (converged) then
            self%t = t_try
            cycle
         end if
         self%s = saved
         self%v = v0
         self%a = a0
         self%jerk = j0
         self%snap = k0
         self%t = t0
         cuts = cuts + 1
         if (cuts > max_cuts) then
            write (text, '(a,i0,a)') 'Newton failed even with the step cut ', max_cuts, ' times ('
            call analysis_error(error, trim(text)//why//'): a dead point of the drive, or a configuration '// &
               & 'that does not assemble; drive another joint or end the run before it')
            return
         end if
         h = h/2
      end do
      self%counts%steps = self%counts%steps + 1
      result%t = t
      result%iterations = total
      result%cuts = cuts
      call fill_result(self, result)
   end subroutine spatial_advance

   !> The predictor: s (+) (h v + h^2/2 a + h^3/6 j + h^4/24 k), the Taylor
   !> series of the motion to its fourth rate (an O(h^5) error).
   subroutine predict(self, h)
      type(spatial_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: h
      call update_state(self%m, self%s, h*self%v + h**2/2*self%a + h**3/6*self%jerk + h**4/24*self%snap)
   end subroutine predict

   !> The third and fourth rates (jerk j and snap k) of the motion at the
   !> accepted state s at time t, in the predictor's form: along the curve
   !> s (+) (sigma v + sigma^2/2 a), whose strains vanish to O(sigma^3), the
   !> residual is sigma^3/6 R3 + O(sigma^4), and K j = -R3 (the free rows;
   !> the drives' j given) makes them vanish to O(sigma^4); with sigma^3/6 j
   !> added, the residual is sigma^4/24 R4 + O(sigma^5) and K k = -R4. R3
   !> and R4 are the odd and even parts of the residual at sigma = +-d
   !> (errors O(d^2) relative); the drives' j and k are differences of their
   !> second rates. In the predictor's own form, the free frames' terms
   !> include what body rates alone would miss (the commutator of omega and
   !> its rate in the third term). Where the two configurations before have
   !> their j (every step but the first two), k is instead the rate at t of
   !> the quadratic through the three j, which saves two of the four
   !> residuals: for additive dofs an O(h^2) error (O(h^6) in the
   !> predictor); a free frame's j is a body quantity, whose rate differs
   !> from its k by commutator terms (an O(h^4) error in the predictor).
   subroutine curve_rates(self, t)
      type(spatial_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      type(spatial_state_type) :: sd
      real(dp) :: vd(self%m%ndof), ap(self%m%ndof), am(self%m%ndof), a0(self%m%ndof), rp(self%m%ndof), &
         & rm(self%m%ndof), d, h1, hh
      real(dp), allocatable :: rhs(:)
      d = self%difference_step
      sd = self%s
      call set_drives(self%m, t + d, sd, vd, ap)
      call set_drives(self%m, t - d, sd, vd, am)
      call set_drives(self%m, t, sd, vd, a0)
      ! The drives' own rates (zero at the free dofs, whose ad is zero).
      self%jerk = (ap - am)/(2*d)
      self%snap = (ap - 2*a0 + am)/d**2
      rp = residual_along(d*self%v + d**2/2*self%a)
      rm = residual_along(-d*self%v + d**2/2*self%a)
      rhs = -3*(rp(self%fdof) - rm(self%fdof))/d**3 - self%kt%product(self%jerk)
      call self%kt%solve(rhs)
      self%jerk(self%fdof) = rhs
      if (self%jerks >= 2 .and. t > self%t1 .and. self%t1 > self%t2) then
         ! j(tau) through (0, j), (-h1, j1), (-hh, j2): its rate at 0.
         h1 = t - self%t1
         hh = t - self%t2
         self%snap = (h1 + hh)/(h1*hh)*self%jerk - hh/(h1*(hh - h1))*self%jerk1 + h1/(hh*(hh - h1))*self%jerk2
         call remember_jerk()
         return
      end if
      call remember_jerk()
      rp = residual_along(d*self%v + d**2/2*self%a + d**3/6*self%jerk)
      rm = residual_along(-d*self%v + d**2/2*self%a - d**3/6*self%jerk)
      rhs = -12*(rp(self%fdof) + rm(self%fdof))/d**4 - self%kt%product(self%snap)
      call self%kt%solve(rhs)
      self%snap(self%fdof) = rhs
   contains
      !> The last two configurations' j for the next ones' k.
      subroutine remember_jerk()
         self%jerk2 = self%jerk1
         self%t2 = self%t1
         self%jerk1 = self%jerk
         self%t1 = t
         self%jerks = min(self%jerks + 1, 2)
      end subroutine remember_jerk

      !> The residual at s (+) dq.
      function residual_along(dq) result(res)
         real(dp), intent(in) :: dq(:)
         real(dp) :: res(self%m%ndof)
         type(spatial_configuration_type) :: c
         type(spatial_state_type) :: moved
         moved = self%s
         call update_state(self%m, moved, dq)
         call configure(self%m, moved, c)
         call assemble_spatial(self%m, c, res)
      end function residual_along
   end subroutine curve_rates

   !> Newton from the current state at time t (the drives set exactly); on
   !> convergence the rates at the solution. `why` says why it failed.
   subroutine solve(self, t, iterations, converged, why)
      type(spatial_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      integer, intent(out) :: iterations
      logical, intent(out) :: converged
      character(:), allocatable, intent(out) :: why
      type(spatial_configuration_type) :: c
      real(dp) :: res(self%m%ndof), ad(self%m%ndof), dq(self%m%ndof)
      real(dp) :: scale(self%m%ndof), correction, last
      real(dp), allocatable :: rhs(:)
      integer :: info, it
      character(len=80) :: text
      logical :: refining
      refining = .false.
      converged = .false.
      iterations = 0
      why = ''
      call set_drives(self%m, t, self%s, self%v, ad)
      scale = merge(1/self%m%length, 1.0_dp, self%m%is_length)
      last = huge(1.0_dp)
      do it = 0, self%max_iter
         call configure(self%m, self%s, c)
         call assemble_spatial(self%m, c, res, sparse=self%kt)
         self%counts%tangent_assemblies = self%counts%tangent_assemblies + 1
         call self%kt%factor(info)
         if (self%kt%is_lu()) then
            self%counts%lu_factorisations = self%counts%lu_factorisations + 1
         else
            self%counts%cholesky_factorisations = self%counts%cholesky_factorisations + 1
         end if
         if (info /= 0) then
            write (text, '(a,i0)') 'singular tangent at dof ', info
            why = trim(text)
            return
         end if
         rhs = -res(self%fdof)
         call self%kt%solve(rhs)
         dq = 0
         dq(self%fdof) = rhs
         correction = maxval(abs(dq*scale))
         if (.not. correction < huge(1.0_dp)) then
            why = 'the correction is not a finite number'
            return
         end if
         if (correction < self%tol .and. (correction < rate_tol .or. refining)) then
            ! Converged at this iterate, which is the solution to round-off:
            ! its factored tangent gives the rates.
            self%residual = norm2(res(self%fdof))
            call spatial_rates_factored(self%m, self%s, c, self%kt, self%v, ad, self%a)
            self%counts%velocity_solves = self%counts%velocity_solves + 1
            self%counts%acceleration_solves = self%counts%acceleration_solves + 1
            call update_state(self%m, self%s, dq)
            call curve_rates(self, t)
            converged = .true.
            return
         end if
         ! Converged, but the rates want the next iterate (once: round-off may keep it above rate_tol).
         if (correction < self%tol) refining = .true.
         if (it >= 2 .and. correction > last .and. .not. refining) then
            write (text, '(a,i0,a)') 'the correction grew at iteration ', it + 1, ''
            why = trim(text)
            return
         end if
         last = correction
         call update_state(self%m, self%s, dq)
         iterations = iterations + 1
         self%counts%iterations = self%counts%iterations + 1
      end do
      write (text, '(a,i0,a)') 'no convergence in ', self%max_iter, ' iterations'
      why = trim(text)
   end subroutine solve

   !> The accepted state's node positions, rates, joint motions and link
   !> rotations into result (every step, written or not: the links'
   !> quaternions keep their sign from step to step).
   subroutine fill_result(self, result)
      type(spatial_stepper_type), intent(inout) :: self
      type(step_result_type), intent(inout) :: result
      type(spatial_configuration_type) :: c
      real(dp) :: x(3)
      integer :: i, p, n
      call configure(self%m, self%s, c)
      n = size(self%map%node_point)
      if (.not. allocated(result%pos_z)) allocate (result%pos_z(n), result%vel_z(n), result%acc_z(n))
      if (.not. allocated(result%joint_motion)) allocate (result%joint_motion(3, size(self%map%report_dof)))
      if (.not. allocated(result%link_rotation)) then
         allocate (result%link_rotation(4, size(self%links%frame)), result%link_omega(3, size(self%links%frame)), &
            & result%link_alpha(3, size(self%links%frame)))
      end if
      do i = 1, n
         p = self%map%node_point(i)
         x = c%x(:, p)
         result%pos(:, i) = x(1:2)
         result%pos_z(i) = x(3)
         x = point_rate(c, p, self%v)
         result%vel(:, i) = x(1:2)
         result%vel_z(i) = x(3)
         ! Points move linearly in their dofs: the acceleration is G a.
         x = point_rate(c, p, self%a)
         result%acc(:, i) = x(1:2)
         result%acc_z(i) = x(3)
      end do
      do i = 1, size(self%map%report_dof)
         associate (dof => self%map%report_dof(i), sign => self%map%report_sign(i))
            result%joint_motion(:, i) = sign*[self%s%q(dof), self%v(dof), self%a(dof)]
         end associate
      end do
      call fill_link_motion(self%links, self%m, self%s, c, self%v, self%a, result%link_rotation, result%link_omega, &
         & result%link_alpha)
      result%has_velocity = .true.
      result%has_acceleration = .true.
      result%residual = self%residual
   end subroutine fill_result

   !> The listing's plan line: the mechanism's size.
   function spatial_plan_text(self) result(text)
      class(spatial_stepper_type), intent(in) :: self
      character(:), allocatable :: text
      character(len=200) :: line
      integer :: nb, nt
      nb = 0
      nt = 0
      if (allocated(self%m%beams)) nb = size(self%m%beams)
      if (allocated(self%m%trusses)) nt = size(self%m%trusses)
      write (line, '(a,i0,a,i0,a,i0,a,i0,a,i0,a,i0,a,i0,a)') 'spatial mechanism: ', size(self%m%points), &
         & ' points, ', size(self%m%frames), ' frames, ', nb, ' beams, ', nt, ' trusses; ', self%m%ndof, ' dofs, ', &
         & size(self%fdof), ' free (band, half-bandwidth ', self%kt%kff%kd, ')'
      text = trim(line)
   end function spatial_plan_text

end module fekap_spatial_stepper
