!> The spatial stepper's checks of a step (fekap_spatial_stepper), with the
!> rules the planar FEM uses (fekap_stepping_jump, fekap_stepping_change_point;
!> docs/hard-cases.md, sections 1 and 3b):
!>
!> * the condition estimate of a dense LU, for the filled row's tangent
!>   (correct_state; the stepper's iterates use the band tangent's,
!>   fekap_spatial_tangent);
!> * the linear response of the dofs to the drives, R = -K_ff^-1 K_fd, and
!>   the magnitude rule of the branch-jump check on the rotation unknowns:
!>   joint angles (additive) and free frames (the angle of R_old^T R_new
!>   against the norms of their responses);
!> * the orientation rule of the branch-jump check (collinear_crossing)
!>   on the hinges: pairs of beam ends at one point whose frames turn
!>   relative to each other about one axis (revolute joints about parallel
!>   axes), their relative angle an additive sum of joint angle dofs; and
!>   what the step-doubling verification of a crossing step compares (the
!>   distance of two states in model sizes, whether a step was predicted);
!> * the row of a change point stepped over: its state by two-sided Hermite
!>   interpolation (free frames along their body rotation vector from the
!>   state before), corrected onto the mechanism by Newton with the tangent
!>   shifted by fill_shift.
module fekap_spatial_change_point
   use fekap_kinds, only: dp
   use fekap_linalg_lapack, only: dense_lu_factor, dense_lu_solve, dgetrs, dlacn2
   use fekap_element_se3, only: so3_exp, so3_log
   use fekap_stepping_change_point, only: hermite_fill, fill_iterations
   use fekap_vectors, only: cross
   use fekap_stepping_jump, only: jump_bound_ratio, collinear_crossing, crossing_against, crossing_along
   use fekap_spatial_mechanism, only: spatial_mechanism_type, frame_free, frame_fixed, frame_revolute, point_fixed
   use fekap_spatial_tangent, only: spatial_tangent_type
   use fekap_spatial_kinematics, only: spatial_state_type, spatial_configuration_type, configure, assemble_spatial, &
      & update_state, set_drives
   implicit none
   private

   public :: one_norm, dense_rcond, drive_response, rotation_jump, fill_state, correct_state, shortest_element
   public :: find_hinges, hinge_angle, hinge_check, state_distance, predicted_step

   !> Axes of two revolute joints closer to parallel than this (the norm of
   !> the cross product of the unit axes) turn about one axis.
   real(dp), parameter :: parallel_tolerance = 1.0e-9_dp

   !> Two beam ends at one point whose frames turn relative to each other
   !> about one axis n: the frame of the second is the first's turned by
   !> psi - psi_ref about n, psi = psi_ref + sum(signs * q(dofs)) the angle
   !> from the first beam's chord to the second's about n (their projections
   !> on the plane normal to n), unwrapped; psi_ref its value at the deck's
   !> configuration (where every frame is I). The links are collinear where
   !> psi is a multiple of pi.
   type, public :: spatial_hinge_type
      !> The two beams and their common point.
      integer :: beams(2) = 0, point = 0
      real(dp) :: psi_ref = 0
      integer, allocatable :: dofs(:)
      real(dp), allocatable :: signs(:)
      !> What the listing calls the pair (set by the stepper, which knows the names).
      character(:), allocatable :: label
   end type spatial_hinge_type

contains

   !> The 1-norm of a (the largest column sum), before it is factored.
   pure real(dp) function one_norm(a)
      real(dp), contiguous, intent(in) :: a(:, :)
      integer :: j
      one_norm = 0
      do j = 1, size(a, 2)
         one_norm = max(one_norm, sum(abs(a(:, j))))
      end do
   end function one_norm

   !> The reciprocal condition number 1 / (||A||_1 ||A^-1||_1) of a matrix
   !> of 1-norm anorm factored by dense_lu_factor, ||A^-1||_1 estimated by
   !> LAPACK's dlacn2 from solves with the factor (the estimator of dgecon;
   !> the planar band_rcond's). 0 for a matrix of norm 0.
   real(dp) function dense_rcond(anorm, lu, ipiv) result(rcond)
      real(dp), intent(in) :: anorm
      real(dp), contiguous, intent(in) :: lu(:, :)
      integer, contiguous, intent(in) :: ipiv(:)
      real(dp) :: x(size(lu, 1)), v(size(lu, 1)), est
      integer :: isgn(size(lu, 1)), kase, isave(3), n, info
      n = size(lu, 1)
      rcond = 0
      if (n == 0) then
         rcond = 1
         return
      end if
      if (.not. anorm > 0) return
      est = 0
      kase = 0
      do
         call dlacn2(n, v, x, isgn, est, kase, isave)
         if (kase == 0) exit
         if (kase == 1) then
            call dense_lu_solve(lu, ipiv, x, info)
         else
            call dgetrs('T', n, 1, lu, n, ipiv, x, n, info)
         end if
      end do
      if (est > 0) rcond = (1/anorm)/est
   end function dense_rcond

   !> The linear response of every dof to unit changes of the drives, one
   !> column a drive: R(free, j) = -K_ff^-1 K_f,d_j (kt the assembled tangent
   !> with K_ff factored), R(d_j, j) = 1.
   function drive_response(m, kt) result(r)
      type(spatial_mechanism_type), intent(in) :: m
      type(spatial_tangent_type), intent(in) :: kt
      real(dp), allocatable :: r(:, :)
      real(dp) :: unit(m%ndof)
      real(dp), allocatable :: rhs(:)
      integer :: j, nd
      nd = 0
      if (allocated(m%drives)) nd = size(m%drives)
      allocate (r(m%ndof, nd), source=0.0_dp)
      do j = 1, nd
         unit = 0
         unit(m%drives(j)%dof) = 1
         rhs = -kt%product(unit)
         call kt%solve(rhs)
         r(kt%fdof, j) = rhs
         r(m%drives(j)%dof, j) = 1
      end do
   end function drive_response

   !> The magnitude rule of the branch-jump check on the step from s0 to s1
   !> (fekap_stepping_jump): the largest ratio of a rotation over the step to
   !> what explains it, max(|dq_old|, |dq_new|, floor), dq_old and dq_new
   !> the linear responses to the drive increment at the two ends (zero
   !> where not known), floor the increment's size, resolution Newton's
   !> (jump_bound_ratio). A joint angle is one
   !> unknown; a free frame's rotation is the angle of R0^T R1 against the
   !> norms of its responses (frame-independent). Also which dof (the first of
   !> a free frame) has the largest ratio, and its rotation.
   pure subroutine rotation_jump(m, s0, s1, dq_old, dq_new, floor_, resolution, worst, worst_dof, turn)
      type(spatial_mechanism_type), intent(in) :: m
      type(spatial_state_type), intent(in) :: s0, s1
      real(dp), intent(in) :: dq_old(:), dq_new(:), floor_
      !> Newton's resolution of a rotation (jump_bound_ratio's).
      real(dp), intent(in) :: resolution
      real(dp), intent(out) :: worst, turn
      integer, intent(out) :: worst_dof
      logical :: frame_dof(m%ndof)
      real(dp) :: ratio, change
      integer :: i, d
      worst = 0
      worst_dof = 0
      turn = 0
      frame_dof = .false.
      do i = 1, size(s0%r, 3)
         if (m%frames(i)%kind /= frame_free) cycle
         d = m%frames(i)%dof
         frame_dof(d:d + 2) = .true.
         change = norm2(so3_log(matmul(transpose(s0%r(:, :, i)), s1%r(:, :, i))))
         ratio = jump_bound_ratio(change, norm2(dq_old(d:d + 2)), norm2(dq_new(d:d + 2)), floor_, resolution)
         if (ratio > worst) then
            worst = ratio
            worst_dof = d
            turn = change
         end if
      end do
      do i = 1, m%ndof
         if (m%is_length(i) .or. frame_dof(i)) cycle
         change = s1%q(i) - s0%q(i)
         ratio = jump_bound_ratio(change, dq_old(i), dq_new(i), floor_, resolution)
         if (ratio > worst) then
            worst = ratio
            worst_dof = i
            turn = change
         end if
      end do
   end subroutine rotation_jump

   !> The state at time t, t0 < t < t1, by two-sided Hermite interpolation of
   !> the given order (fill_order) between the states s0 and s1 with their
   !> dof rates (v, a: body rates for free frames). The additive dofs are
   !> interpolated as they are; a free frame turns from R0 by the
   !> interpolant of its body rotation vector, from 0 at t0 to log(R0^T R1)
   !> at t1, its rates at t1 taken into R0's axes (exact for rotations about
   !> one axis; otherwise the correction makes up the rest).
   pure function fill_state(m, order, t0, s0, v0, a0, t1, s1, v1, a1, t) result(s)
      type(spatial_mechanism_type), intent(in) :: m
      integer, intent(in) :: order
      real(dp), intent(in) :: t0, t1, t
      type(spatial_state_type), intent(in) :: s0, s1
      real(dp), intent(in) :: v0(:), a0(:), v1(:), a1(:)
      type(spatial_state_type) :: s
      real(dp) :: q(m%ndof), q0(m%ndof), q1(m%ndof), vv1(m%ndof), aa1(m%ndof), rel(3, 3)
      integer :: i, d
      q0 = s0%q
      q1 = s1%q
      vv1 = v1
      aa1 = a1
      do i = 1, size(s0%r, 3)
         if (m%frames(i)%kind /= frame_free) cycle
         d = m%frames(i)%dof
         rel = matmul(transpose(s0%r(:, :, i)), s1%r(:, :, i))
         q0(d:d + 2) = 0
         q1(d:d + 2) = so3_log(rel)
         vv1(d:d + 2) = matmul(rel, v1(d:d + 2))
         aa1(d:d + 2) = matmul(rel, a1(d:d + 2))
      end do
      call hermite_fill(order, t0, q0, v0, a0, t1, q1, vv1, aa1, t, q)
      s = s0
      s%q = q
      do i = 1, size(s0%r, 3)
         if (m%frames(i)%kind /= frame_free) cycle
         d = m%frames(i)%dof
         s%r(:, :, i) = matmul(s0%r(:, :, i), so3_exp(q(d:d + 2)))
         s%q(d:d + 2) = 0
      end do
   end function fill_state

   !> Correct the state s at time t (its drives set exactly) onto the
   !> mechanism's configurations by Newton with the shifted tangent K_ff +
   !> mu I, mu = shift max diag K_ff (shift = fill_shift on a singular
   !> tangent: the residual has no component in its kernel, so the shift
   !> leaves the range correction exact; 0, plain Newton, where it is
   !> regular): at most fill_iterations corrections, until one is below tol
   !> (lengths relative to the mechanism's length). Returns the corrections
   !> taken, the residual of the free dofs at the corrected state and the
   !> reciprocal condition number of the (unshifted) tangent there.
   subroutine correct_state(m, fdof, t, tol, shift, s, iterations, residual, rcond)
      type(spatial_mechanism_type), intent(in) :: m
      integer, intent(in) :: fdof(:)
      real(dp), intent(in) :: t, tol, shift
      type(spatial_state_type), intent(inout) :: s
      integer, intent(out) :: iterations
      real(dp), intent(out) :: residual, rcond
      type(spatial_configuration_type) :: c
      real(dp) :: res(m%ndof), k(m%ndof, m%ndof), vd(m%ndof), ad(m%ndof), dq(m%ndof), scale(m%ndof), mu, anorm
      real(dp), allocatable :: kff(:, :), rhs(:)
      integer, allocatable :: ipiv(:)
      integer :: info, i
      call set_drives(m, t, s, vd, ad)
      scale = merge(1/m%length, 1.0_dp, m%is_length)
      allocate (ipiv(size(fdof)))
      iterations = 0
      do while (iterations < fill_iterations)
         call configure(m, s, c)
         call assemble_spatial(m, c, res, k)
         kff = k(fdof, fdof)
         if (size(kff, 1) == 0) exit
         mu = 0
         do i = 1, size(kff, 1)
            mu = max(mu, kff(i, i))
         end do
         mu = shift*mu
         do i = 1, size(kff, 1)
            kff(i, i) = kff(i, i) + mu
         end do
         call dense_lu_factor(kff, ipiv, info)
         if (info /= 0) exit
         rhs = -res(fdof)
         call dense_lu_solve(kff, ipiv, rhs, info)
         dq = 0
         dq(fdof) = rhs
         call update_state(m, s, dq)
         iterations = iterations + 1
         if (maxval(abs(dq*scale)) <= tol) exit
      end do
      call configure(m, s, c)
      call assemble_spatial(m, c, res, k)
      residual = norm2(res(fdof))
      kff = k(fdof, fdof)
      anorm = one_norm(kff)
      call dense_lu_factor(kff, ipiv, info)
      rcond = 0
      if (info == 0) rcond = dense_rcond(anorm, kff, ipiv)
   end subroutine correct_state

   !> The length of the shortest beam or truss: the unit of stroke drives in
   !> the branch-jump check's floor (as the planar check's shortest link).
   pure real(dp) function shortest_element(m) result(length)
      type(spatial_mechanism_type), intent(in) :: m
      integer :: i
      length = huge(1.0_dp)
      if (allocated(m%beams)) then
         do i = 1, size(m%beams)
            length = min(length, m%beams(i)%element%length)
         end do
      end if
      if (allocated(m%trusses)) then
         do i = 1, size(m%trusses)
            length = min(length, m%trusses(i)%element%length)
         end do
      end if
      if (length == huge(1.0_dp)) length = m%length
   end function shortest_element

   !> The hinges of m: every pair of beam ends at one place (same_place) with frames of
   !> their own that the frame tree relates through revolute joints about
   !> one axis only (and fixed frames): up from each frame to their common
   !> ancestor, every frame revolute about +-n in its parent's axes (a turn
   !> about n leaves n in place, so n is one vector in all of them). A pair
   !> related through a free or universal frame, or whose chord lies along
   !> the axis, has no such angle and is left out.
   function find_hinges(m) result(hinges)
      type(spatial_mechanism_type), intent(in) :: m
      type(spatial_hinge_type), allocatable :: hinges(:)
      type(spatial_hinge_type) :: h
      integer :: nb, i, j, bi, bj, ni, nj, fi, fj
      real(dp) :: n(3), c1(3), c2(3)
      logical :: related
      allocate (hinges(0))
      nb = 0
      if (allocated(m%beams)) nb = size(m%beams)
      ! Beam ends as 2 (b - 1) + e.
      do i = 1, 2*nb
         bi = (i + 1)/2
         ni = m%beams(bi)%nodes(i - 2*(bi - 1))
         fi = m%nodes(ni)%frame
         do j = i + 1, 2*nb
            bj = (j + 1)/2
            nj = m%beams(bj)%nodes(j - 2*(bj - 1))
            if (bj == bi .or. .not. same_place(m%nodes(ni)%point, m%nodes(nj)%point)) cycle
            fj = m%nodes(nj)%frame
            if (fi == fj .or. fi == 0 .or. fj == 0) cycle
            call frame_path(m, fi, fj, n, h%dofs, h%signs, related)
            if (.not. related) cycle
            c1 = across(chord(bi), n)
            c2 = across(chord(bj), n)
            if (.not. (norm2(c1) > parallel_tolerance*norm2(chord(bi)) .and. &
               & norm2(c2) > parallel_tolerance*norm2(chord(bj)))) cycle
            h%beams = [bi, bj]
            h%point = m%nodes(ni)%point
            h%psi_ref = atan2(dot_product(n, cross(c1, c2)), dot_product(c1, c2))
            hinges = [hinges, h]
         end do
      end do
   contains
      !> Whether points a and b are one place: one point, or two fixed
      !> points at one position (the nodes of a pin, each held to the ground
      !> by a joint of its own).
      pure logical function same_place(a, b)
         integer, intent(in) :: a, b
         same_place = a == b
         if (same_place) return
         same_place = m%points(a)%kind == point_fixed .and. m%points(b)%kind == point_fixed .and. &
            & all(m%points(a)%x0 == m%points(b)%x0)
      end function same_place

      !> The chord of beam b at the deck's configuration.
      pure function chord(b) result(c)
         integer, intent(in) :: b
         real(dp) :: c(3)
         c = m%points(m%nodes(m%beams(b)%nodes(2))%point)%x0 - m%points(m%nodes(m%beams(b)%nodes(1))%point)%x0
      end function chord

      !> The part of c normal to the unit vector n.
      pure function across(c, n_) result(p)
         real(dp), intent(in) :: c(3), n_(3)
         real(dp) :: p(3)
         p = c - dot_product(c, n_)*n_
      end function across
   end function find_hinges

   !> Whether frame fb is frame fa turned about one axis n (unit, in fa's
   !> axes) by an angle that is a sum of revolute angle dofs with signs:
   !> R_a^T R_b = exp((sum signs q(dofs)) n^).
   subroutine frame_path(m, fa, fb, n, dofs, signs, related)
      type(spatial_mechanism_type), intent(in) :: m
      integer, intent(in) :: fa, fb
      real(dp), intent(out) :: n(3)
      integer, allocatable, intent(out) :: dofs(:)
      real(dp), allocatable, intent(out) :: signs(:)
      logical, intent(out) :: related
      integer :: up_a(0:size(m%frames)), up_b(0:size(m%frames)), na, nb, common, k
      logical :: has_axis, ok
      call chain(fa, up_a, na)
      call chain(fb, up_b, nb)
      ! The common ancestor (0: the ground): the first of a's chain in b's.
      common = 0
      do k = 0, na
         if (any(up_b(0:nb) == up_a(k))) then
            common = up_a(k)
            exit
         end if
      end do
      allocate (dofs(0), signs(0))
      n = 0
      has_axis = .false.
      related = .false.
      ! R_a = R_common exp(theta_a n^): a's angle enters with a minus sign.
      do k = 0, na
         if (up_a(k) == common) exit
         call add_turn(up_a(k), -1.0_dp, ok)
         if (.not. ok) return
      end do
      do k = 0, nb
         if (up_b(k) == common) exit
         call add_turn(up_b(k), 1.0_dp, ok)
         if (.not. ok) return
      end do
      related = has_axis
   contains
      !> The frames from f up to the ground (0), in up(0:), and the index of the last.
      pure subroutine chain(f, up, last)
         integer, intent(in) :: f
         integer, intent(out) :: up(0:), last
         integer :: g
         last = 0
         up(0) = f
         g = f
         do while (g /= 0)
            g = m%frames(g)%parent
            last = last + 1
            up(last) = g
         end do
      end subroutine chain

      !> Add frame f's angle to the sum (with the side's sign, and of the
      !> first revolute frame's axis n): not ok unless it is fixed or
      !> revolute about +-n.
      subroutine add_turn(f, side, ok)
         integer, intent(in) :: f
         real(dp), intent(in) :: side
         logical, intent(out) :: ok
         ok = .true.
         select case (m%frames(f)%kind)
         case (frame_fixed)
         case (frame_revolute)
            if (.not. has_axis) then
               n = m%frames(f)%axis
               has_axis = .true.
            end if
            ok = norm2(cross(m%frames(f)%axis, n)) <= parallel_tolerance
            if (.not. ok) return
            dofs = [dofs, m%frames(f)%dof]
            signs = [signs, side*sign(1.0_dp, dot_product(m%frames(f)%axis, n))]
         case default
            ok = .false.
         end select
      end subroutine add_turn
   end subroutine frame_path

   !> The hinge's relative angle at dofs q (unwrapped).
   pure real(dp) function hinge_angle(h, q) result(psi)
      type(spatial_hinge_type), intent(in) :: h
      real(dp), intent(in) :: q(:)
      psi = h%psi_ref + sum(h%signs*q(h%dofs))
   end function hinge_angle

   !> The orientation rule of the branch-jump check (fekap_stepping_jump's
   !> collinear_crossing) over the hinges on the step from q0 to q1, with the
   !> linear responses of the dofs to the step's drive increment at either
   !> end (zero where not known): the first hinge that passes through
   !> collinear against them (0 if none), and the largest turn |psi1 - psi0|
   !> of a hinge that passes through collinear in their sense (0 if none),
   !> with that hinge.
   pure subroutine hinge_check(hinges, q0, q1, dq_old, dq_new, flipped, turn, crossing)
      type(spatial_hinge_type), intent(in) :: hinges(:)
      real(dp), intent(in) :: q0(:), q1(:), dq_old(:), dq_new(:)
      integer, intent(out) :: flipped, crossing
      real(dp), intent(out) :: turn
      real(dp) :: psi0, psi1
      integer :: k, outcome
      flipped = 0
      crossing = 0
      turn = 0
      do k = 1, size(hinges)
         associate (h => hinges(k))
            psi0 = hinge_angle(h, q0)
            psi1 = hinge_angle(h, q1)
            outcome = collinear_crossing(psi0, psi1, sum(h%signs*dq_old(h%dofs)), sum(h%signs*dq_new(h%dofs)))
         end associate
         if (outcome == crossing_against) then
            flipped = k
            return
         end if
         if (outcome == crossing_along .and. abs(psi1 - psi0) > turn) then
            turn = abs(psi1 - psi0)
            crossing = k
         end if
      end do
   end subroutine hinge_check

   !> How far apart two states of m are, in model sizes (m%length): the
   !> largest distance of a point, and of a frame's rotation (the angle of
   !> R_a^T R_b, or of an angle dof's difference) times the shortest
   !> element's length (the displacement it gives that element's end).
   pure real(dp) function state_distance(m, sa, sb) result(distance)
      type(spatial_mechanism_type), intent(in) :: m
      type(spatial_state_type), intent(in) :: sa, sb
      type(spatial_configuration_type) :: ca, cb
      real(dp) :: arm
      integer :: i
      call configure(m, sa, ca)
      call configure(m, sb, cb)
      arm = shortest_element(m)/m%length
      distance = 0
      do i = 1, size(ca%x, 2)
         distance = max(distance, norm2(ca%x(:, i) - cb%x(:, i))/m%length)
      end do
      do i = 1, size(ca%r, 3)
         distance = max(distance, arm*norm2(so3_log(matmul(transpose(ca%r(:, :, i)), cb%r(:, :, i)))))
      end do
      do i = 1, m%ndof
         if (.not. m%is_length(i)) distance = max(distance, arm*abs(sa%q(i) - sb%q(i)))
      end do
   end function state_distance

   !> Whether the converged state s lies within `share` of `turn` of the
   !> predictor's state p in every rotation: every angle dof and every free
   !> frame (the angle of R_p^T R). The step then continues the extrapolated
   !> path; landing on the mirror branch would need an extrapolation error of
   !> twice the closest approach to collinear.
   pure logical function predicted_step(m, p, s, share, turn) result(predicted)
      type(spatial_mechanism_type), intent(in) :: m
      type(spatial_state_type), intent(in) :: p, s
      real(dp), intent(in) :: share, turn
      logical :: frame_dof(m%ndof)
      integer :: i, d
      predicted = .false.
      frame_dof = .false.
      do i = 1, size(s%r, 3)
         if (m%frames(i)%kind /= frame_free) cycle
         d = m%frames(i)%dof
         frame_dof(d:d + 2) = .true.
         if (norm2(so3_log(matmul(transpose(p%r(:, :, i)), s%r(:, :, i)))) > share*turn) return
      end do
      do i = 1, m%ndof
         if (m%is_length(i) .or. frame_dof(i)) cycle
         if (abs(s%q(i) - p%q(i)) > share*turn) return
      end do
      predicted = .true.
   end function predicted_step

end module fekap_spatial_change_point
