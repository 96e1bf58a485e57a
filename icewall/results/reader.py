"""Read an icewall HDF5 result file (final or ``.partial``); layout: docs/hdf5_layout.md."""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager

import h5py
import numpy as np

from icewall.deck.load import load_deck_text
from icewall.errors import IcewallError, ResultError
from icewall.mesh.mesh import Mesh, Region
from icewall.results.writer import CORE_COLUMNS, FORMAT, FORMAT_VERSION, PARTIAL_SUFFIX

SUPPORTED_VERSIONS = (1,)


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
            last = int(self.history["step"][-1]) if self._n else 0
            self.steps = sorted(s for s in (int(k) for k in self._f["steps"]) if s <= last)
        except BaseException:
            self._f.close()
            raise
        self._mesh: Mesh | None = None

    def missing_field_steps(self) -> list[int]:
        """History steps whose Gauss/nodal fields the stored deck says were written
        (outputs.fields not empty, every outputs.every-th step) but the file lacks: a damaged
        file (an empty list where the deck cannot be read)."""
        try:
            outputs = load_deck_text(self.deck_text, self.path).deck.outputs
        except (IcewallError, AttributeError, TypeError, ValueError):
            return []
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
        return self._f["deck"].asstr()[()]

    @property
    def mesh(self) -> Mesh:
        if self._mesh is None:
            g = self._f["mesh"]
            r = g["regions"]
            names, kinds = r["name"].asstr()[:], r["kind"].asstr()[:]
            regions = tuple(Region(str(n), str(k), int(t))
                            for n, k, t in zip(names, kinds, r["tag"][:], strict=True))
            self._mesh = Mesh(
                points=g["points"][:], cells=g["cells"][:],
                cell_type=_py(g["cells"].attrs["cell_type"]), cell_region=g["cell_region"][:],
                regions=regions,
                node_sets={k: ds[:] for k, ds in g["node_sets"].items()},
                edge_sets={k: ds[:] for k, ds in g["edge_sets"].items()},
                interface_pairs=g["interface/pairs"][:],
                interface_normals=g["interface/normals"][:],
                interface_corner=g["interface/corner"][:].astype(bool),
            )
        return self._mesh

    def _step_group(self, step: int) -> h5py.Group:
        if step not in self.steps:
            raise ResultError(f"{self.path}: no stored fields at step {step} "
                              f"(stored steps: {_ranges(self.steps)})")
        return self._f["steps"][f"{step:05d}"]

    def displacement(self, step: int) -> np.ndarray:
        """Nodal displacements (n_nodes, 2) in mm at `step`."""
        g = self._step_group(step)
        if "displacement" not in g:
            raise ResultError(f"{self.path}: no displacement stored at step {step}")
        return g["displacement"][:]

    def gauss_fields(self, step: int) -> list[str]:
        """Names of the Gauss-point fields stored at `step`."""
        g = self._step_group(step)
        return sorted(g["gauss"]) if "gauss" in g else []

    def gauss(self, step: int, field: str) -> np.ndarray:
        """Gauss-point field (n_el, n_qp, k) at `step`."""
        g = self._step_group(step)
        if field not in self.gauss_fields(step):
            raise ResultError(f"{self.path}: no Gauss field {field!r} at step {step} "
                              f"(stored: {', '.join(self.gauss_fields(step)) or 'none'})")
        return g["gauss"][field][:]

    def array(self, step: int, name: str) -> np.ndarray:
        """Another per-step field, e.g. "interface/state", at `step`."""
        g = self._step_group(step)
        if name not in g:
            raise ResultError(f"{self.path}: no array {name!r} at step {step}")
        return g[name][:]

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


@contextmanager
def damaged_result(path: str | os.PathLike) -> Iterator[None]:
    """Turn what a damaged result file makes the readers raise (a group or dataset missing,
    an array of the wrong shape, a stored deck that no longer parses) into one ResultError
    naming the file (exit 2), instead of an internal error."""
    try:
        yield
    except (KeyError, ValueError, TypeError, IndexError) as exc:
        text = " ".join(str(exc).split())[:160]
        raise ResultError(f"{os.fspath(path)}: damaged result file ({type(exc).__name__}: "
                          f"{text})") from None
