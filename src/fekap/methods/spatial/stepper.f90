!> The time stepper of a spatial deck's kinematics (fekap_spatial_kinematics
!> driven by the time loop): each step predicts the new configuration by
!> a Taylor series along the last rates, q (+) (h v + h^2/2 a + h^3/6 j +
!> h^4/24 k), j and k the third and fourth rates of the motion at the last
!> configuration (see curve_rates), then runs
!> Newton-Raphson on the free dofs with the material tangent (exact at the
!> stress-free solution): the one Newton driver (newton_solve) on
!> fekap_spatial_newton's system under its contract. Every Newton iteration
!> assembles and factors the tangent at its iterate; the iteration whose
!> correction is below the length tolerance (lengths relative to the
!> longest element), and below rate_tol, ends Newton: its factored tangent,
!> at the converged configuration, gives the velocities and accelerations
!> (Eischen, Sun & Marler eqs. (47)-(53)), and its correction is applied
!> without a further assembly. A step's iterations count the corrections that needed another
!> assembly and factorisation after them, as the planar method counts its
!> check "with the tangent factored at the converged configuration" as no
!> iteration. A step whose Newton fails, or whose configuration the
!> branch-jump check rejects (a joint angle or a free frame turned by more
!> than jump_ratio times what the drive increment explains:
!> fekap_spatial_change_point's rotation_jump, the planar FEM's magnitude
!> rule; a hinge passing through collinear against the responses: its
!> hinge_check, the planar orientation rule), is cut in halves; a step in
!> which a hinge crosses collinear with a large turn is verified by two
!> half steps (verify_step, the planar step doubling). A run's step whose predictor's tangent is near
!> singular against the run's best (a change point: the planar FEM's
!> detection, fekap_stepping_change_point) is stepped over: the next output
!> time is solved from the last regular state as one double step, kept for
!> the next advance, and the row at the change point is filled from both
!> sides (fill_state) and corrected onto the mechanism (correct_state); at a
!> singular configuration its rates are left out (docs/hard-cases.md, 3b).
!> The module is over 600 lines because the step loop, the step over a
!> change point and the predictor's rates all change the stepper's accepted
!> state, which stays private to it; the checks that need none of it are
!> fekap_spatial_change_point's.
module fekap_spatial_stepper
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, analysis_error, input_error
   use fekap_model, only: model_type
   use fekap_model_results, only: step_result_type, note_length
   use fekap_stepping_stepper, only: stepper_type
   use fekap_stepping_change_point, only: change_verdict, change_regular, response_trusted, next_output_time, &
      & fill_order, fill_shift, rates_drop, change_drop
   use fekap_stepping_jump, only: jump_ratio, verify_turn, max_verify_depth
   use fekap_spatial_mechanism, only: spatial_mechanism_type, passes_a_segment_end
   use fekap_spatial_kinematics, only: spatial_state_type, new_spatial_state, spatial_configuration_type, &
      & configure, assemble_spatial, set_drives, update_state, free_dofs, spatial_rates_factored, point_rate, &
      & spatial_rates, tangent_for, free_part, largest_strain
   use fekap_spatial_tangent, only: spatial_tangent_type
   use fekap_spatial_change_point, only: drive_response, rotation_jump, fill_state, correct_state, shortest_element, &
      & spatial_hinge_type, find_hinges, hinge_check, state_distance, predicted_step
   use fekap_spatial_build, only: spatial_map_type, build_spatial_mechanism
   use fekap_spatial_link_motion, only: link_motion_type, new_link_motion, fill_link_motion
   use fekap_spatial_newton, only: spatial_newton_type, spatial_contract, spatial_force_scale
   use fekap_stepping_newton, only: admissible_strain, newton_contract_type, newton_report_type, newton_solve, &
      & always_refactor_type, stop_interrupted
   implicit none
   private

   public :: spatial_stepper_type, new_spatial_stepper

   !> Halvings of one step before it is given up (as the planar step control's).
   integer, parameter :: max_cuts = 8
   !> A verifying pair of half steps contradicts its step when their results
   !> differ by more than this many model sizes (the planar FEM's; see verify_step).
   real(dp), parameter :: verify_agreement = 1.0e-6_dp
   !> The branch check's verdicts on a converged try (check_jump): accept it;
   !> reject it (cut it); accept it pending its verification by two half
   !> steps; reject it for good (a step halved max_verify_depth times is
   !> still suspect: cutting cannot help).
   integer, parameter :: jump_accept = 0, jump_reject = 1, jump_verify = 2, jump_unverifiable = 3
   !> Outcomes of verify_step: the half steps confirm the step; they
   !> contradict it and replace it; they could not be solved.
   integer, parameter :: verify_confirmed = 0, verify_replaced = 1, verify_failed = 2
   !> A crossing step needs no verification when Newton moved every rotation
   !> less than this share of the crossing turn away from the full
   !> predictor. A jump over a near-toggle lands about the turn away from
   !> the true path, so a step within this share of the predictor jumped
   !> only if the predictor itself missed the path by nearly the whole turn.
   !> Ten times the planar FEM's share (fekap_stepping_jump's
   !> verify_predicted, for its Hermite extrapolation): the Taylor predictor
   !> of Example 1 at dt = 0.025 misses its crossing near theta = 0 by 1.5e-3
   !> of the turn, which would verify that step in every one of
   !> fourbar-1000-turns' turns.
   real(dp), parameter :: verify_predicted = 1.0e-2_dp

   !> A name for messages.
   type :: label_type
      character(:), allocatable :: text
   end type label_type

   !> What the stepper keeps of an accepted configuration: to try a step from
   !> it again, and the two regular states on either side of a change point.
   type :: accepted_type
      type(spatial_state_type) :: s
      real(dp) :: t = 0
      real(dp), allocatable :: v(:), a(:), jerk(:), snap(:), jerk1(:), jerk2(:)
      real(dp) :: t1 = 0, t2 = 0, residual = 0, reference_rcond = 0, rcond = 0
      integer :: jerks = 0
      real(dp), allocatable :: response(:, :)
      logical :: has_response = .false., response_signs = .false.
   end type accepted_type

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
      !> Newton: length tolerance of the correction, most iterations (those
      !> followed by another assembly), and the contract (spatial_contract).
      real(dp) :: tol = 1.0e-12_dp
      integer :: max_iter = 25
      type(newton_contract_type) :: contract
      integer, allocatable :: fdof(:)
      !> The tangent's band storage and its factor at the last iterate.
      type(spatial_tangent_type) :: kt
      !> Whether the rates are output (else a converged correction above
      !> rate_tol needs no refining iteration: the rates feed the predictor only).
      logical :: refine_rates = .true.
      !> The least reciprocal condition number of the tangents of the last
      !> solve that watched them (a failed factor 0).
      real(dp) :: least_rcond = 0
      !> The norm of the free dofs' residual at the last converged configuration.
      real(dp) :: residual = 0
      !> The links' rotations of the last step (links.csv).
      type(link_motion_type) :: links
      !> The linear response of every dof to unit drive changes at the accepted
      !> configuration (one column a drive), whether its size is trusted (its
      !> tangent regular against the run's best: response_trusted) and whether
      !> its signs are (signs_trusted), and the one at the last converged try;
      !> the reciprocal condition numbers of the tangent at that try's
      !> predictor and solution, and the run's best.
      real(dp), allocatable :: response(:, :), try_response(:, :)
      logical :: has_response = .false., response_signs = .false.
      real(dp) :: predictor_rcond = 0, try_rcond = 0, reference_rcond = 0
      !> The reciprocal condition number of the tangent at the accepted
      !> configuration (0 where not known: a change point's filled row).
      real(dp) :: rcond = 0
      !> The unit of stroke drives in the branch check (the shortest element).
      real(dp) :: shortest = 1
      !> The hinges of the branch check's orientation rule.
      type(spatial_hinge_type), allocatable :: hinges(:)
      !> Each element's link (beams, then trusses, as element_groups numbers
      !> them), for messages.
      type(label_type), allocatable :: element_link(:)
      !> The largest element strain of a mechanism configuration (check_mechanism).
      real(dp) :: admissible_strain = 0
      !> The run's uniform steps, for the time after a change point.
      real(dp) :: t_start = 0, t_end = 1, dt = 0
      !> A change point stepped over: the regular states on either side, the
      !> one ahead with its iterations and cuts (the next advance's), and
      !> whether it is kept.
      type(accepted_type) :: before, ahead
      logical :: has_ahead = .false.
      integer :: ahead_iterations = 0, ahead_cuts = 0
      !> Whether the accepted state's rates are known (not at a change point's
      !> singular row), and the note of its row.
      logical :: rates_known = .true.
      character(len=note_length) :: note = ''
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
      real(dp) :: force_scale, floor
      integer :: k, e, pass
      call build_spatial_mechanism(model, self%m, self%map, error)
      if (allocated(error)) return
      self%s = new_spatial_state(self%m)
      self%t = model%analysis%t_start
      self%tol = model%analysis%length_tol
      self%max_iter = model%analysis%max_iter
      ! The beams, then the trusses, each in the links' order
      ! (build_spatial_mechanism). A loop: gfortran 12 built the labels of an
      ! array constructor over label_type(name) with empty texts.
      allocate (self%element_link(size(model%links)))
      e = 0
      do pass = 1, 2
         do k = 1, size(model%links)
            if (model%spatial%truss(k) .neqv. pass == 2) cycle
            e = e + 1
            self%element_link(e)%text = model%links(k)%name
         end do
      end do
      self%admissible_strain = admissible_strain(model%analysis%tol)
      call check_determined(self, model%file, error)
      if (allocated(error)) return
      self%fdof = free_dofs(self%m)
      call tangent_for(self%m, self%kt)
      ! A quarter of the run's step (curve_rates), and of the run where the
      ! step is longer than the run (its one step is the run).
      self%difference_step = min(model%analysis%dt, model%analysis%t_end - model%analysis%t_start)/4
      self%t_start = model%analysis%t_start
      self%t_end = model%analysis%t_end
      self%dt = model%analysis%dt
      self%shortest = shortest_element(self%m)
      call name_hinges(self, model)
      self%refine_rates = model%analysis%velocities
      call spatial_force_scale(self%m, self%kt, self%shortest, force_scale, floor)
      ! The deck's iterations count the corrections followed by another
      ! assembly: the last correction is one more.
      self%contract = spatial_contract(model%analysis%tol, self%tol, self%max_iter + 1, force_scale, floor, &
         & self%refine_rates)
      call new_link_motion(self%links, model, self%m, self%map%node_frame, self%map%node_point)
      allocate (self%v(self%m%ndof), self%a(self%m%ndof), self%jerk(self%m%ndof), self%snap(self%m%ndof), &
         & self%jerk1(self%m%ndof), self%jerk2(self%m%ndof), source=0.0_dp)
   end subroutine new_spatial_stepper

   !> A mechanism with a part that moves freely at every configuration
   !> (free_part: more free dofs than its links and slides can hold) is
   !> refused, naming the part's links, as the planar FEM refuses one
   !> (fekap_fem_determinacy's check_determined, with the same message):
   !> its tangent is singular, but round-off hides the zero pivot, and the
   !> run wrote the loose part at rest.
   subroutine check_determined(self, file, error)
      type(spatial_stepper_type), intent(in) :: self
      !> The deck's path, for the message.
      character(*), intent(in) :: file
      type(error_type), allocatable, intent(out) :: error
      logical, allocatable :: in_part(:)
      integer :: excess, k
      character(len=12) :: num
      character(:), allocatable :: names
      call free_part(self%m, excess, in_part)
      if (excess == 0) return
      names = ''
      do k = 1, size(self%element_link)
         if (.not. in_part(k)) cycle
         if (len(names) > 0) names = names//', '
         names = names//self%element_link(k)%text
      end do
      if (len(names) > 0) then
         names = 'links '//names
      else
         names = 'a joint''s angle or stroke that no link depends on'
      end if
      write (num, '(i0)') excess
      call input_error(error, file//': the mechanism is not determined by its joints, drives and '// &
         & 'links: a part of it can move freely, at every configuration (at least '//trim(num)// &
         & ' degree'//trim(merge('s', ' ', excess > 1))//' of freedom that no joints, supports, drives or '// &
         & 'links hold): '//names//'; join, support or drive the part that moves, or remove it')
   end subroutine check_determined

   !> The mechanism's hinges (find_hinges), named by the model's links and
   !> nodes: beams are made one a link that is not a truss, in the links'
   !> order; a point is named by the first node on it.
   subroutine name_hinges(self, model)
      type(spatial_stepper_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      integer, allocatable :: beam_link(:)
      integer :: k, node
      beam_link = pack([(k, k=1, size(model%links))], .not. model%spatial%truss)
      self%hinges = find_hinges(self%m)
      do k = 1, size(self%hinges)
         associate (h => self%hinges(k))
            node = findloc(self%map%node_point, h%point, 1)
            h%label = 'links '//model%links(beam_link(h%beams(1)))%name//' and '// &
               & model%links(beam_link(h%beams(2)))%name//' at node '//model%nodes(node)%name
         end associate
      end do
   end subroutine name_hinges

   !> The deck's configuration at the start time, solved (it is stress free:
   !> Newton's first correction is at round-off) with its rates.
   subroutine spatial_start(self, result, error)
      class(spatial_stepper_type), intent(inout) :: self
      type(step_result_type), intent(inout) :: result
      type(error_type), allocatable, intent(out) :: error
      integer :: iterations
      logical :: converged, found
      character(:), allocatable :: why
      call solve(self, self%t, .false., .false., iterations, converged, found, why, error)
      if (allocated(error)) return
      if (.not. converged) then
         call analysis_error(error, 'the start configuration does not assemble: '//why)
         return
      end if
      ! The start's tangent is the run's first reference, its response trusted.
      self%reference_rcond = self%try_rcond
      self%rcond = self%try_rcond
      call move_alloc(self%try_response, self%response)
      self%has_response = self%try_rcond > 0
      self%response_signs = self%has_response
      result%t = self%t
      result%iterations = iterations
      call fill_result(self, result)
   end subroutine spatial_start

   !> Advance to time t: the state ahead of a change point if it is this
   !> time's; else a step of the run (step_to, whose first try looks for a
   !> change point at its predictor), or the step over a change point found there.
   subroutine spatial_advance(self, t, result, error)
      class(spatial_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      type(step_result_type), intent(inout) :: result
      type(error_type), allocatable, intent(out) :: error
      integer :: cuts, iterations
      logical :: found
      self%rates_known = .true.
      self%note = ''
      if (self%has_ahead) then
         self%has_ahead = .false.
         if (t == self%ahead%t) then
            ! The step over a change point solved this time already (with its rates).
            call restore(self, self%ahead)
            self%counts%steps = self%counts%steps + 1
            result%t = t
            result%iterations = self%ahead_iterations
            result%cuts = self%ahead_cuts
            call fill_result(self, result)
            return
         end if
         ! Another time: from the regular state before the change point.
         call restore(self, self%before)
      end if
      call step_to(self, t, .true., .true., 0, iterations, cuts, found, error)
      if (allocated(error)) return
      if (found) then
         call step_over(self, t, result, error)
         return
      end if
      self%counts%steps = self%counts%steps + 1
      result%t = t
      result%iterations = iterations
      result%cuts = cuts
      call fill_result(self, result)
   end subroutine spatial_advance

   !> Advance the accepted state to time t, cutting the step in halves while
   !> Newton fails or the branch check rejects its configuration. With
   !> `detect`, the first try checks its predictor's tangent: near singular
   !> against the run's best (change_verdict), it ends the advance at once
   !> (found; the state is the one before). A converged step that the branch
   !> check finds suspect (a hinge crossed collinear with a large turn) is
   !> verified by two half steps (verify_step, which calls step_to one level
   !> deeper: depth, 0 for a step of the run); a verification that cannot be
   !> completed below the run's step ends every level above it at once
   !> (error), and the run's step is cut. Without `verify`, the step over a
   !> change point (step_over) is not verified: its half steps would land on
   !> the change point, where Newton has no unique solution; the branch rules
   !> at its two ends, regular, still hold.
   recursive subroutine step_to(self, t, detect, verify, depth, iterations, cuts, found, error)
      type(spatial_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      logical, intent(in) :: detect, verify
      integer, intent(in) :: depth
      integer, intent(out) :: iterations, cuts
      logical, intent(out) :: found
      type(error_type), allocatable, intent(out) :: error
      type(accepted_type) :: saved
      type(spatial_state_type) :: predicted
      real(dp) :: h, t_try, turn
      integer :: its, verdict, crossing, outcome
      logical :: converged
      character(:), allocatable :: why
      character(len=160) :: text
      h = t - self%t
      cuts = 0
      iterations = 0
      found = .false.
      do while (self%t < t)
         t_try = min(self%t + h, t)
         if (t - t_try < 1.0e-9_dp*h) t_try = t
         saved = snapshot(self)
         call predict(self, t_try - self%t, .true.)
         predicted = self%s
         call solve(self, t_try, detect .and. cuts == 0, .false., its, converged, found, why, error)
         if (allocated(error)) then
            call restore(self, saved)
            return
         end if
         iterations = iterations + its
         if (found) then
            call restore(self, saved)
            return
         end if
         verdict = jump_accept
         if (converged) call check_mechanism(self, converged, why)
         if (converged) call check_jump(self, saved, t_try, predicted, .true., verify, depth, verdict, why, crossing, turn)
         converged = converged .and. verdict /= jump_reject .and. verdict /= jump_unverifiable
         if (.not. converged .and. verdict /= jump_unverifiable) then
            ! Once more from the predictor to the second rate (see predict),
            ! watching the tangents: Newton that fails on the run's step
            ! among near-singular tangents is at a change point too.
            call restore(self, saved)
            call predict(self, t_try - self%t, .false.)
            call solve(self, t_try, .false., .true., its, converged, found, why, error)
            if (allocated(error)) then
               call restore(self, saved)
               return
            end if
            iterations = iterations + its
            if (converged) call check_mechanism(self, converged, why)
            if (converged) call check_jump(self, saved, t_try, predicted, .false., verify, depth, verdict, why, crossing, turn)
            converged = converged .and. verdict /= jump_reject .and. verdict /= jump_unverifiable
            if (.not. converged .and. detect .and. cuts == 0) then
               call stop_at_change_point(self, saved, self%least_rcond, found)
               if (found) return
            end if
         end if
         if (verdict == jump_unverifiable) then
            ! Halving cannot help: this verification ends (see verify_step).
            call restore(self, saved)
            call analysis_error(error, why, t=t_try)
            return
         end if
         if (converged .and. detect .and. cuts == 0) then
            ! A predictor far from a change point (j and k off) may still
            ! converge onto it, slowly: a run's step whose configuration has a
            ! near-singular tangent is stepped over as well.
            call stop_at_change_point(self, saved, self%try_rcond, found)
            if (found) return
         end if
         if (converged) then
            self%t = t_try
            self%has_response = response_trusted(self%try_rcond, self%reference_rcond)
            self%response_signs = signs_trusted(self%try_rcond, self%reference_rcond)
            if (self%response_signs) then
               call move_alloc(self%try_response, self%response)
            else
               self%response = 0
            end if
            self%reference_rcond = max(self%reference_rcond, self%try_rcond)
            self%rcond = self%try_rcond
            if (verdict /= jump_verify) cycle
            call verify_step(self, saved, t_try, depth, self%hinges(crossing)%label, turn, its, outcome, why)
            iterations = iterations + its
            if (outcome == verify_confirmed) cycle
            if (outcome == verify_replaced) then
               ! The half steps replaced a jump: a cut step.
               cuts = cuts + 1
               cycle
            end if
            ! The half steps could not be solved (verify_step restored the state before).
            if (depth > 0) then
               call analysis_error(error, why, t=t_try)
               return
            end if
         end if
         call restore(self, saved)
         cuts = cuts + 1
         if (cuts > max_cuts) then
            write (text, '(a,i0,a)') 'Newton failed even with the step cut ', max_cuts, ' times ('
            call analysis_error(error, trim(text)//why//'): a dead point of the drive, or a configuration '// &
               & 'that does not assemble; drive another joint or end the run before it')
            return
         end if
         h = h/2
      end do
   end subroutine step_to

   !> The branch-jump check of a converged try from the accepted state `saved`
   !> to time t (docs/hard-cases.md, section 1, in the spatial stepper's
   !> terms), with the linear responses to the drive increment at either end
   !> (where trusted):
   !> * magnitude (rotation_jump): every joint angle and free frame turns by
   !>   at most jump_ratio times what the responses, or the increment itself
   !>   (strokes in lengths of the shortest element), explain;
   !> * orientation (hinge_check): a hinge whose relative angle passes
   !>   through collinear does so in the sense of the responses;
   !> * a hinge that crosses collinear turning by more than verify_turn,
   !>   where Newton moved some rotation more than verify_predicted of that
   !>   turn away from the full predictor (`smooth`), asks for the step's
   !>   verification by two half steps (jump_verify; jump_unverifiable at
   !>   max_verify_depth), unless the step is not to be verified (`verify`
   !>   false); crossing is that hinge.
   subroutine check_jump(self, saved, t, predicted, smooth, verify, depth, verdict, why, crossing, turn)
      type(spatial_stepper_type), intent(in) :: self
      type(accepted_type), intent(in) :: saved
      real(dp), intent(in) :: t
      type(spatial_state_type), intent(in) :: predicted
      logical, intent(in) :: smooth, verify
      integer, intent(in) :: depth
      integer, intent(out) :: verdict, crossing
      character(:), allocatable, intent(inout) :: why
      real(dp), intent(out) :: turn
      real(dp), allocatable :: dd(:), dq_old(:), dq_new(:)
      real(dp) :: floor_, worst, rotation
      integer :: j, worst_dof, flipped
      character(len=200) :: text
      verdict = jump_accept
      crossing = 0
      turn = 0
      ! Without drives nothing explains a rotation, and nothing is to move.
      if (size(self%response, 2) == 0) return
      allocate (dd(size(self%response, 2)), source=0.0_dp)
      floor_ = 0
      do j = 1, size(dd)
         associate (dof => self%m%drives(j)%dof)
            dd(j) = self%s%q(dof) - saved%s%q(dof)
            floor_ = max(floor_, abs(dd(j))/merge(self%shortest, 1.0_dp, self%m%is_length(dof)))
         end associate
      end do
      allocate (dq_old(self%m%ndof), dq_new(self%m%ndof), source=0.0_dp)
      if (saved%has_response) dq_old = matmul(saved%response, dd)
      if (response_trusted(self%try_rcond, self%reference_rcond)) dq_new = matmul(self%try_response, dd)
      call rotation_jump(self%m, saved%s, self%s, dq_old, dq_new, floor_, self%tol, worst, worst_dof, rotation)
      if (worst > jump_ratio) then
         verdict = jump_reject
         write (text, '(a,es12.5,a,f9.4,a,es9.2,a,i0)') 't = ', t, ': assembly-mode jump rejected (rotation ', &
            & rotation, ' rad over the step, ', worst, ' times what the drive increment explains) at dof ', worst_dof
         why = trim(text)
         return
      end if
      ! The orientation rule needs the responses' signs only: those of the
      ! tangents whose rates the run reports (signs_trusted).
      if (saved%response_signs) dq_old = matmul(saved%response, dd)
      if (signs_trusted(self%try_rcond, self%reference_rcond)) dq_new = matmul(self%try_response, dd)
      call hinge_check(self%hinges, saved%s%q, self%s%q, dq_old, dq_new, flipped, turn, crossing)
      if (flipped > 0) then
         verdict = jump_reject
         write (text, '(a,es12.5,a)') 't = ', t, ': assembly-mode jump rejected ('
         why = trim(text)//self%hinges(flipped)%label//' passed through collinear against the drive increment''s sense)'
         return
      end if
      if (turn <= verify_turn .or. .not. verify) return
      if (smooth) then
         if (predicted_step(self%m, predicted, self%s, verify_predicted, turn)) return
      end if
      verdict = jump_verify
      if (depth >= max_verify_depth) then
         verdict = jump_unverifiable
         write (text, '(a,es12.5,a,f7.4,a,i0,a)') 't = ', t, ': assembly-mode jump rejected ('// &
            & self%hinges(crossing)%label//' crossed collinear turning ', turn, ' rad in a step halved ', &
            & max_verify_depth, ' times)'
         why = trim(text)
      end if
   end subroutine check_jump

   !> Step-doubling verification of the step from `saved` to time t, accepted
   !> but suspect (the hinge `pair` crossed collinear turning by `turn`): the
   !> same interval is solved again from `saved` as two half steps (step_to
   !> one level deeper: cut if they fail, verified if suspect) and the results
   !> compared. Endpoint data cannot tell a crossing from a jump over a
   !> near-toggle onto the mirror branch; a jump turns the pair by its
   !> distances from collinear at both ends, so it stays suspect however
   !> often it is halved, while a real crossing turns less with every
   !> halving. Confirmed (within verify_agreement model sizes), the step's own
   !> state stays; contradicted, the half steps' state replaces it (`why`
   !> says so); if the half steps cannot be solved, the state before the step
   !> is restored (verify_failed, `why` says why). A first half step whose
   !> predictor or solution is near singular (change_verdict: the step
   !> crosses a change point, the double crank's collinear configuration at
   !> its middle) cannot verify anything: Newton has no unique solution
   !> there. Such a step stands on the branch rules at its two regular ends,
   !> as the step over a change point does (step_over).
   recursive subroutine verify_step(self, saved, t, depth, pair, turn, iterations, outcome, why)
      type(spatial_stepper_type), intent(inout) :: self
      type(accepted_type), intent(in) :: saved
      real(dp), intent(in) :: t, turn
      integer, intent(in) :: depth
      character(*), intent(in) :: pair
      integer, intent(out) :: iterations, outcome
      character(:), allocatable, intent(inout) :: why
      type(accepted_type) :: whole
      type(error_type), allocatable :: half_error
      real(dp) :: t_half(2), distance
      integer :: half, its, cuts
      logical :: found
      character(len=200) :: text
      whole = snapshot(self)
      call restore(self, saved)
      t_half = [saved%t + (t - saved%t)/2, t]
      iterations = 0
      do half = 1, 2
         call step_to(self, t_half(half), half == 1, .true., depth + 1, its, cuts, found, half_error)
         iterations = iterations + its
         if (found) then
            outcome = verify_confirmed
            call restore(self, whole)
            return
         end if
         if (allocated(half_error)) exit
      end do
      if (allocated(half_error)) then
         call restore(self, saved)
         outcome = verify_failed
         if (depth > 0) then
            why = half_error%message
         else
            write (text, '(a,es12.5,a,f7.4,a)') 't = ', t, ': possible assembly-mode jump rejected ('//pair// &
               & ' crossed collinear turning ', turn, ' rad; two half steps could not confirm it: '
            why = trim(text)//' '//half_error%message//')'
         end if
         return
      end if
      distance = state_distance(self%m, whole%s, self%s)
      if (distance > verify_agreement) then
         outcome = verify_replaced
         write (text, '(a,es12.5,a,es9.2,a)') 't = ', t, ': assembly-mode jump rejected (the step ends ', distance, &
            & ' model sizes from where two half steps end; '
         why = trim(text)//pair//' crossed collinear); the half steps replace it'
         return
      end if
      outcome = verify_confirmed
      call restore(self, whole)
   end subroutine verify_step

   !> The step onto time t found its predictor's tangent near singular (a
   !> change point): instead of iterating there, solve the next output time
   !> from the last regular state as one double step (kept for the next
   !> advance) and fill the row at t from both sides: the quintic Hermite
   !> interpolant through the two regular states (fill_state), corrected onto
   !> the mechanism with the shifted tangent (correct_state). Its rates are
   !> left out where the tangent there is singular against the run's best
   !> (rates_drop); where it is regular enough (near, not on, a change point)
   !> the row is solved as without the detection, from the state before,
   !> and if that fails the fill is finished by plain Newton and gets rates.
   !> If the double step fails, the row is solved as without the detection.
   subroutine step_over(self, t, result, error)
      type(spatial_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: t
      type(step_result_type), intent(inout) :: result
      type(error_type), allocatable, intent(out) :: error
      type(error_type), allocatable :: over_error, near_error
      type(spatial_state_type) :: filled
      real(dp) :: t_next, residual, rcond, predictor_rcond
      integer :: iterations, cuts, its, order
      logical :: found, singular, tried_step, held
      character(len=note_length) :: text
      character(:), allocatable :: what
      predictor_rcond = self%predictor_rcond
      self%before = snapshot(self)
      t_next = next_output_time(self%t_start, self%t_end, self%dt, self%t, t)
      call step_to(self, t_next, .false., .false., 0, iterations, cuts, found, over_error)
      if (allocated(over_error)) then
         ! The double step failed: solve at t itself, as without the detection.
         call restore(self, self%before)
         call step_to(self, t, .false., .true., 0, iterations, cuts, found, error)
         if (allocated(error)) return
         call take_row(iterations, cuts)
         return
      end if
      self%ahead = snapshot(self)
      self%ahead_iterations = iterations
      self%ahead_cuts = cuts
      self%has_ahead = .true.
      associate (bf => self%before, n => self%ahead)
         ! Through both sides' rates (quintic), or where the correction does
         ! not put the fill on the mechanism, through fewer of them: the
         ! double step may have ended on the change point itself (a02-n2
         ! --spatial at dt 0.001 ended at t = 0.25), whose rates are
         ! unbounded, and the quintic through them was written as row 0.249
         ! with a residual of 2.5e12. A fill that no order puts on the
         ! mechanism (its residual within the Newton contract, its strains
         ! admissible: check_mechanism's test) is no row.
         its = 0
         tried_step = .false.
         do order = fill_order(.true., .true.), 1, -2
            filled = fill_state(self%m, order, bf%t, bf%s, bf%v, bf%a, n%t, n%s, n%v, n%a, t)
            call correct_state(self%m, self%fdof, t, self%tol, fill_shift, filled, iterations, residual, rcond)
            its = its + iterations
            singular = rcond < rates_drop*bf%reference_rcond
            if (.not. singular) then
               if (.not. tried_step) then
                  ! Near, not on, a change point: solve the row itself as without the
                  ! detection, from the state before it (once: it does not depend
                  ! on the fill); the state ahead stays.
                  tried_step = .true.
                  call restore(self, bf)
                  call step_to(self, t, .false., .true., 0, iterations, cuts, found, near_error)
                  if (.not. allocated(near_error)) then
                     call take_row(iterations, cuts)
                     return
                  end if
                  call restore(self, bf)
               end if
               call correct_state(self%m, self%fdof, t, self%tol, 0.0_dp, filled, iterations, residual, rcond)
               its = its + iterations
            end if
            held = fill_holds(self%contract, residual) .and. admissible(filled)
            if (held) exit
         end do
         if (.not. held) then
            write (text, '(a,es12.5,a,es12.5,a,es12.5,a,es9.2,a)') 't = ', t, ': the row of the change point '// &
               & 'stepped over from t = ', bf%t, ' to ', n%t, ' could not be filled (the positions interpolated '// &
               & 'from both sides and corrected leave a residual of ', residual, ', or strained links): take '// &
               & 'another time step, or end the run before it'
            call analysis_error(error, trim(text), t=t)
            return
         end if
         self%s = filled
         self%t = t
         self%residual = residual
         self%rates_known = .not. singular
         if (self%rates_known) call spatial_rates(self%m, t, self%s, self%v, self%a, near_error)
         if (allocated(near_error)) self%rates_known = .false.
         what = ': near a change point ('
         if (singular) what = ': singular configuration (a change point: '
         write (text, '(a,es12.5,a,es9.2,a,es9.2,a,es12.5,a,es12.5,a,i0,a,es9.2,a)') 't = ', t, &
            & what//'the tangent''s condition ', predictor_rcond/max(bf%reference_rcond, tiny(1.0_dp)), &
            & ' at the predictor, ', rcond/max(bf%reference_rcond, tiny(1.0_dp)), &
            & ' at the configuration, of the run''s best): stepped over from t = ', bf%t, ' to ', n%t, &
            & '; positions interpolated from both sides (order ', order, ') and corrected (residual ', residual, ')'
         if (self%rates_known) then
            self%note = trim(text)//': velocities and accelerations are ill-conditioned'
         else
            self%note = trim(text)//': velocities and accelerations are left out of this step'
         end if
      end associate
      call take_row(its, 0)
   contains
      !> Whether the links' strains at state s are admissible (check_mechanism's bound).
      logical function admissible(s)
         type(spatial_state_type), intent(in) :: s
         type(spatial_configuration_type) :: c
         real(dp) :: strain
         integer :: element
         call configure(self%m, s, c)
         call largest_strain(self%m, c, strain, element)
         admissible = strain <= self%admissible_strain
      end function admissible

      !> The row at t is the stepper's state: one step more, its result.
      subroutine take_row(row_iterations, row_cuts)
         integer, intent(in) :: row_iterations, row_cuts
         self%counts%steps = self%counts%steps + 1
         result%t = t
         result%iterations = row_iterations
         result%cuts = row_cuts
         call fill_result(self, result)
      end subroutine take_row
   end subroutine step_over

   !> Whether the configuration Newton converged to is a mechanism
   !> configuration, not a self-stressed equilibrium: every element's strain
   !> within the admissible strain (the planar FEM's check_mechanism, with
   !> its bound). A redundant loop past a change point can converge onto
   !> one with its residual at round-off: the double crank --spatial at dt
   !> 1e-4 went on past t = 0.25 with its links 1e-6 to 0.42 off their
   !> lengths, written as converged rows. Else converged is set .false. and
   !> why says so (the step is cut, as for a jump).
   subroutine check_mechanism(self, converged, why)
      type(spatial_stepper_type), intent(in) :: self
      logical, intent(inout) :: converged
      character(:), allocatable, intent(inout) :: why
      type(spatial_configuration_type) :: c
      real(dp) :: strain
      integer :: element
      character(len=80) :: text
      call configure(self%m, self%s, c)
      call largest_strain(self%m, c, strain, element)
      if (strain <= self%admissible_strain) return
      converged = .false.
      write (text, '(a,es9.2,a)') 'Newton converged to a self-stressed configuration (strain ', strain, ' in link '
      why = trim(text)//' '//self%element_link(element)%text//'), not a mechanism configuration: an '// &
         & 'over-constrained loop whose geometry does not close exactly strains as it moves; give exact '// &
         & 'coordinates, or a looser --tol (the admissible strain is 100 times it, at most 1e-3)'
   end subroutine check_mechanism

   !> Whether a filled row's residual passes the run's Newton contract (the
   !> tolerance times the forces in play, or the round-off floor).
   pure logical function fill_holds(contract, residual)
      type(newton_contract_type), intent(in) :: contract
      real(dp), intent(in) :: residual
      fill_holds = residual <= max(contract%tolerance*contract%force_scale, contract%floor)
   end function fill_holds

   !> The accepted configuration, its rates and its predictor's history.
   function snapshot(self) result(x)
      type(spatial_stepper_type), intent(in) :: self
      type(accepted_type) :: x
      x%s = self%s
      x%t = self%t
      x%v = self%v
      x%a = self%a
      x%jerk = self%jerk
      x%snap = self%snap
      x%jerk1 = self%jerk1
      x%jerk2 = self%jerk2
      x%t1 = self%t1
      x%t2 = self%t2
      x%jerks = self%jerks
      x%residual = self%residual
      x%reference_rcond = self%reference_rcond
      x%rcond = self%rcond
      x%response = self%response
      x%has_response = self%has_response
      x%response_signs = self%response_signs
   end function snapshot

   !> Make x the accepted configuration again.
   !> Whether a tangent of the step's reciprocal condition rcond marks a
   !> change point against the run's best (change_verdict); if so, the state
   !> before the step (saved) is restored and rcond kept as the predictor's,
   !> for the step over the change point (step_over).
   subroutine stop_at_change_point(self, saved, rcond, found)
      type(spatial_stepper_type), intent(inout) :: self
      type(accepted_type), intent(in) :: saved
      real(dp), intent(in) :: rcond
      logical, intent(out) :: found
      found = change_verdict(rcond, self%reference_rcond) /= change_regular
      if (.not. found) return
      self%predictor_rcond = rcond
      call restore(self, saved)
   end subroutine stop_at_change_point

   subroutine restore(self, x)
      type(spatial_stepper_type), intent(inout) :: self
      type(accepted_type), intent(in) :: x
      self%s = x%s
      self%t = x%t
      self%v = x%v
      self%a = x%a
      self%jerk = x%jerk
      self%snap = x%snap
      self%jerk1 = x%jerk1
      self%jerk2 = x%jerk2
      self%t1 = x%t1
      self%t2 = x%t2
      self%jerks = x%jerks
      self%residual = x%residual
      self%reference_rcond = x%reference_rcond
      self%rcond = x%rcond
      self%response = x%response
      self%has_response = x%has_response
      self%response_signs = x%response_signs
   end subroutine restore

   !> The predictor: s (+) (h v + h^2/2 a + h^3/6 j + h^4/24 k), the Taylor
   !> series of the motion to its fourth rate (an O(h^5) error), or without
   !> its last two terms (`full` false: an O(h^3) error, for the retry of a
   !> step whose j and k, from solves with an ill-conditioned tangent, may be
   !> far off).
   subroutine predict(self, h, full)
      type(spatial_stepper_type), intent(inout) :: self
      real(dp), intent(in) :: h
      logical, intent(in) :: full
      if (full) then
         call update_state(self%m, self%s, h*self%v + h**2/2*self%a + h**3/6*self%jerk + h**4/24*self%snap)
      else
         call update_state(self%m, self%s, h*self%v + h**2/2*self%a)
      end if
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
   !> their j (every step but the first two, and those after a slider passed
   !> a hinge of its line of links), k is instead the rate at t of
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
      ! A slider that passed a hinge of its line of links since t2 (its
      ! stroke taken back along its rate): the j before belong to the path
      ! before the corner, where the rates jump; k from the differences.
      if (self%jerks >= 2) then
         if (passes_a_segment_end(self%m, self%s%q, -(t - self%t2)*self%v)) self%jerks = 0
      end if
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

   !> Newton from the current state at time t (the drives set exactly): the
   !> one Newton driver's newton_solve on fekap_spatial_newton's system, under
   !> the spatial contract (spatial_contract); on convergence the rates at
   !> the solution (the iterate the last correction was solved from, whose
   !> tangent is factored) and the drive response there (try_response, with
   !> the tangent's condition try_rcond), the last correction applied. With
   !> `detect`, the tangent at the predictor (the first iteration's) is
   !> checked for a change point: near singular against the run's best,
   !> Newton stops there (found). `why` says why it failed; `interrupt`
   !> is allocated when a signal asked the run to stop.
   subroutine solve(self, t, detect, watch, iterations, converged, found, why, interrupt)
      type(spatial_stepper_type), target, intent(inout) :: self
      real(dp), intent(in) :: t
      !> Check the predictor for a change point; keep the least condition
      !> estimate of the iterates' tangents (least_rcond).
      logical, intent(in) :: detect, watch
      integer, intent(out) :: iterations
      logical, intent(out) :: converged, found
      character(:), allocatable, intent(out) :: why
      type(error_type), allocatable, intent(out) :: interrupt
      type(spatial_newton_type) :: newton
      type(always_refactor_type) :: full
      type(newton_report_type) :: report
      type(error_type), allocatable :: error
      real(dp) :: ad(self%m%ndof)
      why = ''
      call newton%begin(self%m, self%kt, self%counts, self%s, t, self%contract, self%tol, self%refine_rates)
      newton%detect = detect
      newton%watch = watch
      newton%reference_rcond = self%reference_rcond
      call newton_solve(newton, self%contract, full, report, error)
      iterations = newton%iterations
      found = newton%found
      converged = report%converged()
      if (detect) self%predictor_rcond = newton%predictor_rcond
      if (watch) self%least_rcond = newton%least_rcond
      if (.not. converged) then
         if (report%stopped == stop_interrupted) then
            call move_alloc(error, interrupt)
            return
         end if
         why = newton%why(report, error, self%max_iter)
         return
      end if
      ! Converged at the iterate the last correction was solved from, which is
      ! the solution to round-off: its factored tangent gives the rates, the
      ! drive response and the condition estimate.
      self%residual = newton%residual
      call set_drives(self%m, t, newton%at, self%v, ad)
      call spatial_rates_factored(self%m, newton%at, newton%c, self%kt, self%v, ad, self%a)
      self%counts%velocity_solves = self%counts%velocity_solves + 1
      self%counts%acceleration_solves = self%counts%acceleration_solves + 1
      self%try_response = drive_response(self%m, self%kt)
      call self%kt%rcond(self%try_rcond)
      self%s = newton%s
      call curve_rates(self, t)
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
      result%has_velocity = self%rates_known
      result%has_acceleration = self%rates_known
      result%residual = self%residual
      result%note = self%note
      if (len_trim(self%note) == 0) result%note = conditioning_note(self)
   end subroutine fill_result

   !> The listing's note on an accepted configuration near a change point:
   !> its tangent's reciprocal condition number below change_drop times the
   !> run's best (the planar FEM's note on a near-stationary configuration,
   !> with the spatial stepper's measure of it). Its rates, solved with that
   !> tangent, carry the round-off of the solve amplified by the condition
   !> number. '' for a regular one.
   function conditioning_note(self) result(note)
      type(spatial_stepper_type), intent(in) :: self
      character(len=note_length) :: note
      character(len=160) :: text
      note = ''
      if (.not. (self%rcond > 0 .and. self%rcond < change_drop*self%reference_rcond)) return
      write (text, '(a,es12.5,a,es9.2,a)') 't = ', self%t, &
         & ': near a stationary configuration (the tangent''s condition ', self%rcond/self%reference_rcond, &
         & ' of the run''s best)'
      note = text
      if (self%refine_rates) note = trim(text)//': velocities and accelerations are ill-conditioned'
   end function conditioning_note

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

   !> Whether the signs of the drive response of a tangent with reciprocal
   !> condition number rcond are trusted against the run's best so far,
   !> reference: where the run reports the rates of a configuration (above
   !> rates_drop), it reports the signs of this response times the drive's
   !> rate. Its size is trusted from the higher response_trusted on: nearer
   !> a change point the round-off error of the response, about eps over the
   !> tangent's reciprocal condition number relative, still leaves its sign,
   !> while the response grows without bound (the near-toggle of the flat
   !> Peaucellier cell: docs/spatial.md).
   pure logical function signs_trusted(rcond, reference) result(trusted)
      real(dp), intent(in) :: rcond, reference
      trusted = rcond > 0 .and. rcond >= rates_drop*reference
   end function signs_trusted

end module fekap_spatial_stepper
