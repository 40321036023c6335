!> What `fpm test` runs: fpm has no pFUnit support, so FEKAP's suites (the
!> pFUnit suites of test/*.pf and the pytest tests of test/app) are built and
!> run by scripts/test, which this program names. It runs no test itself and
!> says so, so that `fpm test` is never read as a passing suite.
program fpm_test_pointer
   use, intrinsic :: iso_fortran_env, only: error_unit
   implicit none
   write (error_unit, '(a)') 'fpm test runs no FEKAP test: fpm cannot build pFUnit suites.', &
      & 'Run every test with   scripts/test          (ends with "N passed, N failed")', &
      & 'or some of them with  scripts/test NAME     (pFUnit tests and pytest -k NAME)', &
      & 'from the top of the checkout; docs/testing.md says more.'
   stop 77
end program fpm_test_pointer
