!> Tests of fekap_output_vtk and of the generic field output of
!> fekap_model_results: a small result written to a scratch file, read back
!> line by line, its XML structure and its values checked.
module test_output_vtk
   use fekap_kinds, only: dp
   use fekap_testing, only: unittest_type, new_unittest, check, test_failed, error_type
   use fekap_model, only: model_type
   use fekap_model_results, only: step_result_type, new_step_result, fill_fields_from_nodes
   use fekap_output_vtk, only: write_vtu, write_pvd
   implicit none
   private
   public :: collect_output_vtk

   !> Scratch directory (the tests run from the repository root).
   character(*), parameter :: scratch = 'build/test-vtk/'
   integer, parameter :: max_line = 256

contains

   subroutine collect_output_vtk(tests)
      type(unittest_type), allocatable, intent(out) :: tests(:)
      tests = [ &
         & new_unittest('vtu_structure', test_vtu_structure), &
         & new_unittest('vtu_values', test_vtu_values), &
         & new_unittest('vtu_without_rates', test_vtu_without_rates), &
         & new_unittest('pvd_collection', test_pvd), &
         & new_unittest('fields_from_nodes', test_fields_from_nodes) &
         & ]
   end subroutine collect_output_vtk

   !> Three points in a chain of two line cells (links 2 and 1), moved from
   !> their initial positions, with rates and stress resultants.
   subroutine small_result(result, initial)
      type(step_result_type), intent(out) :: result
      real(dp), allocatable, intent(out) :: initial(:, :)
      call new_step_result(result, 3, 2)
      result%step = 7
      result%t = 0.35_dp
      result%has_velocity = .true.
      result%has_acceleration = .true.
      initial = reshape([0.0_dp, 0.0_dp, 1.0_dp, 0.0_dp, 2.0_dp, 0.0_dp], [2, 3])
      result%mesh_pos = reshape([0.0_dp, 0.0_dp, 1.0_dp/3, 0.25_dp, 2.5_dp, -1.0e-20_dp], [2, 3])
      result%mesh_vel = reshape([0.0_dp, 0.0_dp, -1.5_dp, 2.0_dp, 3.0_dp, 4.0_dp], [2, 3])
      result%mesh_acc = reshape([0.0_dp, 0.0_dp, 10.0_dp, -20.0_dp, 1.0e300_dp, 7.0_dp], [2, 3])
      result%cells = reshape([1, 2, 2, 3], [2, 2])
      result%cell_link = [2, 1]
      result%cell_force = reshape([1.0_dp, -2.0_dp, 3.0_dp, 4.0_dp, 5.0_dp, acos(-1.0_dp)], [3, 2])
   end subroutine small_result

   !> Write `result` with `model` to the file `name` in the scratch directory
   !> and read its lines back.
   subroutine write_and_read(name, model, result, initial, lines)
      character(*), intent(in) :: name
      type(model_type), intent(in) :: model
      type(step_result_type), intent(in) :: result
      real(dp), intent(in) :: initial(:, :)
      character(len=max_line), allocatable, intent(out) :: lines(:)
      integer :: unit
      call execute_command_line('mkdir -p '//scratch)
      open (newunit=unit, file=scratch//name, status='replace', action='write')
      call write_vtu(unit, model, result, initial)
      close (unit)
      call read_lines(scratch//name, lines)
   end subroutine write_and_read

   subroutine read_lines(path, lines)
      character(*), intent(in) :: path
      character(len=max_line), allocatable, intent(out) :: lines(:)
      character(len=max_line) :: line
      integer :: unit, ios
      allocate (lines(0))
      open (newunit=unit, file=path, status='old', action='read')
      do
         read (unit, '(a)', iostat=ios) line
         if (ios /= 0) exit
         lines = [character(len=max_line) :: lines, line]
      end do
      close (unit)
   end subroutine read_lines

   !> Index of the first line that contains `text` (0 if none).
   pure integer function find_line(lines, text) result(idx)
      character(len=*), intent(in) :: lines(:)
      character(*), intent(in) :: text
      integer :: i
      idx = 0
      do i = 1, size(lines)
         if (index(lines(i), text) > 0) then
            idx = i
            return
         end if
      end do
   end function find_line

   !> The numbers of the DataArray whose opening line contains `tag`, read up
   !> to its closing line.
   subroutine array_values(lines, tag, values, error)
      character(len=*), intent(in) :: lines(:)
      character(*), intent(in) :: tag
      real(dp), allocatable, intent(out) :: values(:)
      type(error_type), allocatable, intent(inout) :: error
      integer :: first, i, ios, n
      real(dp) :: buffer(3)
      allocate (values(0))
      first = find_line(lines, tag)
      if (first == 0) then
         call test_failed(error, 'no DataArray '//tag)
         return
      end if
      do i = first + 1, size(lines)
         if (index(lines(i), '</DataArray>') > 0) return
         ! Up to three numbers a line: read them one count at a time.
         do n = 3, 1, -1
            read (lines(i), *, iostat=ios) buffer(1:n)
            if (ios == 0) exit
         end do
         values = [values, buffer(1:n)]
      end do
      call test_failed(error, 'DataArray '//tag//' is not closed')
   end subroutine array_values

   subroutine test_vtu_structure(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(step_result_type) :: result
      real(dp), allocatable :: initial(:, :)
      character(len=max_line), allocatable :: lines(:)
      character(*), parameter :: order(*) = [character(len=40) :: '<UnstructuredGrid>', '<Piece ', &
         & '<PointData', 'Name="displacement"', 'Name="velocity"', 'Name="acceleration"', '</PointData>', &
         & '<CellData', 'Name="link"', 'Name="N"', 'Name="V"', 'Name="M"', '</CellData>', '<Points>', &
         & '</Points>', '<Cells>', 'Name="connectivity"', 'Name="offsets"', 'Name="types"', '</Cells>', &
         & '</Piece>', '</UnstructuredGrid>', '</VTKFile>']
      integer :: i, at, last, opened, closed
      call small_result(result, initial)
      call write_and_read('structure.vtu', model, result, initial, lines)
      call check(error, trim(lines(1)) == '<?xml version="1.0"?>', 'XML declaration')
      call check(error, trim(lines(2)) == '<VTKFile type="UnstructuredGrid" version="0.1" '// &
         & 'byte_order="LittleEndian">', 'VTKFile element')
      call check(error, index(lines(find_line(lines, '<Piece ')), 'NumberOfPoints="3" NumberOfCells="2"') > 0, &
         & 'Piece counts')
      last = 0
      do i = 1, size(order)
         at = find_line(lines, trim(order(i)))
         call check(error, at > last, trim(order(i))//' present and in order')
         last = at
      end do
      call check(error, last == size(lines), '</VTKFile> is the last line')
      opened = 0
      closed = 0
      do i = 1, size(lines)
         if (index(lines(i), '<DataArray') > 0) opened = opened + 1
         if (index(lines(i), '</DataArray>') > 0) closed = closed + 1
      end do
      ! TimeValue, 3 point arrays, 4 cell arrays, Points, 3 cell-definition arrays.
      call check(error, opened, 12, 'DataArray elements')
      call check(error, closed, opened, 'closed DataArray elements')
      call check(error, index(lines(find_line(lines, 'Name="link"')), 'type="Int32"') > 0, 'link is Int32')
      call check(error, index(lines(find_line(lines, 'Name="M"')), 'type="Float64"') > 0, 'M is Float64')
      call check(error, index(lines(find_line(lines, 'Name="types"')), 'type="UInt8"') > 0, 'types are UInt8')
      call check(error, index(lines(find_line(lines, 'Name="velocity"')), 'NumberOfComponents="3"') > 0, &
         & 'velocity has 3 components')
   end subroutine test_vtu_structure

   subroutine test_vtu_values(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(step_result_type) :: result
      real(dp), allocatable :: initial(:, :), got(:), want(:)
      character(len=max_line), allocatable :: lines(:)
      call small_result(result, initial)
      call write_and_read('values.vtu', model, result, initial, lines)
      call array_values(lines, 'Name="TimeValue"', got, error)
      call check_all(error, got, [0.35_dp], 'TimeValue')
      ! The Points array (no Name) follows the <Points> line: search from there.
      call array_values(lines(find_line(lines, '<Points>'):), 'NumberOfComponents="3"', got, error)
      want = [0.0_dp, 0.0_dp, 0.0_dp, 1.0_dp/3, 0.25_dp, 0.0_dp, 2.5_dp, -1.0e-20_dp, 0.0_dp]
      call check_all(error, got, want, 'points (17 digits round-trip)')
      call array_values(lines, 'Name="displacement"', got, error)
      want = [0.0_dp, 0.0_dp, 0.0_dp, 1.0_dp/3 - 1, 0.25_dp, 0.0_dp, 0.5_dp, -1.0e-20_dp, 0.0_dp]
      call check_all(error, got, want, 'displacement')
      call array_values(lines, 'Name="velocity"', got, error)
      call check_all(error, got, [0.0_dp, 0.0_dp, 0.0_dp, -1.5_dp, 2.0_dp, 0.0_dp, 3.0_dp, 4.0_dp, 0.0_dp], 'velocity')
      call array_values(lines, 'Name="acceleration"', got, error)
      call check_all(error, got, [0.0_dp, 0.0_dp, 0.0_dp, 10.0_dp, -20.0_dp, 0.0_dp, 1.0e300_dp, 7.0_dp, 0.0_dp], &
         & 'acceleration')
      call array_values(lines, 'Name="link"', got, error)
      call check_all(error, got, [2.0_dp, 1.0_dp], 'link')
      call array_values(lines, 'Name="N"', got, error)
      call check_all(error, got, [1.0_dp, 4.0_dp], 'N')
      call array_values(lines, 'Name="V"', got, error)
      call check_all(error, got, [-2.0_dp, 5.0_dp], 'V')
      call array_values(lines, 'Name="M"', got, error)
      call check_all(error, got, [3.0_dp, acos(-1.0_dp)], 'M')
      call array_values(lines, 'Name="connectivity"', got, error)
      call check_all(error, got, [0.0_dp, 1.0_dp, 1.0_dp, 2.0_dp], 'connectivity (0-based)')
      call array_values(lines, 'Name="offsets"', got, error)
      call check_all(error, got, [2.0_dp, 4.0_dp], 'offsets')
      call array_values(lines, 'Name="types"', got, error)
      call check_all(error, got, [3.0_dp, 3.0_dp], 'types (VTK_LINE)')
   end subroutine test_vtu_values

   !> Rates that were not asked for, or not computed at the step, are left out.
   subroutine test_vtu_without_rates(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(step_result_type) :: result
      real(dp), allocatable :: initial(:, :)
      character(len=max_line), allocatable :: lines(:)
      call small_result(result, initial)
      result%has_acceleration = .false.
      call write_and_read('no-acceleration.vtu', model, result, initial, lines)
      call check(error, find_line(lines, 'Name="velocity"') > 0, 'velocity written')
      call check(error, find_line(lines, 'Name="acceleration"') == 0, 'no acceleration at this step')
      result%has_acceleration = .true.
      model%analysis%accelerations = .false.
      call write_and_read('no-acceleration.vtu', model, result, initial, lines)
      call check(error, find_line(lines, 'Name="acceleration"') == 0, 'no acceleration asked for')
      result%has_velocity = .false.
      call write_and_read('no-rates.vtu', model, result, initial, lines)
      call check(error, find_line(lines, 'Name="velocity"') == 0, 'no velocity at this step')
      call check(error, find_line(lines, 'Name="displacement"') > 0, 'displacement always written')
   end subroutine test_vtu_without_rates

   subroutine test_pvd(error)
      type(error_type), allocatable, intent(out) :: error
      character(len=max_line), allocatable :: lines(:)
      integer :: unit, q
      real(dp) :: t
      call execute_command_line('mkdir -p '//scratch)
      open (newunit=unit, file=scratch//'run.pvd', status='replace', action='write')
      call write_pvd(unit, [0.0_dp, 0.1_dp], [character(len=30) :: 'vtk/run_000000.vtu', 'vtk/run_000004.vtu'])
      close (unit)
      call read_lines(scratch//'run.pvd', lines)
      call check(error, size(lines), 7, 'lines')
      if (allocated(error)) return
      call check(error, trim(lines(1)) == '<?xml version="1.0"?>', 'XML declaration')
      call check(error, index(lines(2), '<VTKFile type="Collection"') == 1, 'VTKFile element')
      call check(error, adjustl(lines(3)) == '<Collection>', 'Collection element')
      call check(error, index(lines(4), '<DataSet timestep="0.0000000000000000E+000" part="0" ' // &
         & 'file="vtk/run_000000.vtu"/>') > 0, 'first DataSet: '//trim(lines(4)))
      call check(error, index(lines(5), 'file="vtk/run_000004.vtu"/>') > 0, 'second file (blanks trimmed)')
      q = index(lines(5), '"')
      read (lines(5)(q + 1:q + index(lines(5)(q + 1:), '"') - 1), *) t
      call check(error, t == 0.1_dp, 'second time round-trips')
      call check(error, adjustl(lines(6)) == '</Collection>', 'closing Collection')
      call check(error, adjustl(lines(7)) == '</VTKFile>', 'closing VTKFile')
   end subroutine test_pvd

   subroutine test_fields_from_nodes(error)
      type(error_type), allocatable, intent(out) :: error
      type(step_result_type) :: result
      integer :: k
      call new_step_result(result, 3, 2)
      result%pos = reshape([1.0_dp, 2.0_dp, 3.0_dp, 4.0_dp, 5.0_dp, 6.0_dp], [2, 3])
      result%vel = -result%pos
      result%acc = 2*result%pos
      do k = 1, 2
         call fill_fields_from_nodes(result, reshape([1, 2, 3, 2], [2, 2]))
      end do
      call check(error, all(result%mesh_pos == result%pos), 'points are the nodes')
      call check(error, all(result%mesh_vel == result%vel) .and. all(result%mesh_acc == result%acc), 'rates')
      call check(error, all(result%cells == reshape([1, 2, 3, 2], [2, 2])), 'cells are the links')
      call check(error, all(result%cell_link == [1, 2]), 'cell l is link l')
      call check(error, all(shape(result%cell_force) == [3, 2]), 'resultants shape')
      call check(error, all(result%cell_force == 0), 'zero resultants')
   end subroutine test_fields_from_nodes

   !> got equals want exactly (the writer's 17 digits round-trip), entry by entry.
   subroutine check_all(error, got, want, message)
      type(error_type), allocatable, intent(inout) :: error
      real(dp), intent(in) :: got(:), want(:)
      character(*), intent(in) :: message
      integer :: i
      call check(error, size(got), size(want), message//': number of values')
      if (allocated(error)) return
      do i = 1, size(want)
         call check(error, got(i), want(i), message, rel=0.0_dp, abs=0.0_dp)
      end do
   end subroutine check_all

end module test_output_vtk
