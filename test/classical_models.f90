!> Models of the paper's examples (geometry of /work/shared/examples.md) and
!> a slider-crank, built directly in Fortran for the tests of the classical
!> methods, with the closed-form motions the tests compare against and a
!> small time loop.
module classical_models
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, fatal_error
   use fekap_model, only: model_type, link_type, weld_type, support_type, drive_type, slideline_type, &
      & find_node, find_link, dof_x, dof_y, dof_rot, joint_pin_in_slot, joint_prismatic
   use fekap_model_drive_law, only: law_type, new_rate_law, new_harmonic_law
   use fekap_model_results, only: step_result_type
   use fekap_stepping_stepper, only: stepper_type
   implicit none
   private

   public :: four_bar_model, appendage_model, double_crank_model, peaucellier_model, slider_crank_model
   public :: prismatic_slider_model, slider_drive_model, quick_return_model, four_bar_exact, slider_crank_exact, run_steps, pi
   public :: check_branch_jump_cut

   real(dp), parameter :: pi = 3.14159265358979323846_dp

contains

   !> Example 1: A = (0,0), D = (4,0), AB = 2, BC = 4, DC = 4; crank angle 2 pi t.
   subroutine four_bar_model(model)
      type(model_type), intent(out) :: model
      type(law_type) :: law
      call start_model(model, ['A', 'B', 'C', 'D'], reshape([0.0_dp, 0.0_dp, 2.0_dp, 0.0_dp, 3.0_dp, sqrt(15.0_dp), &
         & 4.0_dp, 0.0_dp], [2, 4]))
      call add_link(model, 'AB', 'A', 'B')
      call add_link(model, 'BC', 'B', 'C')
      call add_link(model, 'DC', 'D', 'C')
      call add_pin(model, 'A')
      call add_pin(model, 'D')
      call new_rate_law(law, 2*pi, 0.0_dp)
      call add_rotation_drive(model, 'AB', 'A', law)
   end subroutine four_bar_model

   !> Example 2: the four-bar with the coupler split at M and the appendage
   !> M-P (1.5, perpendicular to BC, to its left) welded there.
   subroutine appendage_model(model)
      type(model_type), intent(out) :: model
      type(law_type) :: law
      real(dp) :: c(2), m(2), p(2)
      c = [3.0_dp, sqrt(15.0_dp)]
      m = ([2.0_dp, 0.0_dp] + c)/2
      p = m + 1.5_dp*[-(c(2) - 0), c(1) - 2]/4
      call start_model(model, ['A', 'B', 'M', 'C', 'D', 'P'], reshape([0.0_dp, 0.0_dp, 2.0_dp, 0.0_dp, m, c, &
         & 4.0_dp, 0.0_dp, p], [2, 6]))
      call add_link(model, 'AB', 'A', 'B')
      call add_link(model, 'BM', 'B', 'M')
      call add_link(model, 'MC', 'M', 'C')
      call add_link(model, 'DC', 'D', 'C')
      call add_link(model, 'MP', 'M', 'P')
      call add_weld(model, 'M', ['BM', 'MC', 'MP'])
      call add_pin(model, 'A')
      call add_pin(model, 'D')
      call new_rate_law(law, 2*pi, 0.0_dp)
      call add_rotation_drive(model, 'AB', 'A', law)
   end subroutine appendage_model

   !> Example 3: three parallel cranks O1-D, O2-E, O3-F and the coupler D-E-F
   !> welded at E; crank O1-D at pi/2 + 2 pi t; dt = 0.02.
   subroutine double_crank_model(model)
      type(model_type), intent(out) :: model
      type(law_type) :: law
      call start_model(model, ['O1', 'O2', 'O3', 'D ', 'E ', 'F '], reshape([0.0_dp, 0.0_dp, 2.0_dp, 0.0_dp, &
         & 4.0_dp, 0.0_dp, 0.0_dp, 1.0_dp, 2.0_dp, 1.0_dp, 4.0_dp, 1.0_dp], [2, 6]))
      call add_link(model, 'O1D', 'O1', 'D')
      call add_link(model, 'O2E', 'O2', 'E')
      call add_link(model, 'O3F', 'O3', 'F')
      call add_link(model, 'DE', 'D', 'E')
      call add_link(model, 'EF', 'E', 'F')
      call add_weld(model, 'E', ['DE', 'EF'])
      call add_pin(model, 'O1')
      call add_pin(model, 'O2')
      call add_pin(model, 'O3')
      call new_rate_law(law, 2*pi, pi/2)
      call add_rotation_drive(model, 'O1D', 'O1', law)
      model%analysis%dt = 0.02_dp
   end subroutine double_crank_model

   !> Example 4: Peaucellier-Lipkin; O = (0,0), Q = (1.4,0), QA = 1.4,
   !> OB = OD = 3, rhombus A-B-P-D of side 1.2; angle of QA 60 + 30 cos(2 pi t) deg.
   subroutine peaucellier_model(model)
      type(model_type), intent(out) :: model
      type(law_type) :: law
      real(dp) :: a(2), u(2), ra, along, h, b(2), d(2), p(2)
      a = [1.4_dp, 1.4_dp]
      ra = norm2(a)
      u = a/ra
      along = (3.0_dp**2 - 1.2_dp**2 + ra**2)/(2*ra)
      h = sqrt(3.0_dp**2 - along**2)
      b = along*u + h*[-u(2), u(1)]
      d = along*u - h*[-u(2), u(1)]
      p = b + d - a
      call start_model(model, ['O', 'Q', 'A', 'B', 'D', 'P'], reshape([0.0_dp, 0.0_dp, 1.4_dp, 0.0_dp, a, b, d, p], [2, 6]))
      call add_link(model, 'OB', 'O', 'B')
      call add_link(model, 'AB', 'A', 'B')
      call add_link(model, 'BP', 'B', 'P')
      call add_link(model, 'PD', 'P', 'D')
      call add_link(model, 'DA', 'D', 'A')
      call add_link(model, 'OD', 'O', 'D')
      call add_link(model, 'QA', 'Q', 'A')
      call add_pin(model, 'O')
      call add_pin(model, 'Q')
      call new_harmonic_law(law, pi/3, pi/6, 2*pi, 0.0_dp)
      call add_rotation_drive(model, 'QA', 'Q', law)
      model%analysis%dt = 0.05_dp
   end subroutine peaucellier_model

   !> Crank O-A (1) and rod A-B (3), the slider B on a ground guide from (-5,0)
   !> to (5,0) (pin in slot); crank angle 2 pi t.
   subroutine slider_crank_model(model)
      type(model_type), intent(out) :: model
      type(law_type) :: law
      type(slideline_type) :: s
      call start_model(model, ['O', 'A', 'B'], reshape([0.0_dp, 0.0_dp, 1.0_dp, 0.0_dp, 4.0_dp, 0.0_dp], [2, 3]))
      call add_link(model, 'OA', 'O', 'A')
      call add_link(model, 'AB', 'A', 'B')
      call add_pin(model, 'O')
      call new_rate_law(law, 2*pi, 0.0_dp)
      call add_rotation_drive(model, 'OA', 'O', law)
      s%name = 'slot'
      s%slave = find_node(model, 'B')
      s%kind = joint_pin_in_slot
      s%ground = .true.
      s%guide = reshape([-5.0_dp, 0.0_dp, 5.0_dp, 0.0_dp], [2, 2])
      allocate (s%master_links(0))
      model%slidelines = [model%slidelines, s]
   end subroutine slider_crank_model

   !> The slider-crank with a slider block B-K (0.5 along x) on the ground
   !> guide as a prismatic joint: the block keeps its angle.
   subroutine prismatic_slider_model(model)
      type(model_type), intent(out) :: model
      type(law_type) :: law
      type(slideline_type) :: s
      call start_model(model, ['O', 'A', 'B', 'K'], reshape([0.0_dp, 0.0_dp, 1.0_dp, 0.0_dp, 4.0_dp, 0.0_dp, &
         & 4.5_dp, 0.0_dp], [2, 4]))
      call add_link(model, 'OA', 'O', 'A')
      call add_link(model, 'AB', 'A', 'B')
      call add_link(model, 'BK', 'B', 'K')
      call add_pin(model, 'O')
      call new_rate_law(law, 2*pi, 0.0_dp)
      call add_rotation_drive(model, 'OA', 'O', law)
      s%name = 'block'
      s%slave = find_node(model, 'B')
      s%kind = joint_prismatic
      s%slave_link = find_link(model, 'BK')
      s%ground = .true.
      s%guide = reshape([-5.0_dp, 0.0_dp, 5.0_dp, 0.0_dp], [2, 2])
      allocate (s%master_links(0))
      model%slidelines = [model%slidelines, s]
   end subroutine prismatic_slider_model

   !> Crank O-A (1, at 90 deg) and rod A-B (3) with B on the x axis, driven by
   !> the slider: B.x = sqrt(8) + 0.5 sin(2 pi t) (an x drive).
   subroutine slider_drive_model(model)
      type(model_type), intent(out) :: model
      type(law_type) :: law
      type(slideline_type) :: s
      type(drive_type) :: drive
      call start_model(model, ['O', 'A', 'B'], reshape([0.0_dp, 0.0_dp, 0.0_dp, 1.0_dp, sqrt(8.0_dp), 0.0_dp], [2, 3]))
      call add_link(model, 'OA', 'O', 'A')
      call add_link(model, 'AB', 'A', 'B')
      call add_pin(model, 'O')
      call new_harmonic_law(law, 0.0_dp, 0.5_dp, 2*pi, -pi/2)
      drive%dof = dof_x
      drive%node = find_node(model, 'B')
      drive%law = law
      model%drives = [model%drives, drive]
      s%name = 'slot'
      s%slave = find_node(model, 'B')
      s%ground = .true.
      s%guide = reshape([-5.0_dp, 0.0_dp, 5.0_dp, 0.0_dp], [2, 2])
      allocate (s%master_links(0))
      model%slidelines = [model%slidelines, s]
   end subroutine slider_drive_model

   !> Example 5: quick-return mechanism; crank O2-C whose pin C slides on the
   !> lever O4-B, link B-P, P sliding on the ground guide y = 500; dt = 0.01.
   subroutine quick_return_model(model)
      type(model_type), intent(out) :: model
      type(law_type) :: law
      type(slideline_type) :: s
      real(dp) :: o2(2), c(2), b(2), r10
      r10 = sqrt(10.0_dp)
      o2 = [0.0_dp, 100*r10]
      c = o2 + 100*[3.0_dp, -1.0_dp]/r10
      b = 150*r10*[1.0_dp, 3.0_dp]/r10
      call start_model(model, ['O4', 'O2', 'C ', 'B ', 'P '], reshape([0.0_dp, 0.0_dp, o2, c, b, 0.0_dp, 500.0_dp], [2, 5]))
      call add_link(model, 'O2C', 'O2', 'C')
      call add_link(model, 'O4B', 'O4', 'B')
      call add_link(model, 'BP', 'B', 'P')
      call add_pin(model, 'O2')
      call add_pin(model, 'O4')
      call new_rate_law(law, 2*pi, atan2(-1.0_dp, 3.0_dp))
      call add_rotation_drive(model, 'O2C', 'O2', law)
      s%name = 'lever'
      s%slave = find_node(model, 'C')
      s%kind = joint_pin_in_slot
      s%master_links = [find_link(model, 'O4B')]
      model%slidelines = [model%slidelines, s]
      s%name = 'guide'
      s%slave = find_node(model, 'P')
      s%ground = .true.
      s%guide = reshape([-400.0_dp, 500.0_dp, 100.0_dp, 500.0_dp], [2, 2])
      deallocate (s%master_links)
      allocate (s%master_links(0))
      model%slidelines = [model%slidelines, s]
      model%analysis%dt = 0.01_dp
   end subroutine quick_return_model

   subroutine start_model(model, names, xy)
      type(model_type), intent(inout) :: model
      character(*), intent(in) :: names(:)
      real(dp), intent(in) :: xy(:, :)
      integer :: i
      model%title = 'test model'
      allocate (model%nodes(size(names)))
      do i = 1, size(names)
         model%nodes(i)%name = trim(names(i))
         model%nodes(i)%x = xy(:, i)
      end do
      allocate (model%sections(1))
      model%sections(1)%name = 'bar'
      model%sections(1)%ea = 100
      model%sections(1)%kga = 5.0_dp/6*100
      model%sections(1)%ei = 1
      allocate (model%links(0), model%welds(0), model%supports(0), model%drives(0), model%loads(0), &
         & model%slidelines(0))
      model%analysis%dt = 0.025_dp
   end subroutine start_model

   subroutine add_link(model, name, a, b)
      type(model_type), intent(inout) :: model
      character(*), intent(in) :: name, a, b
      type(link_type) :: link
      link%name = name
      link%node = [find_node(model, a), find_node(model, b)]
      link%section = 1
      model%links = [model%links, link]
   end subroutine add_link

   subroutine add_weld(model, node, links)
      type(model_type), intent(inout) :: model
      character(*), intent(in) :: node, links(:)
      type(weld_type) :: weld
      integer :: i
      weld%node = find_node(model, node)
      allocate (weld%links(size(links)))
      do i = 1, size(links)
         weld%links(i) = find_link(model, trim(links(i)))
      end do
      model%welds = [model%welds, weld]
   end subroutine add_weld

   subroutine add_pin(model, node)
      type(model_type), intent(inout) :: model
      character(*), intent(in) :: node
      type(support_type) :: support
      support%node = find_node(model, node)
      support%fix(dof_x) = .true.
      support%fix(dof_y) = .true.
      model%supports = [model%supports, support]
   end subroutine add_pin

   subroutine add_rotation_drive(model, link, node, law)
      type(model_type), intent(inout) :: model
      character(*), intent(in) :: link, node
      type(law_type), intent(in) :: law
      type(drive_type) :: drive
      drive%dof = dof_rot
      drive%node = find_node(model, node)
      drive%link = find_link(model, link)
      drive%law = law
      model%drives = [model%drives, drive]
   end subroutine add_rotation_drive

   !> Closed-form motion of Example 1 (upper branch): B on the crank circle,
   !> C = midpoint of B and D + k perp(D - B), k = sqrt(l**2/s - 1/4), s = |D - B|**2,
   !> and the exact time derivatives of both (crank rate 2 pi, no angular acceleration).
   pure subroutine four_bar_exact(t, b, vb, ab, c, vc, ac)
      real(dp), intent(in) :: t
      real(dp), intent(out) :: b(2), vb(2), ab(2), c(2), vc(2), ac(2)
      real(dp), parameter :: l1 = 2, l = 4, d(2) = [4.0_dp, 0.0_dp]
      real(dp) :: w, e(2), ed(2), edd(2), s, sd, sdd, k, kd, kdd
      w = 2*pi
      b = l1*[cos(w*t), sin(w*t)]
      vb = l1*w*[-sin(w*t), cos(w*t)]
      ab = -w**2*b
      e = d - b
      ed = -vb
      edd = -ab
      s = dot_product(e, e)
      sd = 2*dot_product(e, ed)
      sdd = 2*(dot_product(ed, ed) + dot_product(e, edd))
      k = sqrt(l**2/s - 0.25_dp)
      kd = -l**2*sd/(2*k*s**2)
      kdd = (-l**2*(sdd/s**2 - 2*sd**2/s**3) - 2*kd**2)/(2*k)
      c = (b + d)/2 + k*rot90(e)
      vc = vb/2 + kd*rot90(e) + k*rot90(ed)
      ac = ab/2 + kdd*rot90(e) + 2*kd*rot90(ed) + k*rot90(edd)
   end subroutine four_bar_exact

   !> Slider position, velocity and acceleration of the slider-crank (1, 3) at crank angle 2 pi t.
   pure subroutine slider_crank_exact(t, x, vx, ax)
      real(dp), intent(in) :: t
      real(dp), intent(out) :: x, vx, ax
      real(dp) :: w, s, c, r
      w = 2*pi
      s = sin(w*t)
      c = cos(w*t)
      r = sqrt(9 - s**2)
      x = c + r
      vx = w*(-s - s*c/r)
      ax = w**2*(-c - (c**2 - s**2)/r - s**2*c**2/r**3)
   end subroutine slider_crank_exact

   pure function rot90(v) result(w)
      real(dp), intent(in) :: v(2)
      real(dp) :: w(2)
      w = [-v(2), v(1)]
   end function rot90

   !> Start `stepper` and advance it over the model's time range; results(0:nstep).
   subroutine run_steps(stepper, model, results, error)
      class(stepper_type), intent(inout) :: stepper
      type(model_type), intent(in) :: model
      type(step_result_type), allocatable, intent(out) :: results(:)
      type(error_type), allocatable, intent(out) :: error
      integer :: nstep, k
      nstep = nint((model%analysis%t_end - model%analysis%t_start)/model%analysis%dt)
      allocate (results(0:nstep))
      call stepper%start(results(0), error)
      if (allocated(error)) return
      do k = 1, nstep
         call stepper%advance(model%analysis%t_start + k*model%analysis%dt, results(k), error)
         if (allocated(error)) return
      end do
   end subroutine run_steps

   !> Example 1 at dt = 0.5 with the extrapolating predictor landed on the
   !> other assembly branch (C = (3, -3.873) at t = 1) before the jump check;
   !> now, with either classical stepper (made from `model`), the step to
   !> t = 1 is cut, its note names the rejection, and C follows the closed form;
   !> `error` says which of these failed (the suites assert that it is not set).
   subroutine check_branch_jump_cut(stepper, model, error)
      class(stepper_type), intent(inout) :: stepper
      type(model_type), intent(in) :: model
      type(error_type), allocatable, intent(out) :: error
      type(step_result_type), allocatable :: res(:)
      real(dp) :: b(2), vb(2), ab(2), c(2), vc(2), ac(2)
      character(len=24) :: t_text
      integer :: k
      call run_steps(stepper, model, res, error)
      if (allocated(error)) return
      if (size(res) /= 3) then
         write (t_text, '(i0)') size(res)
         call fatal_error(error, 'number of results: got '//trim(t_text)//', want 3')
         return
      end if
      do k = 0, ubound(res, 1)
         call four_bar_exact(res(k)%t, b, vb, ab, c, vc, ac)
         write (t_text, '(g0)') res(k)%t
         if (.not. norm2(res(k)%pos(:, 3) - c) < 1.0e-9_dp) then
            call fatal_error(error, 'C not on the upper branch at t = '//trim(t_text))
            return
         end if
      end do
      if (res(2)%cuts < 1) then
         call fatal_error(error, 'the step to t = 1 was not cut')
         return
      end if
      if (.not. (index(res(2)%note, 'step cut ') == 1 .and. index(res(2)%note, 'assembly-mode jump rejected') > 0)) then
         call fatal_error(error, 'note: '//trim(res(2)%note))
      end if
   end subroutine check_branch_jump_cut

end module classical_models
