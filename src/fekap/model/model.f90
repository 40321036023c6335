!> Model data as the deck states it: named nodes, sections, links, joints,
!> supports, drives, loads, slidelines, and the analysis and output settings.
!> The finite element mesh (element ends, degrees of freedom) is derived from
!> this by fekap_assembly_mesh; the classical methods read it directly.
module fekap_model
   use fekap_kinds, only: dp
   use fekap_model_drive_law, only: law_type
   use fekap_strings, only: same_name
   use fekap_model_spatial, only: spatial_model_type
   implicit none
   private

   public :: model_type, node_type, section_type, link_type, weld_type
   public :: support_type, drive_type, load_type, slideline_type, mass_type, start_velocity_type
   public :: analysis_type, output_type, source_loc_type, file_name_type, parameter_type
   public :: find_node, find_link, model_size, loc_file

   !> Degree-of-freedom kinds at a node.
   integer, parameter, public :: dof_x = 1, dof_y = 2, dof_rot = 3

   !> Analysis methods.
   integer, parameter, public :: method_fem = 1, method_cartesian = 2, method_angles = 3
   !> The methods' names, each at the position of its code: the deck and the
   !> command line both take a name, or a prefix of at least 4 letters of it,
   !> through word_index.
   character(*), parameter, public :: method_names = 'fem cartesian angles'
   !> Predictors: last converged configuration (the paper's), polynomial
   !> extrapolation of the last converged configurations (default), Taylor
   !> series from the last velocities and accelerations.
   integer, parameter, public :: predictor_previous = 1, predictor_extrapolate = 2, predictor_taylor = 3
   !> The predictors' names, each at the position of its code (as method_names).
   character(*), parameter, public :: predictor_names = 'previous extrapolate taylor'
   !> Convergence tests: the paper's ||P(i)||/||P(0)|| < tol, or FEKAP's
   !> default (residual against the drive-increment scale and a correction length test).
   integer, parameter, public :: convergence_paper = 1, convergence_default = 2
   !> Linear solvers of the finite element method: the symmetric band solver
   !> (default), or a dense LU of the same matrix (for comparison).
   integer, parameter, public :: solver_band = 1, solver_dense = 2
   !> Slideline kinds: the paper's pin-in-slot (slave rotation free) or a
   !> prismatic joint (slave link keeps its angle relative to the master).
   integer, parameter, public :: joint_pin_in_slot = 1, joint_prismatic = 2
   !> Effects a run simulates (ANALysis type): chosen from the deck (auto), pure
   !> kinematics, kinetostatics (drive and joint reactions of the computed
   !> motion), statics (equilibrium under loads) or dynamics (see fekap_model_effects).
   integer, parameter, public :: effects_auto = 0, effects_kinematics = 1, effects_kinetostatics = 2, &
      & effects_statics = 3, effects_dynamics = 4
   !> Time integrators of dynamics (ANALysis integrator): generalized-alpha (Chung & Hulbert 1993),
   !> energy-momentum (the midpoint rule with the beams' discrete gradient, docs/dynamics.md).
   integer, parameter, public :: integrator_generalized_alpha = 1, integrator_energy_momentum = 2
   !> The integrators' names, each at the position of its code (as method_names).
   character(*), parameter, public :: integrator_names = 'generalized-alpha energy-momentum'
   !> Each integrator's rho_inf when its line gives none: Chung-Hulbert's
   !> usual 0.8, and 1 (conserving) for energy-momentum.
   real(dp), parameter, public :: default_rho_inf(2) = [0.8_dp, 1.0_dp]

   !> Where an entity was declared: for diagnostics that point into the deck.
   !> The file is an index into model_type%files (loc_file names it): an
   !> entity's own copy of the file's name, for each of a large mechanism's
   !> nodes, links and welds in the deck's model and in its method's copy,
   !> was megabytes (docs/performance.md, the lift's memory).
   type :: source_loc_type
      integer :: file = 0
      integer :: line = 0
      integer :: col = 0
   end type source_loc_type

   !> The name of a file that the deck was read from.
   type :: file_name_type
      character(:), allocatable :: name
   end type file_name_type

   !> A named point of the mechanism (a hinge, a pivot, a tracked point).
   type :: node_type
      character(:), allocatable :: name
      !> Initial coordinates.
      real(dp) :: x(2) = 0
      type(source_loc_type) :: loc
   end type node_type

   !> Section stiffnesses of the paper's constitutive law (30).
   type :: section_type
      character(:), allocatable :: name
      !> Axial EA, shear kGA and bending EI stiffness, all positive.
      real(dp) :: ea = 0, kga = 0, ei = 0
      !> Mass per length rho*A and rotary inertia per length rho*I (0: massless).
      real(dp) :: rho_a = 0, rho_i = 0
      !> Rayleigh damping of the section's elements, C_e = alpha M_e + beta K_e
      !> (K_e the material tangent), both >= 0 (0: undamped).
      real(dp) :: alpha = 0, beta = 0
      type(source_loc_type) :: loc
   end type section_type

   !> A straight link between two nodes, meshed with nelem beam elements.
   type :: link_type
      character(:), allocatable :: name
      !> Indices into model%nodes of its first and second end.
      integer :: node(2) = 0
      !> Index into model%sections.
      integer :: section = 0
      integer :: nelem = 1
      type(source_loc_type) :: loc
   end type link_type

   !> Links rigidly joined at a node: their end rotations there are one unknown.
   !> Where links meet without a weld they are hinged (shared translations only).
   type :: weld_type
      integer :: node = 0
      !> Indices into model%links; each has an end at `node`.
      integer, allocatable :: links(:)
      type(source_loc_type) :: loc
   end type weld_type

   !> Ground support of a node: fixed x and/or y, and optionally the rotation
   !> of one link's end there (a clamp).
   type :: support_type
      integer :: node = 0
      !> fix(dof_x), fix(dof_y), fix(dof_rot).
      logical :: fix(3) = .false.
      !> The link whose end rotation is fixed when fix(dof_rot).
      integer :: link = 0
      type(source_loc_type) :: loc
   end type support_type

   !> A prescribed motion. For dof_x/dof_y the law gives the node's absolute
   !> coordinate; for dof_rot it gives the absolute angle (from +x,
   !> counterclockwise, radians) of the link's direction, first node to second.
   type :: drive_type
      !> dof_x, dof_y or dof_rot.
      integer :: dof = 0
      !> The node (for dof_rot: the link end whose rotation is driven).
      integer :: node = 0
      !> For dof_rot: the driven link.
      integer :: link = 0
      type(law_type) :: law
      type(source_loc_type) :: loc
   end type drive_type

   !> An external nodal load: its values times a factor of time, the load
   !> factor t by default, or its own law (see fekap_model_loads for the
   !> values at a time, docs/deck-format.md for the deck).
   type :: load_type
      integer :: node = 0
      real(dp) :: force(2) = 0
      real(dp) :: moment = 0
      !> The link end (at node) that carries the moment.
      integer :: link = 0
      !> Whether the load has a law of its own (`timed`), and the law: its
      !> factor at time t; without one the factor is the load factor t.
      logical :: timed = .false.
      type(law_type) :: law
      type(source_loc_type) :: loc
   end type load_type

   !> A point mass at a node (the pin's: it moves with the node's translations)
   !> and a rotary inertia on one link end there (it turns with that end).
   type :: mass_type
      integer :: node = 0
      real(dp) :: mass = 0
      real(dp) :: inertia = 0
      !> The link end (at node) that carries the rotary inertia (0 without one).
      integer :: link = 0
      type(source_loc_type) :: loc
   end type mass_type

   !> A link's rigid velocity at the start of dynamics (VELOcities): its first
   !> node's velocity and its angular velocity.
   type :: start_velocity_type
      integer :: link = 0
      real(dp) :: v(2) = 0
      real(dp) :: omega = 0
      type(source_loc_type) :: loc
   contains
      procedure :: velocity_at => start_velocity_at
   end type start_velocity_type

   !> A sliding joint: a slave node kept on a master line by a penalty spring.
   type :: slideline_type
      character(:), allocatable :: name
      integer :: slave = 0
      !> joint_pin_in_slot or joint_prismatic.
      integer :: kind = joint_pin_in_slot
      !> For joint_prismatic: the slave link whose angle is tied to the master.
      integer :: slave_link = 0
      !> Master line made of links, in order along the line (empty for a ground guide).
      integer, allocatable :: master_links(:)
      !> A fixed ground guide: from guide(:,1) to guide(:,2).
      logical :: ground = .false.
      real(dp) :: guide(2, 2) = 0
      !> Penalty parameter; <= 0 selects the default scaled from element stiffness.
      real(dp) :: penalty = 0
      !> Dynamics: a dashpot on the gap rate (force per velocity), 0 for none.
      real(dp) :: damping = 0
      type(source_loc_type) :: loc
   end type slideline_type

   !> What to compute and how.
   type :: analysis_type
      integer :: method = method_fem
      real(dp) :: t_start = 0
      real(dp) :: t_end = 1
      real(dp) :: dt = 0.025_dp
      !> Newton tolerance on the residual ratio.
      real(dp) :: tol = 1.0e-10_dp
      !> Length tolerance of the last Newton correction, relative to the model size.
      real(dp) :: length_tol = 1.0e-12_dp
      integer :: max_iter = 25
      integer :: predictor = predictor_extrapolate
      integer :: convergence = convergence_default
      logical :: velocities = .true.
      logical :: accelerations = .true.
      !> Gauss points per element: 1 (reduced, default) or 2 (full).
      integer :: gauss_points = 1
      !> Cartesian method: drop redundant constraint equations instead of stopping.
      logical :: remove_redundant = .false.
      !> Linear solver of the finite element method: solver_band or solver_dense.
      integer :: solver = solver_band
      !> Effects asked for (ANALysis type): effects_auto, effects_kinematics, ...
      integer :: effects = effects_auto
      !> Dynamics: the time integrator and its spectral radius at infinite
      !> frequency rho_inf in [0, 1] (1: the trapezoidal rule, no numerical damping).
      integer :: integrator = integrator_generalized_alpha
      real(dp) :: rho_inf = default_rho_inf(integrator_generalized_alpha)
      !> Dynamics: the start on the slow manifold (ANALysis start consistent, the
      !> default: the rigid-link accelerations and the deflection that carries
      !> their forces, docs/dynamics.md), or unstrained with M a0 = -R (start
      !> unstrained).
      logical :: start_unstrained = .false.
      !> Where an energy-momentum integrator line is (for the errors of what it does not cover).
      type(source_loc_type) :: integrator_loc
      !> A spatial mechanism (ANALysis `type kinematics spatial`): the model's
      !> `spatial` component holds its 3D data (fekap_model_spatial).
      logical :: spatial = .false.
      !> Dynamics: adaptive steps (`time T0 T1 DT adaptive TOL`) keeping each
      !> step's local error estimate below adaptive_tol (a length), with rows
      !> at T0 + k DT; and where `adaptive` is on its line.
      logical :: adaptive = .false.
      real(dp) :: adaptive_tol = 0
      type(source_loc_type) :: adaptive_loc
   end type analysis_type

   !> What to write.
   type :: output_type
      !> Tracked nodes (indices into model%nodes); points.csv has one row per tracked node per step.
      integer, allocatable :: points(:)
      !> Reported links (indices into model%links); default all links.
      integer, allocatable :: links(:)
      !> Write every k-th step (the first and the last step always).
      integer :: every = 1
      logical :: csv = .true.
      logical :: listing = .true.
      logical :: vtk = .false.
      !> `files points`: of the CSV files points.csv alone (the tracked
      !> points, what a benchmark against another code stores); csv includes it.
      logical :: points_csv = .false.
      !> Kinetostatics: write the elastic deflection of the nodes (deflection.csv).
      logical :: deflection = .false.
      !> nodes.csv holds every point of the mesh: the named nodes, then the
      !> interior points of each link meshed with several elements, named
      !> LINK#k (k = 1 .. elements - 1 from the first end). OUTPut `mesh on|off`;
      !> without it (mesh_nodes_given false) main sets it from the analysis:
      !> on for statics and dynamics of a model with a meshed link.
      logical :: mesh_nodes = .false.
      logical :: mesh_nodes_given = .false.
      !> Names of the deck's length and time units, for the plots' axis labels
      !> (the numbers are used as given; angles are always radians), and
      !> whether the deck's OUTPut block has a units line (without one the
      !> plots label lengths 'length', not metres).
      character(len=16) :: length_unit = 'm'
      character(len=16) :: time_unit = 's'
      logical :: units_given = .false.
   end type output_type

   !> A deck parameter (PARAmeters block): a named number that later numeric
   !> fields of the deck may use.
   type :: parameter_type
      !> Its name as spelt in the deck (matched case-insensitively).
      character(:), allocatable :: name
      real(dp) :: value = 0
      !> Whether `fekap --set` gave the value instead of the deck.
      logical :: set_on_command_line = .false.
      type(source_loc_type) :: loc
   end type parameter_type

   !> The whole model of one deck.
   type :: model_type
      !> The deck's file name, for diagnostics.
      character(:), allocatable :: file
      !> The files read: the deck, then those it INCLudes (source_loc_type's file).
      type(file_name_type), allocatable :: files(:)
      character(:), allocatable :: title
      type(node_type), allocatable :: nodes(:)
      type(section_type), allocatable :: sections(:)
      type(link_type), allocatable :: links(:)
      type(weld_type), allocatable :: welds(:)
      type(support_type), allocatable :: supports(:)
      type(drive_type), allocatable :: drives(:)
      type(load_type), allocatable :: loads(:)
      type(slideline_type), allocatable :: slidelines(:)
      type(mass_type), allocatable :: masses(:)
      !> Dynamics: links' velocities at the start (VELOcities; the others at rest).
      type(start_velocity_type), allocatable :: start_velocities(:)
      !> Gravity acceleration (GRAVity card), and where it was given.
      real(dp) :: gravity(2) = 0
      type(source_loc_type) :: gravity_loc
      type(analysis_type) :: analysis
      type(output_type) :: output
      !> The deck's parameters in the order defined, with the values used.
      type(parameter_type), allocatable :: parameters(:)
      !> A spatial deck's nodes' z, 3D sections, trusses, joints and drives.
      type(spatial_model_type) :: spatial
   end type model_type

contains

   !> The name of the file of an entity's place loc (the deck's when not known).
   pure function loc_file(model, loc) result(name)
      type(model_type), intent(in) :: model
      type(source_loc_type), intent(in) :: loc
      character(:), allocatable :: name
      name = model%file
      if (.not. allocated(model%files)) return
      if (loc%file >= 1 .and. loc%file <= size(model%files)) name = model%files(loc%file)%name
   end function loc_file

   !> Index of the node called `name` (case-insensitive), 0 if there is none.
   pure integer function find_node(model, name) result(idx)
      type(model_type), intent(in) :: model
      character(*), intent(in) :: name
      integer :: i
      idx = 0
      if (.not. allocated(model%nodes)) return
      do i = 1, size(model%nodes)
         if (same_name(model%nodes(i)%name, name)) then
            idx = i
            return
         end if
      end do
   end function find_node

   !> Index of the link called `name` (case-insensitive), 0 if there is none.
   pure integer function find_link(model, name) result(idx)
      type(model_type), intent(in) :: model
      character(*), intent(in) :: name
      integer :: i
      idx = 0
      if (.not. allocated(model%links)) return
      do i = 1, size(model%links)
         if (same_name(model%links(i)%name, name)) then
            idx = i
            return
         end if
      end do
   end function find_link

   !> Diagonal of the bounding box of the nodes (1 for a model without extent).
   pure real(dp) function model_size(model) result(size_)
      type(model_type), intent(in) :: model
      integer :: i
      real(dp) :: lo(2), hi(2)
      size_ = 1
      if (.not. allocated(model%nodes)) return
      if (size(model%nodes) == 0) return
      lo = model%nodes(1)%x
      hi = lo
      do i = 2, size(model%nodes)
         lo = min(lo, model%nodes(i)%x)
         hi = max(hi, model%nodes(i)%x)
      end do
      size_ = norm2(hi - lo)
      if (size_ <= 0) size_ = 1
   end function model_size

   !> The velocity at point x of the link's rigid motion, its first node at x1.
   pure function start_velocity_at(self, x1, x) result(v)
      class(start_velocity_type), intent(in) :: self
      real(dp), intent(in) :: x1(2), x(2)
      real(dp) :: v(2)
      v = self%v + self%omega*[-(x(2) - x1(2)), x(1) - x1(1)]
   end function start_velocity_at

end module fekap_model
