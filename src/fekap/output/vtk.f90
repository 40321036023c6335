!> ParaView (VTK XML) output: one UnstructuredGrid file (.vtu, ASCII) per
!> written step and a .pvd collection that lists them with their times.
!> Writers take an open unit and never open files themselves. Reals are
!> written with 17 significant digits, enough to round-trip.
!>
!> A .vtu file holds the analysis mesh at one step in ParaView's convention
!> for displacements: its points at their reference (first-step) positions
!> (z = 0 in a planar run), its line cells (VTK_LINE, type 3), the point data `displacement`
!> (current position minus reference position: Warp By Vector with scale 1
!> shows the mechanism where it is), `velocity` and `acceleration` (when
!> computed at that step), the cell data `link` (1-based link index) and
!> `N`, `V`, `M` (the stress resultants of each cell), and the field data
!> `TimeValue` and `node_names` (the names of the model's nodes, which are
!> the first points, in the deck's order, as the bytes of each name ended by
!> a 0 in a UInt8 array: VTK's String arrays are unreadable to meshio).
module fekap_output_vtk
   use fekap_kinds, only: dp
   use fekap_model, only: model_type
   use fekap_model_results, only: step_result_type
   use fekap_output_format, only: real_text, integer_text
   implicit none
   private

   public :: write_vtu, write_pvd

   !> VTK's cell type of a two-point line.
   integer, parameter :: vtk_line = 3

contains

   !> One step's mesh and fields as a VTK XML UnstructuredGrid file.
   subroutine write_vtu(unit, model, result, initial_pos)
      !> An open formatted unit.
      integer, intent(in) :: unit
      !> The model (which rates the analysis computes).
      type(model_type), intent(in) :: model
      !> The step, with its field output (mesh_pos, cells, ...) filled.
      type(step_result_type), intent(in) :: result
      !> (2 or 3, npoint): the positions of the points at the first step, for the displacement.
      real(dp), intent(in) :: initial_pos(:, :)
      integer :: npoint, ncell, c
      logical :: vel, acc

      npoint = size(result%mesh_pos, 2)
      ncell = size(result%cells, 2)
      vel = model%analysis%velocities .and. result%has_velocity
      acc = vel .and. model%analysis%accelerations .and. result%has_acceleration

      write (unit, '(a)') '<?xml version="1.0"?>'
      write (unit, '(a)') '<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian">'
      write (unit, '(a)') '  <UnstructuredGrid>'
      write (unit, '(a)') '    <FieldData>'
      write (unit, '(a)') '      <DataArray type="Float64" Name="TimeValue" NumberOfTuples="1" format="ascii">'
      write (unit, '(8x,a)') real_text(result%t)
      write (unit, '(a)') '      </DataArray>'
      call write_names(unit, 'node_names', model)
      write (unit, '(a)') '    </FieldData>'
      write (unit, '(a)') '    <Piece NumberOfPoints="'//integer_text(npoint)//'" NumberOfCells="'//integer_text(ncell)//'">'

      write (unit, '(a)') '      <PointData Vectors="displacement">'
      call write_vectors(unit, 'displacement', result%mesh_pos - initial_pos)
      if (vel) call write_vectors(unit, 'velocity', result%mesh_vel)
      if (acc) call write_vectors(unit, 'acceleration', result%mesh_acc)
      write (unit, '(a)') '      </PointData>'

      write (unit, '(a)') '      <CellData Scalars="link">'
      call open_array(unit, 'Int32', 'link')
      do c = 1, ncell
         write (unit, '(10x,i0)') result%cell_link(c)
      end do
      call close_array(unit)
      call write_scalars(unit, 'N', result%cell_force(1, :))
      call write_scalars(unit, 'V', result%cell_force(2, :))
      call write_scalars(unit, 'M', result%cell_force(3, :))
      write (unit, '(a)') '      </CellData>'

      write (unit, '(a)') '      <Points>'
      call write_vectors(unit, '', initial_pos)
      write (unit, '(a)') '      </Points>'

      write (unit, '(a)') '      <Cells>'
      call open_array(unit, 'Int32', 'connectivity')
      do c = 1, ncell
         ! VTK numbers points from 0.
         write (unit, '(10x,i0,1x,i0)') result%cells(:, c) - 1
      end do
      call close_array(unit)
      call open_array(unit, 'Int32', 'offsets')
      do c = 1, ncell
         write (unit, '(10x,i0)') 2*c
      end do
      call close_array(unit)
      call open_array(unit, 'UInt8', 'types')
      do c = 1, ncell
         write (unit, '(10x,i0)') vtk_line
      end do
      call close_array(unit)
      write (unit, '(a)') '      </Cells>'

      write (unit, '(a)') '    </Piece>'
      write (unit, '(a)') '  </UnstructuredGrid>'
      write (unit, '(a)') '</VTKFile>'
   end subroutine write_vtu

   !> The .pvd collection: one DataSet per step file, with its time.
   subroutine write_pvd(unit, times, files)
      !> An open formatted unit.
      integer, intent(in) :: unit
      !> Time of each step file.
      real(dp), intent(in) :: times(:)
      !> Path of each step file relative to the .pvd (trailing blanks ignored).
      character(*), intent(in) :: files(:)
      integer :: i
      write (unit, '(a)') '<?xml version="1.0"?>'
      write (unit, '(a)') '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">'
      write (unit, '(a)') '  <Collection>'
      do i = 1, size(times)
         write (unit, '(a)') '    <DataSet timestep="'//real_text(times(i))//'" part="0" file="'// &
            & trim(files(i))//'"/>'
      end do
      write (unit, '(a)') '  </Collection>'
      write (unit, '(a)') '</VTKFile>'
   end subroutine write_pvd

   !> A Float64 array of 3-component vectors from (2, n) values (z = 0: a
   !> planar run) or (3, n) values (a spatial run); without a name (the
   !> Points array) the Name attribute is left out.
   subroutine write_vectors(unit, name, values)
      integer, intent(in) :: unit
      character(*), intent(in) :: name
      real(dp), intent(in) :: values(:, :)
      integer :: i
      if (len(name) > 0) then
         write (unit, '(a)') '        <DataArray type="Float64" Name="'//name// &
            & '" NumberOfComponents="3" format="ascii">'
      else
         write (unit, '(a)') '        <DataArray type="Float64" NumberOfComponents="3" format="ascii">'
      end if
      if (size(values, 1) == 3) then
         do i = 1, size(values, 2)
            write (unit, '(10x,a)') real_text(values(1, i))//' '//real_text(values(2, i))//' '//real_text(values(3, i))
         end do
      else
         do i = 1, size(values, 2)
            write (unit, '(10x,a)') real_text(values(1, i))//' '//real_text(values(2, i))//' 0'
         end do
      end if
      call close_array(unit)
   end subroutine write_vectors

   !> The names of the model's nodes as one UInt8 array: each name's bytes,
   !> ended by a 0. A numeric array, not a vtkStringArray, because the
   !> Python ecosystem's mesh reader (meshio) reads only numeric arrays.
   subroutine write_names(unit, name, model)
      integer, intent(in) :: unit
      character(*), intent(in) :: name
      type(model_type), intent(in) :: model
      integer :: i, j
      character(len=4) :: code
      if (.not. allocated(model%nodes)) return
      ! VTK reads a field-data array only with its length.
      write (unit, '(a)') '      <DataArray type="UInt8" Name="'//name//'" NumberOfTuples="'// &
         & integer_text(sum([(len(model%nodes(i)%name) + 1, i=1, size(model%nodes))]))//'" format="ascii">'
      do i = 1, size(model%nodes)
         write (unit, '(8x)', advance='no')
         do j = 1, len(model%nodes(i)%name)
            write (code, '(i0)') iachar(model%nodes(i)%name(j:j))
            write (unit, '(a,1x)', advance='no') trim(code)
         end do
         write (unit, '(a)') '0'
      end do
      write (unit, '(a)') '      </DataArray>'
   end subroutine write_names

   !> A Float64 array of scalars.
   subroutine write_scalars(unit, name, values)
      integer, intent(in) :: unit
      character(*), intent(in) :: name
      real(dp), intent(in) :: values(:)
      integer :: i
      call open_array(unit, 'Float64', name)
      do i = 1, size(values)
         write (unit, '(10x,a)') real_text(values(i))
      end do
      call close_array(unit)
   end subroutine write_scalars

   subroutine open_array(unit, type_, name)
      integer, intent(in) :: unit
      character(*), intent(in) :: type_, name
      write (unit, '(a)') '        <DataArray type="'//type_//'" Name="'//name//'" format="ascii">'
   end subroutine open_array

   subroutine close_array(unit)
      integer, intent(in) :: unit
      write (unit, '(a)') '        </DataArray>'
   end subroutine close_array

end module fekap_output_vtk
