"""The restart checkpoint of a running analysis: a sidecar file beside the ``.partial`` result
holding the full solver state of the last converged step (docs/hdf5_layout.md, "Resuming").

One ``.npz`` file of named arrays, replaced atomically after every step (written to a temporary
name, then renamed), so a kill at any moment leaves either the previous or the new checkpoint.
"""

from __future__ import annotations

import os
import zipfile

import numpy as np

from icewall import safe_write
from icewall.errors import ResultError
from icewall.results.output_safety import DiskFullError, ensure_space, is_disk_full, refuse_symlink

CHECKPOINT_SUFFIX = ".checkpoint.npz"
CHECKPOINT = safe_write.Kind("checkpoint", starts=b"PK\x03\x04")  # an .npz is a zip file


def checkpoint_path(result_path: str | os.PathLike) -> str:
    """Where the checkpoint of the result `result_path` (final name, not .partial) lives."""
    return os.fspath(result_path) + CHECKPOINT_SUFFIX


def write_checkpoint(path: str | os.PathLike, arrays: dict[str, np.ndarray]) -> None:
    """Replace the checkpoint at `path` by `arrays` (names may contain '/'). The temporary is
    created exclusively and never through a link, and replaces only a checkpoint
    (safe_write.commit); on a full disk it is removed, the previous checkpoint stays and
    DiskFullError is raised."""
    path = os.fspath(path)
    tmp = path + ".tmp"
    arrays = {name: np.asarray(a) for name, a in arrays.items()}
    refuse_symlink(path, "checkpoint")
    ensure_space(path, sum(a.nbytes for a in arrays.values()) + 64 * 1024, "the checkpoint")
    remove_checkpoint_temporary(tmp)
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0)
    try:
        with os.fdopen(os.open(tmp, flags, 0o644), "wb") as fh:
            np.savez(fh, **arrays)
        safe_write.commit(tmp, path, CHECKPOINT)
    except ResultError:
        remove_checkpoint_temporary(tmp)
        raise
    except OSError as exc:
        remove_checkpoint_temporary(tmp)
        if is_disk_full(exc):
            raise DiskFullError(f"disk full writing the checkpoint {path}: {exc.strerror}"
                                ) from None
        raise ResultError(f"cannot write the checkpoint {path}: {exc}") from None


def remove_checkpoint_temporary(tmp: str) -> None:
    """Remove a half-written checkpoint temporary (a link is removed, never followed)."""
    try:
        os.remove(tmp)
    except FileNotFoundError:
        pass


def read_checkpoint(path: str | os.PathLike) -> dict[str, np.ndarray]:
    """All arrays of a checkpoint; ResultError if it is missing or unreadable."""
    path = os.fspath(path)
    try:
        with np.load(path, allow_pickle=False) as data:
            return {name: data[name] for name in data.files}
    except (OSError, ValueError, zipfile.BadZipFile) as exc:
        raise ResultError(f"cannot read the checkpoint {path}: {exc}") from None


def remove_checkpoint(path: str | os.PathLike) -> None:
    """Delete a checkpoint and any half-written temporary of it."""
    for name in (os.fspath(path), os.fspath(path) + ".tmp"):
        try:
            os.remove(name)
        except FileNotFoundError:
            pass
