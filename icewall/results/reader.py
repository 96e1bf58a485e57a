"""Read an icewall HDF5 result file (final or ``.partial``); layout: docs/hdf5_layout.md."""

from __future__ import annotations

import json
import os
import stat
from collections.abc import Iterator
from contextlib import contextmanager

import h5py
import numpy as np

from icewall.deck.load import LoadedDeck, load_deck_text
from icewall.errors import IcewallError, ResultError
from icewall.mesh.mesh import Mesh, Region
from icewall.results.writer import CORE_COLUMNS, FORMAT, FORMAT_VERSION, PARTIAL_SUFFIX

SUPPORTED_VERSIONS = (1,)


class FieldMissing(ResultError):
    """A step's field (or the step's fields) is not stored: a reader may go on without it;
    a field that is stored but damaged (NaN, wrong shape) is a plain ResultError."""


def _py(value):
    """HDF5 attribute value -> plain Python value."""
    if isinstance(value, bytes):
        return value.decode()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    return value


def _open(path: str) -> h5py.File:
    # locking=False lets another process read the .partial of a run that is still writing; a
    # file this process itself has open for writing must be opened with the same locking flag.
    try:
        return h5py.File(path, "r", locking=False)
    except OSError as exc:
        if "locking" not in str(exc):
            raise
        return h5py.File(path, "r")


def _checked_n_steps(path: str, attrs: dict, history: h5py.Group) -> int:
    """The n_steps attribute, checked against the history columns: every core column is there
    and holds n_steps values (one more is allowed in a file whose run died between appending
    a step and counting it: status running or failed). A tampered or truncated count would
    drop or invent steps silently."""
    n = attrs.get("n_steps", 0)
    if isinstance(n, bool) or not isinstance(n, int) or n < 0:
        raise ResultError(f"{path}: corrupt result file, n_steps = {n!r}")
    if missing := [name for name in CORE_COLUMNS if name not in history]:
        raise ResultError(f"{path}: corrupt result file, history/{', history/'.join(missing)} "
                          "missing")
    slack = 1 if attrs.get("status") in ("running", "failed") else 0
    for name, ds in history.items():
        if not isinstance(ds, h5py.Dataset) or ds.ndim != 1:
            raise ResultError(f"{path}: corrupt result file, history/{name} is not a column")
        if not n <= len(ds) <= n + slack:
            raise ResultError(f"{path}: corrupt result file, n_steps = {n} but history/{name} "
                              f"holds {len(ds)} values")
    return n


def non_finite_error(path: str, dataset: str, values: np.ndarray,
                     steps: np.ndarray | None = None, step: int | None = None) -> ResultError:
    """The error naming the first non-finite value of `values` (dataset, step): icewall never
    writes one (results/step_record.py), so the file is damaged, and a NaN is never a figure."""
    flat = np.asarray(values).reshape(-1) if steps is None else np.asarray(values)
    i = int(np.flatnonzero(~np.isfinite(flat))[0])
    if steps is not None:
        step = int(steps[i]) if i < len(steps) else None
    at = f" at step {step}" if step is not None else ""
    return ResultError(f"{path}: damaged result file: {dataset} holds {flat[i]}{at} (icewall "
                       "writes no NaN or infinity)")


STATUSES = ("completed", "stopped", "failed", "running")
MAX_LABEL = 200  # the deck's longest specimen name (deck.validate.MAX_NAME)


def _check_labels(path: str, attrs: dict) -> None:
    """ResultError on a status icewall does not write, or a specimen name no deck gives (too
    long, control characters): what every reader prints or draws as a title."""
    if attrs.get("status", "running") not in STATUSES:
        raise ResultError(f"{path}: damaged result file: status "
                          f"{' '.join(str(attrs.get('status')).split())[:40]!r} is none of "
                          f"{', '.join(STATUSES)}")
    name = attrs.get("specimen", "")
    if not isinstance(name, str) or len(name) > MAX_LABEL or any(
            ord(c) < 32 or ord(c) == 127 for c in name):
        raise ResultError(f"{path}: damaged result file: attribute specimen is not a name "
                          f"(at most {MAX_LABEL} characters, no control character)")


def _check_finite(path: str, attrs: dict, history: dict[str, np.ndarray]) -> None:
    """ResultError on a non-finite number where icewall writes none: a float attribute, a
    core history column, an extra column beyond its NaN fill (an infinity)."""
    for key, value in attrs.items():
        if isinstance(value, float) and not np.isfinite(value):
            raise ResultError(f"{path}: damaged result file: attribute {key} = {value} (icewall "
                              "writes no NaN or infinity)")
    steps = history.get("step")
    for name, column in history.items():
        column = np.asarray(column)
        if column.dtype.kind != "f":
            continue
        bad = ~np.isfinite(column) if name in CORE_COLUMNS else np.isinf(column)
        if bad.any():  # (an extra column's NaN is its fill where a step gave no value)
            raise non_finite_error(path, f"history/{name}", np.where(bad, column, 0.0),
                                   steps)


def _checked_mesh(path: str, mesh: Mesh) -> Mesh:
    """`mesh` if its coordinates are finite and its node numbers name its nodes."""
    points = np.asarray(mesh.points)
    if points.ndim != 2 or points.shape[1] != 2 or points.dtype.kind != "f":
        raise ResultError(f"{path}: damaged result file: mesh/points is not (n, 2) numbers")
    if not np.isfinite(points).all():
        raise non_finite_error(path, "mesh/points", points)
    n = len(points)
    for name, ids in [("cells", mesh.cells), ("interface/pairs", mesh.interface_pairs),
                      *((f"node_sets/{k}", v) for k, v in mesh.node_sets.items()),
                      *((f"edge_sets/{k}", v) for k, v in mesh.edge_sets.items())]:
        ids = np.asarray(ids)
        if ids.size and (ids.dtype.kind not in "iu" or ids.min() < 0 or ids.max() >= n):
            raise ResultError(f"{path}: damaged result file: mesh/{name} names nodes outside "
                              f"0..{n - 1}")
    return mesh


class ResultFile:
    """An open result file. Use as a context manager or call close()."""

    def __init__(self, path: str | os.PathLike) -> None:
        self.path = os.fspath(path)
        if not os.path.exists(self.path):
            hint = ""
            if os.path.exists(self.path + PARTIAL_SUFFIX):
                hint = (f" (an unfinished run left {self.path + PARTIAL_SUFFIX}; open that, or "
                        "go on with it: icewall run DECK --resume)")
            raise ResultError(f"result file {self.path} not found{hint}")
        if not stat.S_ISREG(os.stat(self.path).st_mode):  # a FIFO would block HDF5 forever
            raise ResultError(f"{self.path}: not a result file (not a regular file)")
        try:
            self._f = _open(self.path)
        except OSError as exc:
            raise ResultError(f"{self.path}: not an HDF5 file or unreadable ({exc})") from exc
        try:
            self.attrs = {k: _py(v) for k, v in self._f.attrs.items()}
            if self.attrs.get("format") != FORMAT:
                raise ResultError(f"{self.path}: not an icewall result file "
                                  f"(format attribute {self.attrs.get('format')!r})")
            version = self.attrs.get("format_version")
            if version not in SUPPORTED_VERSIONS:
                raise ResultError(f"{self.path}: unsupported format_version {version!r} "
                                  f"(this icewall reads {FORMAT_VERSION})")
            for name in ("deck", "mesh", "history", "steps"):
                if name not in self._f:
                    raise ResultError(f"{self.path}: corrupt result file, /{name} missing")
            self._n = _checked_n_steps(self.path, self.attrs, self._f["history"])
            self.history = {k: ds[: self._n] for k, ds in self._f["history"].items()}
            _check_finite(self.path, self.attrs, self.history)
            _check_labels(self.path, self.attrs)
            last = int(self.history["step"][-1]) if self._n else 0
            self.steps = sorted(s for s in (int(k) for k in self._f["steps"]) if s <= last)
        except (KeyError, ValueError, TypeError, IndexError, AttributeError) as exc:
            self._f.close()
            raise _damaged(self.path, exc) from None
        except BaseException:
            self._f.close()
            raise
        self._mesh: Mesh | None = None
        self._stored: tuple[LoadedDeck | None, str] | None = None

    @property
    def overrides(self) -> list[str]:
        """The run's deck overrides (attribute deck_overrides, else a sweep's sweep_overrides:
        a JSON list of strings); ResultError if the attribute is damaged."""
        raw = self.attrs.get("deck_overrides") or self.attrs.get("sweep_overrides") or "[]"
        try:
            value = json.loads(raw) if isinstance(raw, str) else None
        except (ValueError, RecursionError):
            value = None
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise ResultError(f"{self.path}: damaged result file: attribute deck_overrides is "
                              f"not a JSON list of strings ({' '.join(str(raw).split())[:60]})")
        return value

    def stored_deck(self) -> LoadedDeck | None:
        """The run's deck, rebuilt from the stored text and overrides; None where it no longer
        loads (stored_deck_problem says why). The rule of every reader: such a file is read
        for what its history and fields hold, and a figure that needs the deck (f_y, the
        tolerances, the jack load, the reference values, the target) is unknown."""
        if self._stored is None:
            try:
                loaded = load_deck_text(self.deck_text, f"the stored deck of {self.path}",
                                        self.overrides)
                self._stored = (loaded, "")
            except (IcewallError, KeyError, ValueError, TypeError, AttributeError,
                    RecursionError) as exc:
                self._stored = (None, " ".join(str(exc).split())[:160])
        return self._stored[0]

    @property
    def stored_deck_problem(self) -> str:
        """Why stored_deck() is None ("" where the deck loads)."""
        self.stored_deck()
        return self._stored[1] if self._stored else ""

    def missing_field_steps(self) -> list[int]:
        """History steps whose Gauss/nodal fields the stored deck says were written
        (outputs.fields not empty, every outputs.every-th step) but the file lacks: a damaged
        file (an empty list where the deck cannot be read)."""
        loaded = self.stored_deck()
        if loaded is None:
            return []
        outputs = loaded.deck.outputs
        if not outputs.fields:
            return []
        stored = set(self.steps)
        return [int(s) for s in self.history["step"]
                if int(s) % outputs.every == 0 and int(s) not in stored]

    @property
    def status(self) -> str:
        """"completed", "stopped", "failed", or "running" (still running or killed)."""
        return str(self.attrs.get("status", ""))

    @property
    def deck_text(self) -> str:
        """The stored deck text; ResultError where /deck is not one string."""
        try:
            text = self._f["deck"].asstr()[()]
        except (KeyError, TypeError, ValueError, OSError) as exc:
            raise _damaged(self.path, exc) from None
        if not isinstance(text, str):
            raise ResultError(f"{self.path}: damaged result file: /deck is not a text")
        return text

    @property
    def mesh(self) -> Mesh:
        """The stored mesh; ResultError where it is damaged (a group missing, a coordinate not
        finite, a node number out of range)."""
        if self._mesh is None:
            try:
                self._mesh = _checked_mesh(self.path, self._read_mesh())
            except (KeyError, ValueError, TypeError, IndexError, AttributeError) as exc:
                raise _damaged(self.path, exc) from None
        return self._mesh

    def _read_mesh(self) -> Mesh:
        g = self._f["mesh"]
        r = g["regions"]
        names, kinds = r["name"].asstr()[:], r["kind"].asstr()[:]
        regions = tuple(Region(str(n), str(k), int(t))
                        for n, k, t in zip(names, kinds, r["tag"][:], strict=True))
        return Mesh(
            points=g["points"][:], cells=g["cells"][:],
            cell_type=_py(g["cells"].attrs["cell_type"]), cell_region=g["cell_region"][:],
            regions=regions,
            node_sets={k: ds[:] for k, ds in g["node_sets"].items()},
            edge_sets={k: ds[:] for k, ds in g["edge_sets"].items()},
            interface_pairs=g["interface/pairs"][:],
            interface_normals=g["interface/normals"][:],
            interface_corner=g["interface/corner"][:].astype(bool),
        )

    def _step_group(self, step: int) -> h5py.Group:
        if step not in self.steps:
            raise FieldMissing(f"{self.path}: no stored fields at step {step} "
                              f"(stored steps: {_ranges(self.steps)})")
        return self._f["steps"][f"{step:05d}"]

    def _finite(self, step: int, name: str, values: np.ndarray) -> np.ndarray:
        if values.dtype.kind == "f" and not np.isfinite(values).all():
            raise non_finite_error(self.path, f"steps/{step:05d}/{name}", values, step=step)
        return values

    def displacement(self, step: int) -> np.ndarray:
        """Nodal displacements (n_nodes, 2) in mm at `step`."""
        g = self._step_group(step)
        if "displacement" not in g:
            raise FieldMissing(f"{self.path}: no displacement stored at step {step}")
        return self._finite(step, "displacement", g["displacement"][:])

    def gauss_fields(self, step: int) -> list[str]:
        """Names of the Gauss-point fields stored at `step`."""
        g = self._step_group(step)
        return sorted(g["gauss"]) if "gauss" in g else []

    def gauss(self, step: int, field: str) -> np.ndarray:
        """Gauss-point field (n_el, n_qp, k) at `step`."""
        g = self._step_group(step)
        if field not in self.gauss_fields(step):
            raise FieldMissing(f"{self.path}: no Gauss field {field!r} at step {step} "
                              f"(stored: {', '.join(self.gauss_fields(step)) or 'none'})")
        return self._finite(step, f"gauss/{field}", g["gauss"][field][:])

    def array(self, step: int, name: str) -> np.ndarray:
        """Another per-step field, e.g. "interface/state", at `step`."""
        g = self._step_group(step)
        if name not in g:
            raise FieldMissing(f"{self.path}: no array {name!r} at step {step}")
        return self._finite(step, name, g[name][:])

    def forensics(self, step: int) -> dict[str, np.ndarray]:
        """Per-iteration convergence forensics of `step` (empty if none were stored)."""
        g = self._f.get(f"forensics/{step:05d}")
        return {} if g is None else {name: ds[:] for name, ds in g.items()}

    def close(self) -> None:
        self._f.close()

    def __enter__(self) -> ResultFile:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _ranges(steps: list[int]) -> str:
    if not steps:
        return "none"
    return f"{steps[0]}..{steps[-1]} ({len(steps)} steps)" if len(steps) > 3 else str(steps)


def open_result(path: str | os.PathLike) -> ResultFile:
    """Open a result file (final path or ``.partial``); ResultError if it is not one."""
    return ResultFile(path)


def _damaged(path: str | os.PathLike, exc: BaseException) -> ResultError:
    text = " ".join(str(exc).split())[:160]
    return ResultError(f"{os.fspath(path)}: damaged result file ({type(exc).__name__}: "
                       f"{text})")


@contextmanager
def damaged_result(path: str | os.PathLike) -> Iterator[None]:
    """Turn what a damaged result file makes the readers raise (a group or dataset missing,
    an array of the wrong shape) into one ResultError naming the file (exit 2), instead of
    an internal error. (A stored deck that no longer loads is no error: stored_deck.)"""
    try:
        yield
    except (KeyError, ValueError, TypeError, IndexError, AttributeError) as exc:
        raise _damaged(path, exc) from None
