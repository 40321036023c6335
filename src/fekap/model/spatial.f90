!> Model data of a spatial deck (ANALysis `type kinematics spatial`) beside
!> the planar model's names: each node's z, each section's 3D stiffnesses
!> and orientation vector, which links are trusses, the joints as double
!> nodes with their axes, and the drives of joint angles and strokes. The
!> nodes, links and sections themselves (names, x, y, end nodes, places in
!> the deck) are the model's own lists, index for index.
module fekap_model_spatial
   use fekap_kinds, only: dp
   use fekap_model_drive_law, only: law_type
   implicit none
   private

   public :: reported_joints

   !> Joint kinds; their names in the deck are joint_names, each at its code's place.
   integer, parameter, public :: joint_spherical = 1, joint_revolute = 2, joint_universal = 3, &
      & joint_prismatic = 4, joint_cylindrical = 5, joint_weld = 6
   character(*), parameter, public :: joint_names = 'spherical revolute universal prismatic cylindrical weld'

   !> A section's stiffnesses in its axes: EA, GA2, GA3, GJ, EI2, EI3 (a
   !> truss's section needs EA only), and the orientation vector that gives
   !> the section's axis 2 (NASTRAN's CBAR v; zero: not given).
   type, public :: spatial_section_type
      real(dp) :: c(6) = 0
      logical :: given(6) = .false.
      real(dp) :: orientation(3) = 0
   end type spatial_section_type

   !> A joint: two coincident nodes (node(2) = 0: the ground at node(1)'s
   !> place, `ground` written first or second: ground_first), its kind and
   !> axes in global coordinates at the deck's configuration.
   type, public :: spatial_joint_type
      character(:), allocatable :: name
      integer :: kind = 0
      integer :: node(2) = 0
      logical :: ground_first = .false.
      real(dp) :: axis(3) = 0, axis2(3) = 0
      !> A prismatic joint along a line of several segments (`fekap --spatial`
      !> on a planar slider on a chain of links): the two nodes of each
      !> segment, in order along the line, the first carrying it (node(1) is
      !> segments(1, 1)); its second node's point slides along them and its
      !> rotation is not held. Not allocated: one line, the joint's axis.
      integer, allocatable :: segments(:, :)
      !> The deck's place of the joint's line, for errors found later.
      character(:), allocatable :: file
      integer :: line = 0, col = 0
   end type spatial_joint_type

   !> A drive of a revolute joint's angle or a prismatic joint's stroke: the
   !> joint moves by law(t) - law(t_start) from the deck's configuration.
   type, public :: spatial_drive_type
      integer :: joint = 0
      !> Whether it drives the joint's stroke (prismatic, cylindrical), not its angle.
      logical :: stroke = .false.
      type(law_type) :: law
   end type spatial_drive_type

   type, public :: spatial_model_type
      !> z of each node of model%nodes.
      real(dp), allocatable :: z(:)
      !> One per model%sections.
      type(spatial_section_type), allocatable :: sections(:)
      !> One per model%links: a co-rotational truss (translations only) or a beam.
      logical, allocatable :: truss(:)
      type(spatial_joint_type), allocatable :: joints(:)
      type(spatial_drive_type), allocatable :: drives(:)
   end type spatial_model_type

contains

   !> The rows of joints.csv, in the deck's order: the joint of each row,
   !> and whether the row is its stroke (else its angle): a revolute joint's
   !> angle, a prismatic joint's stroke, a cylindrical joint's angle and then
   !> its stroke (the row named JOINT.stroke).
   pure subroutine reported_joints(spatial, list, stroke)
      type(spatial_model_type), intent(in) :: spatial
      integer, allocatable, intent(out) :: list(:)
      logical, allocatable, intent(out) :: stroke(:)
      integer :: k
      allocate (list(0), stroke(0))
      if (.not. allocated(spatial%joints)) return
      do k = 1, size(spatial%joints)
         select case (spatial%joints(k)%kind)
         case (joint_revolute)
            list = [list, k]
            stroke = [stroke, .false.]
         case (joint_prismatic)
            list = [list, k]
            stroke = [stroke, .true.]
         case (joint_cylindrical)
            list = [list, k, k]
            stroke = [stroke, .false., .true.]
         case default                                    ! spherical, universal, weld: not reported
         end select
      end do
   end subroutine reported_joints

end module fekap_model_spatial
