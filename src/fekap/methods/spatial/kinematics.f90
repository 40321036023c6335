!> Kinematic analysis of a spatial mechanism (fekap_spatial_mechanism) by the
!> paper's method carried to SE(3): every configuration is the stress-free
!> solution of the finite element equations with the drives prescribed,
!> found by Newton-Raphson with the material tangent K = sum G^T B^T k B G
!> (exact at a stress-free state, where the geometric part vanishes); the
!> rates follow from linear solves with the same tangent (Eischen, Sun &
!> Marler, eqs. (47)-(53), here with B the SE(3) compatibility):
!>
!>   velocities     K_ff v_f = -K_fd v_d,
!>   accelerations  K_ff a_f = -K_fd a_d - sum G_f^T B^T k c,
!>
!> c the convective term, the second derivative of each element's strain
!> along q (+) s v (fekap_element_se3_beam), which includes the curvature of
!> the joints' dof maps (a child frame of a turning parent). Generalized
!> dofs q: translations of free points (absolute, global axes), strokes of
!> line points, joint angles (additive), and body rotation increments of free
!> frames (their rotation matrices are the state, updated multiplicatively).
module fekap_spatial_kinematics
   use fekap_kinds, only: dp
   use fekap_vectors, only: cross
   use fekap_error, only: error_type, analysis_error
   use fekap_linalg_lapack, only: dense_lu_factor, dense_lu_solve
   use fekap_element_se3, only: so3_exp, so3_update
   use fekap_element_se3_beam, only: se3_beam_residual, se3_beam_convective, truss_residual, truss_convective
   use fekap_spatial_mechanism, only: spatial_mechanism_type, point_free, point_line, frame_free, frame_revolute, &
      & frame_universal
   use fekap_spatial_slideline, only: assemble_slides
   implicit none
   private

   public :: spatial_state_type, new_spatial_state, spatial_configuration_type, configure, frame_curvature
   public :: assemble_spatial, set_drives, update_state, spatial_newton, spatial_rates, spatial_report_type
   public :: point_position, point_rate, free_dofs, spatial_rates_factored, singular

   !> Where a mechanism is: its generalized dofs and its free frames' rotations.
   type :: spatial_state_type
      real(dp), allocatable :: q(:)
      !> Rotation of each frame that is free (I for the others, unused).
      real(dp), allocatable :: r(:, :, :)
   end type spatial_state_type

   !> The nodes' placement at a state and its derivatives in the dofs:
   !> point positions x and G = dx/dq, frame rotations R and W = dtheta/dq
   !> (body increments).
   type :: spatial_configuration_type
      !> The state's dofs (the slides' strokes).
      real(dp), allocatable :: q(:)
      real(dp), allocatable :: x(:, :), g(:, :, :)
      real(dp), allocatable :: r(:, :, :), w(:, :, :)
   end type spatial_configuration_type

   !> The outcome of one Newton solve.
   type :: spatial_report_type
      integer :: iterations = 0
      !> The last correction, lengths divided by the mechanism's length.
      real(dp) :: correction = 0
      logical :: converged = .false.
   end type spatial_report_type

contains

   !> The reference configuration: free points at their positions, every
   !> stroke and angle 0, every frame I.
   pure function new_spatial_state(m) result(s)
      type(spatial_mechanism_type), intent(in) :: m
      type(spatial_state_type) :: s
      integer :: i, nf
      allocate (s%q(m%ndof), source=0.0_dp)
      nf = 0
      if (allocated(m%frames)) nf = size(m%frames)
      allocate (s%r(3, 3, nf), source=0.0_dp)
      do i = 1, 3
         s%r(i, i, :) = 1
      end do
      do i = 1, size(m%points)
         if (m%points(i)%kind == point_free) s%q(m%points(i)%dof:m%points(i)%dof + 2) = m%points(i)%x0
      end do
   end function new_spatial_state

   !> The dofs that are not driven.
   pure function free_dofs(m) result(list)
      type(spatial_mechanism_type), intent(in) :: m
      integer, allocatable :: list(:)
      logical :: driven(m%ndof)
      integer :: i
      driven = .false.
      if (allocated(m%drives)) then
         do i = 1, size(m%drives)
            driven(m%drives(i)%dof) = .true.
         end do
      end if
      list = pack([(i, i=1, m%ndof)], .not. driven)
   end function free_dofs

   !> Positions, rotations and their dof derivatives at state s.
   pure subroutine configure(m, s, c)
      type(spatial_mechanism_type), intent(in) :: m
      type(spatial_state_type), intent(in) :: s
      type(spatial_configuration_type), intent(out) :: c
      real(dp) :: rp(3, 3), wp(3, m%ndof), e1(3, 3), e2(3, 3)
      integer :: i, k, np, nf
      np = size(m%points)
      nf = size(s%r, 3)
      allocate (c%x(3, np), c%g(3, m%ndof, np), c%r(3, 3, nf), c%w(3, m%ndof, nf), source=0.0_dp)
      c%q = s%q
      do i = 1, np
         associate (p => m%points(i))
            select case (p%kind)
            case (point_free)
               c%x(:, i) = s%q(p%dof:p%dof + 2)
               do k = 1, 3
                  c%g(k, p%dof + k - 1, i) = 1
               end do
            case (point_line)
               c%x(:, i) = p%x0 + s%q(p%dof)*p%axis
               c%g(:, p%dof, i) = p%axis
            case default                                 ! point_fixed
               c%x(:, i) = p%x0
            end select
         end associate
      end do
      do i = 1, nf
         associate (f => m%frames(i))
            call parent_of(f%parent, rp, wp)
            select case (f%kind)
            case (frame_free)
               c%r(:, :, i) = s%r(:, :, i)
               do k = 1, 3
                  c%w(k, f%dof + k - 1, i) = 1
               end do
            case (frame_revolute)
               e1 = so3_exp(s%q(f%dof)*f%axis)
               c%r(:, :, i) = matmul(rp, e1)
               c%w(:, :, i) = matmul(transpose(e1), wp)
               c%w(:, f%dof, i) = c%w(:, f%dof, i) + f%axis
            case (frame_universal)
               e1 = so3_exp(s%q(f%dof)*f%axis)
               e2 = so3_exp(s%q(f%dof + 1)*f%axis2)
               c%r(:, :, i) = matmul(rp, matmul(e1, e2))
               c%w(:, :, i) = matmul(transpose(matmul(e1, e2)), wp)
               c%w(:, f%dof, i) = c%w(:, f%dof, i) + matmul(f%axis, e2)
               c%w(:, f%dof + 1, i) = c%w(:, f%dof + 1, i) + f%axis2
            case default                                 ! frame_fixed
               do k = 1, 3
                  c%r(k, k, i) = 1
               end do
            end select
         end associate
      end do
   contains
      pure subroutine parent_of(j, rp, wp)
         integer, intent(in) :: j
         real(dp), intent(out) :: rp(3, 3), wp(:, :)
         integer :: k
         if (j == 0) then
            rp = 0
            do k = 1, 3
               rp(k, k) = 1
            end do
            wp = 0
         else
            rp = c%r(:, :, j)
            wp = c%w(:, :, j)
         end if
      end subroutine parent_of
   end subroutine configure

   !> The body angular acceleration each frame has along q (+) s v at s = 0
   !> with no dof acceleration: zero for free and fixed frames; for a child,
   !> R = R_p exp(theta n^) gives omega = E^T omega_p + n theta' and
   !> d omega/ds = -(n theta') x (E^T omega_p) + E^T kappa_p (twice for a
   !> universal joint).
   pure function frame_curvature(m, s, c, v) result(kappa)
      type(spatial_mechanism_type), intent(in) :: m
      type(spatial_state_type), intent(in) :: s
      type(spatial_configuration_type), intent(in) :: c
      real(dp), intent(in) :: v(:)
      real(dp) :: kappa(3, size(c%r, 3))
      real(dp) :: wp(3), kp(3), e1(3, 3), e2(3, 3), w1(3), k1(3)
      integer :: i
      kappa = 0
      do i = 1, size(c%r, 3)
         associate (f => m%frames(i))
            wp = 0
            kp = 0
            if (f%parent > 0) then
               wp = matmul(c%w(:, :, f%parent), v)
               kp = kappa(:, f%parent)
            end if
            select case (f%kind)
            case (frame_revolute)
               e1 = so3_exp(s%q(f%dof)*f%axis)
               kappa(:, i) = -cross(f%axis*v(f%dof), matmul(wp, e1)) + matmul(kp, e1)
            case (frame_universal)
               e1 = so3_exp(s%q(f%dof)*f%axis)
               e2 = so3_exp(s%q(f%dof + 1)*f%axis2)
               w1 = matmul(wp, e1) + f%axis*v(f%dof)
               k1 = -cross(f%axis*v(f%dof), matmul(wp, e1)) + matmul(kp, e1)
               kappa(:, i) = -cross(f%axis2*v(f%dof + 1), matmul(w1, e2)) + matmul(k1, e2)
            case default                                 ! fixed and free frames: none
            end select
         end associate
      end do
   end function frame_curvature

   !> The residual r = sum G^T f and, if asked, the material tangent
   !> K = sum G^T B^T k B G at state s. With v (and kappa, from
   !> frame_curvature), conv = sum G^T B^T k c, the convective load.
   pure subroutine assemble_spatial(m, c, residual, tangent, v, kappa, conv)
      type(spatial_mechanism_type), intent(in) :: m
      type(spatial_configuration_type), intent(in) :: c
      real(dp), intent(out) :: residual(:)
      real(dp), intent(out), optional :: tangent(:, :)
      real(dp), intent(in), optional :: v(:), kappa(:, :)
      real(dp), intent(out), optional :: conv(:)
      real(dp) :: x(3, 2), r(3, 3, 2), f(12), ke(12, 12), ge(12, m%ndof), b(6, 12), ce(6)
      real(dp) :: nv(3, 2), nw(3, 2), na(3, 2), ft(6), kt(6, 6), gt(6, m%ndof), et
      integer :: i, n, p, fr
      residual = 0
      if (present(tangent)) tangent = 0
      if (present(conv)) conv = 0
      if (allocated(m%beams)) then
         do i = 1, size(m%beams)
            do n = 1, 2
               p = m%nodes(m%beams(i)%nodes(n))%point
               fr = m%nodes(m%beams(i)%nodes(n))%frame
               x(:, n) = c%x(:, p)
               r(:, :, n) = c%r(:, :, fr)
               ge(6*n - 5:6*n - 3, :) = c%g(:, :, p)
               ge(6*n - 2:6*n, :) = c%w(:, :, fr)
               if (present(conv)) then
                  nv(:, n) = matmul(c%g(:, :, p), v)
                  nw(:, n) = matmul(c%w(:, :, fr), v)
                  na(:, n) = kappa(:, fr)
               end if
            end do
            if (present(tangent)) then
               call se3_beam_residual(m%beams(i)%element, x, r, f, ke, material_only=.true., compatibility=b)
               tangent = tangent + matmul(transpose(ge), matmul(ke, ge))
            else
               call se3_beam_residual(m%beams(i)%element, x, r, f, compatibility=b)
            end if
            residual = residual + matmul(f, ge)
            if (present(conv)) then
               ce = se3_beam_convective(x, r, nv, nw, na)
               conv = conv + matmul(matmul(matmul(m%beams(i)%element%k, ce), b), ge)
            end if
         end do
      end if
      if (allocated(m%trusses)) then
         do i = 1, size(m%trusses)
            do n = 1, 2
               p = m%trusses(i)%points(n)
               x(:, n) = c%x(:, p)
               gt(3*n - 2:3*n, :) = c%g(:, :, p)
               if (present(conv)) nv(:, n) = matmul(c%g(:, :, p), v)
            end do
            if (present(tangent)) then
               call truss_residual(m%trusses(i)%element, x, ft, kt)
               tangent = tangent + matmul(transpose(gt), matmul(kt, gt))
            else
               call truss_residual(m%trusses(i)%element, x, ft)
            end if
            residual = residual + matmul(ft, gt)
            if (present(conv)) then
               ! B = (-u, u), k = EA/L.
               et = truss_convective(x, nv)*m%trusses(i)%element%ea/m%trusses(i)%element%length
               x(:, 1) = (x(:, 2) - x(:, 1))/norm2(x(:, 2) - x(:, 1))
               conv = conv + et*matmul([-x(:, 1), x(:, 1)], gt)
            end if
         end do
      end if
      ! Points on lines carried by moving frames (penalty slidelines).
      call assemble_slides(m, c%q, c%x, c%g, c%r, c%w, residual, tangent, v, kappa, conv)
   end subroutine assemble_spatial

   !> The drives' values at t in s%q; their rates and second rates in vd, ad
   !> (full-length vectors, zero at the free dofs).
   pure subroutine set_drives(m, t, s, vd, ad)
      type(spatial_mechanism_type), intent(in) :: m
      real(dp), intent(in) :: t
      type(spatial_state_type), intent(inout) :: s
      real(dp), intent(out) :: vd(:), ad(:)
      integer :: i
      vd = 0
      ad = 0
      if (.not. allocated(m%drives)) return
      do i = 1, size(m%drives)
         call m%drives(i)%law%eval(t, s%q(m%drives(i)%dof), vd(m%drives(i)%dof), ad(m%drives(i)%dof))
      end do
   end subroutine set_drives

   !> s <- s (+) dq: additive dofs added, free frames turned by their body increments.
   pure subroutine update_state(m, s, dq)
      type(spatial_mechanism_type), intent(in) :: m
      type(spatial_state_type), intent(inout) :: s
      real(dp), intent(in) :: dq(:)
      integer :: i
      s%q = s%q + dq
      do i = 1, size(s%r, 3)
         if (m%frames(i)%kind /= frame_free) cycle
         call so3_update(s%r(:, :, i), dq(m%frames(i)%dof:m%frames(i)%dof + 2))
         s%q(m%frames(i)%dof:m%frames(i)%dof + 2) = 0
      end do
   end subroutine update_state

   !> Newton-Raphson on the free dofs at time t (drives set first) until the
   !> correction is below tol (lengths relative to the mechanism's length).
   subroutine spatial_newton(m, t, s, tol, max_iterations, report, error)
      type(spatial_mechanism_type), intent(in) :: m
      real(dp), intent(in) :: t, tol
      type(spatial_state_type), intent(inout) :: s
      integer, intent(in) :: max_iterations
      type(spatial_report_type), intent(out) :: report
      type(error_type), allocatable, intent(out) :: error
      type(spatial_configuration_type) :: c
      real(dp) :: res(m%ndof), k(m%ndof, m%ndof), vd(m%ndof), ad(m%ndof), dq(m%ndof), scale(m%ndof)
      real(dp), allocatable :: kff(:, :), rhs(:)
      integer, allocatable :: fdof(:), ipiv(:)
      integer :: it, info
      fdof = free_dofs(m)
      call set_drives(m, t, s, vd, ad)
      scale = merge(1/m%length, 1.0_dp, m%is_length)
      allocate (ipiv(size(fdof)))
      do it = 1, max_iterations
         call configure(m, s, c)
         call assemble_spatial(m, c, res, k)
         kff = k(fdof, fdof)
         rhs = -res(fdof)
         call dense_lu_factor(kff, ipiv, info)
         if (info /= 0) then
            call singular(error, fdof(info), t)
            return
         end if
         call dense_lu_solve(kff, ipiv, rhs, info)
         dq = 0
         dq(fdof) = rhs
         call update_state(m, s, dq)
         report%iterations = it
         report%correction = maxval(abs(dq*scale))
         if (report%correction < tol) then
            report%converged = .true.
            return
         end if
      end do
      call analysis_error(error, 'Newton did not converge in the spatial kinematics: '// &
         & 'a dead point or a configuration that does not assemble; drive another joint or take smaller steps')
   end subroutine spatial_newton

   !> Velocities v and accelerations a of every dof at state s, time t.
   subroutine spatial_rates(m, t, s, v, a, error)
      type(spatial_mechanism_type), intent(in) :: m
      real(dp), intent(in) :: t
      type(spatial_state_type), intent(in) :: s
      real(dp), intent(out) :: v(:), a(:)
      type(error_type), allocatable, intent(out) :: error
      type(spatial_configuration_type) :: c
      type(spatial_state_type) :: sd
      real(dp) :: res(m%ndof), k(m%ndof, m%ndof), ad(m%ndof)
      real(dp), allocatable :: kff(:, :)
      integer, allocatable :: fdof(:), ipiv(:)
      integer :: info
      fdof = free_dofs(m)
      sd = s
      call set_drives(m, t, sd, v, ad)
      call configure(m, s, c)
      call assemble_spatial(m, c, res, k)
      kff = k(fdof, fdof)
      allocate (ipiv(size(fdof)))
      call dense_lu_factor(kff, ipiv, info)
      if (info /= 0) then
         call singular(error, fdof(info), t)
         return
      end if
      call spatial_rates_factored(m, s, c, k, kff, ipiv, fdof, v, ad, a)
   end subroutine spatial_rates

   !> The rates at state s (configuration c, tangent k, its free block kff
   !> factored by dense_lu_factor with ipiv) given the drives' rates in v and
   !> second rates ad (zero at the free dofs): v and a of every dof.
   subroutine spatial_rates_factored(m, s, c, k, kff, ipiv, fdof, v, ad, a)
      type(spatial_mechanism_type), intent(in) :: m
      type(spatial_state_type), intent(in) :: s
      type(spatial_configuration_type), intent(in) :: c
      real(dp), intent(in) :: k(:, :), ad(:)
      real(dp), contiguous, intent(in) :: kff(:, :)
      integer, contiguous, intent(in) :: ipiv(:)
      integer, intent(in) :: fdof(:)
      real(dp), intent(inout) :: v(:)
      real(dp), intent(out) :: a(:)
      real(dp) :: res(m%ndof), conv(m%ndof), kappa(3, size(s%r, 3))
      real(dp), allocatable :: rhs(:)
      integer :: info
      rhs = -matmul(k(fdof, :), v)
      call dense_lu_solve(kff, ipiv, rhs, info)
      v(fdof) = rhs
      kappa = frame_curvature(m, s, c, v)
      call assemble_spatial(m, c, res, v=v, kappa=kappa, conv=conv)
      a = ad
      rhs = -matmul(k(fdof, :), a) - conv(fdof)
      call dense_lu_solve(kff, ipiv, rhs, info)
      a(fdof) = rhs
   end subroutine spatial_rates_factored

   subroutine singular(error, dof, t)
      type(error_type), allocatable, intent(out) :: error
      integer, intent(in) :: dof
      real(dp), intent(in) :: t
      character(len=80) :: text
      write (text, '(a,i0,a,es12.5)') 'singular tangent at dof ', dof, ', t = ', t
      call analysis_error(error, trim(text)//': a mode with no stiffness '// &
         & '(a beam between two spherical joints spins freely: make it a truss)')
   end subroutine singular

   !> The position of point p.
   pure function point_position(c, p) result(x)
      type(spatial_configuration_type), intent(in) :: c
      integer, intent(in) :: p
      real(dp) :: x(3)
      x = c%x(:, p)
   end function point_position

   !> The rate of point p for dof rates v (or its acceleration for dof
   !> accelerations: points move linearly in their dofs).
   pure function point_rate(c, p, v) result(xd)
      type(spatial_configuration_type), intent(in) :: c
      integer, intent(in) :: p
      real(dp), intent(in) :: v(:)
      real(dp) :: xd(3)
      xd = matmul(c%g(:, :, p), v)
   end function point_rate

end module fekap_spatial_kinematics
