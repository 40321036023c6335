!> The assembly-mode (branch) check of a converged FEM step. A converged,
!> unstrained configuration may still lie on another assembly branch than the
!> last one: Newton from a poor predictor can cross over. What the drive
!> increment dd of the step explains is its linear response, dq = R dd with
!> R = -K_ff^-1 K_fd the response to unit drive changes, at either end of the
!> step (the stepper computes both). Two tests:
!> * magnitude: every rotation unknown changes by |d| <= jump_ratio * B with
!>   B = max(|dq_n|, |dq|, drive increment) (rotation drives in radians,
!>   translation drives in lengths of the shortest link);
!> * orientation (hinge_flip): two hinged links that pass through
!>   collinear within the step must do so in the sense of the response.
!> Rotations and responses to the drive increment are scale-free. A step
!> that passes both but crosses collinear with a large turn is to be
!> verified (by two half steps): endpoint data cannot tell a crossing from a
!> jump over a near-toggle onto the mirror branch.
module fekap_fem_branch
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, analysis_error
   use fekap_model, only: model_type, dof_rot
   use fekap_assembly_mesh, only: mesh_type, describe_dof
   use fekap_stepping_jump, only: jump_ratio, jump_bound_ratio, collinear_crossing, crossing_none, crossing_against, &
      & verify_turn, max_verify_depth, verify_predicted
   implicit none
   private

   public :: branch_check_type, new_branch_check, drive_increment, branch_verdict
   ! The magnitude rule (fekap_stepping_jump), for this module's users.
   public :: jump_ratio, jump_bound_ratio
   ! The verification's depth (fekap_stepping_jump), for fekap_fem_verification.
   public :: max_verify_depth

   !> Verdicts of branch_verdict: accept the step; reject it (cut it); accept
   !> it pending verification by two half steps; reject it for good (a step
   !> halved max_verify_depth times is still suspect: cutting cannot help).
   integer, parameter, public :: branch_accept = 0, branch_reject = 1, branch_verify = 2, branch_unverifiable = 3

   !> What the check knows of the mechanism, found once.
   type :: branch_check_type
      !> Length of the shortest link, the unit of translation drives.
      real(dp) :: shortest_link = 1
      !> (4, npairs): link ends hinged to each other (link, end, link, end),
      !> for the collinear crossings.
      integer, allocatable :: hinge_pairs(:, :)
      !> The rotation dofs, in increasing order (the magnitude rule's).
      integer, allocatable :: rotations(:)
      !> Of each hinge pair: the rotation dofs of its two link ends (2,
      !> npairs), and the difference of the two links' initial angles, the
      !> relative angle's constant part (found once: hinge_flip's per step).
      integer, allocatable :: pair_rot(:, :)
      real(dp), allocatable :: pair_angle0(:)
   end type branch_check_type

contains

   !> The check for a model and its mesh.
   subroutine new_branch_check(self, model, mesh)
      type(branch_check_type), intent(out) :: self
      type(model_type), intent(in) :: model
      type(mesh_type), intent(in) :: mesh
      integer :: i
      self%shortest_link = huge(1.0_dp)
      do i = 1, size(model%links)
         self%shortest_link = min(self%shortest_link, norm2(model%nodes(model%links(i)%node(2))%x - &
            & model%nodes(model%links(i)%node(1))%x))
      end do
      call find_hinge_pairs(model, mesh, self%hinge_pairs)
      allocate (self%pair_rot(2, size(self%hinge_pairs, 2)), self%pair_angle0(size(self%hinge_pairs, 2)))
      do i = 1, size(self%hinge_pairs, 2)
         associate (l1 => self%hinge_pairs(1, i), e1 => self%hinge_pairs(2, i), l2 => self%hinge_pairs(3, i), &
            & e2 => self%hinge_pairs(4, i))
            self%pair_rot(:, i) = [mesh%link_rot(e1, l1), mesh%link_rot(e2, l2)]
            self%pair_angle0(i) = mesh%link_angle0(l1) - mesh%link_angle0(l2)
         end associate
      end do
      self%rotations = pack([(i, i=1, mesh%ndof)], mesh%dof_kind(1:mesh%ndof) == dof_rot)
   end subroutine new_branch_check

   !> The drive increment dd from q to qt (read off the driven dofs), and its
   !> size `floor`: rotation drives in radians, translation drives in lengths
   !> of the shortest link.
   subroutine drive_increment(self, mesh, q, qt, dd, floor_)
      type(branch_check_type), intent(in) :: self
      type(mesh_type), intent(in) :: mesh
      real(dp), contiguous, intent(in) :: q(:), qt(:)
      real(dp), intent(out) :: floor_
      real(dp), contiguous, intent(out) :: dd(:)
      integer :: j
      floor_ = 0
      do j = 1, mesh%ndriven
         dd(j) = qt(mesh%driven_dof(j)) - q(mesh%driven_dof(j))
         if (mesh%dof_kind(mesh%driven_dof(j)) == dof_rot) then
            floor_ = max(floor_, abs(dd(j)))
         else
            floor_ = max(floor_, abs(dd(j))/self%shortest_link)
         end if
      end do
   end subroutine drive_increment

   !> The verdict on the step at time t from q to qt, given the linear
   !> responses dq_old and dq_new to its drive increment (of size floor_) at
   !> the two ends (zero where not known). smooth: q_predicted was a smooth
   !> extrapolation (Hermite or Adams) of the last configurations. can_verify:
   !> the step may still be halved for verification. A rejection comes with
   !> its message in `error`; a step to verify with the crossing pair (link,
   !> link, node) and its turn.
   subroutine branch_verdict(self, mesh, model, t, q, qt, dq_old, dq_new, floor_, smooth, q_predicted, can_verify, &
      & verdict, error, crossing, turn)
      type(branch_check_type), intent(in) :: self
      type(mesh_type), intent(in) :: mesh
      type(model_type), intent(in) :: model
      real(dp), intent(in) :: t, floor_
      real(dp), contiguous, intent(in) :: q(:), qt(:), dq_old(:), dq_new(:)
      logical, intent(in) :: smooth
      real(dp), contiguous, intent(in) :: q_predicted(:)
      logical, intent(in) :: can_verify
      integer, intent(out) :: verdict
      type(error_type), allocatable, intent(out) :: error
      integer, intent(out) :: crossing(3)
      real(dp), intent(out) :: turn
      real(dp) :: ratio, worst
      integer :: i, j, worst_dof, flip_link(2), flip_node
      character(len=200) :: msg
      worst = 0
      worst_dof = 0
      do j = 1, size(self%rotations)
         i = self%rotations(j)
         ratio = jump_bound_ratio(qt(i) - q(i), dq_old(i), dq_new(i), floor_, model%analysis%length_tol)
         if (ratio > worst) then
            worst = ratio
            worst_dof = i
         end if
      end do
      call hinge_flip(self, model, q, qt, dq_old, dq_new, flip_link, flip_node, turn, crossing)
      verdict = branch_reject
      if (worst > jump_ratio) then
         write (msg, '(a,es12.5,a,f9.4,a,es9.2,a)') 't = ', t, ': assembly-mode jump rejected (rotation ', &
            & qt(worst_dof) - q(worst_dof), ' rad over the step, ', worst, &
            & ' times what the drive increment explains) at'
         call analysis_error(error, trim(msg)//' '//describe_dof(mesh, model, worst_dof), t=t)
         return
      end if
      if (flip_link(1) > 0) then
         write (msg, '(a,es12.5,a)') 't = ', t, ': assembly-mode jump rejected (links'
         call analysis_error(error, trim(msg)//' '//model%links(flip_link(1))%name//' and '// &
            & model%links(flip_link(2))%name//' at node '//model%nodes(flip_node)%name// &
            & ' passed through collinear against the drive increment''s sense)', t=t)
         return
      end if
      verdict = branch_accept
      ! Unless the crossing pair turns by less than verify_turn, or the step
      ! continues a smooth prediction, have it confirmed by two half steps.
      if (turn > verify_turn .and. .not. predicted_step(mesh, qt, q_predicted, smooth, turn)) then
         verdict = branch_verify
         if (.not. can_verify) then
            write (msg, '(a,es12.5,a,f7.4,a,i0,a)') 't = ', t, ': assembly-mode jump rejected (links '// &
               & model%links(crossing(1))%name//' and '//model%links(crossing(2))%name// &
               & ' crossed collinear turning ', turn, ' rad in a step halved ', max_verify_depth, ' times)'
            call analysis_error(error, trim(msg), t=t)
            verdict = branch_unverifiable
         end if
      end if
   end subroutine branch_verdict

   !> Whether the step to qt was predicted: a smooth extrapolation q_predicted
   !> of the last configurations and velocities lies within verify_predicted *
   !> turn of qt in every rotation. The step then continues the resolved path;
   !> landing on the mirror branch would need an extrapolation error of twice
   !> the closest approach to collinear.
   pure logical function predicted_step(mesh, qt, q_predicted, smooth, turn) result(predicted)
      type(mesh_type), intent(in) :: mesh
      real(dp), contiguous, intent(in) :: qt(:), q_predicted(:)
      logical, intent(in) :: smooth
      real(dp), intent(in) :: turn
      integer :: i
      predicted = smooth
      if (.not. predicted) return
      do i = 1, mesh%ndof
         if (mesh%dof_kind(i) /= dof_rot) cycle
         if (abs(qt(i) - q_predicted(i)) > verify_predicted*turn) then
            predicted = .false.
            return
         end if
      end do
   end function predicted_step

   !> Orientation part of the check. Two links hinged at a node have a
   !> relative angle psi; in a continuous motion psi crosses k pi (the links
   !> collinear) in the sense in which the drive increment moves it. A jump
   !> to the mirror assembly mode near a flattened configuration (a fold)
   !> crosses against the linear response at the start or at the end of the
   !> step. Returns the first such pair of links (flip_link(1) = 0 if none)
   !> and their node. A zero response (not known) does not object. Also
   !> returns the largest turn |psi_1 - psi_0| of a pair that crossed
   !> collinear in the sense of the responses (0 if none did), and that pair
   !> (link, link, node).
   pure subroutine hinge_flip(self, model, q, qt, dq_old, dq_new, flip_link, flip_node, turn, crossing)
      type(branch_check_type), intent(in) :: self
      type(model_type), intent(in) :: model
      real(dp), contiguous, intent(in) :: q(:), qt(:), dq_old(:), dq_new(:)
      integer, intent(out) :: flip_link(2), flip_node
      real(dp), intent(out) :: turn
      integer, intent(out) :: crossing(3)
      integer :: k, l1, l2, e1, r1, r2, outcome
      real(dp) :: psi0, psi1
      flip_link = 0
      flip_node = 0
      turn = 0
      crossing = 0
      associate (links => model%links)
         do k = 1, size(self%hinge_pairs, 2)
            r1 = self%pair_rot(1, k)
            r2 = self%pair_rot(2, k)
            ! (angle0(l1) - angle0(l2)) + q(r1) - q(r2), as written out before: the same sums.
            psi0 = self%pair_angle0(k) + q(r1) - q(r2)
            psi1 = self%pair_angle0(k) + qt(r1) - qt(r2)
            outcome = collinear_crossing(psi0, psi1, dq_old(r1) - dq_old(r2), dq_new(r1) - dq_new(r2))
            if (outcome == crossing_none) cycle
            l1 = self%hinge_pairs(1, k)
            e1 = self%hinge_pairs(2, k)
            l2 = self%hinge_pairs(3, k)
            if (outcome == crossing_against) then
               flip_link = [l1, l2]
               flip_node = links(l1)%node(e1)
               return
            end if
            if (abs(psi1 - psi0) > turn) then
               turn = abs(psi1 - psi0)
               crossing = [l1, l2, links(l1)%node(e1)]
            end if
         end do
      end associate
   end subroutine hinge_flip

   !> The pairs of link ends that meet at a node with rotations of their own
   !> (hinged, not welded), found once through the ends at each node.
   subroutine find_hinge_pairs(model, mesh, hinge_pairs)
      type(model_type), intent(in) :: model
      type(mesh_type), intent(in) :: mesh
      integer, allocatable, intent(out) :: hinge_pairs(:, :)
      integer, allocatable :: ends_at(:), first(:), ends(:, :)
      integer :: nnode, l, e, node, i, j, npair
      nnode = size(model%nodes)
      allocate (ends_at(nnode), source=0)
      do l = 1, size(model%links)
         ends_at(model%links(l)%node) = ends_at(model%links(l)%node) + 1
      end do
      allocate (first(nnode + 1))
      first(1) = 1
      do node = 1, nnode
         first(node + 1) = first(node) + ends_at(node)
      end do
      ! ends(:, first(node):first(node+1)-1): (link, end) of every link end at node.
      allocate (ends(2, first(nnode + 1) - 1))
      ends_at = 0
      do l = 1, size(model%links)
         do e = 1, 2
            node = model%links(l)%node(e)
            ends(:, first(node) + ends_at(node)) = [l, e]
            ends_at(node) = ends_at(node) + 1
         end do
      end do
      npair = 0
      do node = 1, nnode
         do i = first(node), first(node + 1) - 1
            do j = i + 1, first(node + 1) - 1
               if (.not. welded(i, j)) npair = npair + 1
            end do
         end do
      end do
      allocate (hinge_pairs(4, npair))
      npair = 0
      do node = 1, nnode
         do i = first(node), first(node + 1) - 1
            do j = i + 1, first(node + 1) - 1
               if (welded(i, j)) cycle
               npair = npair + 1
               hinge_pairs(:, npair) = [ends(:, i), ends(:, j)]
            end do
         end do
      end do
   contains
      !> Whether the link ends i and j of `ends` share their rotation.
      logical function welded(i_, j_)
         integer, intent(in) :: i_, j_
         welded = mesh%link_rot(ends(2, i_), ends(1, i_)) == mesh%link_rot(ends(2, j_), ends(1, j_))
      end function welded
   end subroutine find_hinge_pairs

end module fekap_fem_branch
