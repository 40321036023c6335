!> What every analysis method delivers at each step, whatever its unknowns:
!> positions, velocities and accelerations of all named nodes and the angle,
!> angular velocity and angular acceleration of every link.
module fekap_model_results
   use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
   use fekap_kinds, only: dp
   implicit none
   private

   public :: step_result_type, new_step_result, fill_fields_from_nodes, has_note, not_finite

   !> Length of a step's note for the listing (fixed-length: gfortran 12 has had
   !> bugs with deferred-length character components of derived types).
   integer, parameter, public :: note_length = 400

   !> What not_finite's index names.
   character(len=*), parameter, public :: result_kinds(4) = [character(len=31) :: 'positions', 'velocities', &
      & 'accelerations', 'forces, deflections or energies']

   type :: step_result_type
      integer :: step = 0
      real(dp) :: t = 0
      !> Newton iterations (linear solves) of this step.
      integer :: iterations = 0
      !> Norm of the residual at the accepted configuration.
      real(dp) :: residual = 0
      !> Times the step was cut in halves to converge.
      integer :: cuts = 0
      !> The (sub-)steps of this step accepted at the round-off floor with the
      !> residual above the tolerance (the FEM, the classical methods,
      !> dynamics); -1: not reported (steps.csv's `floor` column is written
      !> only for results that report it: not the spatial kinematics').
      integer :: floor = -1
      !> Dynamics: the largest local error estimate (a length) of the step's
      !> (sub-)steps (fekap_dynamics_local_error); negative: not reported
      !> (steps.csv's `error_estimate` column is written only for results that report it).
      real(dp) :: estimate = -1
      !> Whether the run writes this step's rows (set by the time loop): a
      !> stepper may leave the rows' values of a step not written unfilled.
      logical :: written = .true.
      !> A remark for the listing (a near-singular configuration, rates left
      !> out), or empty; left-aligned, so that has_note can tell at once.
      character(len=note_length) :: note = ''
      logical :: has_velocity = .false.
      logical :: has_acceleration = .false.
      !> (2, number of nodes): x, y of every model node.
      real(dp), allocatable :: pos(:, :), vel(:, :), acc(:, :)
      !> (number of links): direction angle (radians, not wrapped) and its rates.
      real(dp), allocatable :: angle(:), omega(:), alpha(:)
      !> (2, interior points): x, y of the interior points of the meshed links
      !> (the mesh's points after the model's nodes), filled by the finite
      !> element method when the run writes them (output%mesh_nodes).
      real(dp), allocatable :: interior(:, :)
      !> Field output (filled only when the deck asks for VTK files): the
      !> analysis mesh's points (2, npoint; the VTK writer of a spatial run,
      !> whose stepper fills none, makes them (3, npoint)) with their velocities and
      !> accelerations, its line cells (2, ncell) as point indices, the link of
      !> each cell, and each cell's stress resultants (N, V, M) (3, ncell).
      !> The finite element method gives its elements; the classical methods
      !> the model's nodes and links (with zero resultants).
      real(dp), allocatable :: mesh_pos(:, :), mesh_vel(:, :), mesh_acc(:, :)
      integer, allocatable :: cells(:, :), cell_link(:)
      real(dp), allocatable :: cell_force(:, :)
      !> Kinetostatics (filled only when the run simulates it): the
      !> reactions (fx, fy, m) of each row (see fekap_reactions_kinetostatics:
      !> drives, supports, then both ends of every link), and whether they are
      !> known at this step (not at a singular configuration).
      logical :: has_reactions = .false.
      real(dp), allocatable :: reactions(:, :)
      !> Dynamics (filled only when the run simulates it): energies, work and
      !> momenta (see fekap_dynamics_dynamic_stepper's energy_names).
      logical :: has_energy = .false.
      real(dp), allocatable :: energy(:)
      !> Kinetostatics with OUTPut deflection: the elastic deflection (ux, uy)
      !> of every node (2, number of nodes), and whether it is known at this step.
      logical :: has_deflection = .false.
      real(dp), allocatable :: deflection(:, :)
      !> Spatial runs only (allocated by the spatial stepper): z, its velocity
      !> and acceleration of every node, and each reported joint's motion
      !> (3, joints): angle (stroke), rate and second rate (fekap_spatial_build).
      real(dp), allocatable :: pos_z(:), vel_z(:), acc_z(:)
      real(dp), allocatable :: joint_motion(:, :)
      !> Spatial runs only: each link's rotation, a unit quaternion (4, links)
      !> with its sign kept continuous, and its angular velocity and
      !> acceleration in global axes (3, links) (fekap_spatial_link_motion).
      real(dp), allocatable :: link_rotation(:, :), link_omega(:, :), link_alpha(:, :)
   end type step_result_type

contains

   !> Whether a note text (left-aligned, as every note is written) holds a
   !> note: its first character is not blank. (len_trim would scan all
   !> note_length characters of an empty note, every step; so did the
   !> comparison note(1:1) /= ' ', through the run-time library's
   !> len_trim, four times a step: the character's code is compared.)
   pure logical function has_note(note)
      character(*), intent(in) :: note
      has_note = len(note) > 0
      if (has_note) has_note = iachar(note(1:1)) /= iachar(' ')
   end function has_note

   !> Which of a step's results is not a finite number (NaN or infinity: a
   !> failure that the method's own checks missed), as an index into
   !> result_kinds for the time loop's error; 0 if every value is finite.
   !> Rates are looked at where the step has them, the optional parts where
   !> they are allocated. A sum finds such a value at the cost of its
   !> additions (finite values sum to infinity only beyond huge, no result
   !> either); ieee_is_finite, unlike a comparison, raises no
   !> invalid-operation flag on a NaN.
   pure integer function not_finite(result) result(kind)
      type(step_result_type), intent(in) :: result
      real(dp) :: s
      ! A result without optional parts (a kinematic step's): the kinds'
      ! sums below, the same values in the same order, without
      ! motion_total's descriptors of the optional parts.
      if (no_optional_parts(result)) then
         kind = 1
         s = total(result%pos, size(result%pos)) + total(result%angle, size(result%angle)) + result%residual
         if (.not. ieee_is_finite(s)) return
         kind = 2
         if (result%has_velocity) then
            s = total(result%vel, size(result%vel)) + total(result%omega, size(result%omega))
            if (.not. ieee_is_finite(s)) return
         end if
         kind = 3
         if (result%has_acceleration) then
            s = total(result%acc, size(result%acc)) + total(result%alpha, size(result%alpha))
            if (.not. ieee_is_finite(s)) return
         end if
         kind = 0
         return
      end if
      kind = 1
      s = motion_total(result%pos, result%angle, result%pos_z, result%joint_motion, 1, result%link_rotation, &
         & result%mesh_pos) + result%residual
      if (allocated(result%interior)) s = s + total(result%interior, size(result%interior))
      if (.not. ieee_is_finite(s)) return
      kind = 2
      if (result%has_velocity) then
         s = motion_total(result%vel, result%omega, result%vel_z, result%joint_motion, 2, result%link_omega, &
            & result%mesh_vel)
         if (.not. ieee_is_finite(s)) return
      end if
      kind = 3
      if (result%has_acceleration) then
         s = motion_total(result%acc, result%alpha, result%acc_z, result%joint_motion, 3, result%link_alpha, &
            & result%mesh_acc)
         if (.not. ieee_is_finite(s)) return
      end if
      kind = 4
      s = 0
      if (allocated(result%cell_force)) s = s + total(result%cell_force, size(result%cell_force))
      if (result%has_reactions) s = s + total(result%reactions, size(result%reactions))
      if (result%has_deflection) s = s + total(result%deflection, size(result%deflection))
      if (result%has_energy) s = s + total(result%energy, size(result%energy))
      if (.not. ieee_is_finite(s)) return
      kind = 0
   end function not_finite

   !> The sum of one kind of motion (positions, or a rate) over a result's
   !> parts: nodes, links, and where allocated the nodes' z, row `row` of
   !> the joints' motion, the links' spatial rotation (or its rate) and the
   !> mesh's points.
   pure real(dp) function motion_total(nodes, links, z, joints, row, spatial_links, mesh) result(s)
      real(dp), contiguous, intent(in) :: nodes(:, :), links(:)
      real(dp), allocatable, intent(in) :: z(:), joints(:, :), spatial_links(:, :), mesh(:, :)
      integer, intent(in) :: row
      s = total(nodes, size(nodes)) + total(links, size(links))
      if (allocated(z)) s = s + total(z, size(z))
      if (allocated(joints)) s = s + sum(joints(row, :))
      if (allocated(spatial_links)) s = s + total(spatial_links, size(spatial_links))
      if (allocated(mesh)) s = s + total(mesh, size(mesh))
   end function motion_total

   !> Whether a result has none of the optional parts that not_finite looks at.
   pure logical function no_optional_parts(result)
      type(step_result_type), intent(in) :: result
      no_optional_parts = .not. (allocated(result%interior) .or. allocated(result%pos_z) .or. &
         & allocated(result%vel_z) .or. allocated(result%acc_z) .or. allocated(result%joint_motion) .or. &
         & allocated(result%link_rotation) .or. allocated(result%link_omega) .or. allocated(result%link_alpha) .or. &
         & allocated(result%mesh_pos) .or. allocated(result%mesh_vel) .or. allocated(result%mesh_acc) .or. &
         & allocated(result%cell_force) .or. result%has_reactions .or. result%has_deflection .or. result%has_energy)
   end function no_optional_parts

   !> The sum of the n values of x, a whole array of any rank (contiguous:
   !> an allocatable component), in a plain loop: the sum intrinsic on the
   !> results' small two-dimensional arrays costs several times more.
   pure real(dp) function total(x, n)
      integer, intent(in) :: n
      real(dp), intent(in) :: x(n)
      integer :: i
      total = 0
      do i = 1, n
         total = total + x(i)
      end do
   end function total

   !> Allocate a zeroed result for a model with nnode nodes and nlink links.
   pure subroutine new_step_result(self, nnode, nlink)
      type(step_result_type), intent(out) :: self
      integer, intent(in) :: nnode, nlink
      allocate (self%pos(2, nnode), self%vel(2, nnode), self%acc(2, nnode), source=0.0_dp)
      allocate (self%angle(nlink), self%omega(nlink), self%alpha(nlink), source=0.0_dp)
   end subroutine new_step_result

   !> The field output of a method without a mesh (the classical methods):
   !> points are the model's nodes, cells its links (cell l is link l), and
   !> the stress resultants are zero (rigid links carry no computed forces).
   pure subroutine fill_fields_from_nodes(result, links_nodes)
      type(step_result_type), intent(inout) :: result
      !> (2, number of links): indices into the nodes of each link's ends.
      integer, intent(in) :: links_nodes(:, :)
      integer :: l
      result%mesh_pos = result%pos
      result%mesh_vel = result%vel
      result%mesh_acc = result%acc
      ! The cells do not change from step to step: set once.
      if (allocated(result%cell_force)) return
      result%cells = links_nodes
      result%cell_link = [(l, l=1, size(links_nodes, 2))]
      allocate (result%cell_force(3, size(links_nodes, 2)), source=0.0_dp)
   end subroutine fill_fields_from_nodes

end module fekap_model_results
