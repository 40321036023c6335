!> The FEM stepper's factor record: whether the linear system (or, in the
!> square-root form, the strain-rate operator B_f) holds the factor of the
!> tangent at the accepted configuration, and whether factoring it there
!> failed (a singular configuration). Its fields are private: a step marks
!> the factor it made at the accepted configuration (mark), anything that
!> overwrites the factor invalidates it, a new step resets both; the rates,
!> the free-motion probe and kinetostatics ask (is_current, is_singular).
!> A factor carried to the accepted configuration from Newton's last
!> iterate (fekap_fem_factor's carry_factor) comes with the drive response
!> made there, which the branch check takes once (take_carried). A factor
!> made at the predictor and kept for the accepted configuration, a
!> correction of round-off size away (a step accepted at its predictor),
!> keeps B's geometry there too in the square-root form; rates that are
!> refined ask once whether to move it (take_kept_predictor).
module fekap_fem_factor_record
   implicit none
   private

   public :: factor_record_type

   type :: factor_record_type
      private
      logical :: current = .false., singular = .false., carried = .false., kept_predictor = .false.
   contains
      !> Whether the system holds the factor of the tangent at the accepted configuration.
      procedure :: is_current => record_is_current
      !> Whether factoring the tangent at the accepted configuration failed.
      procedure :: is_singular => record_is_singular
      !> The factorisation at the accepted configuration ended with LAPACK's
      !> info: held if 0, singular if not.
      procedure :: mark => record_mark
      !> The factor was overwritten (another configuration's, a shifted one):
      !> no longer the accepted configuration's. Whether that one is singular stays known.
      procedure :: invalidate => record_invalidate
      !> A new configuration is being solved: nothing is known about its factor.
      procedure :: reset => record_reset
      !> The factor held was carried to the accepted configuration, with its
      !> drive response (made by carry_factor).
      procedure :: carry => record_carry
      !> Whether a carried factor's drive response is waiting; it is taken once.
      procedure :: take_carried => record_take_carried
      !> The factor held is the predictor's, kept for the accepted
      !> configuration (its geometry with it, in the square-root form).
      procedure :: keep_predictor => record_keep_predictor
      !> Whether the factor held was kept from the predictor; asked once.
      procedure :: take_kept_predictor => record_take_kept_predictor
   end type factor_record_type

contains

   pure logical function record_is_current(self) result(current)
      class(factor_record_type), intent(in) :: self
      current = self%current
   end function record_is_current

   pure logical function record_is_singular(self) result(singular)
      class(factor_record_type), intent(in) :: self
      singular = self%singular
   end function record_is_singular

   pure subroutine record_mark(self, info)
      class(factor_record_type), intent(inout) :: self
      integer, intent(in) :: info
      self%current = info == 0
      self%singular = info /= 0
   end subroutine record_mark

   pure subroutine record_invalidate(self)
      class(factor_record_type), intent(inout) :: self
      self%current = .false.
      self%carried = .false.
      self%kept_predictor = .false.
   end subroutine record_invalidate

   pure subroutine record_reset(self)
      class(factor_record_type), intent(inout) :: self
      call record_invalidate(self)
      self%singular = .false.
   end subroutine record_reset

   pure subroutine record_carry(self)
      class(factor_record_type), intent(inout) :: self
      self%carried = .true.
   end subroutine record_carry

   pure subroutine record_take_carried(self, carried)
      class(factor_record_type), intent(inout) :: self
      logical, intent(out) :: carried
      carried = self%carried
      self%carried = .false.
   end subroutine record_take_carried

   pure subroutine record_keep_predictor(self)
      class(factor_record_type), intent(inout) :: self
      self%kept_predictor = .true.
   end subroutine record_keep_predictor

   pure subroutine record_take_kept_predictor(self, kept)
      class(factor_record_type), intent(inout) :: self
      logical, intent(out) :: kept
      kept = self%kept_predictor
      self%kept_predictor = .false.
   end subroutine record_take_kept_predictor

end module fekap_fem_factor_record
