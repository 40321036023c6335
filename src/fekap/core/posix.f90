!> The few POSIX calls FEKAP needs that Fortran does not offer, through
!> ISO_C_BINDING: directories made without a shell, renames, removals and
!> truncations with the OS error, an advisory lock, a directory listing, and
!> SIGPIPE and SIGXFSZ ignored. Each call returns the C `errno` of its failure (0 on
!> success), which os_error_text turns into the system's message.
!>
!> The constants (open flags, flock operations) and the layout of `struct
!> dirent` are those of Linux with glibc (the same on x86-64 and AArch64).
module fekap_posix
   use, intrinsic :: iso_c_binding, only: c_int, c_char, c_ptr, c_null_char, c_associated, &
      & c_f_pointer, c_size_t, c_long, c_int64_t, c_short, c_funptr, c_intptr_t
   implicit none
   private

   public :: os_mkdir, os_make_path, os_is_directory, os_rename, os_unlink, os_rmdir, os_truncate
   public :: os_open_lock, os_close, os_append_probe, os_error_text, os_ignore_write_signals
   public :: os_list_directory, name_list_type, os_read_all, os_file_size, os_file_kind, os_same_file
   ! The C library's signal(2), for the interrupt module.
   public :: c_signal

   integer(c_int), parameter :: o_rdonly = 0, o_wronly = 1, o_append = 1024, o_cloexec = 524288
   integer(c_int), parameter :: lock_ex = 2, lock_nb = 4
   integer(c_int), parameter :: eexist = 17, eintr = 4, enotdir = 20, efbig = 27
   !> Most bytes os_read_all reads (256 MiB).
   integer, parameter :: max_read = 268435456
   integer(c_int), parameter :: sigpipe = 13, sigxfsz = 25
   !> Kinds of file (os_file_kind): the S_IFMT bits of st_mode.
   integer, parameter, public :: kind_regular = 32768, kind_directory = 16384, kind_fifo = 4096, &
      & kind_character_device = 8192, kind_block_device = 24576, kind_socket = 49152
   !> statx(2): AT_FDCWD, AT_EMPTY_PATH, STATX_TYPE | STATX_INO.
   integer(c_int), parameter :: at_fdcwd = -100, at_empty_path = 4096, statx_type_ino = 257
   !> Permissions of a new directory, before the umask: 0777.
   integer(c_int), parameter :: mode_directory = 511

   !> Names of a directory's entries.
   type :: name_type
      character(:), allocatable :: text
   end type name_type

   type, public :: name_list_type
      type(name_type), allocatable :: names(:)
      integer :: count = 0
   end type name_list_type

   !> glibc's struct dirent on 64-bit Linux.
   type, bind(C) :: dirent_type
      integer(c_int64_t) :: ino
      integer(c_int64_t) :: off
      integer(c_short) :: reclen
      character(kind=c_char) :: kind
      character(kind=c_char) :: name(256)
   end type dirent_type

   interface
      function c_mkdir(path, mode) bind(C, name='mkdir') result(status)
         import :: c_int, c_char
         implicit none
         character(kind=c_char), intent(in) :: path(*)
         integer(c_int), value :: mode
         integer(c_int) :: status
      end function c_mkdir
      function c_rename(from, to) bind(C, name='rename') result(status)
         import :: c_int, c_char
         implicit none
         character(kind=c_char), intent(in) :: from(*), to(*)
         integer(c_int) :: status
      end function c_rename
      function c_unlink(path) bind(C, name='unlink') result(status)
         import :: c_int, c_char
         implicit none
         character(kind=c_char), intent(in) :: path(*)
         integer(c_int) :: status
      end function c_unlink
      function c_rmdir(path) bind(C, name='rmdir') result(status)
         import :: c_int, c_char
         implicit none
         character(kind=c_char), intent(in) :: path(*)
         integer(c_int) :: status
      end function c_rmdir
      function c_truncate(path, length) bind(C, name='truncate') result(status)
         import :: c_int, c_char, c_long
         implicit none
         character(kind=c_char), intent(in) :: path(*)
         integer(c_long), value :: length
         integer(c_int) :: status
      end function c_truncate
      function c_open(path, flags, mode) bind(C, name='open') result(fd)
         import :: c_int, c_char
         implicit none
         character(kind=c_char), intent(in) :: path(*)
         integer(c_int), value :: flags, mode
         integer(c_int) :: fd
      end function c_open
      function c_read(fd, buffer, count) bind(C, name='read') result(got)
         import :: c_int, c_char, c_size_t, c_long
         implicit none
         integer(c_int), value :: fd
         character(kind=c_char), intent(out) :: buffer(*)
         integer(c_size_t), value :: count
         integer(c_long) :: got
      end function c_read
      function c_lseek(fd, offset, whence) bind(C, name='lseek') result(position)
         import :: c_int, c_long
         implicit none
         integer(c_int), value :: fd, whence
         integer(c_long), value :: offset
         integer(c_long) :: position
      end function c_lseek
      function c_close(fd) bind(C, name='close') result(status)
         import :: c_int
         implicit none
         integer(c_int), value :: fd
         integer(c_int) :: status
      end function c_close
      function c_write(fd, buffer, count) bind(C, name='write') result(written)
         import :: c_int, c_char, c_size_t, c_long
         implicit none
         integer(c_int), value :: fd
         character(kind=c_char), intent(in) :: buffer(*)
         integer(c_size_t), value :: count
         integer(c_long) :: written
      end function c_write
      function c_flock(fd, operation) bind(C, name='flock') result(status)
         import :: c_int
         implicit none
         integer(c_int), value :: fd, operation
         integer(c_int) :: status
      end function c_flock
      function c_errno_location() bind(C, name='__errno_location') result(where)
         import :: c_ptr
         implicit none
         type(c_ptr) :: where
      end function c_errno_location
      function c_strerror(errnum) bind(C, name='strerror') result(text)
         import :: c_int, c_ptr
         implicit none
         integer(c_int), value :: errnum
         type(c_ptr) :: text
      end function c_strerror
      function c_strlen(text) bind(C, name='strlen') result(length)
         import :: c_ptr, c_size_t
         implicit none
         type(c_ptr), value :: text
         integer(c_size_t) :: length
      end function c_strlen
      function c_opendir(path) bind(C, name='opendir') result(dir)
         import :: c_char, c_ptr
         implicit none
         character(kind=c_char), intent(in) :: path(*)
         type(c_ptr) :: dir
      end function c_opendir
      function c_readdir(dir) bind(C, name='readdir') result(entry)
         import :: c_ptr
         implicit none
         type(c_ptr), value :: dir
         type(c_ptr) :: entry
      end function c_readdir
      function c_closedir(dir) bind(C, name='closedir') result(status)
         import :: c_ptr, c_int
         implicit none
         type(c_ptr), value :: dir
         integer(c_int) :: status
      end function c_closedir
      function c_statx(dirfd, path, flags, mask, buffer) bind(C, name='statx') result(status)
         import :: c_int, c_char
         implicit none
         integer(c_int), value :: dirfd, flags, mask
         character(kind=c_char), intent(in) :: path(*)
         !> struct statx: 256 bytes, the same layout on every architecture.
         character(kind=c_char), intent(out) :: buffer(256)
         integer(c_int) :: status
      end function c_statx
      function c_signal(signum, handler) bind(C, name='signal') result(previous)
         import :: c_int, c_funptr
         implicit none
         integer(c_int), value :: signum
         type(c_funptr), value :: handler
         type(c_funptr) :: previous
      end function c_signal
   end interface

contains

   !> `text` as a C string.
   pure function c_string(text) result(c)
      character(*), intent(in) :: text
      character(kind=c_char, len=len(text) + 1) :: c
      c = text//c_null_char
   end function c_string

   !> The calling thread's errno.
   integer function errno()
      integer(c_int), pointer :: value
      call c_f_pointer(c_errno_location(), value)
      errno = value
   end function errno

   !> The system's message for an errno value, e.g. "No space left on device".
   function os_error_text(code) result(text)
      integer, intent(in) :: code
      character(:), allocatable :: text
      character(kind=c_char), pointer :: chars(:)
      type(c_ptr) :: p
      integer :: i, n
      p = c_strerror(int(code, c_int))
      if (.not. c_associated(p)) then
         text = 'error'
         return
      end if
      n = int(c_strlen(p))
      call c_f_pointer(p, chars, [n])
      allocate (character(len=n) :: text)
      do i = 1, n
         text(i:i) = chars(i)
      end do
   end function os_error_text

   !> mkdir(2): 0, or the errno (EEXIST when something is there already).
   integer function os_mkdir(path) result(code)
      character(*), intent(in) :: path
      code = 0
      if (c_mkdir(c_string(path), mode_directory) /= 0) code = errno()
   end function os_mkdir

   !> The path names a directory (or a link to one).
   logical function os_is_directory(path)
      character(*), intent(in) :: path
      type(c_ptr) :: dir
      integer(c_int) :: status
      dir = c_opendir(c_string(path))
      os_is_directory = c_associated(dir)
      if (os_is_directory) status = c_closedir(dir)
   end function os_is_directory

   !> Make a directory and its missing parents, the path taken literally (no
   !> shell). 0, or the errno of the component that could not be made, with
   !> `failed` the path up to it.
   integer function os_make_path(path, failed) result(code)
      character(*), intent(in) :: path
      character(:), allocatable, intent(out) :: failed
      integer :: i
      code = 0
      failed = ''
      do i = 2, len(path) + 1
         if (i <= len(path)) then
            if (path(i:i) /= '/') cycle
            if (path(i - 1:i - 1) == '/') cycle
         end if
         code = os_mkdir(path(:i - 1))
         if (code == eexist) then
            code = 0
            if (.not. os_is_directory(path(:i - 1))) code = enotdir
         end if
         if (code /= 0) then
            failed = path(:i - 1)
            return
         end if
      end do
   end function os_make_path

   !> rename(2): replaces `to` atomically. 0 or the errno.
   integer function os_rename(from, to) result(code)
      character(*), intent(in) :: from, to
      code = 0
      if (c_rename(c_string(from), c_string(to)) /= 0) code = errno()
   end function os_rename

   !> unlink(2). 0 or the errno.
   integer function os_unlink(path) result(code)
      character(*), intent(in) :: path
      code = 0
      if (c_unlink(c_string(path)) /= 0) code = errno()
   end function os_unlink

   !> rmdir(2) (an empty directory). 0 or the errno.
   integer function os_rmdir(path) result(code)
      character(*), intent(in) :: path
      code = 0
      if (c_rmdir(c_string(path)) /= 0) code = errno()
   end function os_rmdir

   !> truncate(2): cut the file to `length` bytes. 0 or the errno.
   integer function os_truncate(path, length) result(code)
      character(*), intent(in) :: path
      integer(c_int64_t), intent(in) :: length
      code = 0
      if (c_truncate(c_string(path), int(length, c_long)) /= 0) code = errno()
   end function os_truncate

   !> Open `path` (a file or a directory) for reading and take an exclusive
   !> flock(2) on it without waiting. The lock belongs to the open file: the
   !> kernel releases it when the process ends, however it ends, so a lock is
   !> never stale. `fd` stays open for the life of the process. 0, or the
   !> errno (EWOULDBLOCK when another process holds the lock).
   integer function os_open_lock(path, fd) result(code)
      character(*), intent(in) :: path
      integer, intent(out) :: fd
      integer(c_int) :: status
      code = 0
      fd = int(c_open(c_string(path), ior(o_rdonly, o_cloexec), 0_c_int))
      if (fd < 0) then
         code = errno()
         return
      end if
      do
         if (c_flock(int(fd, c_int), ior(lock_ex, lock_nb)) == 0) exit
         code = errno()
         if (code == eintr) cycle
         status = c_close(int(fd, c_int))
         fd = -1
         return
      end do
      code = 0
   end function os_open_lock

   !> close(2) of a descriptor from os_open_lock (releasing its lock).
   subroutine os_close(fd)
      integer, intent(in) :: fd
      integer(c_int) :: status
      status = c_close(int(fd, c_int))
   end subroutine os_close

   !> Why a file took fewer bytes than written to it: append one byte with
   !> write(2) and return its errno (0 if the byte went in; the caller cuts
   !> the file back to its valid length afterwards).
   integer function os_append_probe(path) result(code)
      character(*), intent(in) :: path
      integer(c_int) :: fd, status
      code = 0
      fd = c_open(c_string(path), ior(o_wronly, o_append), 0_c_int)
      if (fd < 0) then
         code = errno()
         return
      end if
      if (c_write(fd, new_line('a'), 1_c_size_t) /= 1) code = errno()
      status = c_close(fd)
   end function os_append_probe

   !> The whole content of `path` read with read(2) until its end: also a pipe
   !> or a terminal (`fekap /dev/stdin`), whose size is not known in advance.
   !> Reading stops early at a NUL byte (not text: /dev/zero ends at once, and
   !> the caller reports a binary file) and at max_read bytes (EFBIG: an
   !> endless stream). 0 or the errno.
   integer function os_read_all(path, text) result(code)
      character(*), intent(in) :: path
      character(:), allocatable, intent(out) :: text
      character(kind=c_char, len=65536) :: chunk
      character(:), allocatable :: grown
      integer(c_int) :: fd, status
      integer(c_long) :: got
      integer :: n
      code = 0
      allocate (character(len=65536) :: text)
      n = 0
      fd = c_open(c_string(path), ior(o_rdonly, o_cloexec), 0_c_int)
      if (fd < 0) then
         code = errno()
         text = ''
         return
      end if
      do
         got = c_read(fd, chunk, int(len(chunk), c_size_t))
         ! EINTR too ends the read: only the signals that stop the run interrupt it.
         if (got < 0) then
            code = errno()
            exit
         end if
         if (got == 0) exit
         if (n + got > max_read) then
            code = efbig
            exit
         end if
         if (n + got > len(text)) then
            allocate (character(len=2*len(text) + int(got)) :: grown)
            grown(1:n) = text(1:n)
            call move_alloc(grown, text)
         end if
         text(n + 1:n + got) = chunk(1:got)
         n = n + int(got)
         code = 0
         if (index(chunk(1:got), c_null_char) > 0) exit
      end do
      status = c_close(fd)
      text = text(1:n)
   end function os_read_all

   !> The size in bytes of the file `path` on disk, -1 if it cannot be opened.
   !> (gfortran's INQUIRE SIZE= of an open file answers from the unit's own
   !> record of what was written, not from the file.)
   integer(c_int64_t) function os_file_size(path) result(size_)
      character(*), intent(in) :: path
      integer(c_int) :: fd, status
      integer(c_int), parameter :: seek_end = 2
      size_ = -1
      fd = c_open(c_string(path), ior(o_rdonly, o_cloexec), 0_c_int)
      if (fd < 0) return
      size_ = int(c_lseek(fd, 0_c_long, seek_end), c_int64_t)
      status = c_close(fd)
   end function os_file_size

   !> The kind of file `path` names (kind_regular, kind_directory,
   !> kind_fifo, ...; symbolic links followed), without opening it (opening a
   !> FIFO waits for a writer), and whether it is the process's standard
   !> input (`fekap /dev/stdin`: the same device and inode as descriptor 0).
   !> 0 or the errno of statx(2).
   integer function os_file_kind(path, kind, is_stdin) result(code)
      character(*), intent(in) :: path
      integer, intent(out) :: kind
      logical, intent(out) :: is_stdin
      character(kind=c_char) :: file(256), stdin(256)
      integer(c_int), parameter :: stdin_fd = 0
      code = 0
      kind = 0
      is_stdin = .false.
      if (c_statx(at_fdcwd, c_string(path), 0_c_int, statx_type_ino, file) /= 0) then
         code = errno()
         return
      end if
      ! stx_mode: bytes 29-30 (little-endian u16); stx_ino 33-40; stx_dev_major, _minor 137-144.
      kind = iand(iachar(file(29)) + 256*iachar(file(30)), 61440)
      if (c_statx(stdin_fd, c_string(''), at_empty_path, statx_type_ino, stdin) == 0) then
         is_stdin = all(file(33:40) == stdin(33:40)) .and. all(file(137:144) == stdin(137:144))
      end if
   end function os_file_kind

   !> Whether paths `a` and `b` name the same file (the same device and
   !> inode, links followed); .false. when either cannot be looked at.
   logical function os_same_file(a, b)
      character(*), intent(in) :: a, b
      character(kind=c_char) :: sa(256), sb(256)
      os_same_file = .false.
      if (c_statx(at_fdcwd, c_string(a), 0_c_int, statx_type_ino, sa) /= 0) return
      if (c_statx(at_fdcwd, c_string(b), 0_c_int, statx_type_ino, sb) /= 0) return
      os_same_file = all(sa(33:40) == sb(33:40)) .and. all(sa(137:144) == sb(137:144))
   end function os_same_file

   !> Writes to a closed pipe (`fekap ... | head -1`) then fail with EPIPE
   !> instead of killing the process with SIGPIPE, and writes past the
   !> file-size limit (`ulimit -f`) with EFBIG (exit 4, the rows before kept
   !> whole) instead of SIGXFSZ, for which the Fortran runtime installs a
   !> handler that prints a backtrace and leaves half a row.
   subroutine os_ignore_write_signals()
      type(c_funptr) :: previous
      ! SIG_IGN is the handler address 1.
      previous = c_signal(sigpipe, transfer(1_c_intptr_t, previous))
      previous = c_signal(sigxfsz, transfer(1_c_intptr_t, previous))
   end subroutine os_ignore_write_signals

   !> The names in directory `path` (without . and ..). 0 or the errno of opendir.
   integer function os_list_directory(path, list) result(code)
      character(*), intent(in) :: path
      type(name_list_type), intent(out) :: list
      type(c_ptr) :: dir, entry
      type(dirent_type), pointer :: d
      type(name_type), allocatable :: grown(:)
      character(:), allocatable :: name
      integer :: n
      integer(c_int) :: status
      code = 0
      allocate (list%names(16))
      dir = c_opendir(c_string(path))
      if (.not. c_associated(dir)) then
         code = errno()
         return
      end if
      do
         entry = c_readdir(dir)
         if (.not. c_associated(entry)) exit
         call c_f_pointer(entry, d)
         n = 0
         do while (n < size(d%name))
            if (d%name(n + 1) == c_null_char) exit
            n = n + 1
         end do
         allocate (character(len=n) :: name)
         name = transfer(d%name(1:n), name)
         if (name /= '.' .and. name /= '..') then
            if (list%count == size(list%names)) then
               allocate (grown(2*size(list%names)))
               grown(1:list%count) = list%names(1:list%count)
               call move_alloc(grown, list%names)
            end if
            list%count = list%count + 1
            list%names(list%count)%text = name
         end if
         deallocate (name)
      end do
      status = c_closedir(dir)
   end function os_list_directory

end module fekap_posix
