!> Test driver: `tester [suite [test]]` runs every suite, one suite, or one test.
program tester
   use fekap_testing, only: unittest_type, run_testsuite
   use test_element_beam, only: collect_element_beam
   use test_assembly_band, only: collect_assembly_band
   use test_assembly_mesh, only: collect_assembly_mesh
   use test_assembly_assemble, only: collect_assembly_assemble
   use test_solver_fem, only: collect_solver_fem
   use test_solver_convergence, only: collect_solver_convergence
   use test_solver_stepper, only: collect_solver_stepper
   use test_contact_slideline, only: collect_contact_slideline
   use test_classical_angles, only: collect_classical_angles
   use test_classical_constraints, only: collect_classical_constraints
   use test_classical_cartesian, only: collect_classical_cartesian
   use test_deck_expression, only: collect_deck_expression
   use test_deck, only: collect_deck
   use test_output_vtk, only: collect_output_vtk
   use test_output_format, only: collect_output_format
   use test_output_buffer, only: collect_output_buffer
   implicit none

   abstract interface
      subroutine collect_interface(tests)
         import :: unittest_type
         type(unittest_type), allocatable, intent(out) :: tests(:)
      end subroutine collect_interface
   end interface

   character(len=128) :: only_suite, only_test
   integer :: passed, failed

   only_suite = ''
   only_test = ''
   if (command_argument_count() >= 1) call get_command_argument(1, only_suite)
   if (command_argument_count() >= 2) call get_command_argument(2, only_test)
   passed = 0
   failed = 0

   call run('element_beam', collect_element_beam)
   call run('assembly_band', collect_assembly_band)
   call run('assembly_mesh', collect_assembly_mesh)
   call run('assembly_assemble', collect_assembly_assemble)
   call run('solver_convergence', collect_solver_convergence)
   call run('solver_stepper', collect_solver_stepper)
   call run('solver_fem', collect_solver_fem)
   call run('contact_slideline', collect_contact_slideline)
   call run('classical_angles', collect_classical_angles)
   call run('classical_constraints', collect_classical_constraints)
   call run('classical_cartesian', collect_classical_cartesian)
   call run('deck_expression', collect_deck_expression)
   call run('deck', collect_deck)
   call run('output_vtk', collect_output_vtk)
   call run('output_format', collect_output_format)
   call run('output_buffer', collect_output_buffer)

   if (failed > 0) error stop 1

contains

   subroutine run(name, collect)
      character(*), intent(in) :: name
      procedure(collect_interface) :: collect
      type(unittest_type), allocatable :: tests(:)
      if (len_trim(only_suite) > 0 .and. trim(only_suite) /= name) return
      call collect(tests)
      call run_testsuite(name, tests, passed, failed, trim(only_test))
   end subroutine run

end program tester
