!> Inertia of the 2-node planar Simo-Reissner beam: the consistent mass of
!> linear interpolation, in the element's dofs (x1, y1, theta1, x2, y2, theta2).
!>
!> The kinetic energy of a beam is T = 1/2 int (rhoA |x_t|^2 + rhoI theta_t^2) dS
!> (Simo & Vu-Quoc 1986, planar: no gyroscopic term). With the element's linear
!> shape functions N1 = 1 - S/L, N2 = S/L for the positions and the rotation,
!> int N_a N_b dS = L/6 [2 1; 1 2], so
!>   M = rhoA L/6 [2 1; 1 2] (x) I2 on the translations,
!>   M = rhoI L/6 [2 1; 1 2]        on the rotations,
!> constant (positions are absolute, rotations planar). A rigid motion has a
!> velocity field linear along the element, which the interpolation holds
!> exactly: M gives a rigid link its exact kinetic energy, 1/2 m |v_G|^2 +
!> 1/2 (m L^2/12 + rhoI L) omega^2 (m = rhoA L), and its inertia forces -M a
!> have the exact resultant force and moment of the distributed ones.
module fekap_element_inertia
   use fekap_kinds, only: dp
   implicit none
   private

   public :: beam_mass_matrix, beam_inertia_force, beam_gravity_force, beam_kinetic_energy

contains

   !> The consistent mass matrix of an element of length `length`.
   pure function beam_mass_matrix(length, rho_a, rho_i) result(m)
      real(dp), intent(in) :: length
      !> Mass per length and rotary inertia per length.
      real(dp), intent(in) :: rho_a, rho_i
      real(dp) :: m(6, 6)
      real(dp) :: ct, cr
      integer :: k
      ct = rho_a*length/6
      cr = rho_i*length/6
      m = 0
      do k = 1, 2
         m(k, k) = 2*ct
         m(k + 3, k + 3) = 2*ct
         m(k, k + 3) = ct
         m(k + 3, k) = ct
      end do
      m(3, 3) = 2*cr
      m(6, 6) = 2*cr
      m(3, 6) = cr
      m(6, 3) = cr
   end function beam_mass_matrix

   !> The element's inertia forces -M ae from its nodal accelerations ae.
   pure function beam_inertia_force(length, rho_a, rho_i, ae) result(f)
      real(dp), intent(in) :: length, rho_a, rho_i
      real(dp), intent(in) :: ae(6)
      real(dp) :: f(6)
      real(dp) :: ct, cr
      ct = -rho_a*length/6
      cr = -rho_i*length/6
      f(1:2) = ct*(2*ae(1:2) + ae(4:5))
      f(4:5) = ct*(ae(1:2) + 2*ae(4:5))
      f(3) = cr*(2*ae(3) + ae(6))
      f(6) = cr*(ae(3) + 2*ae(6))
   end function beam_inertia_force

   !> The element's weight under gravity g as consistent nodal forces: half
   !> of rhoA L g at each node (int N_a dS = L/2), no moments.
   pure function beam_gravity_force(length, rho_a, g) result(f)
      real(dp), intent(in) :: length, rho_a
      real(dp), intent(in) :: g(2)
      real(dp) :: f(6)
      f(1:2) = rho_a*length/2*g
      f(3) = 0
      f(4:5) = f(1:2)
      f(6) = 0
   end function beam_gravity_force

   !> Kinetic energy 1/2 ve^T M ve of nodal velocities ve.
   pure real(dp) function beam_kinetic_energy(length, rho_a, rho_i, ve) result(energy)
      real(dp), intent(in) :: length, rho_a, rho_i
      real(dp), intent(in) :: ve(6)
      energy = -0.5_dp*dot_product(ve, beam_inertia_force(length, rho_a, rho_i, ve))
   end function beam_kinetic_energy

end module fekap_element_inertia
