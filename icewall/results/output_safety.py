"""Guards around writing a result: one writer per output, no writing through planted symbolic
links, no HDF5 write on a full disk.

* ``OutputLock``: an exclusive ``flock`` on ``NAME.h5.lock`` (opened without truncation and
  without following links), taken before anything of a run is opened for writing; a second run
  on the same output is refused, and the lock vanishes with its holder (no stale locks).
* ``refuse_symlink``: the ``.partial``, final, lock and checkpoint paths must not be symbolic
  links (a link planted in a shared directory would make icewall overwrite its target); the
  rule of every output, icewall.safe_write, which also writes the final file and checkpoint.
* ``ensure_space``: HDF5 cannot recover from a failed write (the file cannot be closed cleanly
  after it, h5py 3 crashes), so every step checks the free space first and stops with
  ``DiskFullError`` while the file still holds every converged step and can be closed.
"""

from __future__ import annotations

import errno
import os
import stat

from icewall.errors import IcewallError, ResultError
from icewall.safe_write import refuse_link

LOCK_SUFFIX = ".lock"
FREE_FLOOR = 1 << 20  # bytes left free after a step: room to record the outcome and close
DISK_FULL_ERRNOS = (errno.ENOSPC, errno.EDQUOT, errno.EFBIG)

try:
    import fcntl
except ImportError:  # pragma: no cover - not POSIX: exclusive create, a stale lock stays
    fcntl = None  # type: ignore[assignment]


class DiskFullError(IcewallError):
    """No room left for the next step; the converged steps are kept (exit code 1)."""

    exit_code = 1


def refuse_symlink(path: str | os.PathLike, what: str = "output") -> None:
    """Raise ResultError if `path` is a symbolic link (icewall writes through none)."""
    refuse_link(path, what)


def free_bytes(directory: str | os.PathLike) -> int:
    """Bytes an unprivileged writer may still use on the filesystem of `directory`."""
    st = os.statvfs(directory)
    return st.f_bavail * st.f_frsize


def ensure_space(path: str | os.PathLike, need: int, what: str) -> None:
    """DiskFullError unless `need` bytes plus FREE_FLOOR are free beside `path`."""
    directory = os.path.dirname(os.path.abspath(path))
    try:
        free = free_bytes(directory)
    except OSError:  # no statvfs here: the writes themselves report a full disk
        return
    if free < need + FREE_FLOOR:
        raise DiskFullError(f"disk full: {free / 1e6:.2f} MB free in {directory}, {what} "
                            f"needs {(need + FREE_FLOOR) / 1e6:.2f} MB")


def is_disk_full(exc: BaseException) -> bool:
    """Whether `exc` (an OSError, or h5py's wrapping of one) says the disk or quota is full."""
    if isinstance(exc, OSError) and exc.errno in DISK_FULL_ERRNOS:
        return True
    return "errno = 28" in str(exc) or "No space left" in str(exc)


class OutputLock:
    """Exclusive lock of one result path (``<path>.lock``), held for the whole run."""

    def __init__(self, result_path: str | os.PathLike) -> None:
        self.result_path = os.fspath(result_path)
        self.path = self.result_path + LOCK_SUFFIX
        self._fd: int | None = None

    @property
    def held(self) -> bool:
        return self._fd is not None

    def acquire(self) -> OutputLock:
        """Take the lock or raise ResultError (exit 2) naming the run that holds it."""
        if self._fd is not None:
            return self
        for _ in range(100):  # retried only while a previous holder removes its lock file
            fd = self._open()
            try:
                if self._lock(fd):
                    os.ftruncate(fd, 0)
                    os.write(fd, f"{os.getpid()}\n".encode())
                    self._fd = fd
                    return self
            except BaseException:
                os.close(fd)
                raise
            os.close(fd)
        raise ResultError(f"cannot lock {self.path}: it keeps being replaced")

    def _open(self) -> int:
        flags = os.O_RDWR | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0)
        if fcntl is None:
            flags |= os.O_EXCL
        try:
            fd = os.open(self.path, flags, 0o644)
        except OSError as exc:
            if exc.errno == errno.ELOOP or os.path.islink(self.path):
                refuse_symlink(self.path, "lock file")
            if exc.errno == errno.EEXIST:  # no flock: an existing lock file is a lock
                raise ResultError(f"{self.result_path} is being written by another icewall "
                                  f"run (lock {self.path}; remove it if no run is left)"
                                  ) from None
            if exc.errno in DISK_FULL_ERRNOS:
                raise DiskFullError(f"disk full: cannot create {self.path}") from None
            raise ResultError(f"cannot create the lock file {self.path}: {exc.strerror}"
                              ) from None
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            os.close(fd)
            raise ResultError(f"cannot lock {self.result_path}: {self.path} is not a file")
        held = os.pread(fd, 64, 0).strip()
        if held and not held.isdigit():  # a lock holds its holder's pid, or nothing yet
            os.close(fd)
            raise ResultError(f"refusing to use {self.path} as the lock of {self.result_path}: "
                              "it is not a lock file icewall wrote; remove it or choose "
                              "another output")
        return fd

    def _lock(self, fd: int) -> bool:
        """flock `fd`; False if its file was unlinked or replaced meanwhile (retry)."""
        if fcntl is None:
            return True
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(fd, 32, 0).decode(errors="replace").strip() or "?"
            raise ResultError(f"{self.result_path} is being written by another icewall run "
                              f"(pid {holder}); wait for it or choose another output") from None
        try:
            now = os.lstat(self.path)
        except FileNotFoundError:
            return False
        mine = os.fstat(fd)
        return (now.st_dev, now.st_ino) == (mine.st_dev, mine.st_ino)

    def release(self) -> None:
        """Remove the lock file and drop the lock (idempotent)."""
        if self._fd is None:
            return
        fd, self._fd = self._fd, None
        try:
            now, mine = os.lstat(self.path), os.fstat(fd)
            if (now.st_dev, now.st_ino) == (mine.st_dev, mine.st_ino):
                os.remove(self.path)
        except OSError:
            pass
        finally:
            os.close(fd)

    def __enter__(self) -> OutputLock:
        return self.acquire()

    def __exit__(self, *exc) -> None:
        self.release()
