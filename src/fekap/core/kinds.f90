!> The one real kind of FEKAP.
module fekap_kinds
   implicit none
   private

   !> Double precision, used for every real in the program.
   integer, parameter, public :: dp = selected_real_kind(15, 307)

end module fekap_kinds
