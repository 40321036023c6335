!> Models of the paper's mechanisms built directly in Fortran, and their
!> independent closed-form solutions, for tests that must not depend on the
!> deck reader.
module test_mechanisms
   use fekap_kinds, only: dp
   use fekap_model, only: model_type, node_type, section_type, link_type, support_type, drive_type, &
      & dof_rot, joint_pin_in_slot
   use fekap_model_drive_law, only: new_rate_law
   implicit none
   private

   public :: fourbar_model, add_node, add_link, cantilever_model, slider_crank_model, parallelogram_model

   real(dp), parameter :: pi = acos(-1.0_dp)

contains

   subroutine add_node(model, name, x, y)
      type(model_type), intent(inout) :: model
      character(*), intent(in) :: name
      real(dp), intent(in) :: x, y
      type(node_type) :: node
      node%name = name
      node%x = [x, y]
      if (.not. allocated(model%nodes)) allocate (model%nodes(0))
      model%nodes = [model%nodes, node]
   end subroutine add_node

   subroutine add_link(model, name, n1, n2, nelem)
      type(model_type), intent(inout) :: model
      character(*), intent(in) :: name
      integer, intent(in) :: n1, n2, nelem
      type(link_type) :: link
      link%name = name
      link%node = [n1, n2]
      link%section = 1
      link%nelem = nelem
      if (.not. allocated(model%links)) allocate (model%links(0))
      model%links = [model%links, link]
   end subroutine add_link

   !> Example 1: A = (0, 0), D = (4, 0), crank AB = 2, coupler BC = 4, rocker
   !> DC = 4; crank angle 2*pi*t. Section data scaled by `factor` (1: the paper's).
   subroutine fourbar_model(model, dt, factor, nelem)
      type(model_type), intent(out) :: model
      real(dp), intent(in) :: dt
      real(dp), intent(in), optional :: factor
      integer, intent(in), optional :: nelem
      real(dp) :: s
      integer :: ne
      s = 1
      if (present(factor)) s = factor
      ne = 1
      if (present(nelem)) ne = nelem
      model%file = 'fourbar'
      call add_node(model, 'A', 0.0_dp, 0.0_dp)
      call add_node(model, 'B', 2.0_dp, 0.0_dp)
      call add_node(model, 'C', 3.0_dp, sqrt(15.0_dp))
      call add_node(model, 'D', 4.0_dp, 0.0_dp)
      call add_bar_section(model, s)
      call add_link(model, 'AB', 1, 2, ne)
      call add_link(model, 'BC', 2, 3, ne)
      call add_link(model, 'DC', 4, 3, ne)
      call pin_and_drive(model, [1, 4], dt)
      model%output%points = [2, 3]
      model%output%links = [1, 2, 3]
   end subroutine fourbar_model


   !> The four-bars' one section `bar`: E = G = 1, A = 100, I = 1, k = 5/6,
   !> all scaled by s.
   subroutine add_bar_section(model, s)
      type(model_type), intent(inout) :: model
      real(dp), intent(in) :: s
      allocate (model%sections(1))
      model%sections(1)%name = 'bar'
      model%sections(1)%ea = 100*s
      model%sections(1)%kga = 5.0_dp/6*100*s
      model%sections(1)%ei = s
   end subroutine add_bar_section

   !> The four-bars' frame: pins at the two nodes, link 1 driven at its
   !> first node at 2 pi rad/s, time step dt, no welds, loads or slidelines.
   subroutine pin_and_drive(model, pins, dt)
      type(model_type), intent(inout) :: model
      integer, intent(in) :: pins(2)
      real(dp), intent(in) :: dt
      integer :: k
      allocate (model%supports(2))
      do k = 1, 2
         model%supports(k)%node = pins(k)
         model%supports(k)%fix = [.true., .true., .false.]
      end do
      allocate (model%drives(1))
      model%drives(1)%dof = dof_rot
      model%drives(1)%link = 1
      model%drives(1)%node = 1
      call new_rate_law(model%drives(1)%law, 2*pi)
      model%analysis%dt = dt
      allocate (model%welds(0), model%loads(0), model%slidelines(0))
   end subroutine pin_and_drive

   !> The IFToMM A02 chain with N = 1 (a parallelogram four-bar): pivots
   !> O0 = (0, 0), O1 = (1, 0), tips T0 = (0, 1), T1 = (1, 1), cranks O0-T0
   !> (driven, pi/2 + 2 pi t) and O1-T1, coupler T0-T1, all of length 1. At
   !> t = 0.25 and 0.75 every bar is horizontal and the tangent loses a rank (a
   !> change point); on the parallelogram Tk = (k + cos q, sin q), q = pi/2 + 2 pi t.
   subroutine parallelogram_model(model, dt)
      type(model_type), intent(out) :: model
      real(dp), intent(in) :: dt
      model%file = 'parallelogram'
      call add_node(model, 'O0', 0.0_dp, 0.0_dp)
      call add_node(model, 'O1', 1.0_dp, 0.0_dp)
      call add_node(model, 'T0', 0.0_dp, 1.0_dp)
      call add_node(model, 'T1', 1.0_dp, 1.0_dp)
      call add_bar_section(model, 1.0_dp)
      call add_link(model, 'crank0', 1, 3, 1)
      call add_link(model, 'crank1', 2, 4, 1)
      call add_link(model, 'coupler0', 3, 4, 1)
      call pin_and_drive(model, [1, 2], dt)
      model%output%points = [3, 4]
      model%output%links = [1, 2, 3]
   end subroutine parallelogram_model

   !> A cantilever R-T of length 1 along +x, clamped at R, meshed with nelem
   !> elements, under an end moment M = t * 2*pi*EI/L at T (EI = 1).
   subroutine cantilever_model(model, nelem, dt)
      type(model_type), intent(out) :: model
      integer, intent(in) :: nelem
      real(dp), intent(in) :: dt
      model%file = 'cantilever'
      call add_node(model, 'R', 0.0_dp, 0.0_dp)
      call add_node(model, 'T', 1.0_dp, 0.0_dp)
      allocate (model%sections(1))
      model%sections(1)%name = 'strip'
      model%sections(1)%ea = 1.0e3_dp
      model%sections(1)%kga = 5.0_dp/6*1.0e3_dp
      model%sections(1)%ei = 1
      call add_link(model, 'RT', 1, 2, nelem)
      allocate (model%supports(1))
      model%supports(1)%node = 1
      model%supports(1)%fix = .true.
      model%supports(1)%link = 1
      allocate (model%loads(1))
      model%loads(1)%node = 2
      model%loads(1)%link = 1
      model%loads(1)%moment = 2*pi
      allocate (model%drives(0), model%welds(0), model%slidelines(0))
      model%analysis%dt = dt
      model%output%points = [2]
      model%output%links = [1]
   end subroutine cantilever_model

   !> Slider-crank: crank O-A of length 1 at the origin (A = (1, 0) at t = 0),
   !> connecting rod A-B of length 3, slider B on a ground guide along the x
   !> axis from x = -5 to x = 5, crank angle 2*pi*t. With `master_link`, the
   !> guide is instead a grounded link G1-G2 meshed with nelem_guide elements.
   subroutine slider_crank_model(model, dt, nelem_guide)
      type(model_type), intent(out) :: model
      real(dp), intent(in) :: dt
      integer, intent(in), optional :: nelem_guide
      model%file = 'slider-crank'
      call add_node(model, 'O', 0.0_dp, 0.0_dp)
      call add_node(model, 'A', 1.0_dp, 0.0_dp)
      call add_node(model, 'B', 4.0_dp, 0.0_dp)
      allocate (model%sections(1))
      model%sections(1)%name = 'bar'
      model%sections(1)%ea = 100
      model%sections(1)%kga = 5.0_dp/6*100
      model%sections(1)%ei = 1
      call add_link(model, 'OA', 1, 2, 1)
      call add_link(model, 'AB', 2, 3, 1)
      allocate (model%slidelines(1))
      model%slidelines(1)%name = 'rail'
      model%slidelines(1)%slave = 3
      model%slidelines(1)%kind = joint_pin_in_slot
      if (present(nelem_guide)) then
         call add_node(model, 'G1', -5.0_dp, 0.0_dp)
         call add_node(model, 'G2', 5.0_dp, 0.0_dp)
         call add_link(model, 'G', 4, 5, nelem_guide)
         model%slidelines(1)%master_links = [3]
         allocate (model%supports(3))
         model%supports(3)%node = 5
         model%supports(3)%fix = [.true., .true., .false.]
      else
         model%slidelines(1)%ground = .true.
         model%slidelines(1)%guide = reshape([-5.0_dp, 0.0_dp, 5.0_dp, 0.0_dp], [2, 2])
         allocate (model%supports(1))
      end if
      model%supports(1)%node = 1
      model%supports(1)%fix = [.true., .true., .false.]
      if (present(nelem_guide)) then
         model%supports(2)%node = 4
         model%supports(2)%fix = [.true., .true., .false.]
      end if
      allocate (model%drives(1))
      model%drives(1)%dof = dof_rot
      model%drives(1)%link = 1
      model%drives(1)%node = 1
      call new_rate_law(model%drives(1)%law, 2*pi)
      allocate (model%welds(0), model%loads(0))
      model%analysis%dt = dt
      model%output%points = [3]
      model%output%links = [1, 2]
   end subroutine slider_crank_model


end module test_mechanisms
