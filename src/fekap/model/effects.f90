!> Which effects a run simulates, chosen from the deck: pure kinematics,
!> kinetostatics (the drive torques and forces and the joint reactions that
!> the masses and gravity ask for along the computed motion), statics
!> (equilibrium under loads) or dynamics. ANALysis type auto (the default)
!> decides from the deck (docs/dynamics.md):
!>
!> - no masses and no loads: kinematics;
!> - loads without masses: statics;
!> - masses on a fully driven mechanism (drives, and a mobility count of 0
!>   or less: the drives leave no free motion): kinetostatics;
!> - masses on an under-driven scene (a positive mobility count) or a
!>   flexible one (no drives): dynamics.
!>
!> An effect that cannot run (another method, no accelerations, ...) leaves
!> auto at kinematics, and the plan says why and what is left out; an
!> explicit type that cannot run is a problem the deck reader (and the app,
!> after the command line's overrides) reports.
module fekap_model_effects
   use fekap_error, only: error_type, input_error
   use fekap_model, only: model_type, method_fem, effects_auto, effects_kinematics, effects_kinetostatics, &
      & effects_statics, effects_dynamics, joint_prismatic, integrator_energy_momentum
   use fekap_strings, only: int_text
   use fekap_model_loads, only: load_count
   implicit none
   private

   public :: effects_plan_type, plan_effects, planned_effects, check_effects_request, has_masses, has_gravity, effects_name
   public :: mobility, integrator_obstacle

   !> The plan: the effects, why they were chosen, what is left out, and why
   !> an explicit request cannot be met ('' if it can).
   type :: effects_plan_type
      integer :: effects = effects_kinematics
      character(:), allocatable :: why, left_out, problem
   end type effects_plan_type

contains

   !> The plan of the analysis type a deck asks for (effects): it runs, or
   !> the obstacle (if not '') is the plan's problem.
   pure subroutine plan_asked(plan, effects, obstacle)
      type(effects_plan_type), intent(inout) :: plan
      integer, intent(in) :: effects
      character(*), intent(in) :: obstacle
      if (len(obstacle) > 0) then
         plan%problem = effects_name(effects)//' cannot run: '//obstacle
      else
         plan%effects = effects
         plan%why = 'ANALysis type '//effects_name(effects)
      end if
   end subroutine plan_asked

   !> The effects `model` asks for, and why.
   pure function plan_effects(model) result(plan)
      type(model_type), intent(in) :: model
      type(effects_plan_type) :: plan
      logical :: masses, gravity, loads, driven
      integer :: m
      masses = has_masses(model)
      gravity = has_gravity(model)
      loads = load_count(model) > 0
      driven = count_of_drives(model) > 0
      m = mobility(model)
      plan%effects = effects_kinematics
      plan%why = ''
      plan%left_out = ''
      plan%problem = ''
      select case (model%analysis%effects)
      case (effects_kinematics)
         plan%why = 'ANALysis type kinematics'
         if (masses .or. gravity) plan%left_out = 'masses and gravity are not used (ANALysis type kinematics)'
         if (loads) plan%problem = 'LOADs ask for statics (the finite element method always takes them): '// &
            & 'ANALysis type statics or auto'
      case (effects_kinetostatics)
         if (.not. masses) then
            plan%problem = 'kinetostatics needs masses: give rho= (or rhoA=) on SECTions, or a MASSes block'
         else
            call plan_asked(plan, effects_kinetostatics, kinetostatics_obstacle(model))
         end if
      case (effects_statics)
         call plan_asked(plan, effects_statics, statics_obstacle(model))
      case (effects_dynamics)
         call plan_asked(plan, effects_dynamics, dynamics_obstacle(model))
      case default
         call plan_auto(model, masses, gravity, loads, driven, m, plan)
      end select
      if (gravity .and. .not. masses) plan%left_out = 'GRAVity does nothing without masses (no rho= or rhoA= on '// &
         & 'SECTions, no MASSes)'
      select case (plan%effects)
      case (effects_kinetostatics)
         plan%left_out = 'left out: the elastic deflection''s effect on the motion (the motion is the kinematic '// &
            & 'one), statics under loads, dynamics'
      case (effects_statics)
         if (masses) then
            plan%left_out = 'left out: inertia (statics: the masses act through their weight only), dynamics'
         else if (gravity) then
            plan%left_out = plan%left_out//'; left out: inertia and dynamics (there are no masses)'
         else
            plan%left_out = 'left out: inertia and dynamics (there are no masses)'
         end if
      case default
         continue
      end select
      if (model%output%deflection .and. plan%effects /= effects_kinetostatics) then
         if (len(plan%left_out) > 0) plan%left_out = plan%left_out//'; '
         plan%left_out = plan%left_out//'OUTPut deflection: not written (only kinetostatics computes the '// &
            & 'elastic deflection)'
      end if

   end function plan_effects

   !> ANALysis type auto: the rule of this module's header.
   pure subroutine plan_auto(model, masses, gravity, loads, driven, m, plan)
      type(model_type), intent(in) :: model
      logical, intent(in) :: masses, gravity, loads, driven
      !> The mobility count.
      integer, intent(in) :: m
      type(effects_plan_type), intent(inout) :: plan
      character(:), allocatable :: scene, obstacle
      if (.not. masses .and. .not. loads) then
         plan%why = 'auto: no masses, no loads'
         if (gravity) plan%why = 'auto: no masses'
         return
      end if
      if (.not. masses) then
         obstacle = statics_obstacle(model)
         if (len(obstacle) == 0) then
            plan%effects = effects_statics
            plan%why = 'auto: loads without masses'
         else
            plan%why = 'auto: loads are given, but '//obstacle
            plan%left_out = 'the loads are left out'
         end if
         return
      end if
      if (driven .and. m <= 0) then
         obstacle = kinetostatics_obstacle(model)
         if (len(obstacle) == 0) then
            plan%effects = effects_kinetostatics
            plan%why = 'auto: masses on a mechanism moved by its drives'
         else
            plan%why = 'auto: masses are given, but '//obstacle
            plan%left_out = 'masses and gravity are left out'
         end if
         return
      end if
      if (driven) then
         scene = 'masses on an under-driven mechanism (mobility '//int_text(m)//' with its drives held)'
      else
         scene = 'masses on a flexible scene without drives'
      end if
      obstacle = dynamics_obstacle(model)
      if (len(obstacle) == 0) then
         plan%effects = effects_dynamics
         plan%why = 'auto: '//scene
      else
         ! Auto does not fall back to another analysis of a moving scene: it says what to write.
         plan%why = 'auto: '//scene//' asks for dynamics'
         plan%problem = scene//' ask for dynamics, which cannot run: '//obstacle// &
            & '; ANALysis type statics (weights and loads only) or kinematics runs without inertia'
      end if
   end subroutine plan_auto

   !> The effects the plan of `model` simulates (effects_kinematics, ...).
   pure integer function planned_effects(model) result(effects)
      type(model_type), intent(in) :: model
      type(effects_plan_type) :: plan
      plan = plan_effects(model)
      effects = plan%effects
   end function planned_effects

   !> An input error when the ANALysis type asked for cannot run (the deck
   !> reader reports this at the type line; this catches what the command
   !> line's overrides changed, e.g. --method cartesian, and auto's plans).
   subroutine check_effects_request(model, error)
      type(model_type), intent(in) :: model
      type(error_type), allocatable, intent(out) :: error
      type(effects_plan_type) :: plan
      plan = plan_effects(model)
      if (len(plan%problem) > 0) call input_error(error, model%file//': '//plan%problem)
   end subroutine check_effects_request

   !> What keeps the model from kinetostatics, or ''.
   pure function kinetostatics_obstacle(model) result(text)
      type(model_type), intent(in) :: model
      character(:), allocatable :: text
      text = ''
      if (model%analysis%method /= method_fem) then
         text = 'kinetostatics runs with method fem only'
      else if (.not. (model%analysis%velocities .and. model%analysis%accelerations)) then
         text = 'kinetostatics needs the accelerations (compute ... accelerations)'
      else if (count_of_drives(model) == 0) then
         text = 'kinetostatics needs drives (DRIVes) that move the mechanism'
      end if
   end function kinetostatics_obstacle

   !> What keeps the model from statics, or ''.
   pure function statics_obstacle(model) result(text)
      type(model_type), intent(in) :: model
      character(:), allocatable :: text
      text = ''
      if (model%analysis%method /= method_fem) then
         text = 'statics runs with method fem only'
      else if (load_count(model) == 0 .and. .not. (has_masses(model) .and. has_gravity(model))) then
         text = 'statics needs loads: LOADs, or masses under GRAVity'
      end if
   end function statics_obstacle

   !> What keeps the model from dynamics, or ''.
   pure function dynamics_obstacle(model) result(text)
      type(model_type), intent(in) :: model
      character(:), allocatable :: text
      text = ''
      if (.not. has_masses(model)) then
         text = 'dynamics needs masses: give rho= (or rhoA=) on SECTions, or a MASSes block'
      else if (model%analysis%method /= method_fem) then
         text = 'dynamics runs with method fem only'
      else
         text = integrator_obstacle(model)
      end if
   end function dynamics_obstacle

   !> What the dynamics integrator asked for does not cover in `model`, or
   !> '': slidelines' penalty forces have no discrete gradient (yet).
   pure function integrator_obstacle(model) result(text)
      type(model_type), intent(in) :: model
      character(:), allocatable :: text
      text = ''
      if (model%analysis%integrator /= integrator_energy_momentum) return
      if (allocated(model%slidelines)) then
         if (size(model%slidelines) > 0) text = 'the energy-momentum integrator does not cover SLIDelines '// &
            & '(use integrator generalized-alpha)'
      end if
   end function integrator_obstacle

   !> The mobility count (Gruebler-Kutzbach) of the scene with its supports
   !> and drives held: the free degrees of freedom at the nodes (two
   !> translations and one rotation per rigid group of link ends, less the
   !> supported and driven ones), less three per link (a link meshed with
   !> several elements adds as many dofs as constraints), less one per
   !> pin-in-slot and two per prismatic slideline. Positive: the drives leave
   !> a free motion (under-driven; special geometry can only add to it); 0 or
   !> less: the drives move the mechanism, or it is a structure.
   pure integer function mobility(model) result(m)
      type(model_type), intent(in) :: model
      integer :: n, l, i
      integer, allocatable :: ends(:)
      m = 0
      if (.not. allocated(model%nodes) .or. .not. allocated(model%links)) return
      ! Link ends per node, in one pass over the links (a search per node is quadratic).
      allocate (ends(size(model%nodes)), source=0)
      do l = 1, size(model%links)
         do i = 1, 2
            n = model%links(l)%node(i)
            if (n >= 1 .and. n <= size(ends)) ends(n) = ends(n) + 1
         end do
      end do
      m = sum(2 + ends, mask=ends > 0)
      if (allocated(model%welds)) then
         do i = 1, size(model%welds)
            m = m - (size(model%welds(i)%links) - 1)
         end do
      end if
      if (allocated(model%supports)) then
         do i = 1, size(model%supports)
            m = m - count(model%supports(i)%fix)
         end do
      end if
      if (allocated(model%drives)) m = m - size(model%drives)
      m = m - 3*size(model%links)
      if (allocated(model%slidelines)) then
         do i = 1, size(model%slidelines)
            m = m - merge(2, 1, model%slidelines(i)%kind == joint_prismatic)
         end do
      end if
   end function mobility

   pure integer function count_of_drives(model) result(n)
      type(model_type), intent(in) :: model
      n = 0
      if (allocated(model%drives)) n = size(model%drives)
   end function count_of_drives

   !> Whether some link has a section with mass or some node a point mass or rotary inertia.
   pure logical function has_masses(model)
      type(model_type), intent(in) :: model
      integer :: l, s
      has_masses = .false.
      if (allocated(model%masses)) has_masses = any(model%masses%mass > 0 .or. model%masses%inertia > 0)
      if (has_masses .or. .not. allocated(model%links) .or. .not. allocated(model%sections)) return
      do l = 1, size(model%links)
         s = model%links(l)%section
         if (s < 1 .or. s > size(model%sections)) cycle
         if (model%sections(s)%rho_a > 0) has_masses = .true.
      end do
   end function has_masses

   pure logical function has_gravity(model)
      type(model_type), intent(in) :: model
      has_gravity = any(model%gravity /= 0)
   end function has_gravity

   !> The ANALysis type word of an effects constant.
   pure function effects_name(effects) result(name)
      integer, intent(in) :: effects
      character(:), allocatable :: name
      select case (effects)
      case (effects_auto)
         name = 'auto'
      case (effects_kinematics)
         name = 'kinematics'
      case (effects_kinetostatics)
         name = 'kinetostatics'
      case (effects_statics)
         name = 'statics'
      case default
         name = 'dynamics'
      end select
   end function effects_name

end module fekap_model_effects
