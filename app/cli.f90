!> The command line of fekap: options, overrides of the deck's settings.
module fekap_app_cli
   use fekap_kinds, only: dp
   use fekap_error, only: error_type, input_error
   use fekap_model, only: model_type, method_names, predictor_names, convergence_default
   use fekap_strings, only: lower, word_index
   use fekap_deck_expression, only: evaluate_expression
   use fekap_deck, only: override_type
   implicit none
   private

   public :: cli_type, parse_command_line, apply_overrides, usage_text

   character(*), parameter, public :: fekap_version = '0.1.0'

   type :: cli_type
      character(:), allocatable :: deck
      character(:), allocatable :: outdir
      logical :: quiet = .false.
      logical :: help = .false.
      logical :: version = .false.
      !> Print the output directory and exit (used by scripts/fekap).
      logical :: print_outdir = .false.
      !> Replace files of FEKAP's names in the output directory that no earlier run recorded.
      logical :: force = .false.
      !> Run the planar deck as a spatial model (z = 0, hinges revolute joints about +z).
      logical :: spatial = .false.
      character(:), allocatable :: method, dt, tol, predictor, compute
      !> `--set name=value` values of deck parameters, in the order given.
      type(override_type), allocatable :: sets(:)
      !> A note on the overrides for the user (apply_overrides), '' for none.
      character(:), allocatable :: note
   end type cli_type

contains

   function usage_text() result(text)
      character(:), allocatable :: text
      character(*), parameter :: nl = new_line('a')
      text = 'usage: fekap [options] DECK'//nl//nl// &
         & 'Kinematic analysis of a planar mechanism described by a card deck'//nl// &
         & '(see docs/deck-format.md). Results go to out/<deck stem>/ unless -o is given.'//nl//nl// &
         & 'options:'//nl// &
         & '  -o DIR              output directory'//nl// &
         & '  -q                  quiet: print nothing but errors'//nl// &
         & '  --method NAME       fem | cartesian | angles (overrides the deck)'//nl// &
         & '  --dt VALUE          time step (overrides the deck; an expression as in a'//nl// &
         & '                      deck: 0.01, 2*0.05, pi/100)'//nl// &
         & '  --tol VALUE         Newton tolerance (overrides the deck; an expression)'//nl// &
         & '  --predictor NAME    previous | extrapolate | taylor (overrides the deck)'//nl// &
         & '  --compute LIST      positions[,velocities[,accelerations]] (overrides the deck)'//nl// &
         & '  --set NAME=VALUE    value of the deck parameter NAME (PARAmeters block); repeatable'//nl// &
         & '  --spatial           run a planar kinematics deck as a spatial mechanism: z = 0,'//nl// &
         & '                      every hinge and pin a revolute joint about +z, SE(3) beams'//nl// &
         & '                      (see docs/deck-format.md, "Planar decks in 3D")'//nl// &
         & '  --force             remove files of FEKAP''s output names (any run''s CSV files,'//nl// &
         & '                      listing, pictures) that no earlier run recorded in the output'//nl// &
         & '                      directory''s .fekap-manifest, even those this run does not write'//nl// &
         & '  --print-outdir      print the output directory and exit'//nl// &
         & '  --version           print the version and exit'//nl// &
         & '  --help              print this help and exit'//nl//nl// &
         & 'exit codes:'//nl// &
         & '  0  success'//nl// &
         & '  1  anything else, including a run stopped by SIGINT, SIGTERM or SIGHUP'//nl// &
         & '  2  input error (bad deck or command line; also: another run is writing'//nl// &
         & '     into the output directory)'//nl// &
         & '  3  the analysis did not converge (the rows of the completed steps are kept)'//nl// &
         & '  4  an output file or directory could not be written (full disk, no'//nl// &
         & '     permission: the message names the file and the reason; the rows'//nl// &
         & '     written before are kept, whole)'
   end function usage_text

   !> Read the command line into `cli`.
   subroutine parse_command_line(cli, error)
      type(cli_type), intent(out) :: cli
      type(error_type), allocatable, intent(out) :: error
      integer :: i, n
      character(:), allocatable :: arg
      n = command_argument_count()
      allocate (cli%sets(0))
      i = 0
      do while (i < n)
         i = i + 1
         call argument(i, arg)
         select case (arg)
         case ('-h', '--help')
            cli%help = .true.
         case ('--version')
            cli%version = .true.
         case ('-q', '--quiet')
            cli%quiet = .true.
         case ('--print-outdir')
            cli%print_outdir = .true.
         case ('--force')
            cli%force = .true.
         case ('--spatial')
            cli%spatial = .true.
         case ('--set')
            if (i == n) then
               call input_error(error, 'fekap: option --set needs a value NAME=VALUE (see fekap --help)')
               return
            end if
            i = i + 1
            cli%sets = [cli%sets, override_type('')]
            call argument(i, cli%sets(size(cli%sets))%text)
         case ('-o', '--method', '--dt', '--tol', '--predictor', '--compute')
            if (i == n) then
               call input_error(error, 'fekap: option '//arg//' needs a value (see fekap --help)')
               return
            end if
            i = i + 1
            select case (arg)
            case ('-o')
               call argument(i, cli%outdir)
               if (len(cli%outdir) == 0) then
                  call input_error(error, "fekap: option -o needs a directory name, got '' (see fekap --help)")
                  return
               end if
            case ('--method')
               call argument(i, cli%method)
            case ('--dt')
               call argument(i, cli%dt)
            case ('--tol')
               call argument(i, cli%tol)
            case ('--predictor')
               call argument(i, cli%predictor)
            case ('--compute')
               call argument(i, cli%compute)
            end select
         case default
            if (len(arg) > 1 .and. arg(1:1) == '-') then
               call input_error(error, 'fekap: unknown option '//arg//' (see fekap --help)')
               return
            end if
            if (allocated(cli%deck)) then
               call input_error(error, 'fekap: one deck at a time: got '//cli%deck//' and '//arg)
               return
            end if
            cli%deck = arg
         end select
      end do
      if (.not. (cli%help .or. cli%version) .and. .not. allocated(cli%deck)) then
         call input_error(error, 'fekap: no deck given (usage: fekap [options] DECK; see fekap --help)')
         return
      end if
      if (allocated(cli%deck) .and. .not. allocated(cli%outdir)) cli%outdir = 'out/'//stem(cli%deck)
   end subroutine parse_command_line

   subroutine argument(i, arg)
      integer, intent(in) :: i
      character(:), allocatable, intent(out) :: arg
      integer :: length
      call get_command_argument(i, length=length)
      allocate (character(len=length) :: arg)
      call get_command_argument(i, arg)
   end subroutine argument

   !> File name without directory and extension.
   pure function stem(path) result(name)
      character(*), intent(in) :: path
      character(:), allocatable :: name
      integer :: slash, dot
      slash = index(path, '/', back=.true.)
      name = path(slash + 1:)
      dot = index(name, '.', back=.true.)
      if (dot > 1) name = name(:dot - 1)
   end function stem

   !> The code of `value` of an option among the blank-separated `names`
   !> (model's method_names or predictor_names): a name, or 4 letters of it,
   !> as in the deck; code is left as it was when value is none of them.
   subroutine named_code(option, value, names, code, error)
      character(*), intent(in) :: option, value, names
      integer, intent(inout) :: code
      type(error_type), allocatable, intent(out) :: error
      integer :: found, last
      found = word_index(value, names)
      if (found == 0) then
         last = index(names, ' ', back=.true.)
         call input_error(error, 'fekap: '//option//' '//value//': expected '// &
            & replace_blanks(names(:last - 1))//' or '//names(last + 1:))
         return
      end if
      code = found
   contains
      !> "a b c" as "a, b, c".
      pure recursive function replace_blanks(text) result(listed)
         character(*), intent(in) :: text
         character(:), allocatable :: listed
         integer :: blank
         blank = index(text, ' ')
         if (blank == 0) then
            listed = text
         else
            listed = text(:blank - 1)//', '//replace_blanks(text(blank + 1:))
         end if
      end function replace_blanks
   end subroutine named_code

   !> Apply the command-line overrides to the model's analysis settings.
   subroutine apply_overrides(cli, model, error)
      type(cli_type), intent(inout) :: cli
      type(model_type), intent(inout) :: model
      type(error_type), allocatable, intent(out) :: error
      real(dp) :: value
      integer :: start, comma
      character(:), allocatable :: item
      if (allocated(cli%method)) then
         call named_code('--method', cli%method, method_names, model%analysis%method, error)
         if (allocated(error)) return
      end if
      if (allocated(cli%predictor)) then
         call named_code('--predictor', cli%predictor, predictor_names, model%analysis%predictor, error)
         if (allocated(error)) return
      end if
      if (allocated(cli%dt)) then
         call option_number('--dt', cli%dt, value, error)
         if (allocated(error)) return
         if (.not. value > 0) then
            call input_error(error, "fekap: --dt '"//cli%dt//"': expected a positive number")
            return
         end if
         if ((model%analysis%t_end - model%analysis%t_start)/value > 1.0e7_dp) then
            call input_error(error, "fekap: --dt '"//cli%dt//"': more than 10,000,000 steps")
            return
         end if
         model%analysis%dt = value
      end if
      if (allocated(cli%tol)) then
         call option_number('--tol', cli%tol, value, error)
         if (allocated(error)) return
         if (.not. (value > 0 .and. value < 1)) then
            call input_error(error, "fekap: --tol '"//cli%tol//"': expected a number between 0 and 1")
            return
         end if
         ! A residual ratio below round-off asks for what no residual can
         ! show: the residual floor would decide instead, silently.
         if (value < 1.0e-15_dp) then
            call input_error(error, "fekap: --tol '"//cli%tol//"': below 1e-15, under the round-off of a residual ratio "// &
               & '(2.2e-16), which no Newton iterate can show; give at least 1e-15')
            return
         end if
         model%analysis%tol = value
         if (model%analysis%convergence == convergence_default) cli%note = 'fekap: note: --tol sets the '// &
            & 'residual ratio of the default convergence test, which ends a step only when the last '// &
            & 'correction is also below the length tolerance (ANALysis length, 1e-12 of the model size '// &
            & 'by default); that one usually decides, so --tol seldom changes the results. '// &
            & 'The paper''s test (ANALysis convergence paper) is decided by --tol alone.'
      end if
      if (allocated(cli%compute)) then
         model%analysis%velocities = .false.
         model%analysis%accelerations = .false.
         start = 1
         do while (start <= len(cli%compute))
            comma = index(cli%compute(start:), ',')
            if (comma == 0) then
               item = lower(cli%compute(start:))
               start = len(cli%compute) + 1
            else
               item = lower(cli%compute(start:start + comma - 2))
               start = start + comma
            end if
            select case (item)
            case ('positions')
            case ('velocities')
               model%analysis%velocities = .true.
            case ('accelerations')
               model%analysis%velocities = .true.
               model%analysis%accelerations = .true.
            case default
               call input_error(error, 'fekap: --compute '//cli%compute//': expected a list of positions, '// &
                  & 'velocities, accelerations')
               return
            end select
         end do
      end if
   end subroutine apply_overrides

   !> The value of a numeric option, read as a deck field is (an expression:
   !> `2*0.05`, `pi/100`, `1e-3`), the whole text and nothing else.
   subroutine option_number(option, text, value, error)
      character(*), intent(in) :: option, text
      real(dp), intent(out) :: value
      type(error_type), allocatable, intent(out) :: error
      character(:), allocatable :: detail
      call evaluate_expression(text, value, error, detail)
      if (.not. allocated(error)) return
      if (len(detail) > 0) then
         error%message = 'fekap: '//option//" '"//text//"': "//error%message//' ('//detail//')'
      else
         error%message = 'fekap: '//option//" '"//text//"': "//error%message
      end if
   end subroutine option_number


end module fekap_app_cli
