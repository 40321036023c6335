!> Tests of fekap_output_format: the fast texts equal what the formatted
!> write gives (es25.16e3 without leading blanks, i0) for values of every
!> magnitude, both signs, powers of ten and their neighbours, and halfway cases.
module test_output_format
   use fekap_kinds, only: dp
   use fekap_testing, only: unittest_type, new_unittest, check, error_type
   use fekap_output_format, only: real_text, integer_text, append_es, append_i
   implicit none
   private
   public :: collect_output_format

contains

   subroutine collect_output_format(tests)
      type(unittest_type), allocatable, intent(out) :: tests(:)
      tests = [ &
         & new_unittest('real_text', test_real_text), &
         & new_unittest('integer_text', test_integer_text), &
         & new_unittest('append_es', test_append_es), &
         & new_unittest('append_i', test_append_i) &
         & ]
   end subroutine collect_output_format

   !> real_text(x) equals the formatted write; the error names the first value that differs.
   subroutine check_real(error, x)
      type(error_type), allocatable, intent(inout) :: error
      real(dp), intent(in) :: x
      character(len=25) :: want
      character(len=80) :: msg
      write (want, '(es25.16e3)') x
      if (real_text(x) /= trim(adjustl(want))) then
         write (msg, '(a,es25.16e3,a)') 'real_text(', x, ') = '//real_text(x)
         call check(error, .false., trim(msg))
      end if
   end subroutine check_real

   subroutine test_real_text(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: x, u
      integer :: k, i, seed_size
      integer, allocatable :: seed(:)
      ! Zero, the extremes, subnormals and exact integers.
      call check_real(error, 0.0_dp)
      call check_real(error, -0.0_dp)
      call check_real(error, huge(1.0_dp))
      call check_real(error, -tiny(1.0_dp))
      call check_real(error, tiny(1.0_dp)/3)
      call check_real(error, 2.0_dp)
      call check_real(error, 12345678901234567.0_dp)
      call check_real(error, 0.1_dp)
      if (allocated(error)) return
      ! Powers of ten and their neighbours, where log10 may miss by one.
      do k = -30, 40
         x = 10.0_dp**k
         call check_real(error, x)
         call check_real(error, nearest(x, 1.0_dp))
         call check_real(error, -nearest(x, -1.0_dp))
         if (allocated(error)) return
      end do
      ! Halfway cases of the 17th digit: small integers times powers of two
      ! with exact decimal expansions longer than 17 digits.
      do k = 1, 60
         x = scale(real(2*k + 1, dp)*1.0e16_dp + 0.5_dp, -1)
         call check_real(error, x)
         call check_real(error, scale(1.0_dp + k*epsilon(1.0_dp), -k))
         if (allocated(error)) return
      end do
      ! Random values over 1e-20 .. 1e40, both signs.
      call random_seed(size=seed_size)
      allocate (seed(seed_size))
      seed = 20261121
      call random_seed(put=seed)
      do i = 1, 20000
         call random_number(u)
         call random_number(x)
         x = (x - 0.5_dp)*10.0_dp**(60*u - 20)
         call check_real(error, x)
         if (allocated(error)) return
      end do
   end subroutine test_real_text

   subroutine test_integer_text(error)
      type(error_type), allocatable, intent(out) :: error
      integer :: values(7), k
      character(len=12) :: want
      values = [0, 7, -7, 10, 123456789, huge(1), -huge(1) - 1]
      do k = 1, size(values)
         write (want, '(i0)') values(k)
         call check(error, integer_text(values(k)) == trim(want), 'integer_text of '//trim(want))
         if (allocated(error)) return
      end do
   end subroutine test_integer_text

   !> append_es equals the formatted write for the listing's descriptors
   !> es20.11 and es16.6 (two-digit exponents, three without the E beyond 99).
   subroutine test_append_es(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: x, u
      character(len=40) :: want, got
      integer :: i, n, f
      integer, parameter :: widths(2) = [20, 16], decimals(2) = [11, 6]
      character(len=10), parameter :: forms(2) = ['(es20.11) ', '(es16.6)  ']
      do i = 1, 4000
         call random_number(u)
         call random_number(x)
         x = (x - 0.5_dp)*10.0_dp**(300*u - 150)
         if (i == 1) x = 0
         if (i == 2) x = 9.9999999999995e-7_dp
         if (i == 3) x = 1.0e100_dp
         do f = 1, 2
            write (want, forms(f)) x
            n = 0
            got = ''
            call append_es(got, n, x, widths(f), decimals(f), 0)
            call check(error, n == widths(f) .and. got(1:n) == want(1:widths(f)), &
               & 'append_es '//trim(forms(f))//': '//got(1:n)//' against '//want(1:widths(f)))
            if (allocated(error)) return
         end do
      end do
   end subroutine test_append_es

   subroutine test_append_i(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=20) :: want, got
      integer :: values(5), k, n
      values = [0, 42, -42, 1234567, -huge(1) - 1]
      do k = 1, size(values)
         write (want, '(i8)') values(k)
         n = 0
         got = ''
         call append_i(got, n, values(k), 8)
         call check(error, got(1:n) == want(1:8), 'append_i: '//got(1:n)//' against '//want(1:8))
         if (allocated(error)) return
      end do
   end subroutine test_append_i

end module test_output_format
