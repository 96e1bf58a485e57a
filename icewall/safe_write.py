"""The one place icewall writes files through: never through a link it did not create, never
over a file it did not create (issue 38; the rules the run's HDF5 output always held, for every
output: tables, baselines, figures, reports, exports, meshes, schemas, checkpoints, results).

* Content goes to a new temporary file beside the destination, created exclusively and without
  following links (``O_CREAT | O_EXCL | O_NOFOLLOW``) under an unpredictable name (``.NAME.``,
  12 random characters, ``.tmp``), or, for a library that writes by file name (meshio, gmsh),
  into a private temporary directory beside it (``mkdtemp``) under the destination's own name.
* The destination may be absent, or a regular file that its :class:`Kind` recognises as one
  icewall wrote (a header or a mark in its first bytes). A symbolic link, a directory or other
  non-file, a file icewall did not write, or a read-only file is refused (:class:`ResultError`,
  exit 2) and left untouched, before anything is written where possible.
* The finished temporary then takes the destination's name: as a hard link where the name is
  free (which never replaces: a file planted meanwhile makes it fail, and it is checked again),
  else by ``os.replace`` over icewall's own file (a link planted there is replaced, never
  followed). On any failure the temporary is removed and the destination keeps what it held.

Recognising a file by its content means a file of the same format that icewall did not write
but that carries its header (a CSV table with the same first columns, a ``.vtu`` meshio wrote,
a gmsh ``.msh``) at a name icewall writes is taken for icewall's: README, "What icewall
promises", says which formats carry an icewall mark and which a library's signature.
"""

from __future__ import annotations

import errno
import os
import secrets
import shutil
import stat
import tempfile
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from typing import IO, Any

from icewall import __version__
from icewall.errors import ResultError

HEAD_BYTES = 1 << 16
"""How much of an existing file its Kind reads to recognise it."""
MARK = f"icewall {__version__}"
"""The mark icewall puts in the outputs whose format allows one (PNG/SVG metadata, HTML
generator, .pvd comment)."""
_NO_HARD_LINKS = {errno.EPERM, errno.EOPNOTSUPP, errno.EXDEV, errno.EMLINK, errno.ENOSYS,
                  getattr(errno, "ENOTSUP", errno.EOPNOTSUPP)}


@dataclass(frozen=True)
class Kind:
    """One kind of output and how to recognise an existing file of it as icewall's: its first
    HEAD_BYTES start with `starts` and hold every one of `marks`, and `check(path)` (if given)
    holds; `empty_ok`: an empty file counts too (one whose writer was killed at its start)."""

    what: str
    starts: bytes = b""
    marks: tuple[bytes, ...] = ()
    check: Callable[[str], bool] | None = None
    empty_ok: bool = False

    def recognises(self, path: str) -> bool:
        head = _head(path)
        if head is None:
            return False
        if not head and self.empty_ok:
            return True
        return (head.startswith(self.starts) and all(m in head for m in self.marks)
                and (self.check is None or self.check(path)))


def csv_kind(what: str, columns: tuple[str, ...] | list[str]) -> Kind:
    """A CSV table recognised by its first two header columns."""
    return Kind(what, starts=(",".join(list(columns)[:2]) + ",").encode())


def _is_deck_schema(path: str) -> bool:
    """Whether `path` is icewall's deck JSON Schema (its title; the file is small)."""
    import json

    try:
        with open(path, "rb") as handle:
            title = json.loads(handle.read(1 << 22)).get("title", "")
    except (OSError, ValueError, AttributeError, RecursionError):
        return False
    return isinstance(title, str) and title.startswith("icewall deck")


BASELINE = Kind("compare baseline", starts=b"# icewall compare baseline")
SCHEMA = Kind("deck JSON Schema", starts=b"{", check=_is_deck_schema)
REPORT = Kind("HTML report", starts=b"<!DOCTYPE html>",
              marks=(b'<meta name="generator" content="icewall',))
PNG = Kind("figure", starts=b"\x89PNG\r\n\x1a\n", marks=(b"Software\x00icewall",))
SVG = Kind("figure", starts=b"<?xml", marks=(b"<svg", b"<dc:title>icewall"))
FIGURES = {"png": PNG, "svg": SVG}
PVD = Kind("ParaView collection", starts=b"<?xml",
           marks=(b'<VTKFile type="Collection"', b"<!-- written by icewall"))
VTU = Kind("VTU file", starts=b"<?xml",
           marks=(b'<VTKFile type="UnstructuredGrid"', b"created by meshio"))
MSH = Kind("gmsh mesh file", starts=b"$MeshFormat")
XDMF = Kind("XDMF mesh file", starts=b"<Xdmf")
HDF5_MAGIC = b"\x89HDF\r\n\x1a\n"


def _head(path: str) -> bytes | None:
    """The first HEAD_BYTES of the regular file `path` (None: not one, or unreadable); opened
    without following a link and without blocking on a FIFO planted meanwhile."""
    flags = os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0)
    try:
        fd = os.open(path, flags)
    except OSError:
        return None
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            return None
        return os.read(fd, HEAD_BYTES)
    except OSError:
        return None
    finally:
        os.close(fd)


def refuse_link(path: str | os.PathLike, what: str = "output") -> None:
    """ResultError if `path` is a symbolic link (icewall writes through none)."""
    if os.path.islink(path):
        raise ResultError(f"refusing to write the {what} through the symbolic link {path} "
                          f"(-> {os.readlink(path)}); remove it or choose another output")


def check_replaceable(path: str | os.PathLike, kind: Kind) -> None:
    """ResultError unless `path` is absent, or a writable regular file `kind` recognises as
    one icewall wrote."""
    path = os.fspath(path)
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return
    except OSError as exc:
        raise ResultError(f"cannot write the {kind.what} {path}: {exc.strerror}") from None
    if stat.S_ISLNK(st.st_mode):
        refuse_link(path, kind.what)
    if not stat.S_ISREG(st.st_mode):
        what = "a directory" if stat.S_ISDIR(st.st_mode) else "not a regular file"
        raise ResultError(f"refusing to write the {kind.what} {path}: it is {what}")
    if not kind.recognises(path):
        raise ResultError(f"refusing to replace {path}: it is not a {kind.what} icewall "
                          "wrote; remove it or choose another output")
    if not os.access(path, os.W_OK):
        raise ResultError(f"refusing to replace {path}: it is read-only")


def create_temp(path: str | os.PathLike) -> tuple[int, str]:
    """(fd, name) of a new, empty temporary file beside `path` (exclusive, no link followed)."""
    path = os.fspath(path)
    directory, name = os.path.split(os.path.abspath(path))
    flags = (os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0)
             | getattr(os, "O_CLOEXEC", 0))
    while True:
        temp = os.path.join(directory, f".{name}.{secrets.token_hex(6)}.tmp")
        try:
            return os.open(temp, flags, 0o666), temp
        except FileExistsError:
            continue


def commit(temp: str | os.PathLike, path: str | os.PathLike, kind: Kind) -> None:
    """Give the finished file `temp` the name `path` (module docstring); ResultError, with
    `temp` left for the caller to remove, where `path` may not be replaced."""
    temp, path = os.fspath(temp), os.fspath(path)
    check_replaceable(path, kind)
    try:
        os.link(temp, path)
    except FileExistsError:  # ours (checked) or planted since: check again, then replace
        check_replaceable(path, kind)
        os.replace(temp, path)
        return
    except OSError as exc:
        if exc.errno not in _NO_HARD_LINKS:
            raise
        os.replace(temp, path)  # a filesystem without hard links
        return
    os.unlink(temp)


def remove_quietly(path: str) -> None:
    """Remove a temporary of ours (a link is removed, never followed); absent is fine."""
    try:
        os.remove(path)
    except FileNotFoundError:
        pass


def remove(path: str | os.PathLike, kind: Kind) -> None:
    """Delete `path` if it is a file `kind` recognises as icewall's (absent: nothing to do);
    ResultError, the file untouched, otherwise."""
    check_replaceable(path, kind)
    remove_quietly(os.fspath(path))


@contextmanager
def open_for_write(path: str | os.PathLike, kind: Kind, mode: str = "w",
                   **open_args: Any) -> Iterator[IO]:
    """A file object on a new temporary; when the block ends without error the temporary takes
    `path`'s place (commit). Refused destinations are refused before anything is written."""
    path = os.fspath(path)
    check_replaceable(path, kind)
    if "b" not in mode:
        open_args = {"encoding": "utf-8", "newline": "", **open_args}
    fd, temp = create_temp(path)
    try:
        with os.fdopen(fd, mode, **open_args) as handle:
            yield handle
        commit(temp, path, kind)
    finally:
        remove_quietly(temp)


def write_bytes(path: str | os.PathLike, data: bytes, kind: Kind) -> str:
    """Write `data` to `path` through open_for_write; returns the path."""
    with open_for_write(path, kind, "wb") as handle:
        handle.write(data)
    return os.fspath(path)


def write_text(path: str | os.PathLike, text: str, kind: Kind) -> str:
    """Write `text` (UTF-8, newlines as given) to `path` through open_for_write."""
    with open_for_write(path, kind) as handle:
        handle.write(text)
    return os.fspath(path)


@contextmanager
def library_output(path: str | os.PathLike, kind: Kind,
                   companions: Mapping[str, Kind] | None = None) -> Iterator[str]:
    """A file name for a library that writes by name: `path`'s name in a private temporary
    directory beside it. After the block that file, and each companion the library wrote
    beside it (file name -> Kind, e.g. the .h5 of an .xdmf), take their places (commit); a
    file not named there is an error. The private directory is removed in any case."""
    path = os.fspath(path)
    directory, name = os.path.split(os.path.abspath(path))
    kinds = {name: kind, **dict(companions or {})}
    for entry, entry_kind in kinds.items():
        check_replaceable(os.path.join(directory, entry), entry_kind)
    private = tempfile.mkdtemp(prefix=f".{name}.", suffix=".tmp", dir=directory)
    try:
        yield os.path.join(private, name)
        for entry in sorted(os.listdir(private)):
            if entry not in kinds:
                raise ResultError(f"writing {path} also wrote {entry}, which icewall does "
                                  "not know")
            commit(os.path.join(private, entry), os.path.join(directory, entry), kinds[entry])
    finally:
        shutil.rmtree(private, ignore_errors=True)


@contextmanager
def open_existing(path: str | os.PathLike, kind: Kind) -> Iterator[IO[bytes]]:
    """The file `path`, which must be one `kind` recognises as icewall's, opened to be changed
    in place (``r+b``) without following a link: for a small update of a finished file (an
    attribute of a result, h5py's ``fileobj`` driver)."""
    path = os.fspath(path)
    check_replaceable(path, kind)
    if not os.path.lexists(path):
        raise ResultError(f"cannot update the {kind.what} {path}: it does not exist")
    fd = os.open(path, os.O_RDWR | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0))
    with os.fdopen(fd, "r+b") as handle:
        yield handle


def own_directory(path: str | os.PathLike, what: str) -> None:
    """Create the directory `path` that icewall names itself (a .pvd's folder of .vtu), with
    its parents; a symbolic link or a file there is refused."""
    refuse_link(path, what)
    if os.path.lexists(path) and not os.path.isdir(path):
        raise ResultError(f"cannot create the {what} {path}: a file of that name exists")
    os.makedirs(path, exist_ok=True)
