!> Tests of fekap_model_drive_law: every law's rate and second rate against
!> central differences of its value, and the laws' defining values.
module test_drive_law
   use fekap_kinds, only: dp
   use fekap_testing, only: unittest_type, new_unittest, check, error_type
   use fekap_model_drive_law, only: law_type, new_rate_law, new_harmonic_law, new_polynomial_law, &
      & new_table_law
   implicit none
   private
   public :: collect_drive_law

contains

   subroutine collect_drive_law(tests)
      type(unittest_type), allocatable, intent(out) :: tests(:)
      tests = [ &
         & new_unittest('new_rate_law', test_rate), &
         & new_unittest('new_harmonic_law', test_harmonic), &
         & new_unittest('new_polynomial_law', test_polynomial), &
         & new_unittest('new_table_law', test_table) &
         & ]
   end subroutine collect_drive_law

   !> Rate and second rate of `law` equal central differences of its value at t.
   subroutine check_rates(error, law, t)
      type(error_type), allocatable, intent(inout) :: error
      type(law_type), intent(in) :: law
      real(dp), intent(in) :: t
      real(dp), parameter :: h = 1.0e-5_dp
      real(dp) :: f, df, ddf, fp, fm, dfp, dfm, dummy
      call law%eval(t, f, df, ddf)
      call law%eval(t + h, fp, dfp, dummy)
      call law%eval(t - h, fm, dfm, dummy)
      call check(error, df, (fp - fm)/(2*h), 'rate', rel=1.0e-7_dp, abs=1.0e-8_dp)
      call check(error, ddf, (dfp - dfm)/(2*h), 'second rate', rel=1.0e-6_dp, abs=1.0e-7_dp)
   end subroutine check_rates

   subroutine test_rate(error)
      type(error_type), allocatable, intent(out) :: error
      type(law_type) :: law
      real(dp) :: f, df, ddf
      call new_rate_law(law, 2.5_dp, 1.0_dp)
      call law%eval(2.0_dp, f, df, ddf)
      call check(error, f, 6.0_dp)
      call check(error, df, 2.5_dp)
      call check(error, ddf, 0.0_dp, abs=0.0_dp)
      call check(error, law%absolute, 'given v0 makes the law absolute')
      call new_rate_law(law, 2.5_dp)
      call check(error, .not. law%absolute, 'without v0 the law is relative')
   end subroutine test_rate

   subroutine test_harmonic(error)
      type(error_type), allocatable, intent(out) :: error
      type(law_type) :: law
      real(dp) :: f, df, ddf, pi
      pi = acos(-1.0_dp)
      ! Example 4: 60 deg + 30 deg cos(2 pi t) is 90 deg at t = 0.
      call new_harmonic_law(law, pi/3, pi/6, 2*pi, 0.0_dp)
      call law%eval(0.0_dp, f, df, ddf)
      call check(error, f, pi/2)
      call check_rates(error, law, 0.3_dp)
   end subroutine test_harmonic

   subroutine test_polynomial(error)
      type(error_type), allocatable, intent(out) :: error
      type(law_type) :: law
      real(dp) :: f, df, ddf
      call new_polynomial_law(law, [1.0_dp, -2.0_dp, 3.0_dp, 0.5_dp])
      call law%eval(2.0_dp, f, df, ddf)
      call check(error, f, 1 - 4 + 12 + 4.0_dp)
      call check(error, df, -2 + 12 + 6.0_dp)
      call check(error, ddf, 6 + 6.0_dp)
      call check_rates(error, law, -0.7_dp)
   end subroutine test_polynomial

   subroutine test_table(error)
      type(error_type), allocatable, intent(out) :: error
      type(law_type) :: law
      real(dp) :: f, df, ddf
      integer :: i
      call new_table_law(law, [0.0_dp, 0.3_dp, 0.5_dp, 1.0_dp], [0.0_dp, 1.0_dp, 0.5_dp, 2.0_dp])
      do i = 1, 4
         call law%eval(law%tt(i), f, df, ddf)
         call check(error, f, law%tv(i), 'knot value', abs=1.0e-14_dp)
      end do
      call law%eval(1.0_dp, f, df, ddf)
      call check(error, ddf, 0.0_dp, 'natural end', abs=1.0e-12_dp)
      call check_rates(error, law, 0.4_dp)
      ! A straight table reproduces the line with zero second rate.
      call new_table_law(law, [0.0_dp, 1.0_dp, 3.0_dp], [1.0_dp, 3.0_dp, 7.0_dp])
      call law%eval(2.0_dp, f, df, ddf)
      call check(error, f, 5.0_dp)
      call check(error, df, 2.0_dp)
      call check(error, ddf, 0.0_dp, abs=1.0e-13_dp)
   end subroutine test_table

end module test_drive_law
