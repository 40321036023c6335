!> The spatial kinematics' tangent K in sparse form: its free block K_ff as
!> a symmetric band matrix (fekap_linalg_band: the in-house square-root-free
!> Cholesky for narrow bands, dpbtrf beyond, band LU where it is not positive
!> definite) in a bandwidth-reducing order of the free dofs (reverse
!> Cuthill-McKee of the elements' couplings, fekap_assembly_ordering), and
!> its coupling K_fd to the driven dofs as a dense block (one column a
!> drive). Vectors at this module's interface are in the order of the free
!> dofs list (free_dofs), the equation order stays inside.
module fekap_spatial_tangent
   use fekap_kinds, only: dp
   use fekap_linalg_band, only: band_matrix_type, new_band_matrix
   use fekap_assembly_ordering, only: group_adjacency, cuthill_mckee
   implicit none
   private

   public :: spatial_tangent_type, new_spatial_tangent

   type :: spatial_tangent_type
      !> All dofs, free ones.
      integer :: ndof = 0, nfree = 0
      !> (ndof): the equation of a free dof (0: driven); the column of K_fd of
      !> a driven dof (0: free).
      integer, allocatable :: equation(:), driven_column(:)
      !> (nfree): the position in the free dofs list of each equation.
      integer, allocatable :: free_of_equation(:)
      !> (nfree): the free dofs list (free_dofs), and the equation of each entry.
      integer, allocatable :: fdof(:), equation_of_free(:)
      !> K_ff in equation order, and its factor.
      type(band_matrix_type) :: kff
      !> (nfree, ndriven): K_fd in equation order.
      real(dp), allocatable :: kfd(:, :)
   contains
      procedure :: zero => tangent_zero
      procedure :: add_element => tangent_add_element
      procedure :: factor => tangent_factor
      procedure :: solve => tangent_solve
      procedure :: product => tangent_product
      procedure :: is_lu => tangent_is_lu
      procedure :: rcond => tangent_rcond
   end type spatial_tangent_type

contains

   !> The storage of K for ndof dofs with free dofs list fdof, whose elements
   !> couple the dofs group_dof(group_start(e):group_start(e + 1) - 1).
   subroutine new_spatial_tangent(self, ndof, fdof, group_start, group_dof)
      type(spatial_tangent_type), intent(out) :: self
      integer, intent(in) :: ndof, fdof(:), group_start(:), group_dof(:)
      integer, allocatable :: adj_start(:), adj(:), deg(:), order(:), top(:), free_index(:)
      integer :: i, e, a, lo, kd, nd
      self%ndof = ndof
      self%nfree = size(fdof)
      self%fdof = fdof
      allocate (free_index(ndof), self%equation(ndof), self%driven_column(ndof), source=0)
      do i = 1, size(fdof)
         free_index(fdof(i)) = i
      end do
      nd = 0
      do i = 1, ndof
         if (free_index(i) > 0) cycle
         nd = nd + 1
         self%driven_column(i) = nd
      end do
      call group_adjacency(group_start, group_dof, free_index, self%nfree, adj_start, adj, deg)
      allocate (order(self%nfree), self%free_of_equation(self%nfree), self%equation_of_free(self%nfree))
      call cuthill_mckee(adj_start, adj, deg, order)
      ! The reverse order: equation k is the vertex order(nfree + 1 - k).
      do i = 1, self%nfree
         self%free_of_equation(i) = order(self%nfree + 1 - i)
         self%equation_of_free(self%free_of_equation(i)) = i
         self%equation(fdof(self%free_of_equation(i))) = i
      end do
      ! Half-bandwidth and envelope (each column's first coupled equation).
      allocate (top(self%nfree))
      top = [(i, i=1, self%nfree)]
      kd = 0
      do e = 1, size(group_start) - 1
         lo = huge(1)
         do i = group_start(e), group_start(e + 1) - 1
            a = self%equation(group_dof(i))
            if (a > 0) lo = min(lo, a)
         end do
         do i = group_start(e), group_start(e + 1) - 1
            a = self%equation(group_dof(i))
            if (a == 0) cycle
            top(a) = min(top(a), lo)
            kd = max(kd, a - lo)
         end do
      end do
      call new_band_matrix(self%kff, self%nfree, kd, top=top)
      allocate (self%kfd(self%nfree, nd), source=0.0_dp)
   end subroutine new_spatial_tangent

   pure subroutine tangent_zero(self)
      class(spatial_tangent_type), intent(inout) :: self
      call self%kff%zero()
      self%kfd = 0
   end subroutine tangent_zero

   !> K(dofs, dofs) += ke (ke symmetric; dofs without repeats).
   pure subroutine tangent_add_element(self, dofs, ke)
      class(spatial_tangent_type), intent(inout) :: self
      integer, intent(in) :: dofs(:)
      real(dp), intent(in) :: ke(:, :)
      integer :: i, j, ei, ej
      do j = 1, size(dofs)
         ej = self%equation(dofs(j))
         do i = 1, size(dofs)
            ei = self%equation(dofs(i))
            if (ei == 0) cycle
            if (ej == 0) then
               self%kfd(ei, self%driven_column(dofs(j))) = self%kfd(ei, self%driven_column(dofs(j))) + ke(i, j)
            else if (ei <= ej) then
               call self%kff%add(ei, ej, ke(i, j))
            end if
         end do
      end do
   end subroutine tangent_add_element

   !> Factor K_ff. info: 0, or the dof at which it is singular.
   pure subroutine tangent_factor(self, info)
      class(spatial_tangent_type), intent(inout) :: self
      integer, intent(out) :: info
      call self%kff%factor(info)
      if (info > 0) info = self%fdof(self%free_of_equation(info))
   end subroutine tangent_factor

   !> x <- K_ff^-1 x, x in the order of the free dofs list.
   pure subroutine tangent_solve(self, x)
      class(spatial_tangent_type), intent(in) :: self
      real(dp), intent(inout) :: x(:)
      real(dp) :: b(self%nfree, 1)
      b(self%equation_of_free, 1) = x
      call self%kff%solve(b)
      x = b(self%equation_of_free, 1)
   end subroutine tangent_solve

   !> The free rows of K x for x of every dof, in the order of the free dofs list.
   pure function tangent_product(self, x) result(y)
      class(spatial_tangent_type), intent(in) :: self
      real(dp), intent(in) :: x(:)
      real(dp) :: y(self%nfree)
      real(dp) :: xe(self%nfree), ye(self%nfree), aij
      integer :: i, j, kd, d
      kd = self%kff%kd
      xe(self%equation_of_free) = x(self%fdof)
      ye = 0
      do j = 1, self%nfree
         do i = max(1, j - kd), j - 1
            aij = self%kff%a(kd + 1 + i - j, j)
            ye(i) = ye(i) + aij*xe(j)
            ye(j) = ye(j) + aij*xe(i)
         end do
         ye(j) = ye(j) + self%kff%a(kd + 1, j)*xe(j)
      end do
      do d = 1, self%ndof
         if (self%driven_column(d) > 0 .and. x(d) /= 0) ye = ye + self%kfd(:, self%driven_column(d))*x(d)
      end do
      y = ye(self%equation_of_free)
   end function tangent_product

   !> Whether the last factor is a band LU (K_ff not positive definite) rather than a Cholesky factor.
   pure logical function tangent_is_lu(self)
      class(spatial_tangent_type), intent(in) :: self
      tangent_is_lu = self%kff%is_lu
   end function tangent_is_lu

   !> The reciprocal condition number of the factored K_ff in the 1-norm
   !> (fekap_linalg_band's estimate: a few solves with the factor; 0 where
   !> the factor failed).
   subroutine tangent_rcond(self, rcond)
      class(spatial_tangent_type), intent(inout) :: self
      real(dp), intent(out) :: rcond
      call self%kff%rcond(rcond)
   end subroutine tangent_rcond

end module fekap_spatial_tangent
