!> The FEM's tangent at the accepted configuration and the square-root
!> form's solves: whether the system (or the strain-rate operator B_f) holds
!> the factor at the accepted configuration and refactoring it there when
!> not; its pivot ratio, condition estimate and drive response on K's scale
!> whichever form holds it; a Newton iteration's assembly and, in the
!> square-root form, its correction from B_f (docs/theory.md, "Rates at
!> scale"); the tangent at a change point's filled row; and the return to a
!> saved accepted state.
module fekap_fem_factor
   use fekap_kinds, only: dp
   use fekap_fem_linear_system, only: assemble_system, assemble_system_residual, factor_system, system_pivot, &
      & newton_correction, apply_correction, drive_response, system_rcond, phase_start, phase_end
   use fekap_fem_rates, only: root_drive_response, root_refined_response, near_singular_drop, plain_rates_rcond
   use fekap_fem_convergence, only: estimate_margin
   use fekap_model, only: predictor_taylor
   use fekap_assembly_strain_rate, only: assemble_strain_rate, factor_strain_rate, solve_strain_rate, &
      & strain_rate_rcond, carry_geometry, strain_rate_rcond_bounds
   use fekap_fem_state, only: fem_state_type, fem_core_type
   implicit none
   private

   public :: refactor_at_accepted, newton_assembly, root_correction, factor_root, accepted_pivot
   public :: accepted_rcond, accepted_response, fill_tangent, take_correction, restore_state, carry_factor
   public :: root_rcond

   !> The largest contraction (the drive response's refinement correction
   !> against the response, see carry_factor) at which a factor made one
   !> Newton correction away serves the accepted configuration: the rates'
   !> one refinement (fekap_fem_rates' root_passes) then leaves an error of
   !> its square, 1e-16 of the rates, below their round-off.
   real(dp), parameter :: carry_contraction = 1.0e-8_dp

contains

   !> Make the system hold the factor of the tangent at the accepted
   !> configuration, unless it does already; info > 0 names the equation where
   !> it is singular. For a kinematic analysis this is the material tangent
   !> (46): the last Newton iterate's tangent will not do, because its
   !> residual stresses make a geometric stiffness comparable to the bending
   !> stiffness EI/L^3 of slender links, which spoils accelerations. A loaded
   !> model is stressed by design and uses the full tangent.
   subroutine refactor_at_accepted(self, info)
      class(fem_core_type), intent(inout) :: self
      integer, intent(out) :: info
      info = 0
      if (self%factor%is_current()) return
      call assemble_system(self%system, self%mesh, self%state%q, self%state%t, self%seg, &
         & merge(0.0_dp, huge(1.0_dp), self%loaded), self%counts)
      if (self%root_form) then
         call factor_root(self, self%state%q, self%state%seg, info, self%system%section)
      else
         call factor_system(self%system, info, self%counts)
      end if
      call self%factor%mark(info)
   end subroutine refactor_at_accepted

   !> The assembly of a Newton iteration at qt: the residual and the tangent
   !> (K form), or the residual, B and the strains (square-root form), with
   !> the largest element strain in the system either way. The square-root
   !> form's correction is Newton's with the material tangent (K = B^T W B,
   !> B_f square), which is the K form's below kg_above; an iterate strained
   !> more takes the K form's full Newton step, as before (its path, e.g.
   !> from a poor predictor, stays the one the branch check was built on),
   !> and K is assembled too.
   subroutine newton_assembly(self, qt, t, kg_above)
      class(fem_core_type), intent(inout) :: self
      real(dp), contiguous, intent(in) :: qt(:)
      real(dp), intent(in) :: t, kg_above
      real(dp) :: clock
      if (.not. self%root_form) then
         call assemble_system(self%system, self%mesh, qt, t, self%seg, kg_above, self%counts)
         return
      end if
      call assemble_system_residual(self%system, self%mesh, qt, t, self%seg, self%counts, sections=.true.)
      clock = phase_start(self%system)
      call assemble_strain_rate(self%root, self%mesh, qt, self%seg, .false., self%root_work, &
         & self%system%assembled_strain, self%system%assembled_element, self%system%residual_section)
      call phase_end(self%system, clock, self%counts%seconds_assembly)
      if (self%system%assembled_strain >= kg_above) then
         call assemble_system(self%system, self%mesh, qt, t, self%seg, kg_above, self%counts)
      end if
   end subroutine newton_assembly

   !> The Newton correction of the square-root form at qt: B_f dq = -eps with
   !> B the exact gradient of the strains and gaps eps at qt (assembled here,
   !> or by newton_assembly with eps in root_work), into the system's
   !> right-hand side (as newton_correction), and its length; solved =
   !> .false. if B_f is singular there (the caller uses K). With `section`
   !> (assemble only): B_f stress-free instead, with the sections of the
   !> system's last assembly at qt, so that its factor is factor_root's at
   !> qt to the bit (the rates' factor) and eps is still the residual.
   subroutine root_correction(self, qt, assemble, correction, solved, section, carry)
      class(fem_core_type), intent(inout) :: self
      real(dp), contiguous, intent(in) :: qt(:)
      logical, intent(in) :: assemble
      real(dp), intent(out) :: correction
      logical, intent(out) :: solved
      real(dp), contiguous, intent(in), optional :: section(:, :, :)
      !> With the factor B_f holds, carried to qt (carry_geometry; carry_factor;
      !> `assemble` is then not looked at). A flag rather than a procedure of
      !> its own for the shared solve: that procedure was not inlined, and
      !> Example 1's step took 61 instructions more (13,209 -> 13,270).
      logical, intent(in), optional :: carry
      real(dp) :: clock
      integer :: info, k
      logical :: carried
      correction = 0
      solved = .false.
      carried = .false.
      if (present(carry)) carried = carry
      if (carried) then
         if (.not. self%root%factored) return
         clock = phase_start(self%system)
         call carry_geometry(self%root, self%mesh, qt, self%seg, self%root_work, section)
         call phase_end(self%system, clock, self%counts%seconds_assembly)
      else
         if (assemble) then
            clock = phase_start(self%system)
            if (present(section)) then
               call assemble_strain_rate(self%root, self%mesh, qt, self%seg, .true., self%root_work, section=section)
            else
               call assemble_strain_rate(self%root, self%mesh, qt, self%seg, .false., self%root_work)
            end if
            call phase_end(self%system, clock, self%counts%seconds_assembly)
         end if
         call timed_root_factor(self, info)
         if (info /= 0) return
      end if
      solved = .true.
      clock = phase_start(self%system)
      call negate(self%mesh%nfree, self%root_work)
      call solve_strain_rate(self%root, self%root_work)
      call phase_end(self%system, clock, self%counts%seconds_solves)
      ! The correction into rhs and its length in one pass (B_f square: nfree rows).
      associate (dq => self%root_work, rhs => self%system%rhs)
         do k = 1, self%mesh%nfree
            rhs(k, 1) = dq(k)
            correction = max(correction, abs(dq(k))*self%dof_length(self%mesh%eq_dof(k)))
         end do
      end associate
   end subroutine root_correction

   !> Whether the factor of Newton's last B_f (at the iterate one correction
   !> before qt, with its strains) serves at qt, where Newton stopped (on
   !> its estimate, or by the contract after a correction of B_f), in place
   !> of the stress-free B_f factored at qt (the second factorisation of
   !> such a step). The stop is checked with it as solve_step checks an
   !> estimated stop with qt's own factor: the correction for the
   !> strains at qt within estimate_margin of the length tolerance, the pivot
   !> ratio not near singular against the run's best. Then the drive
   !> response at qt (the branch check's, fekap_fem_converged's branch_jump,
   !> and the predictor's velocity) is solved with it and refined once with
   !> its residual at qt (the strain rates of the response, B's geometry and
   !> B_d moved to qt: carry_geometry); the refinement's correction against
   !> the response is the factor's contraction rho = ||I - B_f^-1 B(qt)||
   !> along it. The factor serves if rho <= carry_contraction: each solve of
   !> the rates with their one refinement then leaves rho**2 of the rates.
   !> At the lift of N = 1,000 (dt 0.01) rho is 3e-11 to 5e-9 a step, a Newton
   !> correction of 1e-7 against kappa_1(B_f) up to 1e7: the change of B_f
   !> over a correction is not a worst case for its inverse. The response
   !> stays in jump_response_new for the branch check (accepted_response);
   !> the factor is marked carried (no condition bounds: B_f is not the
   !> last estimate's, and the rates refine). Otherwise nothing is kept: the
   !> caller factors qt's B_f as before. The slidelines' segments are the
   !> factor's (Newton's last pass was on them).
   subroutine carry_factor(self, qt, carried)
      class(fem_core_type), intent(inout) :: self
      real(dp), contiguous, intent(in) :: qt(:)
      logical, intent(out) :: carried
      real(dp) :: correction, rho, low, high, clock
      logical :: solved
      carried = .false.
      ! Not under the Taylor predictor, whose positions come from the rates
      ! (a change of their round-off is amplified near a change point; as
      ! solve_rates' refinement there), nor loaded (the full tangent's
      ! factor), nor in kinetostatics, whose deflection takes the factor
      ! unrefined (solve_at_accepted: a carried one would leave up to
      ! carry_contraction of it).
      if (self%loaded .or. self%kinetostatic .or. self%model%analysis%predictor == predictor_taylor) return
      ! Nor where the rates take the plain solve (B_f's bounds from the last
      ! estimate show it well conditioned: plain_rates_rcond), which needs
      ! the factor at qt itself; a carried factor's rates are refined.
      call strain_rate_rcond_bounds(self%root, low, high)
      if (low >= plain_rates_rcond) return
      if (self%root%pivot_ratio < near_singular_drop*self%state%reference_pivot) return
      call root_correction(self, qt, .false., correction, solved, self%system%section, carry=.true.)
      if (.not. solved .or. correction > estimate_margin*self%conv%length) return
      clock = phase_start(self%system)
      call root_refined_response(self%root, self%mesh, self%jump_response_new, self%root_work, rho)
      call phase_end(self%system, clock, self%counts%seconds_solves)
      if (rho > carry_contraction) return
      carried = .true.
      call self%factor%carry()
   end subroutine carry_factor

   !> x = -x on an array of explicit shape (a loop the compiler vectorises;
   !> the assignment on the allocatable component checked its allocation and
   !> shape first).
   pure subroutine negate(n, x)
      integer, intent(in) :: n
      real(dp), intent(inout) :: x(n)
      x = -x
   end subroutine negate

   !> Assemble and factor the stress-free B at q (slidelines on seg): the
   !> square-root form's factor at a configuration; info > 0 if B_f is singular there.
   !> `section`: the sections at q of the system's last assembly there
   !> (assemble_strain_rate's).
   subroutine factor_root(self, q, seg, info, section)
      class(fem_core_type), intent(inout) :: self
      real(dp), contiguous, intent(in) :: q(:)
      integer, intent(in) :: seg(:)
      integer, intent(out) :: info
      real(dp), contiguous, intent(in), optional :: section(:, :, :)
      real(dp) :: clock
      clock = phase_start(self%system)
      call assemble_strain_rate(self%root, self%mesh, q, seg, .true., section=section)
      call phase_end(self%system, clock, self%counts%seconds_assembly)
      call timed_root_factor(self, info)
   end subroutine factor_root

   !> The band LU of the assembled B_f, timed as the system's factorisations
   !> are (the listing's factorisation time is either form's).
   subroutine timed_root_factor(self, info)
      class(fem_core_type), intent(inout) :: self
      integer, intent(out) :: info
      real(dp) :: clock
      clock = phase_start(self%system)
      call factor_strain_rate(self%root, info)
      call phase_end(self%system, clock, self%counts%seconds_factorisation)
      self%counts%root_factorisations = self%counts%root_factorisations + 1
   end subroutine timed_root_factor

   !> The pivot ratio of the factor at the accepted configuration (B_f's on
   !> K's scale in the square-root form, else K's).
   real(dp) function accepted_pivot(self) result(ratio)
      class(fem_core_type), intent(inout) :: self
      if (self%root_form) then
         ratio = self%root%pivot_ratio
      else
         call system_pivot(self%system, ratio)
      end if
   end function accepted_pivot

   !> The condition estimate of the factor at the accepted configuration, on
   !> K's scale: B_f's squared in the square-root form, else K's.
   subroutine accepted_rcond(self, rcond)
      class(fem_core_type), intent(inout) :: self
      real(dp), intent(out) :: rcond
      if (self%root_form) then
         call root_rcond(self, rcond)
      else
         call system_rcond(self%system, rcond, self%counts)
      end if
   end subroutine accepted_rcond

   !> The condition estimate of B_f's factor, squared (strain_rate_rcond),
   !> timed with the solves as the K form's (system_rcond): its work is
   !> the factor's solves.
   subroutine root_rcond(self, rcond)
      class(fem_core_type), intent(inout) :: self
      real(dp), intent(out) :: rcond
      real(dp) :: clock
      clock = phase_start(self%system)
      call strain_rate_rcond(self%root, rcond)
      call phase_end(self%system, clock, self%counts%seconds_solves)
   end subroutine root_rcond

   !> The drive response at the accepted configuration, whose factor the
   !> system (or root) holds: from B_f in the square-root form, else from K_ff.
   !> A factor carried to it (carry_factor) made it already, refined, into
   !> jump_response_new, which the branch check passes as resp.
   subroutine accepted_response(self, resp)
      class(fem_core_type), intent(inout) :: self
      real(dp), contiguous, intent(inout) :: resp(:, :)
      real(dp) :: clock
      logical :: carried
      if (self%root_form) then
         if (self%root%carried) then
            call self%factor%take_carried(carried)
            if (carried) return
         end if
         clock = phase_start(self%system)
         call root_drive_response(self%root, self%mesh, resp, self%root_work)
         call phase_end(self%system, clock, self%counts%seconds_solves)
      else
         call drive_response(self%system, self%mesh, resp, self%counts)
      end if
   end subroutine accepted_response

   !> Assemble and factor the material tangent at the filled configuration q
   !> at time t; its condition estimate (0 if singular), B_f's squared in the
   !> square-root form.
   subroutine fill_tangent(self, q, t, rcond)
      class(fem_core_type), intent(inout) :: self
      real(dp), contiguous, intent(in) :: q(:)
      real(dp), intent(in) :: t
      real(dp), intent(out) :: rcond
      integer :: info
      integer :: root_info
      call assemble_system(self%system, self%mesh, q, t, self%seg, huge(1.0_dp), self%counts)
      call factor_system(self%system, info, self%counts)
      call self%factor%invalidate()
      rcond = 0
      if (self%root_form) then
         ! On the scale of the run's best, which is B_f's in the square-root form.
         call factor_root(self, q, self%seg, root_info, self%system%section)
         if (root_info == 0) call root_rcond(self, rcond)
      else if (info == 0) then
         call system_rcond(self%system, rcond, self%counts)
      end if
   end subroutine fill_tangent

   !> Add the correction in the system's right-hand side to q: one Newton iteration more.
   subroutine take_correction(self, q, iterations)
      class(fem_core_type), intent(inout) :: self
      real(dp), contiguous, intent(inout) :: q(:)
      integer, intent(inout) :: iterations
      call apply_correction(self%system, self%mesh, q)
      iterations = iterations + 1
      self%counts%iterations = self%counts%iterations + 1
   end subroutine take_correction

   !> Make `before` the accepted state again; the tangent (and its free-driven
   !> block, which scales the convergence test) is refactored there.
   subroutine restore_state(self, before)
      class(fem_core_type), intent(inout) :: self
      type(fem_state_type), intent(in) :: before
      integer :: info
      self%state = before
      self%seg = before%seg
      call self%factor%invalidate()
      call refactor_at_accepted(self, info)
   end subroutine restore_state

end module fekap_fem_factor
