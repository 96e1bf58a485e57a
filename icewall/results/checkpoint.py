"""The restart checkpoint of a running analysis: a sidecar file beside the ``.partial`` result
holding the full solver state of the last converged step (docs/hdf5_layout.md, "Resuming").

One ``.npz`` file of named arrays, replaced atomically after every step (written to a temporary
name, then renamed), so a kill at any moment leaves either the previous or the new checkpoint.
"""

from __future__ import annotations

import os
import zipfile

import numpy as np

from icewall.errors import ResultError

CHECKPOINT_SUFFIX = ".checkpoint.npz"


def checkpoint_path(result_path: str | os.PathLike) -> str:
    """Where the checkpoint of the result `result_path` (final name, not .partial) lives."""
    return os.fspath(result_path) + CHECKPOINT_SUFFIX


def write_checkpoint(path: str | os.PathLike, arrays: dict[str, np.ndarray]) -> None:
    """Replace the checkpoint at `path` by `arrays` (names may contain '/')."""
    path = os.fspath(path)
    tmp = path + ".tmp"
    with open(tmp, "wb") as fh:
        np.savez(fh, **{name: np.asarray(a) for name, a in arrays.items()})
    os.replace(tmp, path)


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
