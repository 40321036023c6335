!> External loads as functions of time: a LOADs line's values (force and
!> moment) times its factor, the load factor t unless the line gives a law of
!> its own (constant, rate, harmonic, polynomial, cubic table, linear table;
!> fekap_model_drive_law). Statics, kinetostatics and dynamics all evaluate
!> loads here.
module fekap_model_loads
   use fekap_kinds, only: dp
   use fekap_model, only: model_type, load_type
   implicit none
   private

   public :: load_factor, load_at, load_count, has_timed_loads

contains

   !> The factor of `load` at time t and its first and second rates: its
   !> law's, or the load factor lambda = t (lambda' = 1, lambda'' = 0).
   elemental subroutine load_factor(load, t, f, df, ddf)
      type(load_type), intent(in) :: load
      real(dp), intent(in) :: t
      real(dp), intent(out) :: f, df, ddf
      if (load%timed) then
         call load%law%eval(t, f, df, ddf)
      else
         f = t
         df = 1
         ddf = 0
      end if
   end subroutine load_factor

   !> The force (fx, fy) and the moment of `load` at time t.
   pure subroutine load_at(load, t, force, moment)
      type(load_type), intent(in) :: load
      real(dp), intent(in) :: t
      real(dp), intent(out) :: force(2), moment
      real(dp) :: f, df, ddf
      call load_factor(load, t, f, df, ddf)
      force = f*load%force
      moment = f*load%moment
   end subroutine load_at

   !> Number of LOADs lines of the model.
   pure integer function load_count(model) result(n)
      type(model_type), intent(in) :: model
      n = 0
      if (allocated(model%loads)) n = size(model%loads)
   end function load_count

   !> Whether some load has a law of its own (not the load factor t).
   pure logical function has_timed_loads(model)
      type(model_type), intent(in) :: model
      has_timed_loads = .false.
      if (allocated(model%loads)) has_timed_loads = any(model%loads%timed)
   end function has_timed_loads

end module fekap_model_loads
