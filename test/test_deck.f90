!> Tests of fekap_deck: a good deck maps to the expected model, every example
!> deck in decks/ reads, and each kind of bad input gives an input error whose
!> message points at the right line with the right phrase.
module test_deck
   use fekap_kinds, only: dp
   use fekap_testing, only: unittest_type, new_unittest, check, test_failed, error_type
   use fekap_error, only: error_input
   use fekap_model, only: model_type, find_node, find_link, dof_x, dof_y, dof_rot, method_cartesian, &
      & predictor_taylor, convergence_paper, joint_pin_in_slot, joint_prismatic
   use fekap_model_drive_law, only: law_rate, law_harmonic, law_polynomial, law_table
   use fekap_deck, only: read_deck, read_deck_string
   use test_example_decks, only: example_decks
   implicit none
   private
   public :: collect_deck

   real(dp), parameter :: pi = acos(-1.0_dp)
   character(*), parameter :: nl = new_line('a')
   !> Scratch directory for decks written to files (the tests run from the repository root).
   character(*), parameter :: scratch = 'build/test-deck/'

   !> A minimal good deck around which bad-input tests vary one thing.
   character(*), parameter :: base_head = 'SECTions'//nl//' bar E=1 G=1 A=100 I=1 k=5/6'//nl// &
      & 'NODEs'//nl//' A 0 0'//nl//' B 2 0'//nl//'LINKs'//nl//' AB A B bar'//nl

contains

   subroutine collect_deck(tests)
      type(unittest_type), allocatable, intent(out) :: tests(:)
      tests = [ &
         & new_unittest('good_deck_model', test_good_deck), &
         & new_unittest('defaults', test_defaults), &
         & new_unittest('drive_laws', test_drive_laws), &
         & new_unittest('slidelines', test_slidelines), &
         & new_unittest('example_decks', test_example_decks), &
         & new_unittest('keyword_matching', test_keywords), &
         & new_unittest('fields_and_comments', test_fields), &
         & new_unittest('include', test_include), &
         & new_unittest('read_deck_file', test_read_file), &
         & new_unittest('documented_example', test_documented_example), &
         & new_unittest('diagnostic_format', test_format), &
         & new_unittest('all_errors_collected', test_all_errors), &
         & new_unittest('unknown_card', test_unknown_card), &
         & new_unittest('missing_block', test_missing_block), &
         & new_unittest('non_numeric_field', test_non_numeric), &
         & new_unittest('missing_field', test_missing_field), &
         & new_unittest('duplicate_node', test_duplicate_node), &
         & new_unittest('undefined_node', test_undefined_node), &
         & new_unittest('zero_length_link', test_zero_length), &
         & new_unittest('non_positive_section', test_section_property), &
         & new_unittest('time_step', test_time_step), &
         & new_unittest('end_before_start', test_end_before_start), &
         & new_unittest('analysis_values', test_analysis_values), &
         & new_unittest('drive_on_support', test_drive_on_support), &
         & new_unittest('drive_conflicts', test_drive_conflicts), &
         & new_unittest('drive_initial_value', test_drive_initial), &
         & new_unittest('weld_and_clamp_ends', test_link_ends), &
         & new_unittest('slideline_errors', test_slideline_errors), &
         & new_unittest('node_not_on_link', test_unused_node), &
         & new_unittest('empty_file', test_empty_file), &
         & new_unittest('missing_file', test_missing_file), &
         & new_unittest('unterminated_deck', test_unterminated), &
         & new_unittest('binary_file', test_binary_file), &
         & new_unittest('not_finite_numbers', test_not_finite), &
         & new_unittest('name_is_keyword', test_name_keyword), &
         & new_unittest('unknown_parameters', test_unknown_parameters), &
         & new_unittest('text_after_end', test_after_end) &
         & ]
   end subroutine collect_deck

   !> Read `text` as deck t.deck; it must have no error.
   subroutine read_good(error, model, text)
      type(error_type), allocatable, intent(inout) :: error
      type(model_type), intent(out) :: model
      character(*), intent(in) :: text
      type(error_type), allocatable :: failure
      call read_deck_string(model, text, 't.deck', failure)
      if (allocated(failure)) call test_failed(error, 'unexpected error:'//nl//failure%message)
   end subroutine read_good

   !> Read `text` as deck t.deck; it must give an input error whose message
   !> contains `where` (e.g. 't.deck:5:') and `phrase`.
   subroutine expect_error(error, text, where, phrase, also)
      type(error_type), allocatable, intent(inout) :: error
      character(*), intent(in) :: text, where, phrase
      !> A further phrase the message must contain.
      character(*), intent(in), optional :: also
      type(model_type) :: model
      type(error_type), allocatable :: failure
      if (allocated(error)) return
      call read_deck_string(model, text, 't.deck', failure)
      call check_failure(error, failure, where, phrase, also)
   end subroutine expect_error

   subroutine check_failure(error, failure, where, phrase, also)
      type(error_type), allocatable, intent(inout) :: error
      type(error_type), allocatable, intent(in) :: failure
      character(*), intent(in) :: where, phrase
      character(*), intent(in), optional :: also
      if (allocated(error)) return
      if (.not. allocated(failure)) then
         call test_failed(error, 'no error; expected '//where//' '//phrase)
         return
      end if
      if (failure%kind /= error_input) then
         call test_failed(error, 'not an input error: '//failure%message)
      else if (index(failure%message, where) == 0 .or. index(failure%message, phrase) == 0) then
         call test_failed(error, 'expected "'//where//'" and "'//phrase//'" in:'//nl//failure%message)
      else if (present(also)) then
         if (index(failure%message, also) == 0) call test_failed(error, 'expected "'//also//'" in:'//nl//failure%message)
      end if
   end subroutine check_failure

   !> The deck base_head plus `rest` plus END, with a drive.
   pure function with_base(rest) result(text)
      character(*), intent(in) :: rest
      character(:), allocatable :: text
      text = base_head//'SUPPorts'//nl//' A pin'//nl//rest//'DRIVes'//nl//' rotation AB rate 1'//nl//'END'//nl
   end function with_base

   subroutine test_good_deck(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      integer :: b, c, bc
      character(*), parameter :: text = &
         & '* Example 1 with everything'//nl// &
         & 'TITLe   Four-bar linkage, convergence study   ! a comment'//nl// &
         & 'SECTions'//nl// &
         & '  bar   E=1  G=1  A=100  I=1  k=5/6'//nl// &
         & '  stiff EA=1e4 kGA=2e3 EI=3'//nl// &
         & 'NODEs'//nl// &
         & '  A   0   0'//nl// &
         & '  B   2   0'//nl// &
         & '  C   3   sqrt(15)'//nl// &
         & '  D   4   0'//nl// &
         & 'LINKs'//nl// &
         & '  AB  A  B  bar'//nl// &
         & '  BC  B  C  bar 4'//nl// &
         & '  DC  D  C  stiff'//nl// &
         & 'WELDs'//nl// &
         & '  C  BC DC'//nl// &
         & 'SUPPorts'//nl// &
         & '  A  pin'//nl// &
         & '  D  x'//nl// &
         & '  D  y rot DC'//nl// &
         & 'DRIVes'//nl// &
         & '  rotation AB  rate 2*pi'//nl// &
         & 'LOADs'//nl// &
         & '  B  1  -2  moment BC 0.5'//nl// &
         & 'ANALysis'//nl// &
         & '  method cartesian'//nl// &
         & '  time 0 2 0.1'//nl// &
         & '  compute positions velocities'//nl// &
         & '  tolerance 1e-8'//nl// &
         & '  length 1e-10'//nl// &
         & '  iterations 40'//nl// &
         & '  predictor taylor'//nl// &
         & '  convergence paper'//nl// &
         & '  gauss 2'//nl// &
         & '  redundant remove'//nl// &
         & 'OUTPut'//nl// &
         & '  track B C'//nl// &
         & '  angles AB BC'//nl// &
         & '  every 5'//nl// &
         & '  files csv vtk'//nl// &
         & 'END'//nl
      call read_good(error, model, text)
      if (allocated(error)) return
      call check(error, model%title == 'Four-bar linkage, convergence study', 'title "'//model%title//'"')
      call check(error, model%file == 't.deck', 'file')
      ! Sections.
      call check(error, size(model%sections), 2)
      call check(error, model%sections(1)%ea, 100.0_dp)
      call check(error, model%sections(1)%kga, 500.0_dp/6)
      call check(error, model%sections(1)%ei, 1.0_dp)
      call check(error, model%sections(2)%ea, 1.0e4_dp)
      call check(error, model%sections(2)%kga, 2.0e3_dp)
      call check(error, model%sections(2)%ei, 3.0_dp)
      ! Nodes.
      call check(error, size(model%nodes), 4)
      c = find_node(model, 'c')
      call check(error, c, 3)
      call check(error, model%nodes(c)%x(1), 3.0_dp)
      call check(error, model%nodes(c)%x(2), sqrt(15.0_dp))
      call check(error, model%nodes(c)%name == 'C', 'name keeps its spelling')
      call check(error, model%nodes(c)%loc%line, 9)
      call check(error, model%nodes(c)%loc%col, 3)
      call check(error, model%nodes(c)%loc%file == 't.deck', 'loc file')
      ! Links.
      call check(error, size(model%links), 3)
      bc = find_link(model, 'BC')
      b = find_node(model, 'B')
      call check(error, model%links(bc)%node(1), b)
      call check(error, model%links(bc)%node(2), c)
      call check(error, model%links(bc)%section, 1)
      call check(error, model%links(bc)%nelem, 4)
      call check(error, model%links(1)%nelem, 1)
      call check(error, model%links(3)%section, 2)
      call check(error, model%links(bc)%loc%line, 13)
      ! Welds.
      call check(error, size(model%welds), 1)
      call check(error, model%welds(1)%node, c)
      call check(error, all(model%welds(1)%links == [2, 3]), 'weld links')
      ! Supports: D's two lines are merged.
      call check(error, size(model%supports), 2)
      call check(error, all(model%supports(1)%fix .eqv. [.true., .true., .false.]), 'A pinned')
      call check(error, model%supports(2)%node, 4)
      call check(error, all(model%supports(2)%fix .eqv. [.true., .true., .true.]), 'D clamped')
      call check(error, model%supports(2)%link, 3)
      ! Drive.
      call check(error, size(model%drives), 1)
      call check(error, model%drives(1)%dof, dof_rot)
      call check(error, model%drives(1)%link, 1)
      call check(error, model%drives(1)%node, 1)
      call check(error, model%drives(1)%law%kind, law_rate)
      call check(error, model%drives(1)%law%c(1), 2*pi)
      call check(error, .not. model%drives(1)%law%absolute, 'rate without V0 is relative')
      ! Load.
      call check(error, size(model%loads), 1)
      call check(error, model%loads(1)%node, b)
      call check(error, model%loads(1)%force(1), 1.0_dp)
      call check(error, model%loads(1)%force(2), -2.0_dp)
      call check(error, model%loads(1)%moment, 0.5_dp)
      call check(error, model%loads(1)%link, bc)
      ! Analysis.
      call check(error, model%analysis%method, method_cartesian)
      call check(error, model%analysis%t_start, 0.0_dp)
      call check(error, model%analysis%t_end, 2.0_dp)
      call check(error, model%analysis%dt, 0.1_dp)
      call check(error, model%analysis%velocities, 'velocities')
      call check(error, .not. model%analysis%accelerations, 'no accelerations')
      call check(error, model%analysis%tol, 1.0e-8_dp)
      call check(error, model%analysis%length_tol, 1.0e-10_dp)
      call check(error, model%analysis%max_iter, 40)
      call check(error, model%analysis%predictor, predictor_taylor)
      call check(error, model%analysis%convergence, convergence_paper)
      call check(error, model%analysis%gauss_points, 2)
      call check(error, model%analysis%remove_redundant, 'redundant remove')
      ! Output.
      call check(error, all(model%output%points == [2, 3]), 'tracked points')
      call check(error, all(model%output%links == [1, 2]), 'reported links')
      call check(error, model%output%every, 5)
      call check(error, model%output%csv .and. model%output%vtk .and. .not. model%output%listing, 'files')
   end subroutine test_good_deck

   subroutine test_defaults(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      call read_good(error, model, with_base(''))
      if (allocated(error)) return
      call check(error, model%title == '', 'no title')
      call check(error, model%sections(1)%kga, 100.0_dp*5/6)
      call check(error, all(model%output%points == [1, 2]), 'every node tracked')
      call check(error, all(model%output%links == [1]), 'every link reported')
      call check(error, model%output%csv .and. model%output%listing .and. .not. model%output%vtk, 'files')
      call check(error, model%analysis%dt, 0.025_dp)
      call check(error, model%analysis%velocities .and. model%analysis%accelerations, 'compute all')
      call check(error, size(model%welds), 0)
      call check(error, size(model%loads), 0)
      call check(error, size(model%slidelines), 0)
      ! k defaults to 5/6.
      call read_good(error, model, 'SECTions'//nl//' bar E=2 G=3 A=4 I=5'//nl//'NODEs'//nl//' A 0 0'//nl// &
         & ' B 1 0'//nl//'LINKs'//nl//' AB A B bar'//nl//'LOADs'//nl//' B 0 1'//nl//'END')
      if (allocated(error)) return
      call check(error, model%sections(1)%ea, 8.0_dp)
      call check(error, model%sections(1)%kga, 10.0_dp)
      call check(error, model%sections(1)%ei, 10.0_dp)
   end subroutine test_defaults

   subroutine test_drive_laws(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      ! Node B at (2, 0): absolute laws must start there (x = 2, y = 0).
      call read_good(error, model, base_head//'SUPPorts'//nl//' A pin'//nl//'DRIVes'//nl// &
         & ' x B harmonic 1 1 pi'//nl// &
         & ' y B table 0 0 0.5 1 1 0'//nl// &
         & ' rotation AB polynomial 0 1 0.5'//nl//'END')
      if (allocated(error)) return
      call check(error, size(model%drives), 3)
      call check(error, model%drives(1)%dof, dof_x)
      call check(error, model%drives(1)%node, 2)
      call check(error, model%drives(1)%law%kind, law_harmonic)
      call check(error, model%drives(1)%law%c(3), pi)
      call check(error, model%drives(1)%law%c(4), 0.0_dp)
      call check(error, model%drives(2)%dof, dof_y)
      call check(error, model%drives(2)%law%kind, law_table)
      call check(error, size(model%drives(2)%law%tt), 3)
      call check(error, model%drives(2)%law%tv(2), 1.0_dp)
      call check(error, model%drives(3)%law%kind, law_polynomial)
      call check(error, size(model%drives(3)%law%c), 3)
      ! An absolute rate law that matches: the angle of AB is 0 at t = 0, 2*pi counts as 0.
      call read_good(error, model, with_base('') // '')
      call read_good(error, model, base_head//'DRIVes'//nl//' rotation AB rate 1 2*pi'//nl//'END')
      if (allocated(error)) return
      call check(error, model%drives(1)%law%absolute, 'V0 given: absolute')
      call check(error, model%drives(1)%law%c(2), 2*pi)
   end subroutine test_drive_laws

   subroutine test_slidelines(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      call read_good(error, model, &
         & 'SECTions'//nl//' bar EA=1 kGA=1 EI=1'//nl// &
         & 'COORdinates'//nl//' O 0 0'//nl//' M 2 0'//nl//' E 4 0'//nl//' S 1 0'//nl//' T 1 1'//nl// &
         & ' U 3 0'//nl//' V 3 -1'//nl// &
         & 'ELEMents'//nl//' OM O M bar'//nl//' ME M E bar'//nl//' ST S T bar'//nl//' UV U V bar'//nl// &
         & 'SLIDelines'//nl//' s1 S on OM ME prismatic ST penalty=1e3'//nl// &
         & ' s2 U guide 0 0 10 0'//nl// &
         & 'BOUNdary'//nl//' O pin rot OM'//nl// &
         & 'LOADs'//nl//' T 1 0'//nl//'END')
      if (allocated(error)) return
      call check(error, size(model%slidelines), 2)
      associate (s => model%slidelines(1))
         call check(error, s%name == 's1', 'name')
         call check(error, s%slave, find_node(model, 'S'))
         call check(error, all(s%master_links == [1, 2]), 'master links in order')
         call check(error, .not. s%ground, 'not ground')
         call check(error, s%kind, joint_prismatic)
         call check(error, s%slave_link, 3)
         call check(error, s%penalty, 1.0e3_dp)
      end associate
      associate (s => model%slidelines(2))
         call check(error, s%ground, 'ground guide')
         call check(error, s%kind, joint_pin_in_slot)
         call check(error, s%guide(1, 1), 0.0_dp)
         call check(error, s%guide(1, 2), 10.0_dp)
         call check(error, s%guide(2, 2), 0.0_dp)
         call check(error, s%penalty, 0.0_dp)
         call check(error, size(s%master_links), 0)
      end associate
   end subroutine test_slidelines

   subroutine test_example_decks(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(error_type), allocatable :: failure
      integer :: i, o, a, b, d, p
      do i = 1, size(example_decks)
         call read_deck(model, 'decks/'//trim(example_decks(i))//'.deck', failure)
         if (allocated(failure)) then
            call test_failed(error, trim(example_decks(i))//':'//nl//failure%message)
            return
         end if
      end do
      ! Peaucellier: B and D are 3 from O and 1.2 from A and P; B left of O->A.
      call read_deck(model, 'decks/peaucellier.deck', failure)
      o = find_node(model, 'O')
      a = find_node(model, 'A')
      b = find_node(model, 'B')
      d = find_node(model, 'D')
      p = find_node(model, 'P')
      call check(error, norm2(model%nodes(b)%x - model%nodes(o)%x), 3.0_dp, 'OB', rel=1.0e-14_dp)
      call check(error, norm2(model%nodes(d)%x - model%nodes(o)%x), 3.0_dp, 'OD', rel=1.0e-14_dp)
      call check(error, norm2(model%nodes(b)%x - model%nodes(a)%x), 1.2_dp, 'AB', rel=1.0e-14_dp)
      call check(error, norm2(model%nodes(d)%x - model%nodes(p)%x), 1.2_dp, 'PD', rel=1.0e-14_dp)
      call check(error, model%nodes(b)%x(1) < model%nodes(d)%x(1), 'B left of the ray O->A')
      ! Quick-return: C on the lever, crank 100 long.
      call read_deck(model, 'decks/quick-return.deck', failure)
      call check(error, model%nodes(find_node(model, 'C'))%x(1), 30*sqrt(10.0_dp), 'C x', rel=1.0e-14_dp)
      call check(error, model%nodes(find_node(model, 'C'))%x(2), 90*sqrt(10.0_dp), 'C y', rel=1.0e-14_dp)
      call check(error, size(model%slidelines), 2)
      call check(error, model%slidelines(2)%guide(1, 1), -400.0_dp)
      ! Appendage: MP is 1.5 long and perpendicular to BC.
      call read_deck(model, 'decks/fourbar-appendage.deck', failure)
      associate (x => model%nodes)
         call check(error, norm2(x(find_node(model, 'P'))%x - x(find_node(model, 'M'))%x), 1.5_dp, 'MP', &
            & rel=1.0e-14_dp)
         call check(error, dot_product(x(find_node(model, 'P'))%x - x(find_node(model, 'M'))%x, &
            & x(find_node(model, 'C'))%x - x(find_node(model, 'B'))%x), 0.0_dp, 'MP perpendicular', abs=1.0e-14_dp)
      end associate
      call check(error, all(model%output%points == [find_node(model, 'P')]), 'track P')
      call read_deck(model, 'decks/cantilever-rollup.deck', failure)
      call check(error, model%links(1)%nelem, 16)
      call check(error, model%loads(1)%moment, 2*pi)
      call check(error, .not. model%analysis%velocities, 'positions only')
   end subroutine test_example_decks

   subroutine test_keywords(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      ! Keywords: 4-letter prefixes, full words, any case, aliases.
      call read_good(error, model, 'sect'//nl//' bar E=1 G=1 A=1 I=1'//nl//'Coordinates'//nl//' A 0 0'//nl// &
         & ' B 1 0'//nl//'elem'//nl//' AB A B bar'//nl//'BOUN'//nl//' A pin'//nl//'DriVES'//nl// &
         & ' ROTATION ab RATE 1'//nl//'ANAL'//nl//' TIME 0 1 0.5'//nl//'end')
      if (allocated(error)) return
      call check(error, size(model%nodes), 2)
      call check(error, model%drives(1)%link, 1)
      call check(error, model%analysis%dt, 0.5_dp)
      ! COORX is not a card: it is data before any card... here an unknown card.
      call expect_error(error, 'COORX'//nl//with_base(''), 't.deck:1:1:', "unknown card 'COORX'")
      ! Three letters are not a card either.
      call expect_error(error, base_head//'SUP'//nl//' A pin'//nl//'END', 't.deck:8:5:', "missing field 'first-node'")
   end subroutine test_keywords

   subroutine test_fields(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      call read_good(error, model, &
         & '* comment line'//nl//'SECTions ! trailing comment'//nl//achar(9)//'bar,E=1,G=1,A=1,I=1'//nl// &
         & nl//'   '//nl//'NODEs'//nl//' A,0,0'//nl//' B  atan2(-1,3) , 1  ! x is one field'//nl// &
         & 'LINKs'//nl//' AB A B bar'//achar(13)//nl//'LOADs'//nl//' B 0 1'//nl//'END')
      if (allocated(error)) return
      call check(error, model%nodes(2)%x(1), atan2(-1.0_dp, 3.0_dp))
      call check(error, model%nodes(2)%x(2), 1.0_dp)
      call check(error, model%nodes(2)%loc%line, 8)
      call expect_error(error, base_head//'LOADs'//nl//' B 1,,2'//nl//'END', 't.deck:9:6:', 'empty field', &
         & also='   9 |  B 1,,2'//nl//'     |      ^ two commas')
   end subroutine test_fields

   subroutine test_include(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(error_type), allocatable :: failure
      integer :: unit
      call execute_command_line('mkdir -p '//scratch//'sub')
      open (newunit=unit, file=scratch//'sub/geometry.deck', status='replace', action='write')
      write (unit, '(a)') 'NODEs', ' A 0 0', ' B 2 0', 'INCLude links.deck'
      close (unit)
      open (newunit=unit, file=scratch//'sub/links.deck', status='replace', action='write')
      write (unit, '(a)') 'LINKs', ' AB A B bar', 'END', 'ignored? no: after END is an error'
      close (unit)
      open (newunit=unit, file=scratch//'main.deck', status='replace', action='write')
      write (unit, '(a)') 'SECTions', ' bar E=1 G=1 A=1 I=1', 'INCLude sub/geometry.deck', 'LOADs', ' B 0 1', 'END'
      close (unit)
      call read_deck(model, scratch//'main.deck', failure)
      call check_failure(error, failure, scratch//'sub/links.deck:4:1:', 'text after END')
      open (newunit=unit, file=scratch//'sub/links.deck', status='replace', action='write')
      write (unit, '(a)') 'LINKs', ' AB A B bar'
      close (unit)
      call read_deck(model, scratch//'main.deck', failure)
      if (allocated(failure)) then
         call test_failed(error, failure%message)
         return
      end if
      call check(error, size(model%nodes), 2)
      call check(error, size(model%links), 1)
      call check(error, model%links(1)%loc%file == scratch//'sub/links.deck', 'loc in the included file')
      call check(error, model%links(1)%loc%line, 2)
      ! From a string deck, INCLude is relative to the current directory.
      call read_deck_string(model, 'SECTions'//nl//' bar E=1 G=1 A=1 I=1'//nl//'INCLude '//scratch// &
         & 'sub/geometry.deck'//nl//'LOADs'//nl//' B 0 1'//nl//'END', 's.deck', failure)
      if (allocated(failure)) call test_failed(error, failure%message)
      ! A missing include names the file at the INCLude line.
      call expect_error(error, base_head//'INCLude nowhere.deck'//nl//'LOADs'//nl//' B 0 1'//nl//'END', &
         & 't.deck:8:9:', "cannot open 'nowhere.deck'")
      ! An include cycle.
      open (newunit=unit, file=scratch//'self.deck', status='replace', action='write')
      write (unit, '(a)') 'INCLude self.deck'
      close (unit)
      call read_deck(model, scratch//'self.deck', failure)
      call check_failure(error, failure, scratch//'self.deck:1:9:', 'INCLude cycle')
   end subroutine test_include

   subroutine test_read_file(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(error_type), allocatable :: failure
      call read_deck(model, 'decks/fourbar.deck', failure)
      if (allocated(failure)) then
         call test_failed(error, failure%message)
         return
      end if
      call check(error, model%file == 'decks/fourbar.deck', 'file name')
      call check(error, model%nodes(3)%x(2), sqrt(15.0_dp))
      call check(error, model%nodes(3)%loc%file == 'decks/fourbar.deck', 'loc file')
      call check(error, all(model%output%points == [2, 3]), 'track B C')
   end subroutine test_read_file

   !> The complete example deck of docs/deck-format.md reads and matches decks/fourbar.deck.
   subroutine test_documented_example(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(error_type), allocatable :: failure
      character(len=512) :: line
      character(:), allocatable :: text
      integer :: unit, ios
      logical :: in_section, in_block
      open (newunit=unit, file='docs/deck-format.md', status='old', action='read', iostat=ios)
      if (ios /= 0) then
         call test_failed(error, 'cannot open docs/deck-format.md')
         return
      end if
      text = ''
      in_section = .false.
      in_block = .false.
      do
         read (unit, '(a)', iostat=ios) line
         if (ios /= 0) exit
         if (index(line, '## Example 1') == 1) in_section = .true.
         if (.not. in_section) cycle
         if (line(1:3) == '```') then
            if (in_block) exit
            in_block = .true.
            cycle
         end if
         if (in_block) text = text//trim(line)//nl
      end do
      close (unit)
      call read_deck_string(model, text, 'deck-format.md', failure)
      if (allocated(failure)) then
         call test_failed(error, failure%message)
         return
      end if
      call check(error, size(model%nodes), 4)
      call check(error, model%nodes(3)%x(2), sqrt(15.0_dp))
      call check(error, size(model%welds) + size(model%loads) + size(model%slidelines), 0)
      call check(error, all(model%output%links == [1, 2, 3]), 'angles')
   end subroutine test_documented_example

   !> The exact shape of a diagnostic: place, card line, caret under the field.
   subroutine test_format(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(error_type), allocatable :: failure
      character(:), allocatable :: want
      call read_deck_string(model, base_head(:index(base_head, 'NODEs') - 1)//'NODEs'//nl//' A 0 0'//nl// &
         & 'C  3  sqrt(1S)'//nl//'B 2 0'//nl//'LINKs'//nl//' AB A B bar'//nl//'LOADs'//nl//' B 0 1'//nl//'END', &
         & 'decks/x.deck', failure)
      want = 'decks/x.deck:5:7: error: expected a real number'//nl// &
         & '   5 | C  3  sqrt(1S)'//nl// &
         & '     |       ^~~~~~~~ '
      if (.not. allocated(failure)) then
         call test_failed(error, 'no error')
      else if (index(failure%message, want) == 0) then
         call test_failed(error, 'want'//nl//want//nl//'got'//nl//failure%message)
      end if
   end subroutine test_format

   subroutine test_all_errors(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(error_type), allocatable :: failure
      call read_deck_string(model, 'SECTions'//nl//' bar E=1 G=1 A=x I=1'//nl//'NODEs'//nl//' A 0 0'//nl// &
         & ' B 2 zz'//nl//' A 1 1'//nl//'LINKs'//nl//' AB A Q bar'//nl//'LOADs'//nl//' B 0 1'//nl//'END', &
         & 't.deck', failure)
      call check_failure(error, failure, 't.deck:2:14:', 'expected a real number')
      call check_failure(error, failure, 't.deck:5:6:', 'expected a real number')
      call check_failure(error, failure, 't.deck:6:2:', 'duplicate node name')
      call check_failure(error, failure, 't.deck:8:7:', "undefined node 'Q'")
      call check_failure(error, failure, '4 errors', '4 errors')
      ! In deck order.
      if (.not. allocated(error)) then
         call check(error, index(failure%message, 't.deck:2:') < index(failure%message, 't.deck:5:') .and. &
            & index(failure%message, 't.deck:6:') < index(failure%message, 't.deck:8:'), 'sorted by line')
      end if
   end subroutine test_all_errors

   subroutine test_unknown_card(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_error(error, base_head//'MATErials'//nl//' steel 1 2'//nl//'LOADs'//nl//' B 0 1'//nl//'END', &
         & 't.deck:8:1:', "unknown card 'MATErials'", also='SECTions NODEs')
      call expect_error(error, ' A 0 0'//nl//with_base(''), 't.deck:1:2:', 'data line before the first card')
   end subroutine test_unknown_card

   subroutine test_missing_block(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_error(error, 'NODEs'//nl//' A 0 0'//nl//' B 1 0'//nl//'LINKs'//nl//' AB A B bar'//nl// &
         & 'LOADs'//nl//' B 0 1'//nl//'END', 't.deck:8:1:', 'missing required block SECTions')
      call expect_error(error, base_head//'END', 't.deck:8:1:', 'missing required block DRIVes or LOADs')
      call expect_error(error, base_head//'LOADs'//nl//'END', 't.deck:9:1:', 'missing required block DRIVes or LOADs')
      call expect_error(error, 'SECTions'//nl//' bar E=1 G=1 A=1 I=1'//nl//'NODEs'//nl//'LOADs'//nl//' B 0 1'//nl// &
         & 'END', 't.deck:6:1:', 'the NODEs block has no lines')
   end subroutine test_missing_block

   subroutine test_non_numeric(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_error(error, with_base('LOADs'//nl//' B 1 two'//nl), 't.deck:11:6:', 'expected a real number')
      call expect_error(error, with_base('ANALysis'//nl//' iterations 2.5'//nl), 't.deck:11:13:', &
         & 'expected an integer')
   end subroutine test_non_numeric

   subroutine test_missing_field(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_error(error, base_head//'NODEs'//nl//' C 1'//nl//'LOADs'//nl//' B 0 1'//nl//'END', &
         & 't.deck:9:6:', "missing field 'y'", also='name x y')
      call expect_error(error, with_base('LINKs'//nl//' BA B A'//nl), 't.deck:11:9:', "missing field 'section'")
      call expect_error(error, base_head//'DRIVes'//nl//' rotation AB rate'//nl//'END', 't.deck:9:19:', &
         & "missing field 'OMEGA'")
   end subroutine test_missing_field

   subroutine test_duplicate_node(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_error(error, with_base('NODEs'//nl//' a 5 5'//nl), 't.deck:11:2:', "duplicate node name 'a'", &
         & also='t.deck:4:2: note: first defined here')
      call expect_error(error, with_base('LINKs'//nl//' ab B A bar'//nl), 't.deck:11:2:', 'duplicate link name', &
         & also='t.deck:7:2: note: first defined here')
      call expect_error(error, with_base('SECTions'//nl//' BAR EA=1 kGA=1 EI=1'//nl), 't.deck:11:2:', &
         & 'duplicate section name')
   end subroutine test_duplicate_node

   subroutine test_undefined_node(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_error(error, with_base('LINKs'//nl//' BX B X bar'//nl), 't.deck:11:7:', "undefined node 'X'")
      call expect_error(error, with_base('LINKs'//nl//' BX B A steel'//nl), 't.deck:11:9:', "undefined section 'steel'")
      call expect_error(error, with_base('OUTPut'//nl//' angles XY'//nl), 't.deck:11:9:', "undefined link 'XY'")
      call expect_error(error, with_base('OUTPut'//nl//' track Z'//nl), 't.deck:11:8:', "undefined node 'Z'")
   end subroutine test_undefined_node

   subroutine test_zero_length(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_error(error, with_base('NODEs'//nl//' C 2 1e-13'//nl//'LINKs'//nl//' BC B C bar'//nl), &
         & 't.deck:13:2:', 'zero-length link BC')
      call expect_error(error, with_base('LINKs'//nl//' AA A A bar'//nl), 't.deck:11:7:', 'joins node A to itself')
   end subroutine test_zero_length

   subroutine test_section_property(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_error(error, with_base('SECTions'//nl//' s E=1 G=0 A=1 I=1'//nl), 't.deck:11:8:', &
         & 'non-positive section property G')
      call expect_error(error, with_base('SECTions'//nl//' s EA=-1 kGA=1 EI=1'//nl), 't.deck:11:4:', &
         & 'non-positive section property EA')
      call expect_error(error, with_base('SECTions'//nl//' s E=1 G=1 A=1'//nl), 't.deck:11:2:', 'section s has no EI')
      call expect_error(error, with_base('SECTions'//nl//' s E=1e200 G=1 A=1e200 I=1'//nl), 't.deck:11:4:', &
         & 'section property E out of range')
      call expect_error(error, with_base('SECTions'//nl//' s E=1e60 G=1 A=1e60 I=1'//nl), 't.deck:11:2:', &
         & 'section stiffness out of range')
   end subroutine test_section_property

   subroutine test_time_step(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_error(error, with_base('ANALysis'//nl//' time 0 1 0'//nl), 't.deck:11:11:', &
         & 'the time step must be positive')
      call expect_error(error, with_base('ANALysis'//nl//' time 0 1 -0.1'//nl), 't.deck:11:11:', &
         & 'the time step must be positive')
      call expect_error(error, with_base('ANALysis'//nl//' time 0 1e6 1e-3'//nl), 't.deck:11:13:', &
         & 'more than 10,000,000 time steps')
      call expect_error(error, with_base('ANALysis'//nl//' time -1e308 1e308 1'//nl), 't.deck:11:7:', &
         & 'the start time is beyond 1e9')
      call expect_error(error, with_base('ANALysis'//nl//' time 0 1e300 1e299'//nl), 't.deck:11:9:', &
         & 'the end time is beyond 1e9')
   end subroutine test_time_step

   subroutine test_end_before_start(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_error(error, with_base('ANALysis'//nl//' time 0 -1 0.1'//nl), 't.deck:11:9:', &
         & 'the end time must be after the start time')
      call expect_error(error, with_base('ANALysis'//nl//' time 1 1 0.1'//nl), 't.deck:11:9:', &
         & 'the end time must be after the start time')
   end subroutine test_end_before_start

   subroutine test_analysis_values(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_error(error, with_base('ANALysis'//nl//' tolerance 1'//nl), 't.deck:11:12:', &
         & 'the tolerance must be between 0 and 1')
      call expect_error(error, with_base('ANALysis'//nl//' iterations 0'//nl), 't.deck:11:13:', &
         & 'the number of iterations must be at least 1')
      call expect_error(error, with_base('ANALysis'//nl//' method magic'//nl), 't.deck:11:9:', &
         & "unknown value 'magic' of method", also='fem cartesian angles')
      call expect_error(error, with_base('ANALysis'//nl//' gauss 3'//nl), 't.deck:11:8:', 'gauss takes 1 or 2 points')
      call expect_error(error, with_base('OUTPut'//nl//' every 0'//nl), 't.deck:11:8:', 'every needs a positive')
   end subroutine test_analysis_values

   subroutine test_drive_on_support(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_error(error, base_head//'SUPPorts'//nl//' B y'//nl//'DRIVes'//nl//' y B rate 1'//nl//'END', &
         & 't.deck:11:2:', 'drive on a supported degree of freedom', also='t.deck:9:2: note: supported here')
      call expect_error(error, base_head//'SUPPorts'//nl//' A pin rot AB'//nl//'DRIVes'//nl// &
         & ' rotation AB rate 1'//nl//'END', 't.deck:11:2:', 'drive on a supported degree of freedom')
      ! A drive on the free dof of a roller is fine.
      call expect_error(error, base_head//'SUPPorts'//nl//' B y'//nl//'DRIVes'//nl//' x B rate 1'//nl// &
         & ' x Q rate 1'//nl//'END', 't.deck:12:4:', "undefined node 'Q'")
   end subroutine test_drive_on_support

   subroutine test_drive_conflicts(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_error(error, with_base('DRIVes'//nl//' rot AB harmonic 0 0 1'//nl), 't.deck:13:11:', &
         & 'two drives on the same degree of freedom')
      call expect_error(error, with_base('DRIVes'//nl//' spin AB rate 1'//nl), 't.deck:11:2:', "unknown drive 'spin'")
      call expect_error(error, with_base('DRIVes'//nl//' x B wobble 1'//nl), 't.deck:11:6:', &
         & "unknown drive law 'wobble'", also='harmonic MEAN AMP OMEGA')
      call expect_error(error, with_base('DRIVes'//nl//' x B table 0 2 0 3'//nl), 't.deck:11:16:', &
         & 'table times must be strictly increasing')
      call expect_error(error, with_base('DRIVes'//nl//' x B table 0 2 1 3 2'//nl), 't.deck:11:20:', &
         & 'a table needs pairs')
      call expect_error(error, with_base('DRIVes'//nl//' x B rate 1 2 3'//nl), 't.deck:11:15:', 'unexpected field')
   end subroutine test_drive_conflicts

   subroutine test_drive_initial(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_error(error, base_head//'DRIVes'//nl//' rotation AB rate 1 0.5'//nl//'END', 't.deck:9:14:', &
         & 'drive does not match the initial configuration of link AB', also='rate OMEGA` without V0')
      call expect_error(error, base_head//'DRIVes'//nl//' x B polynomial 3 1'//nl//'END', 't.deck:9:6:', &
         & 'drive does not match the initial configuration of node B')
      call expect_error(error, base_head//'DRIVes'//nl//' y B polynomial 1e300 1e300 1e300'//nl//'ANALysis'//nl// &
         & ' time 1e10 1e11 1e9'//nl//'END', 't.deck:9:17:', 'drive-law number too large')
      call expect_error(error, base_head//'DRIVes'//nl//' y B polynomial 1e15 1e15 1e15 1e15 1e15 1e15 1e15 1e15'// &
         & nl//'ANALysis'//nl//' time 1e50 1e51 1e49'//nl//'END', 't.deck:9:6:', &
         & 'value at the start time is not a finite number')
   end subroutine test_drive_initial

   subroutine test_link_ends(error)
      type(error_type), allocatable, intent(out) :: error
      character(*), parameter :: three = 'SECTions'//nl//' bar E=1 G=1 A=1 I=1'//nl//'NODEs'//nl//' A 0 0'//nl// &
         & ' B 1 0'//nl//' C 2 0'//nl//'LINKs'//nl//' AB A B bar'//nl//' BC B C bar'//nl
      call expect_error(error, three//'WELDs'//nl//' A AB BC'//nl//'LOADs'//nl//' B 0 1'//nl//'END', &
         & 't.deck:11:7:', 'link BC has no end at node A')
      call expect_error(error, three//'SUPPorts'//nl//' A pin rot BC'//nl//'LOADs'//nl//' B 0 1'//nl//'END', &
         & 't.deck:11:12:', 'link BC has no end at node A')
      call expect_error(error, three//'SUPPorts'//nl//' B rot'//nl//'LOADs'//nl//' B 0 1'//nl//'END', &
         & 't.deck:11:4:', 'which link''s rotation')
      call expect_error(error, three//'WELDs'//nl//' B AB'//nl//'LOADs'//nl//' B 0 1'//nl//'END', &
         & 't.deck:11:7:', "missing field 'link'")
      call expect_error(error, three//'LOADs'//nl//' C 0 1 moment AB 1'//nl//'END', &
         & 't.deck:11:15:', 'link AB has no end at node C')
   end subroutine test_link_ends

   subroutine test_slideline_errors(error)
      type(error_type), allocatable, intent(out) :: error
      character(*), parameter :: three = 'SECTions'//nl//' bar E=1 G=1 A=1 I=1'//nl//'NODEs'//nl//' A 0 0'//nl// &
         & ' B 1 0'//nl//' C 2 0'//nl//'LINKs'//nl//' AB A B bar'//nl//' BC B C bar'//nl//'LOADs'//nl//' B 0 1'//nl
      call expect_error(error, three//'SLIDelines'//nl//' s B on AB'//nl//'END', 't.deck:13:9:', &
         & 'the slave node B is a node of its master link AB')
      call expect_error(error, three//'SLIDelines'//nl//' s C guide 0 1 2 1'//nl//'END', 't.deck:13:4:', &
         & 'does not start on its master line')
      call expect_error(error, three//'SLIDelines'//nl//' s C guide 0 0 0 0'//nl//'END', 't.deck:13:12:', &
         & 'the guide has zero length')
      call expect_error(error, three//'SLIDelines'//nl//' s C along AB'//nl//'END', 't.deck:13:6:', &
         & "expected 'on' or 'guide'")
      call expect_error(error, three//'SLIDelines'//nl//' s C guide 0 0 3 0 penalty=-1'//nl//'END', 't.deck:13:20:', &
         & 'the penalty must not be negative')
   end subroutine test_slideline_errors

   subroutine test_unused_node(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_error(error, with_base('NODEs'//nl//' Lonely 7 7'//nl), 't.deck:11:2:', 'node Lonely is not on any link')
   end subroutine test_unused_node

   subroutine test_empty_file(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(error_type), allocatable :: failure
      integer :: unit
      call execute_command_line('mkdir -p '//scratch)
      open (newunit=unit, file=scratch//'empty.deck', status='replace', action='write')
      close (unit)
      call read_deck(model, scratch//'empty.deck', failure)
      call check_failure(error, failure, scratch//'empty.deck:1:', 'empty deck')
      call expect_error(error, '* only a comment'//nl//nl//'   ! and another'//nl, 't.deck:1:', 'empty deck')
      call expect_error(error, '', 't.deck:1:', 'empty deck')
   end subroutine test_empty_file

   subroutine test_missing_file(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(error_type), allocatable :: failure
      call read_deck(model, 'decks/no-such.deck', failure)
      call check_failure(error, failure, 'decks/no-such.deck', "cannot open 'decks/no-such.deck': no such file")
   end subroutine test_missing_file

   subroutine test_unterminated(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_error(error, base_head//'LOADs'//nl//' B 0 1'//nl//nl//'* trailing comment'//nl, 't.deck:9:8:', &
         & 'unterminated deck')
   end subroutine test_unterminated

   subroutine test_binary_file(error)
      type(error_type), allocatable, intent(out) :: error
      type(model_type) :: model
      type(error_type), allocatable :: failure
      integer :: unit
      call execute_command_line('mkdir -p '//scratch)
      open (newunit=unit, file=scratch//'binary.deck', access='stream', form='unformatted', status='replace', &
         & action='write')
      write (unit) 'NODEs'//nl//' A 0'//achar(0)//achar(1)//char(200)//nl
      close (unit)
      call read_deck(model, scratch//'binary.deck', failure)
      call check_failure(error, failure, scratch//'binary.deck:2:5:', 'binary file')
      call expect_error(error, 'NODEs'//achar(27)//'[0m', 't.deck:1:6:', 'binary file')
   end subroutine test_binary_file

   subroutine test_not_finite(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_error(error, with_base('NODEs'//nl//' C NaN 0'//nl), 't.deck:11:4:', 'not a finite number')
      call expect_error(error, with_base('NODEs'//nl//' C 0 -Inf'//nl), 't.deck:11:6:', 'not a finite number')
      call expect_error(error, with_base('NODEs'//nl//' C 1e400 0'//nl), 't.deck:11:4:', 'not a finite number')
      call expect_error(error, with_base('NODEs'//nl//' C 1/0 0'//nl), 't.deck:11:4:', 'not a finite number')
      call expect_error(error, with_base('NODEs'//nl//' C sqrt(-1) 0'//nl), 't.deck:11:4:', 'not a finite number')
      call expect_error(error, with_base('NODEs'//nl//' C 1e200 0'//nl), 't.deck:11:4:', 'coordinate too large')
   end subroutine test_not_finite

   subroutine test_name_keyword(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_error(error, with_base('NODEs'//nl//' Link 1 1'//nl), 't.deck:11:2:', &
         & "'Link' reads as the card LINKs", also='a name cannot be a card keyword')
      call expect_error(error, with_base('LINKs'//nl//' node A B bar'//nl), 't.deck:11:2:', "'node' reads as the card NODEs")
      call expect_error(error, with_base('SLIDelines'//nl//' s B guide -1 0 5 0'//nl//' x B on drive'//nl), &
         & 't.deck:12:9:', "undefined link 'drive'")
   end subroutine test_name_keyword

   subroutine test_unknown_parameters(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_error(error, with_base('ANALysis'//nl//' steps 10'//nl), 't.deck:11:2:', &
         & "unknown ANALysis parameter 'steps'", also='method time compute')
      call expect_error(error, with_base('OUTPut'//nl//' plot B'//nl), 't.deck:11:2:', "unknown OUTPut parameter 'plot'")
      call expect_error(error, with_base('SECTions'//nl//' s E=1 G=1 A=1 I=1 nu=0.3'//nl), 't.deck:11:20:', &
         & "unknown section property 'nu'", also='EA= kGA= EI=')
      call expect_error(error, base_head//'SUPPorts'//nl//' A fixed'//nl//'LOADs'//nl//' B 0 1'//nl//'END', &
         & 't.deck:9:4:', "unknown support 'fixed'", also='pin (= x y) | x | y | rot LINK')
   end subroutine test_unknown_parameters

   subroutine test_after_end(error)
      type(error_type), allocatable, intent(out) :: error
      call expect_error(error, with_base('')//'NODEs'//nl, 't.deck:13:1:', 'text after END')
   end subroutine test_after_end

end module test_deck
