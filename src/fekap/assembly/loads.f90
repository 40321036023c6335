!> The external loads over the mesh's dofs as functions of time: columns of
!> nodal loads, each times a factor of t (fekap_model_loads). Column 1 holds
!> every LOADs line without a law of its own (their factor is the load
!> factor t), summed as the mesh always did; each LOADs line with a law has
!> a column of its own; in statics the weights of the masses (GRAVity) are one
!> more column with the constant factor 1 (a dead load). A model whose loads
!> all take the load factor thus computes t*f exactly as before.
module fekap_assembly_loads
   use fekap_kinds, only: dp
   use fekap_model, only: load_type
   use fekap_model_drive_law, only: new_constant_law
   use fekap_model_loads, only: load_factor
   implicit none
   private

   public :: load_set_type

   !> The loads over the dofs: f(t) = sum_g lambda_g(t) f(:, g).
   type :: load_set_type
      !> (ndof, ncolumns): the columns at unit factor.
      real(dp), allocatable :: f(:, :)
      !> (ncolumns): the factor of each column (a load's law, or its
      !> `timed = .false.` for the load factor t).
      type(load_type), allocatable :: factor(:)
   contains
      procedure :: at => load_set_at
      procedure :: change => load_set_change
      procedure :: rate => load_set_rate
      procedure :: is_loaded => load_set_is_loaded
      procedure :: add_column => load_set_add_column
      procedure :: add_dead_column => load_set_add_dead_column
   end type load_set_type

contains

   !> A new column with the factor of `load` (its law, or the load factor t).
   pure subroutine load_set_add_column(self, ndof, load, column)
      class(load_set_type), intent(inout) :: self
      integer, intent(in) :: ndof
      type(load_type), intent(in) :: load
      !> The index of the new column.
      integer, intent(out) :: column
      real(dp), allocatable :: f(:, :)
      type(load_type) :: factor
      if (.not. allocated(self%f)) then
         allocate (self%f(ndof, 0), self%factor(0))
      end if
      column = size(self%f, 2) + 1
      allocate (f(ndof, column), source=0.0_dp)
      f(:, :column - 1) = self%f
      call move_alloc(f, self%f)
      factor = load_type()
      factor%timed = load%timed
      if (load%timed) factor%law = load%law
      self%factor = [self%factor, factor]
   end subroutine load_set_add_column

   !> A new column whose factor is the constant 1 (a dead load: weights).
   pure subroutine load_set_add_dead_column(self, ndof, column)
      class(load_set_type), intent(inout) :: self
      integer, intent(in) :: ndof
      integer, intent(out) :: column
      type(load_type) :: dead
      dead%timed = .true.
      call new_constant_law(dead%law, 1.0_dp)
      call self%add_column(ndof, dead, column)
   end subroutine load_set_add_dead_column

   !> Whether any column has a non-zero load.
   pure logical function load_set_is_loaded(self)
      class(load_set_type), intent(in) :: self
      load_set_is_loaded = .false.
      if (allocated(self%f)) load_set_is_loaded = any(abs(self%f) > 0)
   end function load_set_is_loaded

   !> f = f(t) over all dofs.
   pure subroutine load_set_at(self, t, f, negated)
      class(load_set_type), intent(in) :: self
      real(dp), intent(in) :: t
      real(dp), intent(out) :: f(:)
      !> f = -F(t) instead (the assembly's residual starts from it).
      logical, intent(in), optional :: negated
      real(dp) :: lambda, df, ddf
      integer :: g
      logical :: minus
      ! No array of the factors: an automatic array is a malloc and a free
      ! per call with gfortran, and this is called at every assembly.
      minus = .false.
      if (present(negated)) minus = negated
      if (size(self%f, 2) == 0) then
         f = 0
         if (minus) f = -f
         return
      end if
      call load_factor(self%factor(1), t, lambda, df, ddf)
      if (minus .and. size(self%f, 2) == 1) then
         ! In one pass: (-lambda) F is -(lambda F) to the bit (rounding to
         ! nearest is symmetric), a zero's sign included. Not for several
         ! columns: -(a + b) and (-a) - b differ in the sign of an exact zero.
         f = (-lambda)*self%f(:, 1)
         return
      end if
      f = lambda*self%f(:, 1)
      do g = 2, size(self%f, 2)
         call load_factor(self%factor(g), t, lambda, df, ddf)
         f = f + lambda*self%f(:, g)
      end do
      if (minus) f = -f
   end subroutine load_set_at

   !> f = sum_g (lambda_g(t1) - lambda_g(t0)) f(:, g): the change of the loads
   !> from t0 to t1 (for the load factor exactly (t1 - t0) f).
   pure subroutine load_set_change(self, t0, t1, f)
      class(load_set_type), intent(in) :: self
      real(dp), intent(in) :: t0, t1
      real(dp), intent(out) :: f(:)
      real(dp) :: l0, l1, df, ddf
      integer :: g
      f = 0
      do g = 1, size(self%f, 2)
         call load_factor(self%factor(g), t0, l0, df, ddf)
         call load_factor(self%factor(g), t1, l1, df, ddf)
         if (g == 1) then
            f = (l1 - l0)*self%f(:, 1)
         else
            f = f + (l1 - l0)*self%f(:, g)
         end if
      end do
   end subroutine load_set_change

   !> f = d^order f / dt^order at t (order 1 or 2).
   pure subroutine load_set_rate(self, t, order, f)
      class(load_set_type), intent(in) :: self
      real(dp), intent(in) :: t
      integer, intent(in) :: order
      real(dp), intent(out) :: f(:)
      real(dp) :: lambda, df, ddf, rate
      integer :: g
      f = 0
      do g = 1, size(self%f, 2)
         call load_factor(self%factor(g), t, lambda, df, ddf)
         rate = merge(df, ddf, order == 1)
         if (g == 1) then
            f = rate*self%f(:, 1)
         else
            f = f + rate*self%f(:, g)
         end if
      end do
   end subroutine load_set_rate

end module fekap_assembly_loads
