!> Before the first step: is every motion of the mechanism held by its
!> supports, drives and links? A kinematic, kinetostatic or static FEM run
!> finds each configuration as the stress-free (or loaded) solution of the
!> finite element equations; a part that can move without straining an
!> element (a four-bar without SUPPorts, a second four-bar that nothing
!> drives) has no determined configuration, and its tangent is singular at
!> every configuration, not only at a change point.
!>
!> The test counts, for each connected part of the mesh (the free dofs
!> joined by elements and sliding joints), Grubler's way: its free dofs less
!> the equations that can hold them, each element at most 3 (a rigid plane
!> body: at most as many as the element's free dofs) and each sliding joint 1
!> (a prismatic joint 2). The equations' rank is at most their count, so a
!> part with more free dofs than equations moves at every configuration:
!> that is free motion, for any geometry, and the run is refused with the
!> part's nodes and links named. The count is linear in the mesh's size and
!> needs no factorisation (a factor's pivots cannot tell a long flexible
!> chain from a free one). It cannot see a free motion that only a special
!> geometry allows (an undriven parallelogram with a redundant bar): that is
!> found during the run (check_free_motion).
!>
!> During the run, at every accepted configuration whose tangent is singular,
!> check_free_motion tells a free motion from a change point. A change point
!> (a dead point, a bifurcation such as the A02 chains' flat configuration)
!> is singular at one time that the drives pass through; a free motion moves
!> a part with the drives held at every time. So the singular configuration
!> is probed (probe_free_motion: a finite move of 0.05 rad along the
!> tangent's kernel, corrected back onto unstrained links with that move
!> held), and where it moves freely, so must the run's configuration before
!> it, at an earlier time of the drives: then the run stops naming the part
!> that moves. One time alone does not decide: at the A02 chains' change
!> point a crank and a coupler of equal length meet at a ground pivot and
!> turn freely about it, but only at that instant.
module fekap_fem_determinacy
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, input_error, analysis_error
   use fekap_model, only: model_type, joint_prismatic
   use fekap_model_work, only: work_counts_type
   use fekap_assembly_mesh, only: mesh_type, dof_free
   use fekap_union_find, only: find_root, join
   use fekap_fem_linear_system, only: linear_system_type, assemble_system, residual_norm, factor_system, &
      & solve_system, apply_correction
   use fekap_fem_rates, only: singular_pivot
   use fekap_fem_state, only: fem_core_type
   use fekap_fem_factor, only: accepted_pivot
   implicit none
   private

   public :: check_determined, check_free_motion, probe_free_motion

   !> Most nodes and links named in the message.
   integer, parameter :: max_named = 12
   !> The probe's move along the kernel: its largest rotation, or translation
   !> per model size. Large against the strains a change point's neighbour
   !> moves freely with (the move times its distance from the change point)
   !> and small enough for Newton to follow a free motion's curvature.
   real(dp), parameter :: probe_turn = 0.05_dp
   !> Diagonal shift of the probe's tangent, relative to its largest
   !> diagonal entry (as change_point's fill_shift): it makes the singular
   !> tangent factorable and leaves the corrections in its range exact.
   real(dp), parameter :: probe_shift = 1.0e-8_dp
   !> Inverse iterations for the kernel (the shift puts the kernel's
   !> eigenvalue 1e8 times below the next one: one would do), and the
   !> corrections of the probe at most.
   integer, parameter :: kernel_iterations = 3, probe_iterations = 15
   !> A pivot ratio below which the probe looks, whatever the run's largest:
   !> a run singular from its start (a free motion moves at every time) has
   !> a singular reference too, which the listing's relative test then
   !> misses. A tangent with a null direction has round-off's ratio (1e-14
   !> and below in the hard decks); regular ones of the shipped decks have
   !> 1e-8 and above (slender meshed links: bending against shear stiffness).
   real(dp), parameter :: probe_pivot = 1.0e-12_dp
   !> A dof moves in the free motion if its share of the move is above this.
   real(dp), parameter :: moved_share = 1.0e-3_dp

contains

   !> An input error naming the nodes and links of every part of the mesh
   !> that can move freely (see the module's header).
   subroutine check_determined(mesh, model, error)
      type(mesh_type), intent(in) :: mesh
      type(model_type), intent(in) :: model
      type(error_type), allocatable, intent(out) :: error
      integer, allocatable :: parent(:), balance(:)
      logical, allocatable :: free_part(:), named_node(:), named_link(:)
      integer :: dof, e, k, first, nfree_e, i, root, excess, nslide
      character(:), allocatable :: node_text, link_text
      character(len=12) :: num

      nslide = 0
      if (allocated(model%slidelines)) nslide = size(model%slidelines)
      allocate (parent(mesh%ndof), balance(mesh%ndof), source=0)
      parent = [(dof, dof=1, mesh%ndof)]
      ! Parts: free dofs joined by the elements and the sliding joints.
      do e = 1, size(mesh%elements)
         first = 0
         do k = 1, 6
            dof = mesh%edof(k, e)
            if (mesh%status(dof) /= dof_free) cycle
            if (first == 0) then
               first = dof
            else
               call join(parent, first, dof)
            end if
         end do
      end do
      do i = 1, nslide
         first = slide_dof(mesh, model, i)
         if (first == 0) cycle
         call each_slide_dof(i, first)
      end do

      ! The balance of each part, at its root: free dofs less equations.
      do dof = 1, mesh%ndof
         if (mesh%status(dof) == dof_free) balance(find_root(parent, dof)) = balance(find_root(parent, dof)) + 1
      end do
      do e = 1, size(mesh%elements)
         nfree_e = count(mesh%status(mesh%edof(:, e)) == dof_free)
         if (nfree_e == 0) cycle
         root = find_root(parent, first_free(e))
         balance(root) = balance(root) - min(3, nfree_e)
      end do
      do i = 1, nslide
         first = slide_dof(mesh, model, i)
         if (first == 0) cycle
         root = find_root(parent, first)
         balance(root) = balance(root) - merge(2, 1, model%slidelines(i)%kind == joint_prismatic)
      end do

      allocate (free_part(mesh%ndof), source=.false.)
      do dof = 1, mesh%ndof
         if (parent(dof) == dof .and. mesh%status(dof) == dof_free) free_part(dof) = balance(dof) > 0
      end do
      if (.not. any(free_part)) return

      ! The nodes and links of the free parts.
      allocate (named_node(size(model%nodes)), named_link(size(model%links)), source=.false.)
      do i = 1, size(model%nodes)
         do k = 1, 2
            dof = mesh%tdof(k, i)
            if (mesh%status(dof) == dof_free) then
               if (free_part(find_root(parent, dof))) named_node(i) = .true.
            end if
         end do
      end do
      do e = 1, size(mesh%elements)
         if (count(mesh%status(mesh%edof(:, e)) == dof_free) == 0) cycle
         if (free_part(find_root(parent, first_free(e)))) named_link(mesh%elink(e)) = .true.
      end do
      excess = 0
      do dof = 1, mesh%ndof
         if (free_part(dof)) excess = excess + balance(dof)
      end do
      node_text = listed_names(model, named_node, 'node')
      link_text = listed_names(model, named_link, 'link')
      write (num, '(i0)') excess
      call input_error(error, model%file//': the mechanism is not determined by its supports, drives and '// &
         & 'links: a part of it can move freely, at every configuration (at least '//trim(num)// &
         & ' degree'//trim(merge('s', ' ', excess > 1))//' of freedom that no SUPPorts, DRIVes or '// &
         & 'links hold): '//join_texts(node_text, link_text)//'; support or drive the part that moves, '// &
         & 'or remove it')

   contains

      !> Join the dofs of sliding joint i (the slave node, a prismatic
      !> joint's slave rotation, the master links' free dofs) to `first`.
      subroutine each_slide_dof(i, first)
         integer, intent(in) :: i, first
         integer :: j, e, k, dof
         associate (s => model%slidelines(i))
            do k = 1, 2
               dof = mesh%tdof(k, s%slave)
               if (mesh%status(dof) == dof_free) call join(parent, first, dof)
            end do
            if (s%kind == joint_prismatic .and. s%slave_link > 0) then
               do k = 1, 2
                  dof = mesh%link_rot(k, s%slave_link)
                  if (mesh%status(dof) == dof_free) call join(parent, first, dof)
               end do
            end if
            if (.not. allocated(s%master_links)) return
            do j = 1, size(s%master_links)
               do e = 1, size(mesh%elements)
                  if (mesh%elink(e) /= s%master_links(j)) cycle
                  do k = 1, 6
                     dof = mesh%edof(k, e)
                     if (mesh%status(dof) == dof_free) call join(parent, first, dof)
                  end do
               end do
            end do
         end associate
      end subroutine each_slide_dof

      !> The first free dof of element e (it has one).
      integer function first_free(e)
         integer, intent(in) :: e
         integer :: k
         first_free = 0
         do k = 1, 6
            if (mesh%status(mesh%edof(k, e)) == dof_free) then
               first_free = mesh%edof(k, e)
               return
            end if
         end do
      end function first_free

   end subroutine check_determined

   !> 'nodes A, B, C' of the marked entries of the model's nodes (what =
   !> 'node') or links: the first max_named, and how many more.
   function listed_names(model, marked, what) result(text)
      type(model_type), intent(in) :: model
      logical, intent(in) :: marked(:)
      character(*), intent(in) :: what
      character(:), allocatable :: text
      integer :: i, n, total
      character(len=12) :: more
      text = ''
      total = count(marked)
      if (total == 0) return
      n = 0
      do i = 1, size(marked)
         if (.not. marked(i)) cycle
         n = n + 1
         if (n > max_named) exit
         if (n > 1) text = text//', '
         if (what == 'node') then
            text = text//model%nodes(i)%name
         else
            text = text//model%links(i)%name
         end if
      end do
      if (total > max_named) then
         write (more, '(i0)') total - max_named
         text = text//' and '//trim(more)//' more'
      end if
      text = what//trim(merge('s', ' ', total > 1))//' '//text
   end function listed_names

   !> After a run's step to the accepted state from time t_from (fekap_fem's
   !> advance_to): if it failed (error), free_start_error; if it advanced,
   !> accepted_free_motion (see the module's header).
   subroutine check_free_motion(self, t_from, error)
      class(fem_core_type), intent(inout) :: self
      real(dp), intent(in) :: t_from
      type(error_type), allocatable, intent(inout) :: error
      if (allocated(error)) then
         call free_start_error(self, error)
      else if (self%state%t > t_from) then
         call accepted_free_motion(self, error)
      end if
   end subroutine check_free_motion

   !> During a run (see the module's header): at the accepted configuration,
   !> if its tangent is singular (as the listing's note says: the pivot ratio
   !> of the factor the rates used, against the run's largest; or below
   !> probe_pivot) and a part
   !> moves freely there with the drives held, and also at the configuration
   !> accepted before it, an analysis error naming that part's nodes and
   !> links. Unloaded runs only: a loaded structure's configurations are
   !> strained, and its failures are limit loads. The stepper's state and
   !> factor are left as they are (the probe works on a copy).
   subroutine accepted_free_motion(self, error)
      class(fem_core_type), intent(inout) :: self
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: ratio
      if (self%loaded) return
      if (.not. self%factor%is_singular()) then
         if (.not. self%factor%is_current()) return
         ratio = accepted_pivot(self)
         if (.not. (singular_pivot(ratio, self%state%reference_pivot) .or. ratio < probe_pivot)) return
      end if
      ! Singular (rare): the probes, in a procedure of their own so that the
      ! regular step's path stays a few comparisons.
      call singular_free_motion(self, error)
   end subroutine accepted_free_motion

   !> accepted_free_motion at a singular configuration: its probe and that of
   !> the configuration accepted before it.
   subroutine singular_free_motion(self, error)
      class(fem_core_type), intent(inout) :: self
      type(error_type), allocatable, intent(out) :: error
      logical, allocatable :: moved(:), moved_before(:)
      logical :: free
      integer :: before
      character(len=12) :: now, then
      associate (state => self%state, history => self%state%history)
         if (history%filled < 2) return
         before = history%column(2)
         if (.not. history%t(before) < state%t) return
         call probe_free_motion(self%system, self%mesh, state%q, state%t, state%seg, self%dof_length, &
            & self%model_length, self%conv%length, self%admissible_strain, free, moved)
         if (.not. free) return
         call probe_free_motion(self%system, self%mesh, history%q(:, before), history%t(before), state%seg, &
            & self%dof_length, self%model_length, self%conv%length, self%admissible_strain, free, moved_before)
         if (.not. free) return
         write (now, '(es12.5)') state%t
         write (then, '(es12.5)') history%t(before)
      end associate
      call analysis_error(error, 't = '//now//': the mechanism is not determined by its supports, drives and '// &
         & 'links: with the drives held, a part of it moves freely here and at t = '//then//' (a free motion, '// &
         & 'not a change point that the drives pass through): '//moved_parts(self%mesh, self%model, moved)// &
         & '; support or drive the part that moves, or remove it', t=self%state%t)
   end subroutine singular_free_motion

   !> A run whose first step failed (error, after its cuts) from a start
   !> configuration that moves freely with the drives held: the drives' path
   !> does not determine where the mechanism goes from there (a change point
   !> met at the start, as a chain of parallelograms started flat, or a free
   !> motion), which no dead point nor step size explains. The error then
   !> says so and names the part that moves; otherwise it is left as it is.
   subroutine free_start_error(self, error)
      class(fem_core_type), intent(inout) :: self
      type(error_type), allocatable, intent(inout) :: error
      logical, allocatable :: moved(:)
      logical :: free
      character(len=12) :: start
      if (.not. allocated(error) .or. self%loaded) return
      if (self%state%t /= self%model%analysis%t_start) return
      call probe_free_motion(self%system, self%mesh, self%state%q, self%state%t, self%state%seg, &
         & self%dof_length, self%model_length, self%conv%length, self%admissible_strain, free, moved)
      if (.not. free) return
      write (start, '(es12.5)') self%state%t
      deallocate (error)
      call analysis_error(error, 'the run cannot leave its start: at t = '//start// &
         & ' a part of the mechanism moves freely with the drives held ('// &
         & moved_parts(self%mesh, self%model, moved)//'), so the drives do not determine where it goes '// &
         & '(a change point at the start, as a chain of parallelograms started flat, or a free motion); a '// &
         & 'smaller time step will not help: start the run away from this configuration, or support or drive '// &
         & 'the part that moves')
   end subroutine free_start_error

   !> Whether configuration q at time t (its drives and supports held) moves
   !> freely: the lowest mode of its material tangent (inverse iteration
   !> with the shifted factor) is taken as a move of probe_turn, and the
   !> positions are corrected by Newton, the move's own component held (the
   !> correction projected off it), until a correction is below `length`
   !> (dofs weighted by dof_length); free if that converges to an
   !> unstrained configuration (every element strained less than
   !> `admissible`). moved marks the dofs of the move. `system` is not
   !> changed: the probe assembles and factors a copy.
   subroutine probe_free_motion(system, mesh, q, t, seg, dof_length, model_length, length, admissible, free, moved)
      type(linear_system_type), intent(in) :: system
      type(mesh_type), intent(in) :: mesh
      real(dp), contiguous, intent(in) :: q(:)
      real(dp), intent(in) :: t, model_length, length, admissible
      integer, intent(in) :: seg(:)
      real(dp), contiguous, intent(in) :: dof_length(:)
      logical, intent(out) :: free
      logical, allocatable, intent(out) :: moved(:)
      type(linear_system_type) :: probe
      type(work_counts_type) :: counts
      real(dp), allocatable :: qp(:), mode(:), weight(:), d(:)
      real(dp) :: scale, correction, norm
      integer :: k, it, info
      free = .false.
      allocate (moved(mesh%ndof), source=.false.)
      if (mesh%nfree == 0) return
      probe = system
      probe%timing = .false.
      qp = q
      ! The rotations in radians, the translations per model size.
      weight = dof_length(mesh%eq_dof)/model_length
      ! The lowest mode: inverse iteration from a start with a part along any mode.
      call shifted_factor(probe, qp, info)
      if (info /= 0) return
      mode = [(1 + 0.5_dp*sin(real(k, dp)), k=1, mesh%nfree)]
      do it = 1, kernel_iterations
         probe%rhs(:, 1) = mode
         call solve_system(probe, counts)
         scale = maxval(abs(probe%rhs(:, 1)))
         if (.not. (scale > 0 .and. scale <= huge(1.0_dp))) return
         mode = probe%rhs(:, 1)/scale
      end do
      scale = maxval(abs(mode)*weight)
      if (.not. scale > 0) return
      mode = mode*(probe_turn/scale)
      norm = dot_product(mode, mode)
      do k = 1, mesh%nfree
         qp(mesh%eq_dof(k)) = qp(mesh%eq_dof(k)) + mode(k)
         moved(mesh%eq_dof(k)) = abs(mode(k))*weight(k) > moved_share*probe_turn
      end do
      ! Back onto the links, the move held.
      do it = 1, probe_iterations
         call shifted_factor(probe, qp, info)
         if (info /= 0) return
         call solve_system(probe, counts)
         d = probe%rhs(:, 1)
         d = d - (dot_product(mode, d)/norm)*mode
         probe%rhs(:, 1) = d
         call apply_correction(probe, mesh, qp)
         correction = maxval(abs(d)*dof_length(mesh%eq_dof))
         if (.not. correction <= huge(1.0_dp)) return
         if (correction <= length) exit
      end do
      if (correction > length) return
      call assemble_system(probe, mesh, qp, t, seg, huge(1.0_dp), counts)
      free = probe%assembled_strain <= admissible

   contains

      !> The material tangent at x, shifted by probe_shift of its largest
      !> diagonal entry, factored; the negated residual in rhs.
      subroutine shifted_factor(probe, x, info)
         type(linear_system_type), intent(inout) :: probe
         real(dp), contiguous, intent(in) :: x(:)
         integer, intent(out) :: info
         real(dp) :: residual
         call assemble_system(probe, mesh, x, t, seg, huge(1.0_dp), counts)
         residual = residual_norm(probe, mesh)
         associate (diag => probe%kff%a(probe%kff%kd + 1, :))
            diag = diag + probe_shift*maxval(diag)
         end associate
         call factor_system(probe, info, counts)
      end subroutine shifted_factor
   end subroutine probe_free_motion

   !> 'nodes A, B; links AB, BC' of the dofs marked in moved: the nodes whose
   !> translations move, the links with an element whose dofs move.
   function moved_parts(mesh, model, moved) result(text)
      type(mesh_type), intent(in) :: mesh
      type(model_type), intent(in) :: model
      logical, intent(in) :: moved(:)
      character(:), allocatable :: text
      logical, allocatable :: named_node(:), named_link(:)
      integer :: i, e
      allocate (named_node(size(model%nodes)), named_link(size(model%links)), source=.false.)
      do i = 1, size(model%nodes)
         named_node(i) = any(moved(mesh%tdof(:, i)))
      end do
      do e = 1, size(mesh%elements)
         if (any(moved(mesh%edof(:, e)))) named_link(mesh%elink(e)) = .true.
      end do
      text = join_texts(listed_names(model, named_node, 'node'), listed_names(model, named_link, 'link'))
   end function moved_parts

   !> 'A; B', 'A' or 'B' of two texts ('' left out).
   pure function join_texts(a, b) result(text)
      character(*), intent(in) :: a, b
      character(:), allocatable :: text
      if (len(a) > 0 .and. len(b) > 0) then
         text = a//'; '//b
      else
         text = a//b
      end if
   end function join_texts

   !> A free dof of sliding joint i's slave node, prismatic rotation or
   !> master links, 0 when it has none (everything it touches is held).
   integer function slide_dof(mesh, model, i) result(dof)
      type(mesh_type), intent(in) :: mesh
      type(model_type), intent(in) :: model
      integer, intent(in) :: i
      integer :: k, j, e
      associate (s => model%slidelines(i))
         do k = 1, 2
            dof = mesh%tdof(k, s%slave)
            if (mesh%status(dof) == dof_free) return
         end do
         if (s%kind == joint_prismatic .and. s%slave_link > 0) then
            do k = 1, 2
               dof = mesh%link_rot(k, s%slave_link)
               if (mesh%status(dof) == dof_free) return
            end do
         end if
         if (allocated(s%master_links)) then
            do j = 1, size(s%master_links)
               do e = 1, size(mesh%elements)
                  if (mesh%elink(e) /= s%master_links(j)) cycle
                  do k = 1, 6
                     dof = mesh%edof(k, e)
                     if (mesh%status(dof) == dof_free) return
                  end do
               end do
            end do
         end if
      end associate
      dof = 0
   end function slide_dof

end module fekap_fem_determinacy
