!> The nonzero entries of a band LU factor (dgbtrf's, in its band storage)
!> and the solves with them: the same operations in the same order as
!> dgbtrs's ('N' and 'T'), less the products with entries of the factor
!> that are zero whatever the matrix's values.
!>
!> Why: the strain-rate operator B_f of a mechanism has two to six entries
!> in a row of a band kl + ku + 1 wide (Example 1: 9 equations, kl = ku = 3,
!> 31 entries in the band's 51 places), and its factor keeps most of the
!> band's zeros (Example 1: 14 of L's 21 places, 10 of U's 33). A solve in
!> the band's loops spent most of its instructions on their index
!> arithmetic and on products with zero; each factor of B_f serves six to
!> eleven solves (the Newton correction, the drive response, two for each
!> rate, the condition estimate's).
!>
!> Which places of the factor can hold a nonzero follows from the places
!> of the matrix's entries (`entry_at`, the owner's, fixed for a mesh) and
!> the pivots: a symbolic factorisation, the band LU's loops on booleans
!> (symbolic_factor). It is made again only when the pivots change (along
!> a motion they rarely do); a factorisation with the pivots of the last
!> then only copies the values from those places (gather_nonzeros).
!>
!> What skipping a zero product changes: b - t*0 is b to the bit for every
!> finite t, except that b = -0 becomes +0 when t*0 is -0 (IEEE 754's sign
!> of an exact zero sum); a sum started at +0 that skips zero terms is the
!> same to the bit. So the solutions are those of the band's loops to the
!> bit, but for the sign of a component that is exactly zero (which
!> dgbtrs's own BLAS calls, skipping a zero multiplier, do not keep either).
!> A factor with an infinite or NaN entry is not a factor a solve is asked of.
!>
!> The numeric factorisation too can follow the places found
!> (refactor_nonzeros): along a motion B_f's next matrix has the same
!> places and, mostly, the same pivots, so its elimination multiplies only
!> the multipliers and the entries of U that can be nonzero, as a sparse
!> LU's refactorisation does; the band's loops take over at a column whose
!> last pivot no longer serves. It works in the factor's own slots (the
!> solves' lists), not in the band: with the pivots known, a row
!> interchange only moves a value, so each of the matrix's entries is put
!> at the slot the interchanges would take it to, and each update adds
!> into a slot listed by the symbolic factorisation (which numbers the
!> values as it moves them). No interchange, no fill to clear, no index
!> arithmetic of the band, no gathering afterwards: the same products and
!> sums in the same order, on the places that can be nonzero.
!>
!> The module is over 600 lines with one concept: the factor's places (the
!> symbolic factorisation and the lists' sizes), the refactorisation on
!> them and the solves with them share one record and its layout; apart,
!> each would reach into the others' lists.
module fekap_linalg_band_lu
   use fekap_kinds, only: dp
   use fekap_linalg_lapack, only: band_lu_given_pivots
   implicit none
   private

   public :: band_lu_nonzeros_type, new_band_lu_nonzeros, gather_nonzeros, nonzeros_solve, nonzeros_solve_transposed
   public :: refactor_nonzeros

   !> The symbolic factorisation's window of columns, in multiples of the
   !> kl + ku + 1 columns that one column's elimination reaches: the window's
   !> columns are moved to its front once every window_columns - 1 multiples
   !> (a copy of about 2 ldab / (window_columns - 1) booleans a column).
   integer, parameter :: window_columns = 16

   !> The places of an n x n band LU factor that can hold a nonzero, for
   !> the pivots of its last symbolic factorisation, and their values in
   !> the last factor gathered.
   type :: band_lu_nonzeros_type
      integer :: n = 0, kl = 0, ku = 0
      !> Where the matrix can have entries: places in its band storage taken
      !> as one array, column after column (column j's at entry_start(j) to
      !> entry_start(j + 1) - 1), rows in increasing order (below the fill).
      integer, allocatable :: entry_start(:), entry_at(:)
      !> Whether the lists below hold the places for `pivot`.
      logical :: known = .false.
      !> (n): the pivots (dgbtrf's ipiv) of the places below; the columns
      !> j whose pivot is not row j, in increasing order (the solves' row
      !> interchanges).
      integer, allocatable :: pivot(:), interchange(:)
      !> L's multipliers, column after column (column j's at lower_start(j)
      !> to lower_start(j + 1) - 1, in increasing row order): its place in
      !> the band storage taken as one array, its column (the row of b it
      !> takes) and its row in the order of b after all of the factor's row
      !> interchanges (see nonzeros_solve).
      integer, allocatable :: lower_start(:), lower_at(:), lower_column(:), lower_row(:)
      !> U's columns above the diagonal the same way (rows in increasing
      !> order; rows j - kl - ku to j - 1 of column j).
      integer, allocatable :: upper_start(:), upper_at(:), upper_row(:)
      !> The factor's values at its places, each at its slot: U's diagonal
      !> at 1 to n, L's multipliers at n + 1 to n + size(lower_at) (lower_at's
      !> order), U's entries above the diagonal after them (upper_at's order);
      !> the last a spare, where refactor_nonzeros puts the matrix's entries
      !> outside the n x n matrix (possible's, zero).
      real(dp), allocatable :: values(:)
      !> U's rows right of the diagonal, for refactor_nonzeros's updates: row
      !> j's entries at row_start(j) to row_start(j + 1) - 1, increasing
      !> columns (the lists above by rows): their slots.
      integer, allocatable :: row_start(:), row_slot(:)
      !> refactor_nonzeros's lists, made by the symbolic factorisation: the
      !> slot of each of the matrix's entries (entry_at's order) in the
      !> factor, and the slot each update of the elimination adds into
      !> (column j's: for each of row j's entries of U in increasing column,
      !> one for each of column j's multipliers in increasing row).
      integer, allocatable :: entry_slot(:), update_target(:)
      !> The factor's slots that no entry of the matrix starts (its fill):
      !> zero before refactor_nonzeros's updates add into them.
      integer, allocatable :: fill_slot(:)
      !> How many of update_target's slots the last symbolic factorisation listed.
      integer :: updates = 0
      !> (2 kl + ku + 1, columns): the symbolic factorisation's window of
      !> columns: at each place the number of the value there (0: none; the
      !> matrix's entries 1 to size(entry_at), fill numbered on); all zero
      !> between its calls (it clears each column's places as it lists
      !> them), so that a call need not clear it again.
      integer, allocatable :: window(:, :)
   end type band_lu_nonzeros_type

contains

   !> The nonzeros' record of the factors of n x n band matrices with kl
   !> sub- and ku superdiagonals whose entries can be at the places
   !> `possible` of their band storage ((2 kl + ku + 1, n); rows 1 to kl,
   !> the factor's fill, are ignored). The lists of the factor's places are
   !> sized by the first symbolic factorisation.
   pure subroutine new_band_lu_nonzeros(nz, kl, ku, possible)
      type(band_lu_nonzeros_type), intent(out) :: nz
      integer, intent(in) :: kl, ku
      logical, intent(in) :: possible(:, :)
      integer :: n, i, j, k
      n = size(possible, 2)
      nz%n = n
      nz%kl = kl
      nz%ku = ku
      allocate (nz%entry_start(n + 1), nz%entry_at(count(possible(kl + 1:, :))))
      k = 0
      do j = 1, n
         nz%entry_start(j) = k + 1
         do i = kl + 1, size(possible, 1)
            if (.not. possible(i, j)) cycle
            k = k + 1
            nz%entry_at(k) = i + (j - 1)*size(possible, 1)
         end do
      end do
      nz%entry_start(n + 1) = k + 1
      allocate (nz%pivot(n), nz%lower_start(n + 1), nz%upper_start(n + 1), nz%entry_slot(k))
      ! The factor's lists are sized by the first symbolic factorisation (reserve_lists).
      call reserve_lists(nz, 0, 0, 0)
      ! The spare slot (see values) until the first symbolic factorisation.
      nz%entry_slot = size(nz%values)
      allocate (nz%row_start(n + 1))
      allocate (nz%window(size(possible, 1), min(n, window_columns*(kl + ku + 1))), source=0)
   end subroutine new_band_lu_nonzeros

   !> The values of the factor in ab with pivots ipiv (dgbtrf's band
   !> storage: A(i, j) at ab(kl + ku + 1 + i - j, j), L's multipliers below
   !> row kl + ku + 1) at the places that can hold a nonzero, found again
   !> (symbolic_factor) if the pivots are not those of the last.
   pure subroutine gather_nonzeros(nz, ab, ipiv)
      type(band_lu_nonzeros_type), intent(inout) :: nz
      real(dp), contiguous, intent(in) :: ab(:, :)
      integer, contiguous, intent(in) :: ipiv(:)
      integer :: j
      if (nz%known) then
         do j = 1, nz%n
            if (ipiv(j) /= nz%pivot(j)) then
               nz%known = .false.
               exit
            end if
         end do
      end if
      if (.not. nz%known) then
         call symbolic_factor(nz, ipiv)
         nz%known = .true.
      end if
      call gather_values(nz%n, nz%kl + nz%ku, size(ab, 1), ab, nz%lower_start(nz%n + 1) - 1, nz%lower_at, &
         & nz%upper_start(nz%n + 1) - 1, nz%upper_at, upper_slots(nz), size(nz%values), nz%values)
   end subroutine gather_nonzeros

   !> The slot before U's first entry above the diagonal in nz%values.
   pure integer function upper_slots(nz) result(upper)
      type(band_lu_nonzeros_type), intent(in) :: nz
      upper = nz%n + size(nz%lower_at)
   end function upper_slots

   !> The values at the places found, at their slots (U's above the
   !> diagonal after `upper`); explicit-shape arrays: their addresses
   !> without a descriptor's arithmetic.
   pure subroutine gather_values(n, kv, ldab, ab, nl, lower_at, nu, upper_at, upper, nvalues, values)
      integer, intent(in) :: n, kv, ldab, nl, lower_at(nl), nu, upper_at(nu), upper, nvalues
      real(dp), intent(in) :: ab(ldab*n)
      real(dp), intent(inout) :: values(nvalues)
      integer :: j, k
      do j = 1, n
         values(j) = ab(kv + 1 + (j - 1)*ldab)
      end do
      do k = 1, nl
         values(n + k) = ab(lower_at(k))
      end do
      do k = 1, nu
         values(upper + k) = ab(upper_at(k))
      end do
   end subroutine gather_values

   !> The places of the factor that can hold a nonzero for the pivots ipiv:
   !> the band LU's loops (fekap_linalg_lapack's band_lu_factor_loops,
   !> dgbtf2's) on where values can be, with the given pivots: an
   !> interchange swaps the places of its rows over columns j to ju, and an
   !> update fills the places of column j + jj below row j where column j
   !> has a multiplier and row j an entry of U in that column (a superset
   !> of dgbtf2's, which skips a zero entry of U: every other place of its
   !> factor is exactly zero). Column j's elimination reaches columns j to
   !> j + kl + ku alone, and no later one changes column j; so the places
   !> are kept for a window of columns (nz%window, window_columns (kl + ku
   !> + 1) of them, column c at c - base) rather than for the whole band
   !> (as much memory as the matrix's band storage, at 4 bytes a place):
   !> columns' places are listed when their eliminations are done, and the
   !> columns not yet done moved to the window's front, the next columns'
   !> entries marked after them (symbolic_kernel). Each place holds the
   !> number of the value there (an interchange moves it; an update into an
   !> empty place starts a new one), so that where each of the matrix's
   !> entries and each update's sum end in the factor, their slots, are
   !> known when the places are listed: refactor_nonzeros's lists. Then L's
   !> rows renumbered: the interchange of column j's elimination (rows j
   !> and ipiv(j)) comes before its multipliers are applied and after
   !> column j - 1's, and it moves rows below j only after column j's; so
   !> with every interchange made first, row r of column j's elimination is
   !> row final(r) of the interchanged b, final being the composition of
   !> the interchanges of columns j + 1 to n - 1 (row j itself, and the
   !> rows above, are not moved by them).
   pure subroutine symbolic_factor(nz, ipiv)
      type(band_lu_nonzeros_type), intent(inout) :: nz
      integer, contiguous, intent(in) :: ipiv(:)
      integer, allocatable :: final(:), slot_of(:)
      integer :: n, i, j, k, moved
      n = nz%n
      nz%pivot = ipiv
      nz%interchange = pack([(j, j=1, n)], ipiv(1:n) /= [(j, j=1, n)])
      call list_places(nz, ipiv, slot_of)
      ! Lists too short for these pivots' places: made long enough, and the places listed again.
      if (nz%lower_start(n + 1) - 1 > size(nz%lower_at) .or. nz%upper_start(n + 1) - 1 > size(nz%upper_at) &
         & .or. nz%updates > size(nz%update_target)) then
         call reserve_lists(nz, nz%lower_start(n + 1) - 1, nz%upper_start(n + 1) - 1, nz%updates)
         call list_places(nz, ipiv, slot_of)
      end if
      ! The slots of the entries and of the updates' sums, from their values' numbers.
      do k = 1, size(nz%entry_slot)
         nz%entry_slot(k) = slot_of(k)
         ! A place outside the matrix (possible's corners; zero): the spare slot.
         if (slot_of(k) == 0) nz%entry_slot(k) = size(nz%values)
      end do
      do k = 1, nz%updates
         nz%update_target(k) = slot_of(nz%update_target(k))
      end do
      deallocate (slot_of)
      call list_fill(nz)
      ! The rows in the order after every interchange, from the last column back.
      final = [(i, i=1, n)]
      do j = n - 1, 1, -1
         do k = nz%lower_start(j), nz%lower_start(j + 1) - 1
            nz%lower_row(k) = final(nz%lower_row(k))
         end do
         if (ipiv(j) /= j) then
            moved = final(j)
            final(j) = final(ipiv(j))
            final(ipiv(j)) = moved
         end if
      end do
      ! U's places by rows: as many as it has (the lists by columns have
      ! reserve_lists' slack).
      if (allocated(nz%row_slot)) then
         if (size(nz%row_slot) < nz%upper_start(n + 1) - 1) deallocate (nz%row_slot)
      end if
      if (.not. allocated(nz%row_slot)) allocate (nz%row_slot(max(1, nz%upper_start(n + 1) - 1)))
      call list_rows(n, nz%upper_start, nz%upper_row, upper_slots(nz), nz%row_start, nz%row_slot)
   end subroutine symbolic_factor

   !> The slots of the factor's places (U's diagonal, L's and U's listed)
   !> that are no entry's: nz%fill_slot, as long as they are. nz%values
   !> marks them (1 at an entry's slot, and at the lists' slack and the
   !> spare; 0 at the fill's): no array more at a large lift's symbolic
   !> factorisation, and its values are gathered next (gather_nonzeros).
   pure subroutine list_fill(nz)
      type(band_lu_nonzeros_type), intent(inout) :: nz
      integer :: upper, k, m
      upper = upper_slots(nz)
      nz%values = 0
      do k = 1, size(nz%entry_slot)
         nz%values(nz%entry_slot(k)) = 1
      end do
      ! The places' slots only (not the lists' slack, nor the spare).
      nz%values(nz%n + nz%lower_start(nz%n + 1):upper) = 1
      nz%values(upper + nz%upper_start(nz%n + 1):) = 1
      m = count(nz%values == 0)
      if (allocated(nz%fill_slot)) then
         if (size(nz%fill_slot) /= m) deallocate (nz%fill_slot)
      end if
      if (.not. allocated(nz%fill_slot)) allocate (nz%fill_slot(m))
      m = 0
      do k = 1, size(nz%values)
         if (nz%values(k) /= 0) cycle
         m = m + 1
         nz%fill_slot(m) = k
      end do
   end subroutine list_fill

   !> symbolic_kernel on the record's arrays: its lists, as far as they
   !> reach, the starts of the places found however many they are, the
   !> number of updates (their values' numbers in update_target, as far as
   !> it reaches), and the slot of each value's number (slot_of).
   pure subroutine list_places(nz, ipiv, slot_of)
      type(band_lu_nonzeros_type), intent(inout) :: nz
      integer, contiguous, intent(in) :: ipiv(:)
      integer, allocatable, intent(out) :: slot_of(:)
      ! A number for each place of the factor, as long as the lists hold
      ! them, and for each entry outside the matrix (possible's corners,
      ! ku (ku + 1)/2 and kl (kl + 1)/2 places at most): the entries' own
      ! are places of the factor, the fill's too.
      allocate (slot_of(nz%n + size(nz%lower_at) + size(nz%upper_at) + (nz%ku*(nz%ku + 1) + nz%kl*(nz%kl + 1))/2), &
         & source=0)
      call symbolic_kernel(nz%n, nz%kl, nz%ku, size(nz%window, 2), ipiv, nz%entry_start, size(nz%entry_at), nz%entry_at, &
         & nz%window, size(nz%lower_at), nz%lower_start, nz%lower_column, nz%lower_row, nz%lower_at, size(nz%upper_at), &
         & nz%upper_start, nz%upper_row, nz%upper_at, size(nz%update_target), nz%updates, nz%update_target, &
         & size(slot_of), slot_of)
   end subroutine list_places

   !> The lists of L's and U's places (and the values' slots) for at least
   !> nlower and nupper places, and refactor_nonzeros's for nupdate
   !> updates, and an eighth more, so that the next pivots' few places more
   !> (a pivot changed at a near tie) rarely list them twice. Not the
   !> band's count (n kl and n (kl + ku)): a mechanism's factor keeps most
   !> of the band's zeros, and the band's count made these lists the
   !> largest arrays of a large lift.
   pure subroutine reserve_lists(nz, nlower, nupper, nupdate)
      type(band_lu_nonzeros_type), intent(inout) :: nz
      integer, intent(in) :: nlower, nupper, nupdate
      integer :: ml, mu, mup
      ml = max(1, nlower + nlower/8)
      mu = max(1, nupper + nupper/8)
      mup = max(1, nupdate + nupdate/8)
      if (allocated(nz%lower_at)) deallocate (nz%lower_at, nz%lower_column, nz%lower_row)
      if (allocated(nz%upper_at)) deallocate (nz%upper_at, nz%upper_row)
      if (allocated(nz%values)) deallocate (nz%values, nz%update_target)
      allocate (nz%lower_at(ml), nz%lower_column(ml), nz%lower_row(ml))
      allocate (nz%upper_at(mu), nz%upper_row(mu))
      allocate (nz%values(nz%n + ml + mu + 1), nz%update_target(mup))
   end subroutine reserve_lists

   !> U's places by rows (row_start, and their slots row_slot: after
   !> `upper`) from its lists by columns.
   pure subroutine list_rows(n, upper_start, upper_row, upper, row_start, row_slot)
      integer, intent(in) :: n, upper_start(n + 1), upper_row(:), upper
      integer, intent(out) :: row_start(n + 1), row_slot(:)
      integer :: j, k, i
      row_start = 0
      do k = 1, upper_start(n + 1) - 1
         row_start(upper_row(k)) = row_start(upper_row(k)) + 1
      end do
      ! Counts to starts, then each column's rows in increasing column order.
      k = 1
      do i = 1, n
         j = row_start(i)
         row_start(i) = k
         k = k + j
      end do
      row_start(n + 1) = k
      do j = 1, n
         do k = upper_start(j), upper_start(j + 1) - 1
            i = upper_row(k)
            row_slot(row_start(i)) = upper + k
            row_start(i) = row_start(i) + 1
         end do
      end do
      ! The starts moved to the next row's: back one row.
      do i = n, 2, -1
         row_start(i) = row_start(i - 1)
      end do
      row_start(1) = 1
   end subroutine list_rows

   !> The band LU of ab (the matrix, as fekap_linalg_lapack's
   !> band_lu_factor_loops takes it) with the pivots and places of the last
   !> symbolic factorisation, its values at their slots: column by column,
   !> the last pivot row is kept while its magnitude is at least `keep`
   !> times the column's largest (1: the largest, as partial pivoting), and
   !> the elimination multiplies only the places that can be nonzero (the
   !> same operations as the band's loops on those places, so with the same
   !> pivots the same factor to the bit). ab is left as it is. stopped = 0:
   !> done, ipiv the pivots. Otherwise the column where a pivot did not
   !> serve (or there are no places known): columns 1 to stopped - 1 of ab
   !> are eliminated with the kept pivots, in ipiv (the band's loops,
   !> band_lu_given_pivots), and the band's loops go on from column stopped
   !> (band_lu_factor_loops' first), then gather_nonzeros. Every place of
   !> ab outside the matrix's and the fill rows 1 to kl must be zero, as
   !> for those loops.
   pure subroutine refactor_nonzeros(nz, ab, ipiv, keep, stopped, loaded)
      type(band_lu_nonzeros_type), intent(inout) :: nz
      real(dp), contiguous, intent(inout) :: ab(:, :)
      integer, contiguous, intent(inout) :: ipiv(:)
      real(dp), intent(in) :: keep
      integer, intent(out) :: stopped
      !> Whether the caller has put ab's entries at their slots already
      !> (nz%values(nz%entry_slot(k)) = ab's place nz%entry_at(k), for
      !> every k; the spare slot before the first symbolic factorisation).
      logical, intent(in), optional :: loaded
      integer :: nentry
      stopped = 1
      if (.not. nz%known) return
      nentry = size(nz%entry_at)
      if (present(loaded)) then
         if (loaded) nentry = 0
      end if
      call refactor_kernel(nz%n, nz%kl + nz%ku, size(ab, 1), size(ab), ab, nentry, size(nz%entry_at), nz%entry_at, &
         & nz%entry_slot, size(nz%fill_slot), nz%fill_slot, nz%pivot, keep, nz%lower_start, size(nz%lower_at), nz%lower_at, &
         & nz%row_start, size(nz%row_slot), nz%row_slot, &
         & size(nz%update_target), nz%update_target, size(nz%values), nz%values, stopped)
      if (stopped == 0) then
         ipiv(1:nz%n) = nz%pivot
         return
      end if
      ! ab as the band's loops leave it after column stopped - 1 with these
      ! pivots (the values' own operations, on the whole band).
      ipiv(1:stopped - 1) = nz%pivot(1:stopped - 1)
      call band_lu_given_pivots(ab, nz%kl, nz%ku, ipiv, stopped - 1)
   end subroutine refactor_nonzeros

   !> refactor_nonzeros's elimination on explicit-shape arrays, in the
   !> factor's slots: the matrix's entries (nentry of them: 0 when the
   !> caller has put them there), the fill zero (no row
   !> interchange is made: each value is at its slot from the start, where
   !> the interchanges would have taken it), then for each column j the
   !> pivot's check (the column's values before its interchange are its
   !> slots' values: the diagonal and the multipliers', with row pivot(j)'s
   !> and row j's exchanged), the multipliers (the diagonal's reciprocal
   !> times them) and, for each of row j's entries of U that is not zero
   !> (the band's loops skip a zero one, as dger does), the multipliers
   !> times it taken from the slots of update_target in turn. A place that
   !> cannot be nonzero gets no product: b - t*0 is b to the bit (module
   !> header).
   pure subroutine refactor_kernel(n, kv, ldab, nab, ab, nentry, mentry, entry_at, entry_slot, nfill, fill_slot, pivot, keep, &
      & lower_start, nlower, lower_at, row_start, nrow, row_slot, nupdate, update_target, nvalues, values, stopped)
      integer, intent(in) :: n, kv, ldab, nab, nentry, mentry, entry_at(mentry), entry_slot(mentry), nfill, fill_slot(nfill)
      integer, intent(in) :: pivot(n)
      integer, intent(in) :: lower_start(n + 1), nlower, lower_at(nlower), row_start(n + 1), nrow, row_slot(nrow)
      integer, intent(in) :: nupdate, update_target(nupdate), nvalues
      real(dp), intent(in) :: ab(nab), keep
      real(dp), intent(inout) :: values(nvalues)
      integer, intent(out) :: stopped
      real(dp) :: largest, temp, recip, diagonal
      integer :: j, k, m, t, first, last, row
      !GCC$ unroll 1
      !GCC$ novector
      do k = 1, nfill
         values(fill_slot(k)) = 0
      end do
      !GCC$ unroll 1
      !GCC$ novector
      do k = 1, nentry
         values(entry_slot(k)) = ab(entry_at(k))
      end do
      t = 0
      do j = 1, n
         ! Column j's multipliers at values(first:last).
         first = n + lower_start(j)
         last = n + lower_start(j + 1) - 1
         diagonal = values(j)
         largest = abs(diagonal)
         !GCC$ unroll 1
         !GCC$ novector
         do k = first, last
            largest = max(largest, abs(values(k)))
         end do
         ! Kept while it is a pivot partial pivoting would take, or near one
         ! (not: a zero column, which the band's loops report).
         if (.not. (largest > 0 .and. abs(diagonal) >= keep*largest)) then
            stopped = j
            return
         end if
         if (keep >= 1 .and. pivot(j) /= j) then
            ! The first largest, as idamax takes it: else the loops' pivot
            ! differs. Rows j to pivot(j) - 1 before the interchange; row
            ! j's value is at row pivot(j)'s slot after it.
            do k = first, last
               row = j + lower_at(k - n) - kv - 1 - (j - 1)*ldab
               if (row == pivot(j)) row = j
               if (row < pivot(j) .and. abs(values(k)) >= largest) then
                  stopped = j
                  return
               end if
            end do
         end if
         if (last < first) cycle
         recip = 1/diagonal
         !GCC$ unroll 1
         !GCC$ novector
         do k = first, last
            values(k) = recip*values(k)
         end do
         ! Row j of U times the multipliers, from the slots below.
         do m = row_start(j), row_start(j + 1) - 1
            temp = values(row_slot(m))
            if (temp /= 0) then
               temp = -temp
               !GCC$ unroll 1
               !GCC$ novector
               do k = first, last
                  t = t + 1
                  values(update_target(t)) = values(update_target(t)) + values(k)*temp
               end do
            else
               t = t + last - first + 1
            end if
         end do
      end do
      stopped = 0
   end subroutine refactor_kernel

   !> symbolic_factor's loops and lists on explicit-shape arrays (their
   !> addresses without a descriptor's arithmetic); place is the window of
   !> columns, all zero on entry and on return. The window holds columns
   !> base + 1 to loaded; the elimination runs over those whose columns
   !> reached are all there (to loaded - kl - ku, or to n), then lists them,
   !> and moves the rest to the window's front. The values' numbers: the
   !> matrix's entries 1 to nentry (entry_at's order), fill from nentry + 1
   !> as it appears; update_id, each update's sum's number (nup of them,
   !> counted on past nupdate but not written there), and slot_of (at most
   !> nslot numbers) are refactor_nonzeros's lists.
   pure subroutine symbolic_kernel(n, kl, ku, columns, ipiv, entry_start, nentry, entry_at, place, nlower, lower_start, &
      & lower_column, lower_row, lower_at, nupper, upper_start, upper_row, upper_at, nupdate, nup, update_id, nslot, slot_of)
      integer, intent(in) :: n, kl, ku, columns, ipiv(n), entry_start(n + 1), nentry, entry_at(nentry), nlower, nupper
      integer, intent(in) :: nupdate, nslot
      integer, intent(inout) :: place(2*kl + ku + 1, columns)
      integer, intent(out) :: lower_start(n + 1), lower_column(nlower), lower_row(nlower), lower_at(nlower)
      integer, intent(out) :: upper_start(n + 1), upper_row(nupper), upper_at(nupper)
      integer, intent(out) :: nup, update_id(nupdate)
      integer, intent(inout) :: slot_of(nslot)
      integer :: kv, ldab, i, j, jj, jp, ju, km, nl, nu, base, loaded, c, first, last, live, swap, number
      kv = kl + ku
      ldab = 2*kl + ku + 1
      base = 0
      loaded = columns
      call mark_columns(entry_start(1), entry_start(loaded + 1) - 1, entry_at, 0, size(place), place)
      nl = 0
      nu = 0
      nup = 0
      number = nentry
      ju = 1
      first = 1
      do
         last = loaded - kv
         if (loaded == n) last = n
         do j = first, last
            c = j - base
            km = min(kl, n - j)
            jp = ipiv(j) - j + 1
            ju = max(ju, min(j + ku + jp - 1, n))
            if (jp /= 1) then
               do jj = 0, ju - j
                  swap = place(kv + jp - jj, c + jj)
                  place(kv + jp - jj, c + jj) = place(kv + 1 - jj, c + jj)
                  place(kv + 1 - jj, c + jj) = swap
               end do
            end if
            do jj = 1, ju - j
               if (place(kv + 1 - jj, c + jj) /= 0) then
                  do i = 1, km
                     if (place(kv + 1 + i, c) == 0) cycle
                     if (place(kv + 1 + i - jj, c + jj) == 0) then
                        number = number + 1
                        place(kv + 1 + i - jj, c + jj) = number
                     end if
                     nup = nup + 1
                     if (nup <= nupdate) update_id(nup) = place(kv + 1 + i - jj, c + jj)
                  end do
               end if
            end do
         end do
         call list_columns(n, kl, ku, first, last, base, columns, place, nl, nlower, lower_start, lower_column, lower_row, &
            & lower_at, nu, nupper, upper_start, upper_row, upper_at, nslot, slot_of)
         if (last == n) exit
         ! Columns last + 1 to loaded to the window's front (their old places
         ! cleared), then the next columns' entries after them.
         live = loaded - last
         place(:, 1:live) = place(:, last + 1 - base:loaded - base)
         place(:, max(live + 1, last + 1 - base):loaded - base) = 0
         base = last
         first = last + 1
         c = loaded
         loaded = min(n, base + columns)
         call mark_columns(entry_start(c + 1), entry_start(loaded + 1) - 1, entry_at, base*ldab, size(place), place)
      end do
      lower_start(n + 1) = nl + 1
      upper_start(n + 1) = nu + 1
   end subroutine symbolic_kernel

   !> The places of columns first to last (at first - base to last - base
   !> of the window), their eliminations done, appended to the lists (nl
   !> and nu of them so far; counted on past the lists' ends, nlower and
   !> nupper, but not written there), the slots of their values' numbers
   !> noted in slot_of (U's diagonal at 1 to n, L's after, U's after n +
   !> nlower), and cleared in the window (no other place of the window is
   !> ever set: each is one of the matrix's rows).
   pure subroutine list_columns(n, kl, ku, first, last, base, columns, place, nl, nlower, lower_start, lower_column, &
      & lower_row, lower_at, nu, nupper, upper_start, upper_row, upper_at, nslot, slot_of)
      integer, intent(in) :: n, kl, ku, first, last, base, columns, nlower, nupper, nslot
      integer, intent(inout) :: place(2*kl + ku + 1, columns)
      integer, intent(inout) :: nl, nu
      integer, intent(inout) :: lower_start(n + 1), lower_column(nlower), lower_row(nlower), lower_at(nlower)
      integer, intent(inout) :: upper_start(n + 1), upper_row(nupper), upper_at(nupper), slot_of(nslot)
      integer :: kv, ldab, i, j, c, number
      kv = kl + ku
      ldab = 2*kl + ku + 1
      do j = first, last
         c = j - base
         lower_start(j) = nl + 1
         upper_start(j) = nu + 1
         do i = max(1, j - kv), j - 1
            number = place(kv + 1 + i - j, c)
            if (number /= 0) then
               place(kv + 1 + i - j, c) = 0
               nu = nu + 1
               if (nu > nupper) cycle
               upper_row(nu) = i
               upper_at(nu) = kv + 1 + i - j + (j - 1)*ldab
               if (number <= nslot) slot_of(number) = n + nlower + nu
            end if
         end do
         number = place(kv + 1, c)
         if (number /= 0 .and. number <= nslot) slot_of(number) = j
         place(kv + 1, c) = 0
         do i = 1, min(kl, n - j)
            number = place(kv + 1 + i, c)
            if (number /= 0) then
               place(kv + 1 + i, c) = 0
               nl = nl + 1
               if (nl > nlower) cycle
               lower_column(nl) = j
               lower_row(nl) = j + i
               lower_at(nl) = kv + 1 + i + (j - 1)*ldab
               if (number <= nslot) slot_of(number) = n + nl
            end if
         end do
      end do
   end subroutine list_columns

   !> place (the window taken as one array) at the matrix's places
   !> entry_at(first:last), less offset (the window's first column's
   !> place), the entries' numbers.
   pure subroutine mark_columns(first, last, entry_at, offset, size_of, place)
      integer, intent(in) :: first, last, entry_at(:), offset, size_of
      integer, intent(inout) :: place(size_of)
      integer :: k
      do k = first, last
         place(entry_at(k) - offset) = k
      end do
   end subroutine mark_columns

   !> Solve A x = b with the factor's nonzeros as dgbtrs ('N') does: each
   !> column's row interchange and L's multipliers (all interchanges made
   !> first, the multipliers then applied to the rows renumbered so:
   !> symbolic_factor), then back substitution with U column by column
   !> (dtbsv); b becomes x. The factor's values are those gathered last.
   pure subroutine nonzeros_solve(nz, b)
      type(band_lu_nonzeros_type), intent(in) :: nz
      real(dp), contiguous, intent(inout) :: b(:)
      integer :: n, nl, nu, upper
      n = nz%n
      nl = nz%lower_start(n + 1) - 1
      nu = nz%upper_start(n + 1) - 1
      upper = upper_slots(nz)
      call solve_kernel(n, nl, nu, nz%pivot, size(nz%interchange), nz%interchange, nz%lower_column, nz%lower_row, &
         & nz%values(n + 1:n + nl), nz%upper_start, nz%upper_row, nz%values(upper + 1:upper + nu), nz%values(1:n), b)
   end subroutine nonzeros_solve

   !> nonzeros_solve on explicit-shape arrays.
   pure subroutine solve_kernel(n, nl, nu, pivot, ni, interchange, lower_column, lower_row, lower, upper_start, upper_row, &
      & upper, diagonal, b)
      integer, intent(in) :: n, nl, nu, pivot(n), ni, interchange(ni), lower_column(nl), lower_row(nl), upper_start(n + 1)
      integer, intent(in) :: upper_row(nu)
      real(dp), intent(in) :: lower(nl), upper(nu), diagonal(n)
      real(dp), intent(inout) :: b(n)
      real(dp) :: temp
      integer :: j, l, k, m
      !GCC$ unroll 1
      do m = 1, ni
         j = interchange(m)
         l = pivot(j)
         temp = b(l)
         b(l) = b(j)
         b(j) = temp
      end do
      !GCC$ unroll 1
      !GCC$ novector
      do k = 1, nl
         b(lower_row(k)) = b(lower_row(k)) - b(lower_column(k))*lower(k)
      end do
      do j = n, 1, -1
         b(j) = b(j)/diagonal(j)
         temp = b(j)
         !GCC$ unroll 1
         !GCC$ novector
         do k = upper_start(j), upper_start(j + 1) - 1
            b(upper_row(k)) = b(upper_row(k)) - temp*upper(k)
         end do
      end do
   end subroutine solve_kernel

   !> Solve A^T x = b with the factor's nonzeros as dgbtrs ('T') does:
   !> U^T's substitution (dtbsv's dot products, rows in increasing order),
   !> then L's multipliers as dgemv's dot products in increasing row order,
   !> each followed by its row interchange (here all interchanges last, the
   !> rows read renumbered as in nonzeros_solve); b becomes x.
   pure subroutine nonzeros_solve_transposed(nz, b)
      type(band_lu_nonzeros_type), intent(in) :: nz
      real(dp), contiguous, intent(inout) :: b(:)
      integer :: n, nl, nu, upper
      n = nz%n
      nl = nz%lower_start(n + 1) - 1
      nu = nz%upper_start(n + 1) - 1
      upper = upper_slots(nz)
      call solve_transposed_kernel(n, nl, nu, nz%pivot, size(nz%interchange), nz%interchange, nz%lower_start, nz%lower_row, &
         & nz%values(n + 1:n + nl), nz%upper_start, nz%upper_row, nz%values(upper + 1:upper + nu), nz%values(1:n), b)
   end subroutine nonzeros_solve_transposed

   !> nonzeros_solve_transposed on explicit-shape arrays.
   pure subroutine solve_transposed_kernel(n, nl, nu, pivot, ni, interchange, lower_start, lower_row, lower, upper_start, &
      & upper_row, upper, diagonal, b)
      integer, intent(in) :: n, nl, nu, pivot(n), ni, interchange(ni), lower_start(n + 1), lower_row(nl), upper_start(n + 1)
      integer, intent(in) :: upper_row(nu)
      real(dp), intent(in) :: lower(nl), upper(nu), diagonal(n)
      real(dp), intent(inout) :: b(n)
      real(dp) :: temp
      integer :: j, l, k, m
      do j = 1, n
         temp = b(j)
         !GCC$ unroll 1
         !GCC$ novector
         do k = upper_start(j), upper_start(j + 1) - 1
            temp = temp - upper(k)*b(upper_row(k))
         end do
         b(j) = temp/diagonal(j)
      end do
      do j = n - 1, 1, -1
         if (lower_start(j + 1) > lower_start(j)) then
            temp = 0
            !GCC$ unroll 1
            !GCC$ novector
            do k = lower_start(j), lower_start(j + 1) - 1
               temp = temp + b(lower_row(k))*lower(k)
            end do
            b(j) = b(j) + (-1.0_dp)*temp
         end if
      end do
      !GCC$ unroll 1
      do m = ni, 1, -1
         j = interchange(m)
         l = pivot(j)
         temp = b(l)
         b(l) = b(j)
         b(j) = temp
      end do
   end subroutine solve_transposed_kernel

end module fekap_linalg_band_lu
