!> Tests of fekap_output_format: the fast texts equal what the formatted
!> write gives (es25.16e3 without leading blanks, i0) for values of every
!> magnitude, both signs, powers of ten and their neighbours, and halfway
!> cases; random bit patterns (every exponent, subnormals, infinities)
!> through each ES descriptor of the output files.
module test_output_format
   use fekap_kinds, only: dp
   use fekap_testing, only: unittest_type, new_unittest, check, error_type
   use fekap_output_format, only: real_text, integer_text, append_es, append_i
   implicit none
   private
   public :: collect_output_format

   integer, parameter :: i8 = selected_int_kind(18)

contains

   subroutine collect_output_format(tests)
      type(unittest_type), allocatable, intent(out) :: tests(:)
      tests = [ &
         & new_unittest('real_text', test_real_text), &
         & new_unittest('integer_text', test_integer_text), &
         & new_unittest('append_es', test_append_es), &
         & new_unittest('append_i', test_append_i), &
         & new_unittest('append_es_bits', test_append_es_bits), &
         & new_unittest('append_es_ties', test_append_es_ties) &
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
      integer :: k, i
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
      ! Powers of ten and their neighbours, where the decimal exponent
      ! estimated from the binary one may miss by one.
      do k = -45, 45
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
      call seed_random(20261121)
      do i = 1, 20000
         call random_number(u)
         call random_number(x)
         x = (x - 0.5_dp)*10.0_dp**(60*u - 20)
         call check_real(error, x)
         if (allocated(error)) return
      end do
      ! Random values over 1e-45 .. 1e-14, where m 5**k needs more than 128
      ! bits (the product by the halves of 5**k), and over the kinematic
      ! range 1e-6 .. 1e6.
      do i = 1, 20000
         call random_number(u)
         call random_number(x)
         x = (x - 0.5_dp)*10.0_dp**(31*u - 45)
         call check_real(error, x)
         call random_number(u)
         call random_number(x)
         x = (x - 0.5_dp)*10.0_dp**(12*u - 6)
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
   !> es20.11 and es16.6 with two-digit exponents, and es20.11e3 and es16.6e3
   !> with three (which keep their E; es20.11 writes 1e100 as 1.00000000000+100).
   subroutine test_append_es(error)
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: x, u
      character(len=40) :: want, got
      integer :: i, n, f
      integer, parameter :: widths(2) = [20, 16], decimals(2) = [11, 6]
      character(len=10), parameter :: forms(2) = ['(es20.11) ', '(es16.6)  ']
      character(len=12), parameter :: forms3(2) = ['(es20.11e3)', '(es16.6e3) ']
      do i = 1, 4000
         call random_number(u)
         call random_number(x)
         x = (x - 0.5_dp)*10.0_dp**(300*u - 150)
         if (i == 1) x = 0
         if (i == 2) x = 9.9999999999995e-7_dp
         if (i == 3) x = 1.0e100_dp
         do f = 1, 2
            write (want, forms(f)) x
            if (index(want(1:widths(f)), 'E') == 0) write (want, forms3(f)) x
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

   !> append_es of x equals the formatted write for es25.16e3, es20.11 and es16.6
   !> (es20.11e3 and es16.6e3 for a three-digit exponent).
   subroutine check_es_forms(error, x)
      type(error_type), allocatable, intent(inout) :: error
      real(dp), intent(in) :: x
      integer, parameter :: widths(3) = [25, 20, 16], decimals(3) = [16, 11, 6], exponents(3) = [3, 0, 0]
      character(len=12), parameter :: forms(3) = ['(es25.16e3)', '(es20.11)  ', '(es16.6)   ']
      character(len=12), parameter :: forms3(3) = ['(es25.16e3)', '(es20.11e3)', '(es16.6e3) ']
      character(len=40) :: want, got
      character(len=16) :: bits
      integer :: f, n
      do f = 1, size(forms)
         write (want, forms(f)) x
         ! A three-digit exponent keeps its E (es_text).
         if (index(want(1:widths(f)), 'E') == 0 .and. x == x .and. abs(x) <= huge(x)) write (want, forms3(f)) x
         n = 0
         got = ''
         call append_es(got, n, x, widths(f), decimals(f), exponents(f))
         if (n /= widths(f) .or. got(1:n) /= want(1:widths(f))) then
            write (bits, '(z16.16)') transfer(x, 0_i8)
            call check(error, .false., 'append_es '//trim(forms(f))//' of the bits '//bits//': '//got(1:n)// &
               & ' against '//want(1:widths(f)))
            return
         end if
      end do
   end subroutine check_es_forms

   subroutine test_append_es_bits(error)
      type(error_type), allocatable, intent(out) :: error
      integer(i8) :: bits
      real(dp) :: u(3)
      integer :: i
      call seed_random(1987)
      do i = 1, 20000
         call random_number(u)
         bits = ior(shiftl(int(u(1)*2.0_dp**31, i8), 32), int(u(2)*2.0_dp**32, i8))
         ! No NaN: the tests trap invalid operations, and the output files
         ! never hold one (exponent bits all ones: the infinity instead).
         if (shiftr(bits, 52) == 2047) bits = shiftl(2047_i8, 52)
         if (u(3) < 0.5_dp) bits = ibset(bits, 63)
         call check_es_forms(error, transfer(bits, 1.0_dp))
         if (allocated(error)) return
      end do
   end subroutine test_append_es_bits

   !> Values whose digits beyond those kept are exactly 5 (ties to even) or
   !> end just after it: powers of two, odd multiples of small powers of two,
   !> integers and halves of 12 to 18 digits.
   subroutine test_append_es_ties(error)
      type(error_type), allocatable, intent(out) :: error
      integer :: k, j
      real(dp) :: x
      do k = -80, 80
         do j = 1, 41, 2
            x = scale(real(j, dp), k)
            call check_es_forms(error, x)
            call check_es_forms(error, -x)
            call check_es_forms(error, nearest(x, 1.0_dp))
            if (allocated(error)) return
         end do
      end do
      do k = 1, 2000
         x = 123456789012.5_dp + real(k, dp)
         call check_es_forms(error, x)
         x = 1234567.5_dp + real(k, dp)
         call check_es_forms(error, x)
         x = 12345678901234565.0_dp + 2*real(k, dp)
         call check_es_forms(error, x)
         x = 9999999.5_dp - real(k, dp)
         call check_es_forms(error, x)
         if (allocated(error)) return
      end do
   end subroutine test_append_es_ties

   !> Seed the intrinsic generator with one value (reproducible sequences).
   subroutine seed_random(value)
      integer, intent(in) :: value
      integer :: seed_size
      integer, allocatable :: seed(:)
      call random_seed(size=seed_size)
      allocate (seed(seed_size), source=value)
      call random_seed(put=seed)
   end subroutine seed_random

end module test_output_format
