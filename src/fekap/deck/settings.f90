!> Reading the cards that set up the run rather than the mechanism: TITLe,
!> ANALysis and OUTPut. A setting given twice takes the later value (a deck may
!> INCLude a base deck and then override it).
module fekap_deck_settings
   use fekap_kinds, only: dp
   use fekap_model, only: model_type, method_names, predictor_names, method_fem, method_cartesian, method_angles, &
      & predictor_previous, &
      & predictor_extrapolate, predictor_taylor, convergence_paper, convergence_default, &
      & solver_band, solver_dense, effects_auto, effects_kinematics, effects_kinetostatics, effects_statics, &
      & effects_dynamics, integrator_names, integrator_generalized_alpha, default_rho_inf, &
      & integrator_energy_momentum
   use fekap_deck_card, only: is_word_of
   use fekap_strings, only: lower, word_index
   use fekap_deck_context, only: context_type
   use fekap_deck_geometry, only: lookup_node, lookup_link
   use fekap_deck_safe_arithmetic, only: safe_add
   implicit none
   private

   public :: read_title, read_analysis, read_output

   !> Largest start or end time: the drive laws' values stay far from overflow
   !> (and keep their precision) below it.
   real(dp), parameter :: max_time = 1.0e9_dp

   !> Most time steps of one run.
   real(dp), parameter :: max_steps = 1.0e7_dp

contains

   !> TITLe: the rest of the line (up to a `!` comment) is the title.
   subroutine read_title(ctx, model, lines)
      type(context_type), intent(inout) :: ctx
      type(model_type), intent(inout) :: model
      !> The TITLe card lines themselves.
      integer, intent(in) :: lines(:)
      integer :: i, first
      first = 0
      do i = 1, size(lines)
         associate (line => ctx%source%lines(lines(i)))
            if (first > 0) then
               call ctx%error_at(ctx%loc(lines(i), 1), 'the title is given twice', label='keep one TITLe card', &
                  & note_loc=ctx%loc(first, 1), note='first given here')
               cycle
            end if
            first = lines(i)
            model%title = trim(adjustl(line%code(line%tokens(1)%col + len(line%tokens(1)%text):)))
         end associate
      end do
   end subroutine read_title

   !> ANALysis: `method`, `time`, `compute`, `tolerance`, `length`, `iterations`,
   !> `predictor`, `convergence`, `gauss`, `redundant`, `solver`, `type`, `integrator` lines; then the time
   !> span is checked.
   subroutine read_analysis(ctx, model, lines)
      type(context_type), intent(inout) :: ctx
      type(model_type), intent(inout) :: model
      integer, intent(in) :: lines(:)
      character(*), parameter :: keys = 'method time compute tolerance length iterations predictor convergence '// &
         & 'gauss redundant solver type integrator start'
      integer :: i, iline, k, time_line, ivalue
      real(dp) :: t(3), span, v
      logical :: ok, fine
      character(:), allocatable :: key
      time_line = 0
      do i = 1, size(lines)
         iline = lines(i)
         key = lower(ctx%field(iline, 1))
         if (is_word_of(key, 'method', 4)) then
            if (.not. one_value('method fem|cartesian|angles')) cycle
            model%analysis%method = chosen(method_names, [method_fem, method_cartesian, method_angles], &
               & model%analysis%method)
         else if (is_word_of(key, 'time', 4)) then
            if (.not. ctx%require(iline, 'time START END STEP [adaptive TOL]', 'a time line')) cycle
            if (extra(7, 'time START END STEP [adaptive TOL]')) cycle
            ok = .true.
            do k = 1, 3
               call ctx%real_field(iline, k + 1, t(k), fine)
               ok = ok .and. fine
            end do
            if (.not. ok) cycle
            ! time START END STEP adaptive TOL: dynamics' steps adapt to keep
            ! each step's local error estimate below TOL (docs/dynamics.md).
            if (ctx%nfields(iline) >= 5) then
               if (.not. adaptive_tolerance(v)) cycle
               model%analysis%adaptive = .true.
               model%analysis%adaptive_tol = v
               model%analysis%adaptive_loc = ctx%loc(iline, 5)
            else
               model%analysis%adaptive = .false.
            end if
            model%analysis%t_start = t(1)
            model%analysis%t_end = t(2)
            model%analysis%dt = t(3)
            time_line = iline
         else if (is_word_of(key, 'compute', 4)) then
            if (.not. ctx%require(iline, 'compute WHAT [WHAT ...]', 'a compute line')) cycle
            model%analysis%velocities = .false.
            model%analysis%accelerations = .false.
            do k = 2, ctx%nfields(iline)
               select case (choice(k, 'positions velocities accelerations'))
               case (2)
                  model%analysis%velocities = .true.
               case (3)
                  ! Accelerations need the velocities.
                  model%analysis%velocities = .true.
                  model%analysis%accelerations = .true.
               end select
            end do
         else if (is_word_of(key, 'tolerance', 3)) then
            if (fraction('tolerance VALUE', 'the tolerance', 'e.g. tolerance 1e-10', v)) model%analysis%tol = v
         else if (is_word_of(key, 'length', 4)) then
            if (fraction('length VALUE', 'the length tolerance', 'relative to the model size, e.g. length 1e-12', v)) then
               model%analysis%length_tol = v
            end if
         else if (is_word_of(key, 'iterations', 4)) then
            if (.not. one_value('iterations N')) cycle
            call ctx%integer_field(iline, 2, ivalue, ok)
            if (.not. ok) cycle
            if (ivalue < 1) then
               call ctx%error(iline, 2, 'the number of iterations must be at least 1', label='e.g. iterations 25')
               cycle
            end if
            model%analysis%max_iter = ivalue
         else if (is_word_of(key, 'predictor', 4)) then
            if (.not. one_value('predictor previous|extrapolate|taylor')) cycle
            model%analysis%predictor = chosen(predictor_names, [predictor_previous, predictor_extrapolate, &
               & predictor_taylor], model%analysis%predictor)
         else if (is_word_of(key, 'convergence', 4)) then
            if (.not. one_value('convergence default|paper')) cycle
            model%analysis%convergence = chosen('default paper', [convergence_default, convergence_paper], &
               & model%analysis%convergence)
         else if (is_word_of(key, 'gauss', 4)) then
            if (.not. one_value('gauss 1|2')) cycle
            call ctx%integer_field(iline, 2, ivalue, ok)
            if (.not. ok) cycle
            if (ivalue /= 1 .and. ivalue /= 2) then
               call ctx%error(iline, 2, 'gauss takes 1 or 2 points', label='1 (reduced, default) or 2 (full)')
               cycle
            end if
            model%analysis%gauss_points = ivalue
         else if (is_word_of(key, 'redundant', 4)) then
            if (.not. one_value('redundant stop|remove')) cycle
            model%analysis%remove_redundant = chosen('stop remove', [0, 1], &
               & merge(1, 0, model%analysis%remove_redundant)) == 1
         else if (is_word_of(key, 'solver', 4)) then
            if (.not. one_value('solver band|dense')) cycle
            model%analysis%solver = chosen('band dense', [solver_band, solver_dense], model%analysis%solver)
         else if (is_word_of(key, 'type', 4)) then
            ! Whether the type can run is checked against the whole deck (check_effects).
            ! A third field `spatial` (or `planar`) says what kind of mechanism the deck holds.
            if (.not. ctx%require(iline, 'type auto|kinematics|kinetostatics|statics|dynamics [spatial|planar]', &
               & 'the line')) cycle
            if (extra(4, 'type auto|kinematics|kinetostatics|statics|dynamics [spatial|planar]')) cycle
            model%analysis%effects = chosen('auto kinematics kinetostatics statics dynamics', [effects_auto, &
               & effects_kinematics, effects_kinetostatics, effects_statics, effects_dynamics], model%analysis%effects)
            if (ctx%nfields(iline) == 3) then
               select case (choice(3, 'spatial planar'))
               case (1)
                  model%analysis%spatial = .true.
                  if (all(model%analysis%effects /= [effects_auto, effects_kinematics])) then
                     call ctx%error(iline, 2, 'a spatial deck runs kinematics only', &
                        & label='spatial kinetostatics, statics and dynamics are not there yet: type kinematics spatial')
                  end if
               case (2)
                  model%analysis%spatial = .false.
               end select
            end if
         else if (is_word_of(key, 'start', 4)) then
            ! start consistent|unstrained: dynamics' start state (docs/dynamics.md).
            if (.not. one_value('start consistent|unstrained')) cycle
            model%analysis%start_unstrained = chosen('consistent unstrained', [0, 1], &
               & merge(1, 0, model%analysis%start_unstrained)) == 1
         else if (is_word_of(key, 'integrator', 4)) then
            ! integrator generalized-alpha [RHO_INF]: Chung-Hulbert with rho_inf in [0, 1] (default 0.8);
            ! integrator energy-momentum [RHO_INF]: the midpoint rule with the discrete gradient,
            ! rho_inf in [0, 1] mapped to its dissipation (default 1: conserving).
            if (.not. ctx%require(iline, 'integrator generalized-alpha|energy-momentum [RHO_INF]', &
               & 'an integrator line')) cycle
            if (extra(4, 'integrator generalized-alpha|energy-momentum [RHO_INF]')) cycle
            select case (choice(2, integrator_names))
            case (1)
               model%analysis%integrator = integrator_generalized_alpha
            case (2)
               model%analysis%integrator = integrator_energy_momentum
               model%analysis%integrator_loc = ctx%loc(iline, 2)
            case default
               cycle
            end select
            ! A later integrator line replaces an earlier one, rho_inf included.
            model%analysis%rho_inf = default_rho_inf(model%analysis%integrator)
            if (ctx%nfields(iline) < 3) cycle
            call ctx%real_field(iline, 3, v, ok)
            if (.not. ok) cycle
            if (v < 0 .or. v > 1) then
               call ctx%error(iline, 3, 'rho_inf of '//ctx%field(iline, 2)//' must lie in [0, 1]', &
                  & label='the spectral radius at infinite frequency: 1 no numerical damping (trapezoidal rule, '// &
                  & 'energy-momentum: conserving), 0 the most; default 0.8 (energy-momentum: 1)')
               cycle
            end if
            model%analysis%rho_inf = v
         else
            call ctx%error(iline, 1, "unknown ANALysis parameter '"//ctx%field(iline, 1)//"'", label='allowed: '//keys)
         end if
      end do
      if (time_line > 0) call check_time(time_line)

   contains

      !> The line is `key VALUE`.
      logical function one_value(form)
         character(*), intent(in) :: form
         one_value = ctx%require(iline, form, 'the line')
         if (one_value) one_value = .not. extra(3, form)
      end function one_value

      logical function extra(itok, form)
         integer, intent(in) :: itok
         character(*), intent(in) :: form
         extra = ctx%nfields(iline) >= itok
         if (extra) call ctx%error(iline, itok, "unexpected field '"//ctx%field(iline, itok)//"'", &
            & label='the line is: '//form)
      end function extra

      !> Which of the blank-separated words field itok is (0 after reporting none).
      integer function choice(itok, words)
         integer, intent(in) :: itok
         character(*), intent(in) :: words
         choice = word_index(ctx%field(iline, itok), words)
         if (choice == 0) call ctx%error(iline, itok, "unknown value '"//ctx%field(iline, itok)//"' of "// &
            & ctx%field(iline, 1), label='allowed: '//words)
      end function choice

      !> The setting that the line's value (field 2) names among `words`:
      !> values(k) for the k-th word, or `current` after reporting none.
      integer function chosen(words, values, current)
         character(*), intent(in) :: words
         integer, intent(in) :: values(:), current
         integer :: k
         k = choice(2, words)
         chosen = current
         if (k > 0) chosen = values(k)
      end function chosen

      !> The time line's `adaptive TOL` (fields 5 and 6) with TOL > 0, in v.
      logical function adaptive_tolerance(v) result(ok)
         real(dp), intent(out) :: v
         character(*), parameter :: label = 'time START END STEP adaptive TOL, e.g. adaptive 1e-6 (a length)'
         v = 0
         ok = is_word_of(lower(ctx%field(iline, 5)), 'adaptive', 4)
         if (.not. ok) then
            call ctx%error(iline, 5, "unknown value '"//ctx%field(iline, 5)//"' after the time step", label=label)
            return
         end if
         ok = ctx%nfields(iline) >= 6
         if (.not. ok) then
            call ctx%error(iline, 5, 'adaptive steps need a tolerance', label=label)
            return
         end if
         call ctx%real_field(iline, 6, v, ok)
         if (.not. ok) return
         ok = v > 0 .and. v <= huge(v)
         if (.not. ok) call ctx%error(iline, 6, 'the adaptive tolerance must be positive', label=label)
      end function adaptive_tolerance

      !> The line is `key VALUE` with a real VALUE strictly between 0 and 1
      !> (else an error saying that `what` must be).
      logical function fraction(form, what, label, v) result(ok)
         character(*), intent(in) :: form, what, label
         real(dp), intent(out) :: v
         v = 0
         ok = one_value(form)
         if (.not. ok) return
         call ctx%real_field(iline, 2, v, ok)
         if (.not. ok) return
         ok = .not. (v <= 0 .or. v >= 1)
         if (.not. ok) call ctx%error(iline, 2, what//' must be between 0 and 1', label=label)
      end function fraction

      subroutine check_time(iline_)
         integer, intent(in) :: iline_
         associate (a => model%analysis)
            if (a%dt <= 0) then
               call ctx%error(iline_, 4, 'the time step must be positive', label='time START END STEP with STEP > 0')
            end if
            if (a%t_end <= a%t_start) then
               call ctx%error(iline_, 3, 'the end time must be after the start time', &
                  & label='time START END STEP with END > START')
            end if
            ! Drive values of times like 1e300 overflow in the tangent's products.
            if (abs(a%t_start) > max_time) then
               call ctx%error(iline_, 2, 'the start time is beyond 1e9', label='times from -1e9 to 1e9')
               return
            end if
            if (abs(a%t_end) > max_time) then
               call ctx%error(iline_, 3, 'the end time is beyond 1e9', label='times from -1e9 to 1e9')
               return
            end if
            if (a%dt <= 0 .or. a%t_end <= a%t_start) return
            call safe_add(a%t_end, -a%t_start, span, fine)
            if (.not. fine .or. span/max_steps > a%dt) then
               call ctx%error(iline_, 4, 'more than 10,000,000 time steps', label='take a larger step')
            end if
         end associate
      end subroutine check_time

   end subroutine read_analysis

   !> OUTPut: `track NODE ...`, `angles LINK ...`, `every K`, `files csv|points|listing|vtk ...`,
   !> `units length=NAME time=NAME`, `deflection on|off`, `mesh on|off`.
   !> Without track every node is tracked; without angles every link is reported.
   subroutine read_output(ctx, model, lines)
      type(context_type), intent(inout) :: ctx
      type(model_type), intent(inout) :: model
      integer, intent(in) :: lines(:)
      character(*), parameter :: keys = 'track angles every files units deflection mesh'
      integer :: i, iline, k, idx, every, which
      logical :: ok, tracked, angled
      character(:), allocatable :: key
      integer, allocatable :: points(:), links(:)
      tracked = .false.
      angled = .false.
      allocate (points(0), links(0))
      do i = 1, size(lines)
         iline = lines(i)
         key = lower(ctx%field(iline, 1))
         if (is_word_of(key, 'track', 4)) then
            if (.not. ctx%require(iline, 'track NODE [NODE ...]', 'a track line')) cycle
            tracked = .true.
            do k = 2, ctx%nfields(iline)
               idx = lookup_node(ctx, iline, k)
               if (idx > 0 .and. .not. any(points == idx)) then
                  points = [points, idx]
               end if
            end do
         else if (is_word_of(key, 'angles', 4)) then
            if (.not. ctx%require(iline, 'angles LINK [LINK ...]', 'an angles line')) cycle
            angled = .true.
            do k = 2, ctx%nfields(iline)
               idx = lookup_link(ctx, iline, k)
               if (idx > 0 .and. .not. any(links == idx)) then
                  links = [links, idx]
               end if
            end do
         else if (is_word_of(key, 'every', 4)) then
            if (.not. ctx%require(iline, 'every K', 'an every line')) cycle
            if (ctx%nfields(iline) > 2) then
               call ctx%error(iline, 3, "unexpected field '"//ctx%field(iline, 3)//"'", label='the line is: every K')
               cycle
            end if
            call ctx%integer_field(iline, 2, every, ok)
            if (.not. ok) cycle
            if (every < 1) then
               call ctx%error(iline, 2, 'every needs a positive whole number', label='every 1 writes every step')
               cycle
            end if
            model%output%every = every
         else if (is_word_of(key, 'files', 4)) then
            if (.not. ctx%require(iline, 'files csv|points|listing|vtk [...]', 'a files line')) cycle
            model%output%csv = .false.
            model%output%listing = .false.
            model%output%vtk = .false.
            model%output%points_csv = .false.
            do k = 2, ctx%nfields(iline)
               which = word_index(ctx%field(iline, k), 'csv listing vtk points')
               select case (which)
               case (1)
                  model%output%csv = .true.
               case (2)
                  model%output%listing = .true.
               case (3)
                  model%output%vtk = .true.
               case (4)
                  model%output%points_csv = .true.
               case default
                  call ctx%error(iline, k, "unknown output file kind '"//ctx%field(iline, k)//"'", &
                     & label='allowed: csv points listing vtk')
               end select
            end do
         else if (is_word_of(key, 'deflection', 4)) then
            if (.not. ctx%require(iline, 'deflection on|off', 'a deflection line')) cycle
            if (ctx%nfields(iline) > 2) then
               call ctx%error(iline, 3, "unexpected field '"//ctx%field(iline, 3)//"'", &
                  & label='the line is: deflection on|off')
               cycle
            end if
            select case (word_index(ctx%field(iline, 2), 'on off'))
            case (1)
               model%output%deflection = .true.
            case (2)
               model%output%deflection = .false.
            case default
               call ctx%error(iline, 2, "expected on or off, not '"//ctx%field(iline, 2)//"'", &
                  & label='deflection on writes deflection.csv (kinetostatics)')
            end select
         else if (is_word_of(key, 'mesh', 4)) then
            if (.not. ctx%require(iline, 'mesh on|off', 'a mesh line')) cycle
            if (ctx%nfields(iline) > 2) then
               call ctx%error(iline, 3, "unexpected field '"//ctx%field(iline, 3)//"'", &
                  & label='the line is: mesh on|off')
               cycle
            end if
            select case (word_index(ctx%field(iline, 2), 'on off'))
            case (1)
               model%output%mesh_nodes = .true.
               model%output%mesh_nodes_given = .true.
            case (2)
               model%output%mesh_nodes = .false.
               model%output%mesh_nodes_given = .true.
            case default
               call ctx%error(iline, 2, "expected on or off, not '"//ctx%field(iline, 2)//"'", &
                  & label='mesh on writes every mesh point to nodes.csv')
            end select
         else if (is_word_of(key, 'units', 4)) then
            if (.not. ctx%require(iline, 'units length=NAME [time=NAME]', 'a units line')) cycle
            model%output%units_given = .true.
            do k = 2, ctx%nfields(iline)
               call read_unit(ctx, iline, k, model)
            end do
         else
            call ctx%error(iline, 1, "unknown OUTPut parameter '"//ctx%field(iline, 1)//"'", label='allowed: '//keys)
         end if
      end do
      if (.not. tracked) points = [(k, k=1, size(model%nodes))]
      if (.not. angled) links = [(k, k=1, size(model%links))]
      model%output%points = points
      model%output%links = links
   end subroutine read_output

   !> One `length=NAME` or `time=NAME` field of a units line: the name of the
   !> unit in which the deck's numbers are given, for the plots' labels.
   subroutine read_unit(ctx, iline, k, model)
      type(context_type), intent(inout) :: ctx
      integer, intent(in) :: iline, k
      type(model_type), intent(inout) :: model
      character(:), allocatable :: field, name
      integer :: eq, i
      field = ctx%field(iline, k)
      eq = index(field, '=')
      if (eq == 0) then
         call ctx%error(iline, k, "expected length=NAME or time=NAME, not '"//field//"'", &
            & label='e.g. units length=mm time=s')
         return
      end if
      name = field(eq + 1:)
      if (len(name) == 0 .or. len(name) > len(model%output%length_unit)) then
         call ctx%error(iline, k, 'a unit name of 1 to 16 characters is needed after =', label='e.g. length=mm')
         return
      end if
      do i = 1, len(name)
         if (index(',"', name(i:i)) > 0) then
            call ctx%error(iline, k, 'a unit name cannot hold a comma or a double quote', label='e.g. length=mm')
            return
         end if
      end do
      select case (word_index(field(:eq - 1), 'length time'))
      case (1)
         model%output%length_unit = name
      case (2)
         model%output%time_unit = name
      case default
         call ctx%error(iline, k, "unknown unit '"//field(:eq - 1)//"'", label='allowed: length time')
      end select
   end subroutine read_unit

end module fekap_deck_settings
