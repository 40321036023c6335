!> What every stepper on the FEM's mesh sets up the same way, kinematics
!> (fekap_fem) and dynamics (fekap_dynamics_dynamic_stepper) alike:
!> the model, its mesh and equation numbering, the band linear system, the
!> drive laws' values at the start (drives move from the initial
!> configuration), the model size and the length weight of each dof, the
!> Newton residual's round-off floor; and the start of a run: the initial
!> configuration with its slideline segments. Both steppers extend
!> fem_base_type, so they read these as their own components.
module fekap_fem_setup
   use fekap_kinds, only: dp
   use fekap_error, only: error_type
   use fekap_model, only: model_type, model_size, dof_rot
   use fekap_assembly_mesh, only: mesh_type, new_mesh
   use fekap_assembly_tracking, only: initial_segments
   use fekap_stepping_stepper, only: stepper_type
   use fekap_fem_linear_system, only: linear_system_type, new_linear_system
   use fekap_fem_convergence, only: residual_floor
   implicit none
   private

   public :: fem_base_type, new_fem_base, start_configuration, set_driven, put_driven_values, mesh_plan_line

   !> The model on its mesh, with the storage and scales every FEM stepper needs.
   type, abstract, extends(stepper_type) :: fem_base_type
      type(model_type) :: model
      type(mesh_type) :: mesh
      type(linear_system_type) :: system
      !> Drive laws' values at the start time: drives move from the initial configuration.
      real(dp), allocatable :: law0(:)
      !> Work arrays over the drives: the laws' values, rates and second rates at a time.
      real(dp), allocatable :: law_value(:), law_rate(:), law_rate2(:)
      !> The model size (model_size).
      real(dp) :: model_length = 1
      !> Length weight of each dof for the correction test: 1 for translations,
      !> the model size for rotations.
      real(dp), allocatable :: dof_length(:)
      !> Residual below which Newton has converged at round-off (convergence's residual_floor).
      real(dp) :: residual_floor = 0
   end type fem_base_type

contains

   !> The mesh, the equation numbering, the linear system (dense if asked)
   !> and the drives' start values of a validated model.
   subroutine new_fem_base(self, model, dense)
      class(fem_base_type), intent(inout) :: self
      type(model_type), intent(in) :: model
      logical, intent(in) :: dense
      integer :: i
      real(dp) :: f, df, ddf
      self%model = model
      call new_mesh(self%mesh, model)
      call new_linear_system(self%system, self%mesh, dense=dense)
      associate (nd => self%mesh%ndriven)
         allocate (self%law0(nd), self%law_value(nd), self%law_rate(nd), self%law_rate2(nd), source=0.0_dp)
      end associate
      do i = 1, self%mesh%ndriven
         call model%drives(i)%law%eval(model%analysis%t_start, f, df, ddf)
         self%law0(i) = f
      end do
      self%model_length = model_size(model)
      self%dof_length = merge(self%model_length, 1.0_dp, self%mesh%dof_kind == dof_rot)
      self%residual_floor = residual_floor(self%mesh, self%model_length)
   end subroutine new_fem_base

   !> The start of a run: the start time, the initial configuration q0 over
   !> all dofs and each slideline's master segment there.
   subroutine start_configuration(self, t, q, seg, error)
      class(fem_base_type), intent(in) :: self
      real(dp), intent(out) :: t
      real(dp), contiguous, intent(out) :: q(:)
      integer, contiguous, intent(out) :: seg(:)
      type(error_type), allocatable, intent(out) :: error
      t = self%model%analysis%t_start
      q = self%mesh%q0
      call initial_segments(self%mesh, self%model, q, self%model_length, seg, error)
   end subroutine start_configuration

   !> Driven dofs at time t: the initial value plus the law's change since t_start.
   subroutine set_driven(self, t, q)
      class(fem_base_type), intent(in) :: self
      real(dp), intent(in) :: t
      real(dp), contiguous, intent(inout) :: q(:)
      real(dp) :: f(self%mesh%ndriven), df, ddf
      integer :: i
      do i = 1, self%mesh%ndriven
         call self%model%drives(i)%law%eval(t, f(i), df, ddf)
      end do
      call put_driven_values(self, f, q)
   end subroutine set_driven

   !> Driven dofs from the drives' law values f: the initial value plus the
   !> law's change since t_start (set_driven's, and the predictor's from the
   !> laws it holds already).
   pure subroutine put_driven_values(self, f, q)
      class(fem_base_type), intent(in) :: self
      real(dp), intent(in) :: f(:)
      real(dp), contiguous, intent(inout) :: q(:)
      integer :: i, dof
      do i = 1, self%mesh%ndriven
         dof = self%mesh%driven_dof(i)
         q(dof) = self%mesh%q0(dof) + (f(i) - self%law0(i))
      end do
   end subroutine put_driven_values

   !> The mesh's line of the listing's plan: its size and band.
   function mesh_plan_line(self) result(text)
      class(fem_base_type), intent(in) :: self
      character(:), allocatable :: text
      character(len=160) :: line
      write (line, '(a,i0,a,i0,a,i0,a,i0,a,i0)') 'mesh: ', size(self%mesh%elements), ' elements, ', &
         & self%mesh%ndof, ' dofs, ', self%mesh%nfree, ' equations, ', self%mesh%ndriven, &
         & ' driven; half-bandwidth ', self%mesh%kd
      text = trim(line)
   end function mesh_plan_line

end module fekap_fem_setup
