!> The dynamics stepper's start: the configuration, the velocities (given,
!> or the drives' kinematic velocities when they move the whole mechanism,
!> else rest), the accelerations (fekap_dynamics_consistent_start, or those
!> of M a0 = -R for an unstrained start) and the start's energies.
module fekap_dynamics_stepper_start
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, analysis_error
   use fekap_model_results, only: step_result_type
   use fekap_assembly_assemble, only: scatter_element
   use fekap_fem_setup, only: start_configuration
   use fekap_fem_linear_system, only: assemble_system, factor_system, system_pivot, solve_system
   use fekap_dynamics_dynamic_system, only: external_forces, assemble_dynamics, kinetic_energy, strain_energy, &
      & penalty_energy
   use fekap_dynamics_consistent_start, only: start_report_type, consistent_start
   use fekap_dynamics_dynamic_data, only: dynamic_data_type, drive_motion
   use fekap_dynamics_step_result, only: fill_result
   implicit none
   private

   public :: start_dynamics

contains

   !> The start: velocities, consistent accelerations, energies.
   subroutine start_dynamics(self, result, error)
      class(dynamic_data_type), intent(inout) :: self
      type(step_result_type), intent(inout) :: result
      type(error_type), allocatable, intent(out) :: error
      type(start_report_type) :: report
      integer :: info
      associate (state => self%state, mesh => self%mesh)
         ! The drives' start values law0 are new_fem_base's.
         call start_configuration(self, state%t, state%q, state%seg, error)
         if (allocated(error)) return
         call drive_motion(self, state%t, state%q, state%v, state%acc)
         call start_velocities(self, info)
         if (self%model%analysis%start_unstrained) then
            call start_accelerations(self, error)
            self%start_state = 'unstrained, accelerations of M a = -R (ANALysis start unstrained)'
         else
            call external_forces(self%dynamics, mesh, state%t, state%g)
            call consistent_start(self%dynamics, self%system, mesh, state%q, state%v, state%acc, state%t, state%seg, &
               & self%counts, report, error)
            state%r = self%system%r
            call describe_start(self, report)
            if (.not. allocated(error) .and. .not. report%usable) call start_accelerations(self, error)
         end if
         if (allocated(error)) return
         state%a = state%acc
         state%work_loads = 0
         state%work_drives = 0
         state%dissipated = 0
         state%kinetic = kinetic_energy(self%dynamics, mesh, state%v)
         state%strain = strain_energy(mesh, state%q)
         state%penalty = penalty_energy(mesh, state%q, state%seg)
         state%energy = state%kinetic + state%strain + state%penalty - dot_product(self%dynamics%weight, state%q)
         self%energy0 = state%energy
         result%iterations = 0
         result%residual = 0
         call fill_result(self, result)
         ! The plan is written before the start: the listing's note of step 0 says how it went.
         if (.not. self%model%analysis%start_unstrained) then
            result%note = 'start: '//trim(self%start_velocity)//'; '//trim(self%start_state)
         end if
      end associate
   end subroutine start_dynamics

   !> The plan's line on a consistent start.
   subroutine describe_start(self, report)
      class(dynamic_data_type), intent(inout) :: self
      type(start_report_type), intent(in) :: report
      character(len=200) :: line
      write (line, '(a,es9.2,a,i0,a,i0,a,i0,a,es9.2,a)') 'consistent (rigid-link accelerations; deflection up to ', &
         & report%deflection, '; ', report%passes, ' passes of ', report%iterations_a, ' + ', report%iterations_delta, &
         & ' iterations; residual ', report%residual, ' of the forces)'
      if (.not. report%converged) line = trim(line)//': the iterations stopped short'
      if (.not. report%usable) then
         write (line, '(a,es9.2,a)') 'unstrained, accelerations of M a = -R: the consistent start left ', &
            & report%residual, ' of the forces unbalanced (links too flexible for its linear deflection)'
      end if
      self%start_state = line
   end subroutine describe_start

   !> Velocities at the start: given (v_start), or those the drives' rates
   !> give a mechanism they move whole (K_ff v_f = -K_fd v_d with the material
   !> tangent at the unstrained start, as the kinematics' (47)), else the
   !> drives' own rates with the rest at rest.
   subroutine start_velocities(self, info)
      class(dynamic_data_type), intent(inout) :: self
      integer, intent(out) :: info
      integer :: k, j
      real(dp) :: ratio
      info = 0
      associate (state => self%state, mesh => self%mesh, system => self%system)
         if (.not. allocated(self%v_start) .and. allocated(self%model%start_velocities)) then
            if (size(self%model%start_velocities) > 0) call deck_velocities(self)
         end if
         if (allocated(self%v_start)) then
            state%v = self%v_start
            call drive_motion(self, state%t, self%qt, state%v, self%acct)
            self%start_velocity = 'velocities given (VELOcities), the other links at rest'
            return
         end if
         self%start_velocity = 'at rest'
         if (mesh%ndriven == 0 .or. all(self%law_rate == 0)) return
         call assemble_system(system, mesh, state%q, state%t, state%seg, huge(1.0_dp), self%counts)
         call factor_system(system, info, self%counts)
         ratio = 0
         if (info == 0) call system_pivot(system, ratio)
         if (info /= 0 .or. ratio < 1.0e-12_dp) then
            self%start_velocity = 'the drives'' rates, the rest at rest (the drives do not move the whole mechanism)'
            return
         end if
         system%rhs(:, 1) = 0
         do j = 1, mesh%ndriven
            system%rhs(:, 1) = system%rhs(:, 1) - self%law_rate(j)*system%kfd(:, j)
         end do
         call solve_system(system, self%counts)
         do k = 1, mesh%nfree
            state%v(mesh%eq_dof(k)) = system%rhs(k, 1)
         end do
         self%start_velocity = 'the drives'' kinematic velocities'
      end associate
   end subroutine start_velocities

   !> v_start from the deck's VELOcities: each listed link's rigid motion on
   !> its elements' dofs; the dofs of links not listed at rest, but for their
   !> ends at nodes of listed links.
   subroutine deck_velocities(self)
      class(dynamic_data_type), intent(inout) :: self
      integer :: i, e, a, l
      real(dp) :: x1(2)
      allocate (self%v_start(self%mesh%ndof), source=0.0_dp)
      associate (mesh => self%mesh, model => self%model)
         do i = 1, size(model%start_velocities)
            associate (sv => model%start_velocities(i))
               l = sv%link
               x1 = model%nodes(model%links(l)%node(1))%x
               do e = 1, size(mesh%elements)
                  if (mesh%elink(e) /= l) cycle
                  do a = 0, 1
                     self%v_start(mesh%edof(3*a + 1:3*a + 2, e)) = sv%velocity_at(x1, &
                        & mesh%q0(mesh%edof(3*a + 1:3*a + 2, e)))
                     self%v_start(mesh%edof(3*a + 3, e)) = sv%omega
                  end do
               end do
            end associate
         end do
      end associate
   end subroutine deck_velocities

   !> The consistent accelerations at the start: M_ff a_f = -R_f with R at
   !> a_f = 0 (the drives' second rates on theirs). A free dof without mass
   !> (its row of M is zero) keeps a = 0: its equation is static.
   subroutine start_accelerations(self, error)
      class(dynamic_data_type), intent(inout) :: self
      type(error_type), allocatable, intent(out) :: error
      integer :: k, e, info
      real(dp) :: mdiag
      associate (state => self%state, mesh => self%mesh, system => self%system, dyn => self%dynamics)
         call external_forces(dyn, mesh, state%t, state%g)
         do k = 1, mesh%nfree
            state%acc(mesh%eq_dof(k)) = 0
         end do
         call assemble_dynamics(dyn, system, mesh, state%q, state%v, state%acc, state%t, state%seg, self%counts)
         state%r = system%r
         call system%kff%zero()
         do e = 1, size(mesh%elements)
            ! M_ff only: no entries into the free-driven block.
            call scatter_element(mesh%scatter_map(:, mesh%scatter_start(e):), mesh%scatter_count(1, e), 0, dyn%me(:, :, e), &
               & system%kff%a, system%kfd)
         end do
         do k = 1, mesh%nfree
            mdiag = system%kff%a(mesh%kd + 1, k) + dyn%point_mass(mesh%eq_dof(k))
            system%kff%a(mesh%kd + 1, k) = mdiag
            system%rhs(k, 1) = -state%r(mesh%eq_dof(k))
            if (mdiag == 0) then
               system%kff%a(mesh%kd + 1, k) = 1
               system%rhs(k, 1) = 0
            end if
         end do
         call factor_system(system, info, self%counts)
         if (info /= 0) then
            call analysis_error(error, 'the mass matrix is singular at the start: consistent accelerations '// &
               & 'cannot be found (give every moving dof a mass)')
            return
         end if
         call solve_system(system, self%counts)
         do k = 1, mesh%nfree
            state%acc(mesh%eq_dof(k)) = system%rhs(k, 1)
         end do
         ! The start's residual with its accelerations: the reactions there.
         call assemble_dynamics(dyn, system, mesh, state%q, state%v, state%acc, state%t, state%seg, self%counts)
         state%r = system%r
      end associate
   end subroutine start_accelerations

end module fekap_dynamics_stepper_start
