!> Reading the cards that move the mechanism or constrain it further: DRIVes
!> (with their time laws), LOADs and SLIDelines. Read after the geometry cards
!> and ANALysis, so that every drive can be checked against the supports, the
!> other drives and the initial configuration.
module fekap_deck_motion
   use fekap_kinds, only: dp
   use fekap_model, only: model_type, drive_type, load_type, slideline_type, model_size, &
      & dof_x, dof_y, dof_rot, joint_pin_in_slot, joint_prismatic
   use fekap_model_drive_law, only: law_type, new_rate_law, new_harmonic_law, new_polynomial_law, &
      & new_table_law, new_constant_law, new_linear_law, law_rate, law_harmonic, law_polynomial, law_table
   use fekap_deck_card, only: is_word_of
   use fekap_strings, only: lower, same_name
   use fekap_deck_context, only: context_type
   use fekap_deck_safe_arithmetic, only: safe_add, safe_multiply
   use fekap_deck_geometry, only: has_end, welded, lookup_node, lookup_link, max_coordinate
   implicit none
   private

   public :: read_drives, read_loads, read_slidelines, read_law

   real(dp), parameter :: pi = acos(-1.0_dp)
   !> Tolerances of the initial value of an absolute drive: angle (rad), and
   !> coordinate relative to the model size.
   real(dp), parameter :: angle_tol = 1.0e-6_dp, coordinate_tol = 1.0e-9_dp
   !> A slave must start this close (relative to the model size) to its master line.
   real(dp), parameter :: slave_tol = 1.0e-6_dp
   !> Largest magnitude of a table entry (keeps the spline's arithmetic finite).
   real(dp), parameter :: table_max = 1.0e100_dp
   !> Largest slideline damping (as the sections' Rayleigh coefficients).
   real(dp), parameter :: max_damping = 1.0e100_dp
   !> Largest magnitude of a rate, harmonic or polynomial coefficient: larger
   !> drives overflow the residual long before they mean anything.
   real(dp), parameter :: law_max = 1.0e15_dp
   !> Largest magnitude of a load's force or moment (as coordinates and
   !> gravity: the statics and kinetostatics overflowed at 1.8e308).
   real(dp), parameter :: load_max = 1.0e100_dp

contains

   !> DRIVes: `rotation LINK law`, `x NODE law`, `y NODE law`, with law one of
   !> `rate OMEGA [V0]`, `harmonic MEAN AMP OMEGA [PHASE]`, `polynomial C0 C1 ...`,
   !> `table T1 V1 T2 V2 ...`.
   subroutine read_drives(ctx, model, lines)
      type(context_type), intent(inout) :: ctx
      type(model_type), intent(inout) :: model
      integer, intent(in) :: lines(:)
      character(*), parameter :: form = 'rotation LINK law ... | x NODE law ... | y NODE law ...'
      type(drive_type), allocatable :: list(:)
      type(drive_type) :: drive
      integer :: n, i, iline, j, s
      logical :: ok
      allocate (list(size(lines)))
      n = 0
      do i = 1, size(lines)
         iline = lines(i)
         if (.not. ctx%require(iline, 'what name law', 'a DRIVes line')) cycle
         drive = drive_type()
         drive%loc = ctx%loc(iline, 1)
         if (is_word_of(ctx%field(iline, 1), 'rotation', 3)) then
            drive%dof = dof_rot
            drive%link = lookup_link(ctx, iline, 2)
            if (drive%link == 0) cycle
            drive%node = model%links(drive%link)%node(1)
         else if (lower(ctx%field(iline, 1)) == 'x' .or. lower(ctx%field(iline, 1)) == 'y') then
            drive%dof = merge(dof_x, dof_y, lower(ctx%field(iline, 1)) == 'x')
            drive%node = lookup_node(ctx, iline, 2)
            if (drive%node == 0) cycle
         else
            call ctx%error(iline, 1, "unknown drive '"//ctx%field(iline, 1)//"'", label='allowed: '//form)
            cycle
         end if
         call read_law(ctx, iline, 3, drive%law, ok)
         if (.not. ok) cycle
         ! Conflicts with supports and earlier drives.
         do s = 1, size(model%supports)
            associate (support => model%supports(s))
               if (support%node /= drive%node) cycle
               if (drive%dof /= dof_rot .and. support%fix(drive%dof)) then
                  call ctx%error_at(ctx%loc(iline, 1), 'drive on a supported degree of freedom: '//ctx%field(iline, 1)// &
                     & ' of node '//model%nodes(drive%node)%name//' is fixed by a support', &
                     & label='remove the support or the drive', note_loc=support%loc, note='supported here')
                  ok = .false.
               else if (drive%dof == dof_rot .and. support%fix(dof_rot)) then
                  if (support%link == drive%link .or. welded(model, support%link, drive%link)) then
                     call ctx%error_at(ctx%loc(iline, 1), 'drive on a supported degree of freedom: the rotation of link '// &
                        & model%links(drive%link)%name//' at node '//model%nodes(drive%node)%name// &
                        & ' is clamped by a support', label='remove the rot clamp or the drive', &
                        & note_loc=support%loc, note='clamped here')
                     ok = .false.
                  end if
               end if
            end associate
         end do
         do j = 1, n
            if (list(j)%dof /= drive%dof) cycle
            if (drive%dof == dof_rot) then
               if (list(j)%link /= drive%link .and. .not. welded(model, list(j)%link, drive%link)) cycle
            else if (list(j)%node /= drive%node) then
               cycle
            end if
            call ctx%error_at(ctx%loc(iline, 2), 'two drives on the same degree of freedom', &
               & label='a degree of freedom takes one drive; combine the laws', note_loc=list(j)%loc, &
               & note='driven here already')
            ok = .false.
         end do
         if (ok) call check_start(ctx, model, iline, drive)
         if (.not. ok) cycle
         n = n + 1
         list(n) = drive
      end do
      model%drives = list(:n)
   end subroutine read_drives

   !> The law in fields first... of a DRIVes line, or of a LOADs line (`load`):
   !> a load's law is its factor, and may also be `constant [C]` or a
   !> piecewise-linear `linear T1 V1 T2 V2 ...`; a load's `rate OMEGA` starts at 0.
   subroutine read_law(ctx, iline, first, law, ok, load)
      type(context_type), intent(inout) :: ctx
      integer, intent(in) :: iline, first
      type(law_type), intent(out) :: law
      logical, intent(out) :: ok
      logical, intent(in), optional :: load
      character(:), allocatable :: laws
      real(dp), allocatable :: c(:)
      integer :: k, nc
      logical :: fine, for_load, tabular
      character(:), allocatable :: word, head, what
      for_load = .false.
      if (present(load)) for_load = load
      laws = 'rate OMEGA [V0] | harmonic MEAN AMP OMEGA [PHASE] | polynomial C0 C1 ... | table T1 V1 T2 V2 ...'
      what = 'drive'
      if (for_load) then
         laws = 'constant [C] | '//laws//' | linear T1 V1 T2 V2 ...'
         what = 'load'
      end if
      ok = .false.
      word = ctx%field(iline, first)
      head = ''
      do k = 1, first - 1
         head = head//ctx%field(iline, k)//' '
      end do
      tabular = is_word_of(word, 'table', 4) .or. (for_load .and. is_word_of(word, 'linear', 4))
      nc = ctx%nfields(iline) - first
      allocate (c(nc))
      ok = .true.
      do k = 1, nc
         call ctx%real_field(iline, first + k, c(k), fine)
         ok = ok .and. fine
         if (fine .and. .not. tabular .and. abs(c(k)) > law_max) then
            call ctx%error(iline, first + k, what//'-law number too large', label='at most 1e15 in magnitude')
            ok = .false.
         end if
      end do
      if (for_load .and. is_word_of(word, 'constant', 4)) then
         if (.not. ok) return
         if (nc > 1) call extra(first + 2, 'constant [C]')
         if (.not. ok) return
         if (nc == 0) c = [1.0_dp]
         call new_constant_law(law, c(1))
      else if (is_word_of(word, 'rate', 4)) then
         if (.not. ctx%require(iline, head//'rate OMEGA [V0]', 'a rate law')) ok = .false.
         if (.not. ok) return
         if (nc > 2) call extra(first + 3, 'rate OMEGA [V0]')
         if (.not. ok) return
         if (nc == 1 .and. for_load) then
            call new_rate_law(law, c(1), 0.0_dp)
         else if (nc == 1) then
            call new_rate_law(law, c(1))
         else
            call new_rate_law(law, c(1), c(2))
         end if
      else if (is_word_of(word, 'harmonic', 4)) then
         if (.not. ctx%require(iline, head//'harmonic MEAN AMP OMEGA [PHASE]', 'a harmonic law')) ok = .false.
         if (.not. ok) return
         if (nc > 4) call extra(first + 5, 'harmonic MEAN AMP OMEGA [PHASE]')
         if (.not. ok) return
         if (nc == 3) c = [c, 0.0_dp]
         call new_harmonic_law(law, c(1), c(2), c(3), c(4))
      else if (is_word_of(word, 'polynomial', 4)) then
         if (.not. ctx%require(iline, head//'polynomial C0 [C1 ...]', 'a polynomial law')) ok = .false.
         if (.not. ok) return
         call new_polynomial_law(law, c)
      else if (tabular) then
         if (.not. ctx%require(iline, head//word//' T1 V1 T2 V2 [...]', 'a table law')) ok = .false.
         if (.not. ok) return
         if (mod(nc, 2) /= 0) then
            call ctx%error(iline, first + nc, 'a table needs pairs T V: the last value is missing', &
               & label=word//' T1 V1 T2 V2 ...')
            ok = .false.
            return
         end if
         do k = 1, nc
            if (abs(c(k)) > table_max) then
               call ctx%error(iline, first + k, 'table entry too large', label='at most 1e100 in magnitude')
               ok = .false.
            end if
         end do
         do k = 3, nc, 2
            if (c(k) <= c(k - 2)) then
               call ctx%error(iline, first + k, 'table times must be strictly increasing', &
                  & label='T1 < T2 < T3 ...')
               ok = .false.
            end if
         end do
         if (.not. ok) return
         if (is_word_of(word, 'table', 4)) then
            call new_table_law(law, c(1::2), c(2::2))
         else
            call new_linear_law(law, c(1::2), c(2::2))
         end if
      else if (len(word) == 0) then
         call ctx%error(iline, first, 'missing field ''law''', label='laws: '//laws)
         ok = .false.
      else
         call ctx%error(iline, first, 'unknown '//what//" law '"//word//"'", label='laws: '//laws)
         ok = .false.
      end if

   contains

      subroutine extra(itok, lawform)
         integer, intent(in) :: itok
         character(*), intent(in) :: lawform
         call ctx%error(iline, itok, "unexpected field '"//ctx%field(iline, itok)//"'", label='the law is: '//lawform)
         ok = .false.
      end subroutine extra

   end subroutine read_law

   !> An absolute law must start at the initial configuration.
   subroutine check_start(ctx, model, iline, drive)
      type(context_type), intent(inout) :: ctx
      type(model_type), intent(in) :: model
      integer, intent(in) :: iline
      type(drive_type), intent(in) :: drive
      real(dp) :: f, f_end, initial, d(2), diff
      logical :: fine
      character(len=400) :: text
      character(:), allocatable :: what
      if (drive%law%kind == law_rate .and. .not. drive%law%absolute) return
      call start_value(drive%law, model%analysis%t_start, f, fine)
      if (.not. fine) then
         call ctx%error(iline, 3, 'the drive law''s value at the start time is not a finite number', &
            & label='check the law''s coefficients')
         return
      end if
      ! Beyond the deck's numbers where the run ends (1e15 t^33 at t = 1e9):
      ! refused here, before any arithmetic overflows with it (start_value's
      ! safe arithmetic: the checking build traps an overflow).
      call start_value(drive%law, model%analysis%t_end, f_end, fine)
      if (fine) fine = abs(f_end) <= 1.0e100_dp
      if (.not. fine) then
         call ctx%error(iline, 3, 'the drive law''s value at the end time is beyond 1e100', &
            & label='change the law, or end the run earlier')
         return
      end if
      if (drive%dof == dof_rot) then
         d = model%nodes(model%links(drive%link)%node(2))%x - model%nodes(model%links(drive%link)%node(1))%x
         if (all(d == 0)) return   ! a zero-length link, reported in LINKs
         initial = atan2(d(2), d(1))
         diff = modulo(f - initial + pi, 2*pi) - pi
         if (abs(diff) <= angle_tol) return
         if (abs(f) < 1.0e300_dp) then
            write (text, '(a,g0.10,a,g0.10,a,g0.10,a,g0.10,a)') 'the drive sets the angle to ', f, ' rad (', &
               & f*180/pi, ' deg) at the start, but the link is at ', initial, ' rad (', initial*180/pi, ' deg)'
         else
            write (text, '(a,g0.10,a,g0.10,a)') 'the drive sets the angle to ', f, &
               & ' rad at the start, but the link is at ', initial, ' rad'
         end if
         what = 'link '//model%links(drive%link)%name
      else
         initial = model%nodes(drive%node)%x(drive%dof)
         if (abs(f - initial) <= coordinate_tol*model_size(model)) return
         write (text, '(a,g0.10,a,g0.10)') 'the drive sets the coordinate to ', f, &
            & ' at the start, but the node is at ', initial
         what = 'node '//model%nodes(drive%node)%name
      end if
      call ctx%error(iline, 3, 'drive does not match the initial configuration of '//what//': '//trim(text), &
         & label='fix the law or the NODEs, or use `rate OMEGA` without V0 to start from the initial configuration')
   end subroutine check_start

   !> The law's value at t, computed without overflow (fine = .false. if it overflows).
   pure subroutine start_value(law, t, f, fine)
      type(law_type), intent(in) :: law
      real(dp), intent(in) :: t
      real(dp), intent(out) :: f
      logical, intent(out) :: fine
      real(dp) :: arg, df, ddf, r
      integer :: k
      f = 0
      fine = .true.
      select case (law%kind)
      case (law_rate)
         call safe_multiply(law%c(1), t, r, fine)
         if (fine) call safe_add(r, law%c(2), f, fine)
      case (law_harmonic)
         call safe_multiply(law%c(3), t, r, fine)
         if (fine) call safe_add(r, law%c(4), arg, fine)
         if (fine) call safe_add(law%c(1), law%c(2)*cos(arg), f, fine)
      case (law_polynomial)
         do k = size(law%c), 1, -1
            call safe_multiply(f, t, r, fine)
            if (fine) call safe_add(r, law%c(k), f, fine)
            if (.not. fine) return
         end do
      case (law_table)
         ! Entries are bounded; outside the table the end cubic grows with (t - end)**3.
         if (abs(t) > table_max) then
            fine = .false.
            return
         end if
         call law%eval(max(law%tt(1), min(t, law%tt(size(law%tt)))), f, df, ddf)
         if (t < law%tt(1) .or. t > law%tt(size(law%tt))) then
            fine = .false.
         end if
      end select
   end subroutine start_value

   !> LOADs: `node FX FY [moment LINK M] [LAW ...]`: the values times the law's
   !> factor (the load factor t without a law).
   subroutine read_loads(ctx, model, lines)
      type(context_type), intent(inout) :: ctx
      type(model_type), intent(inout) :: model
      integer, intent(in) :: lines(:)
      character(*), parameter :: form = 'node FX FY [moment LINK M] [LAW ...]'
      type(load_type), allocatable :: list(:)
      integer :: n, i, iline, first_law
      logical :: ok, fine
      allocate (list(size(lines)))
      n = 0
      do i = 1, size(lines)
         iline = lines(i)
         if (.not. ctx%require(iline, form, 'a LOADs line')) cycle
         n = n + 1
         list(n) = load_type()   ! the slot may hold a dropped entry
         list(n)%loc = ctx%loc(iline, 1)
         list(n)%node = lookup_node(ctx, iline, 1)
         ok = list(n)%node > 0
         call ctx%real_field(iline, 2, list(n)%force(1), fine)
         call check_load(2, list(n)%force(1), fine)
         ok = ok .and. fine
         call ctx%real_field(iline, 3, list(n)%force(2), fine)
         call check_load(3, list(n)%force(2), fine)
         ok = ok .and. fine
         first_law = 4
         if (ctx%nfields(iline) > 3) then
            if (is_load_law(ctx%field(iline, 4))) then
               continue
            else if (.not. is_word_of(ctx%field(iline, 4), 'moment', 3)) then
               call ctx%error(iline, 4, "unexpected field '"//ctx%field(iline, 4)//"'", &
                  & label='a LOADs line is: '//form//'; laws: constant rate harmonic polynomial table linear')
               ok = .false.
            else if (ctx%require(iline, 'node FX FY moment LINK M', 'a LOADs line')) then
               first_law = 7
               if (ctx%nfields(iline) > 6) then
                  if (.not. is_load_law(ctx%field(iline, 7))) then
                     call ctx%error(iline, 7, "unexpected field '"//ctx%field(iline, 7)//"'", &
                        & label='a LOADs line is: '//form//'; laws: constant rate harmonic polynomial table linear')
                     ok = .false.
                  end if
               end if
               list(n)%link = lookup_link(ctx, iline, 5)
               if (list(n)%link > 0 .and. list(n)%node > 0) then
                  if (.not. has_end(model, list(n)%link, list(n)%node)) then
                     call ctx%error(iline, 5, 'link '//model%links(list(n)%link)%name//' has no end at node '// &
                        & model%nodes(list(n)%node)%name, label='the moment acts on the end of LINK at the node')
                     ok = .false.
                  end if
               end if
               ok = ok .and. list(n)%link > 0
               call ctx%real_field(iline, 6, list(n)%moment, fine)
               call check_load(6, list(n)%moment, fine)
               ok = ok .and. fine
            else
               ok = .false.
            end if
         end if
         if (ok .and. ctx%nfields(iline) >= first_law) then
            call read_law(ctx, iline, first_law, list(n)%law, fine, load=.true.)
            list(n)%timed = fine
            ok = ok .and. fine
         end if
         if (.not. ok) n = n - 1
      end do
      model%loads = list(:n)
   contains
      !> A value read from field k (fine) beyond load_max is an error at the field (fine false).
      subroutine check_load(k, value, fine)
         integer, intent(in) :: k
         real(dp), intent(in) :: value
         logical, intent(inout) :: fine
         if (.not. fine .or. abs(value) <= load_max) return
         call ctx%error(iline, k, 'load too large', label='at most 1e100 in magnitude')
         fine = .false.
      end subroutine check_load
   end subroutine read_loads

   !> Whether a LOADs field starts a law.
   pure logical function is_load_law(field)
      character(*), intent(in) :: field
      is_load_law = is_word_of(field, 'constant', 4) .or. is_word_of(field, 'rate', 4) .or. &
         & is_word_of(field, 'harmonic', 4) .or. is_word_of(field, 'polynomial', 4) .or. &
         & is_word_of(field, 'table', 4) .or. is_word_of(field, 'linear', 4)
   end function is_load_law

   !> SLIDelines: `name slave on LINK [LINK ...] [pin | prismatic LINK] [penalty=VALUE] [damping=VALUE]`
   !> or `name slave guide X1 Y1 X2 Y2 [pin | prismatic LINK] [penalty=VALUE] [damping=VALUE]`.
   subroutine read_slidelines(ctx, model, lines)
      type(context_type), intent(inout) :: ctx
      type(model_type), intent(inout) :: model
      integer, intent(in) :: lines(:)
      character(*), parameter :: form = 'name slave-node on LINK [LINK ...] | guide X1 Y1 X2 Y2, '// &
         & 'then [pin | prismatic LINK] [penalty=VALUE] [damping=VALUE]'
      type(slideline_type), allocatable :: list(:)
      integer :: n, i, iline, k, link, j, nf
      logical :: ok, fine
      real(dp) :: xy(4)
      character(:), allocatable :: word
      allocate (list(size(lines)))
      n = 0
      do i = 1, size(lines)
         iline = lines(i)
         if (.not. ctx%name_field(iline, 1, 'slideline')) cycle
         if (.not. ctx%require(iline, 'name slave-node on|guide ...', 'a SLIDelines line')) cycle
         nf = ctx%nfields(iline)
         n = n + 1
         list(n) = slideline_type()   ! the slot may hold a dropped entry
         list(n)%name = ctx%field(iline, 1)
         list(n)%loc = ctx%loc(iline, 1)
         allocate (list(n)%master_links(0))
         list(n)%slave = lookup_node(ctx, iline, 2)
         ok = list(n)%slave > 0
         word = lower(ctx%field(iline, 3))
         k = 4
         if (word == 'on') then
            do while (k <= nf)
               if (is_option(ctx%field(iline, k))) exit
               link = lookup_link(ctx, iline, k)
               if (link > 0) then
                  if (list(n)%slave > 0) then
                     if (has_end(model, link, list(n)%slave)) then
                        call ctx%error(iline, k, 'the slave node '//ctx%field(iline, 2)//' is a node of its master link '// &
                           & model%links(link)%name, label='a node cannot slide on a link it belongs to')
                        ok = .false.
                     end if
                  end if
                  if (size(list(n)%master_links) > 0) then
                     j = list(n)%master_links(size(list(n)%master_links))
                     if (.not. any(model%links(link)%node(1) == model%links(j)%node .or. &
                        & model%links(link)%node(2) == model%links(j)%node)) then
                        call ctx%error(iline, k, 'master links '//model%links(j)%name//' and '//model%links(link)%name// &
                           & ' do not share a node', label='list the master links in order along the line')
                        ok = .false.
                     end if
                  end if
                  list(n)%master_links = [list(n)%master_links, link]
               else
                  ok = .false.
               end if
               k = k + 1
            end do
            if (size(list(n)%master_links) == 0 .and. ok) then
               call ctx%error(iline, k, 'missing field ''LINK''', label='a master line of links: on LINK [LINK ...]')
               ok = .false.
            end if
         else if (word == 'guide') then
            list(n)%ground = .true.
            if (ctx%require(iline, 'name slave-node guide X1 Y1 X2 Y2', 'a ground guide')) then
               do j = 1, 4
                  call ctx%real_field(iline, 3 + j, xy(j), fine)
                  if (fine .and. abs(xy(j)) > max_coordinate) then
                     call ctx%error(iline, 3 + j, 'coordinate too large', label='at most 1e100 in magnitude')
                     fine = .false.
                  end if
                  ok = ok .and. fine
               end do
               list(n)%guide = reshape(xy, [2, 2])
               k = 8
               if (ok .and. norm2(list(n)%guide(:, 2) - list(n)%guide(:, 1)) < 1.0e-12_dp*model_size(model)) then
                  call ctx%error(iline, 4, 'the guide has zero length', label='give two different points X1 Y1 X2 Y2')
                  ok = .false.
               end if
            else
               ok = .false.
               k = nf + 1
            end if
         else
            call ctx%error(iline, 3, "expected 'on' or 'guide', not '"//ctx%field(iline, 3)//"'", label=form)
            ok = .false.
            k = nf + 1
         end if
         ! Options: pin | prismatic LINK, penalty=VALUE, damping=VALUE.
         do while (k <= nf)
            word = lower(ctx%field(iline, k))
            if (word == 'pin') then
               list(n)%kind = joint_pin_in_slot
            else if (is_word_of(word, 'prismatic', 4)) then
               list(n)%kind = joint_prismatic
               if (k == nf) then
                  call ctx%error(iline, k + 1, 'missing field ''LINK''', label='prismatic LINK: the slave''s link')
                  ok = .false.
               else
                  k = k + 1
                  list(n)%slave_link = lookup_link(ctx, iline, k)
                  ok = ok .and. list(n)%slave_link > 0
                  if (list(n)%slave_link > 0 .and. list(n)%slave > 0) then
                     if (.not. has_end(model, list(n)%slave_link, list(n)%slave)) then
                        call ctx%error(iline, k, 'link '//ctx%field(iline, k)//' has no end at the slave node '// &
                           & ctx%field(iline, 2), label='prismatic LINK names a link of the slave node')
                        ok = .false.
                     end if
                  end if
               end if
            else if (index(word, 'penalty=') == 1) then
               call ctx%real_field(iline, k, list(n)%penalty, fine, text=word(9:))
               ok = ok .and. fine
               if (fine .and. list(n)%penalty < 0) then
                  call ctx%error(iline, k, 'the penalty must not be negative', label='0 selects the automatic penalty')
                  ok = .false.
               end if
            else if (index(word, 'damping=') == 1) then
               call ctx%real_field(iline, k, list(n)%damping, fine, text=word(9:))
               ok = ok .and. fine
               if (fine .and. .not. (list(n)%damping >= 0 .and. list(n)%damping <= max_damping)) then
                  call ctx%error(iline, k, 'the damping must be zero or positive, at most 1e100', &
                     & label='a dashpot on the gap rate (force per velocity); 0: none')
                  ok = .false.
               end if
            else
               call ctx%error(iline, k, "unexpected field '"//ctx%field(iline, k)//"'", &
                  & label='options: pin | prismatic LINK | penalty=VALUE | damping=VALUE')
               ok = .false.
            end if
            k = k + 1
         end do
         do j = 1, n - 1
            if (same_name(list(j)%name, list(n)%name)) then
               call ctx%error_at(list(n)%loc, "duplicate slideline name '"//list(n)%name//"'", &
                  & note_loc=list(j)%loc, note='first defined here')
               ok = .false.
               exit
            end if
         end do
         if (ok) call check_on_line(ctx, model, iline, list(n))
         if (.not. ok) n = n - 1
      end do
      model%slidelines = list(:n)
   end subroutine read_slidelines

   pure logical function is_option(field)
      character(*), intent(in) :: field
      is_option = lower(field) == 'pin' .or. is_word_of(field, 'prismatic', 4) .or. &
         & index(lower(field), 'penalty=') == 1 .or. index(lower(field), 'damping=') == 1
   end function is_option

   !> The slave must start on its master line.
   subroutine check_on_line(ctx, model, iline, slide)
      type(context_type), intent(inout) :: ctx
      type(model_type), intent(in) :: model
      integer, intent(in) :: iline
      type(slideline_type), intent(in) :: slide
      real(dp) :: p(2), best
      character(len=40) :: text
      integer :: j
      p = model%nodes(slide%slave)%x
      if (slide%ground) then
         best = distance(p, slide%guide(:, 1), slide%guide(:, 2))
      else
         best = huge(best)
         do j = 1, size(slide%master_links)
            associate (link => model%links(slide%master_links(j)))
               best = min(best, distance(p, model%nodes(link%node(1))%x, model%nodes(link%node(2))%x))
            end associate
         end do
      end if
      if (best <= slave_tol*model_size(model)) return
      write (text, '(g0.6)') best
      call ctx%error(iline, 2, 'the slave node '//ctx%field(iline, 2)//' does not start on its master line (distance '// &
         & trim(text)//')', label='move the node onto the line or fix the line')
   end subroutine check_on_line

   !> Distance from p to the segment a-b.
   pure real(dp) function distance(p, a, b)
      real(dp), intent(in) :: p(2), a(2), b(2)
      real(dp) :: s, l2
      l2 = sum((b - a)**2)
      s = 0
      if (l2 > 0) s = max(0.0_dp, min(1.0_dp, dot_product(p - a, b - a)/l2))
      distance = norm2(p - (a + s*(b - a)))
   end function distance

end module fekap_deck_motion
