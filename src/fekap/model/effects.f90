!> Which effects a run simulates, chosen from the deck: pure kinematics, or
!> kinetostatics (the drive torques and forces and the joint reactions that
!> the masses and gravity ask for along the computed motion). ANALysis type
!> auto (the default) takes kinetostatics when the deck gives masses and
!> nothing stands in its way, kinematics otherwise; an explicit type that
!> cannot run is a problem the deck reader (and the app, after the command
!> line's overrides) reports. Masses on a mechanism without drives, or with
!> loads or sliding joints, ask for dynamics (auto); statics is not available yet.
module fekap_model_effects
   use fekap_error, only: error_type, input_error
   use fekap_model, only: model_type, method_fem, effects_auto, effects_kinematics, effects_kinetostatics, &
      & effects_statics, effects_dynamics
   implicit none
   private

   public :: effects_plan_type, plan_effects, planned_effects, check_effects_request, has_masses, has_gravity, effects_name

   !> The plan: the effects, why they were chosen, what is left out, and why
   !> an explicit request cannot be met ('' if it can).
   type :: effects_plan_type
      integer :: effects = effects_kinematics
      character(:), allocatable :: why, left_out, problem
   end type effects_plan_type

contains

   !> The effects `model` asks for, and why.
   pure function plan_effects(model) result(plan)
      type(model_type), intent(in) :: model
      type(effects_plan_type) :: plan
      character(:), allocatable :: obstacle
      logical :: masses, gravity
      masses = has_masses(model)
      gravity = has_gravity(model)
      plan%effects = effects_kinematics
      plan%why = ''
      plan%left_out = ''
      plan%problem = ''
      obstacle = kinetostatics_obstacle(model)
      select case (model%analysis%effects)
      case (effects_statics)
         plan%problem = 'ANALysis type statics is not available yet (issue 19)'
         plan%why = 'ANALysis type statics is not available'
      case (effects_dynamics)
         if (.not. masses) then
            plan%problem = 'dynamics needs masses: give rho= (or rhoA=) on SECTions, or a MASSes block'
         else if (model%analysis%method /= method_fem) then
            plan%problem = 'dynamics runs with method fem only'
         else
            plan%effects = effects_dynamics
            plan%why = 'ANALysis type dynamics'
         end if
      case (effects_kinematics)
         plan%why = 'ANALysis type kinematics'
         if (masses .or. gravity) plan%left_out = 'masses and gravity are not used (ANALysis type kinematics)'
      case (effects_kinetostatics)
         if (.not. masses) then
            plan%problem = 'kinetostatics needs masses: give rho= (or rhoA=) on SECTions, or a MASSes block'
         else if (len(obstacle) > 0) then
            plan%problem = 'kinetostatics cannot run: '//obstacle
         else
            plan%effects = effects_kinetostatics
            plan%why = 'ANALysis type kinetostatics'
         end if
      case default
         if (masses .and. model%analysis%method == method_fem .and. len(dynamics_reason(model)) > 0) then
            plan%effects = effects_dynamics
            plan%why = 'auto: masses on '//dynamics_reason(model)
         else if (masses .and. len(obstacle) == 0) then
            plan%effects = effects_kinetostatics
            plan%why = 'auto: masses on a mechanism moved by its drives'
         else if (masses) then
            plan%why = 'auto: masses are given, but '//obstacle
            plan%left_out = 'masses and gravity are left out'
         else
            plan%why = 'auto: no masses'
         end if
      end select
      if (gravity .and. .not. masses) plan%left_out = 'GRAVity does nothing without masses (no rho= or rhoA= on '// &
         & 'SECTions, no MASSes)'
      if (plan%effects == effects_kinetostatics) plan%left_out = 'left out: the elastic deflection''s effect on the '// &
         & 'motion (the motion is the kinematic one), statics under loads, dynamics'
      if (plan%effects == effects_dynamics .and. count_of_slidelines(model) > 0) plan%left_out = &
         & 'left out: the slidelines'' penalty energy in the '// &
         & 'energy balance (its work is in the balance column)'
   end function plan_effects

   !> The effects the plan of `model` simulates (effects_kinematics, ...).
   pure integer function planned_effects(model) result(effects)
      type(model_type), intent(in) :: model
      type(effects_plan_type) :: plan
      plan = plan_effects(model)
      effects = plan%effects
   end function planned_effects

   !> An input error when the ANALysis type asked for cannot run (the deck
   !> reader reports this at the type line; this catches what the command
   !> line's overrides changed, e.g. --method cartesian).
   subroutine check_effects_request(model, error)
      type(model_type), intent(in) :: model
      type(error_type), allocatable, intent(out) :: error
      type(effects_plan_type) :: plan
      plan = plan_effects(model)
      if (len(plan%problem) > 0) call input_error(error, model%file//': '//plan%problem)
   end subroutine check_effects_request

   !> Why the masses of `model` move it by themselves (dynamics), or '': a
   !> mechanism without drives, or one with loads or sliding joints (which
   !> kinetostatics does not take).
   pure function dynamics_reason(model) result(text)
      type(model_type), intent(in) :: model
      character(:), allocatable :: text
      text = ''
      if (count_of_drives(model) == 0) then
         text = 'a mechanism without drives'
      else if (count_of_loads(model) > 0) then
         text = 'a mechanism with LOADs'
      else if (count_of_slidelines(model) > 0) then
         text = 'a mechanism with sliding joints (SLIDelines)'
      end if
   end function dynamics_reason

   pure integer function count_of_drives(model) result(n)
      type(model_type), intent(in) :: model
      n = 0
      if (allocated(model%drives)) n = size(model%drives)
   end function count_of_drives

   !> What keeps the model from kinetostatics, or ''.
   pure function kinetostatics_obstacle(model) result(text)
      type(model_type), intent(in) :: model
      character(:), allocatable :: text
      text = ''
      if (model%analysis%method /= method_fem) then
         text = 'kinetostatics runs with method fem only'
      else if (.not. (model%analysis%velocities .and. model%analysis%accelerations)) then
         text = 'kinetostatics needs the accelerations (compute ... accelerations)'
      else if (count_of_loads(model) > 0) then
         text = 'masses with LOADs ask for dynamics'
      else if (count_of_slidelines(model) > 0) then
         text = 'sliding joints (SLIDelines) are not in kinetostatics yet'
      end if
   end function kinetostatics_obstacle

   pure integer function count_of_loads(model) result(n)
      type(model_type), intent(in) :: model
      n = 0
      if (allocated(model%loads)) n = size(model%loads)
   end function count_of_loads

   pure integer function count_of_slidelines(model) result(n)
      type(model_type), intent(in) :: model
      n = 0
      if (allocated(model%slidelines)) n = size(model%slidelines)
   end function count_of_slidelines

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
