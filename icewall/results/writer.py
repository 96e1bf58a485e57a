"""Write one analysis to an HDF5 result file, step by step (layout: docs/hdf5_layout.md).

The file is written as ``<path>.partial`` and flushed after every step, so a killed run leaves a
readable file with every finished step; ``finish()`` renames it to ``<path>``. Beside it,
``write_checkpoint`` keeps the solver state of the last step (``<path>.checkpoint.npz``) until the
run finishes, and ``reopen`` goes on writing an interrupted run (``icewall run --resume``).
A writer holds the output's lock (``<path>.lock``, results/output_safety.py) from before the
``.partial`` is created (exclusively, never through a link) until it is closed, and checks the
free space before every step: a full disk stops it with DiskFullError, every converged step kept.
"""

from __future__ import annotations

import atexit
import math
import os
import sys
import time
from datetime import datetime

import h5py
import numpy as np

import icewall
from icewall import safe_write
from icewall.errors import ResultError
from icewall.mesh.mesh import Mesh
from icewall.results.checkpoint import checkpoint_path, remove_checkpoint, write_checkpoint
from icewall.results.output_safety import (
    DiskFullError,
    OutputLock,
    ensure_space,
    is_disk_full,
    refuse_symlink,
)
from icewall.results.step_record import (
    CORE_COLUMNS,
    StepRecord,
    check_name,
    history_value,
    validate_step,
)

FORMAT, FORMAT_VERSION = "icewall-result", 1
PARTIAL_SUFFIX = ".partial"
INT_FILL = -1  # history value of an int column at steps where it was not given
FLOAT_FILL = math.nan  # same for a float column (the only NaN ever written)
RESERVED_ATTRS = ("format", "format_version", "software_version", "units", "length_unit",
                  "force_unit", "stress_unit", "created", "status", "stop_reason", "run_time_s",
                  "n_steps", "resumed_at")
GAUSS_UNITS = {"stress": "MPa", "strain": "1"}
STEP_COMPRESSION: dict = {}  # e.g. {"compression": "lzf"}; see docs/hdf5_layout.md (none chosen)


def _is_result(path: str) -> bool:
    """Whether `path` is an HDF5 file with icewall's format attribute."""
    try:
        with h5py.File(path, "r", locking=False) as f:
            return f.attrs.get("format") in (FORMAT, FORMAT.encode())
    except Exception:  # noqa: BLE001 - unreadable: not recognised, so not replaced
        return False


RESULT = safe_write.Kind("result file", starts=safe_write.HDF5_MAGIC, check=_is_result)
"""A final result (NAME.h5) is replaced only by a run's own file over an icewall result."""
PARTIAL = safe_write.Kind("partial result", starts=safe_write.HDF5_MAGIC, empty_ok=True)
"""A dead run's NAME.h5.partial (an HDF5 file, or empty if it died creating it) is removed
by the next run; anything else there is refused."""


def _write_mesh(g: h5py.Group, mesh: Mesh) -> None:
    g.create_dataset("points", data=np.asarray(mesh.points, dtype=float)).attrs["unit"] = "mm"
    g.create_dataset("cells", data=np.asarray(mesh.cells, dtype=np.int64))
    g["cells"].attrs["cell_type"] = mesh.cell_type
    g.create_dataset("cell_region", data=np.asarray(mesh.cell_region, dtype=np.int64))
    r = g.create_group("regions")
    r.create_dataset("name", data=[x.name for x in mesh.regions], dtype=h5py.string_dtype())
    r.create_dataset("kind", data=[x.kind for x in mesh.regions], dtype=h5py.string_dtype())
    r.create_dataset("tag", data=np.array([x.tag for x in mesh.regions], dtype=np.int64))
    for grp, sets in (("node_sets", mesh.node_sets), ("edge_sets", mesh.edge_sets)):
        sg = g.create_group(grp)
        for name, ids in sets.items():
            check_name(name, grp[:-1].replace("_", " "))
            sg.create_dataset(name, data=np.asarray(ids, dtype=np.int64))
    i = g.create_group("interface")
    i.create_dataset("pairs", data=np.asarray(mesh.interface_pairs, dtype=np.int64).reshape(-1, 2))
    i.create_dataset("normals", data=np.asarray(mesh.interface_normals, float).reshape(-1, 2))
    i.create_dataset("corner", data=np.asarray(mesh.interface_corner, dtype=bool))


def check_writable(path: str | os.PathLike) -> None:
    """Raise ResultError unless a result file can be created at `path`."""
    path = os.fspath(path)
    directory = os.path.dirname(os.path.abspath(path))
    why = (f"directory {directory} does not exist" if not os.path.isdir(directory) else
           "it is a directory" if os.path.isdir(path) else
           f"directory {directory} is not writable"
           if not os.access(directory, os.W_OK | os.X_OK) else "")
    if why:
        raise ResultError(f"cannot write results to {path}: {why}")


def _exit_without_hdf5_shutdown() -> None:
    """atexit hook once an HDF5 write failed: HDF5 crashes (SIGSEGV) closing that file at
    exit, so end the process here with exit code 1, after flushing the output streams."""
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    os._exit(DiskFullError.exit_code)


def refuse_output_links(path: str) -> None:
    """ResultError if the final, ``.partial`` or checkpoint path of `path` is a symbolic link,
    or the final path a file that is not an icewall result (safe_write)."""
    safe_write.check_replaceable(path, RESULT)
    refuse_symlink(path + PARTIAL_SUFFIX, "partial result")
    refuse_symlink(checkpoint_path(path), "checkpoint")


def _take_lock(path: str, lock: OutputLock | None) -> tuple[OutputLock, bool]:
    """The caller's lock of `path` (held), or a new one taken here (owned by the writer)."""
    if lock is not None:
        if not lock.held or lock.result_path != path:
            raise ValueError(f"the lock given is not a held lock of {path}")
        return lock, False
    return OutputLock(path).acquire(), True


def _mesh_bytes(mesh: Mesh) -> int:
    arrays = (mesh.points, mesh.cells, mesh.cell_region, mesh.interface_pairs)
    return sum(np.asarray(a).nbytes for a in arrays) + 256 * 1024


class ResultWriter:
    """Context manager writing one analysis; see the module docstring and docs/hdf5_layout.md."""

    def __init__(self, path: str | os.PathLike, *, deck_text: str, deck_path: str, mesh: Mesh,
                 attrs: dict[str, str | float | int] | None = None,
                 lock: OutputLock | None = None) -> None:
        self.path = os.fspath(path)
        self.partial_path = self.path + PARTIAL_SUFFIX
        self._broken = False
        attrs = dict(attrs or {})
        for key, val in attrs.items():
            check_name(key, "attribute")
            if key in RESERVED_ATTRS:
                raise ValueError(f"attribute {key!r} is reserved")
            if not isinstance(val, str):
                attrs[key] = history_value(f"attrs[{key!r}]", val)
        check_writable(self.path)
        self._lock, self._own_lock = _take_lock(self.path, lock)
        try:
            self._f = self._create_partial(_mesh_bytes(mesh) + len(deck_text.encode()))
        except BaseException:
            self._release()
            raise
        self._t0, self._n, self._last_step, self._done = time.perf_counter(), 0, 0, False
        self._n_nodes, self._n_cells = mesh.n_nodes, mesh.n_cells
        self._columns: dict[str, bool] = {}  # extra history column -> is integer
        try:
            self._init_file(deck_text, deck_path, mesh, attrs)
        except BaseException as exc:
            self._f.close()
            os.remove(self.partial_path)
            self._release()
            if isinstance(exc, OSError | RuntimeError) and is_disk_full(exc):
                raise DiskFullError(f"disk full creating {self.partial_path}") from None
            raise
        remove_checkpoint(checkpoint_path(self.path))  # a stale one of an earlier run

    def _create_partial(self, size: int) -> h5py.File:
        """Create the ``.partial`` exclusively (the lock is held: a leftover one is a dead
        run's and is removed first; a link is refused, never followed)."""
        refuse_output_links(self.path)
        ensure_space(self.partial_path, size, "the new result file")
        safe_write.remove(self.partial_path, PARTIAL)
        try:
            return h5py.File(self.partial_path, "x")
        except OSError as exc:
            if is_disk_full(exc):
                raise DiskFullError(f"disk full creating {self.partial_path}") from None
            raise ResultError(f"cannot create result file {self.partial_path}: {exc}") from None

    @classmethod
    def reopen(cls, path: str | os.PathLike, n_steps: int,
               lock: OutputLock | None = None) -> ResultWriter:
        """Go on writing the ``.partial`` of an interrupted run after its first `n_steps`
        history entries; whatever it holds beyond them (a step cut short) is dropped."""
        self = cls.__new__(cls)
        self.path = os.fspath(path)
        self.partial_path = self.path + PARTIAL_SUFFIX
        self._broken = False
        check_writable(self.path)
        self._lock, self._own_lock = _take_lock(self.path, lock)
        try:
            refuse_output_links(self.path)
            if os.path.exists(self.partial_path) and os.lstat(self.partial_path).st_nlink > 1:
                raise ResultError(f"refusing to resume {self.partial_path}: it is a hard link "
                                  f"to another file")
            self._f = h5py.File(self.partial_path, "a")
        except OSError as exc:
            self._release()
            raise ResultError(f"cannot reopen {self.partial_path}: {exc}") from None
        except BaseException:
            self._release()
            raise
        try:
            self._truncate(n_steps)
        except BaseException:
            self._f.close()
            self._release()
            raise
        return self

    def _release(self) -> None:
        if self._own_lock:
            self._lock.release()

    def _truncate(self, n_steps: int) -> None:
        f = self._f
        hist = f["history"]
        if not 0 <= n_steps <= int(f.attrs["n_steps"]):
            raise ResultError(f"{self.partial_path}: cannot keep {n_steps} of "
                              f"{int(f.attrs['n_steps'])} steps")
        last = int(hist["step"][n_steps - 1]) if n_steps else 0
        self._columns = {}
        for name in list(hist):
            if name not in CORE_COLUMNS and int(hist[name].attrs.get("first_step", 0)) > last:
                del hist[name]  # a column that appeared in a dropped step
                continue
            hist[name].resize((n_steps,))
            if name not in CORE_COLUMNS:
                self._columns[name] = hist[name].dtype.kind == "i"
        for group in ("steps", "forensics"):
            for key in [k for k in f.get(group, {}) if int(k) > last]:
                del f[group][key]
        resumed = [int(x) for x in np.atleast_1d(f.attrs.get("resumed_at", []))]
        f.attrs.update({"status": "running", "stop_reason": "", "n_steps": n_steps,
                        "resumed_at": np.array(resumed + [last], dtype=np.int64)})
        self._t0 = time.perf_counter() - float(f.attrs.get("run_time_s", 0.0))
        self._n, self._last_step, self._done = n_steps, last, False
        self._n_nodes, self._n_cells = f["mesh/points"].shape[0], f["mesh/cells"].shape[0]
        f.flush()

    def _init_file(self, deck_text: str, deck_path: str, mesh: Mesh, attrs: dict) -> None:
        f = self._f
        f.attrs.update({
            "format": FORMAT, "format_version": FORMAT_VERSION,
            "software_version": icewall.__version__, "units": "N, mm, MPa",
            "length_unit": "mm", "force_unit": "N", "stress_unit": "MPa",
            "created": datetime.now().astimezone().isoformat(timespec="seconds"),
            "status": "running", "stop_reason": "", "run_time_s": 0.0, "n_steps": 0,
        })
        f.attrs.update(attrs)
        f.create_dataset("deck", data=deck_text, dtype=h5py.string_dtype())
        f["deck"].attrs["path"] = str(deck_path)
        _write_mesh(f.create_group("mesh"), mesh)
        hist = f.create_group("history")
        for name, (dtype, unit, desc) in CORE_COLUMNS.items():
            ds = hist.create_dataset(name, shape=(0,), maxshape=(None,), dtype=dtype, chunks=(512,))
            ds.attrs["description"] = desc
            if name == "load" and isinstance(attrs.get("load_unit"), str):
                unit = attrs["load_unit"]
            if unit:
                ds.attrs["unit"] = unit
        f.create_group("steps")
        f.flush()

    # -- writing -----------------------------------------------------------------------------
    def write_step(self, record: StepRecord) -> None:
        """Validate the whole record (ValueError names the bad field), then append and flush."""
        if self._done:
            raise RuntimeError("write_step() after finish()")
        if self._broken:
            raise ResultError(f"{self.partial_path}: an earlier write failed")
        core, arrays, extra, forensics = validate_step(record, self._last_step, self._n_nodes,
                                                       self._n_cells, self._columns)
        need = sum(a.nbytes for a in (*arrays.values(), *forensics.values()))
        need += 4096 * (len(arrays) + len(forensics) + len(extra) + len(CORE_COLUMNS))
        try:
            ensure_space(self.partial_path, need, f"step {core['step']}")
        except DiskFullError as exc:
            raise DiskFullError(f"{exc}; the {self._n} converged steps are kept in "
                                f"{self.partial_path}; free space, then run again with "
                                f"--resume") from None
        kept = self._n
        try:
            self._append(core, arrays, extra, forensics)
        except (OSError, RuntimeError) as exc:
            self._broken = True  # HDF5 cannot write this file any more
            atexit.register(_exit_without_hdf5_shutdown)
            if is_disk_full(exc):
                raise DiskFullError(f"disk full writing step {core['step']} to "
                                    f"{self.partial_path} ({kept} steps written before it; "
                                    f"the file may be damaged)") from None
            raise ResultError(f"cannot write step {core['step']} to {self.partial_path}: "
                              f"{exc}") from None

    def _append(self, core: dict, arrays: dict, extra: dict, forensics: dict) -> None:
        f, n = self._f, self._n
        if forensics:
            g = f.require_group("forensics").create_group(f"{core['step']:05d}")
            for name, a in forensics.items():
                g.create_dataset(name, data=a)
        if arrays:
            g = f["steps"].create_group(f"{core['step']:05d}")
            g.attrs.update({k: core[k] for k in ("step", "control_displacement", "load",
                                                 "load_factor")})
            for name, a in arrays.items():
                ds = g.create_dataset(name, data=a, **(STEP_COMPRESSION if a.size > 4096 else {}))
                unit = "mm" if name == "displacement" else GAUSS_UNITS.get(name[6:])
                if unit:
                    ds.attrs["unit"] = unit
        hist = f["history"]
        for name, val in extra.items():
            if name not in self._columns:
                is_int = isinstance(val, int)
                ds = hist.create_dataset(name, shape=(n,), maxshape=(None,), chunks=(512,),
                                         dtype="i8" if is_int else "f8")
                ds[:] = INT_FILL if is_int else FLOAT_FILL
                ds.attrs.update({"fill_value": INT_FILL if is_int else FLOAT_FILL,
                                 "first_step": core["step"]})
                self._columns[name] = is_int
        for name in list(CORE_COLUMNS) + list(self._columns):
            if name in core:
                val = core[name]
            else:
                val = extra.get(name, INT_FILL if self._columns[name] else FLOAT_FILL)
            ds = hist[name]
            ds.resize((n + 1,))
            ds[n] = val
        self._n, self._last_step = n + 1, core["step"]
        f.attrs["n_steps"] = self._n  # readers trust history only up to n_steps
        f.attrs["run_time_s"] = time.perf_counter() - self._t0
        f.flush()

    def write_checkpoint(self, arrays: dict[str, np.ndarray]) -> None:
        """Replace the restart checkpoint (``<path>.checkpoint.npz``) by `arrays`, the solver
        state after the last written step (recorded with it as ``step``)."""
        write_checkpoint(checkpoint_path(self.path), {**arrays, "step": self._last_step})

    # -- closing -----------------------------------------------------------------------------
    def finish(self, status: str = "completed", reason: str = "") -> str:
        """Record the outcome, close, and return the file's path.

        "completed"/"stopped" files are renamed to the final path; "failed" stays ``.partial``.
        """
        if status not in ("completed", "stopped", "failed"):
            raise ValueError(f"status must be completed, stopped or failed, not {status!r}")
        if self._done:
            raise RuntimeError("finish() called twice")
        self._done = True
        try:
            self._close(status, reason)
            if status == "failed" or self._broken:  # keeps the checkpoint: `--resume`
                return self.partial_path
            remove_checkpoint(checkpoint_path(self.path))
            try:  # replaces an icewall result or a link, never writes through one
                safe_write.commit(self.partial_path, self.path, RESULT)
            except ResultError as exc:
                raise ResultError(f"{exc}; the finished result is kept in "
                                  f"{self.partial_path}") from None
            return self.path
        finally:
            self._release()

    def _close(self, status: str, reason: str) -> None:
        if self._broken:  # closing would crash HDF5; the file keeps its last flushed state
            return
        try:
            self._f.attrs.update({"status": status, "stop_reason": str(reason),
                                  "run_time_s": time.perf_counter() - self._t0,
                                  "n_steps": self._n})
        finally:
            self._f.close()

    def __enter__(self) -> ResultWriter:
        return self

    def __exit__(self, exc_type, exc, tb) -> bool:
        if self._done:
            return False
        if exc is None:
            self.finish("completed")
        else:
            self.finish("failed", str(exc) or exc_type.__name__)
        return False
