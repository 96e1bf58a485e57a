"""One step of a result file as the solver hands it to the writer, and its validation: names,
shapes and finite values checked before anything is written (results/writer.py)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from numbers import Integral, Real

import numpy as np

# Core history columns: name -> (dtype, unit or None, description).
CORE_COLUMNS = {
    "step": ("i8", None, "step number, 1-based"),
    "control_displacement": ("f8", "mm", "control displacement, positive in load direction"),
    "load": ("f8", None, "load in the deck's load measure (root attrs load_measure, load_unit)"),
    "load_factor": ("f8", None, "load factor"),
    "iterations": ("i8", None, "equilibrium iterations of the step"),
    "displacement_norm": ("f8", None, "final displacement convergence norm"),
    "load_norm": ("f8", None, "final out-of-balance load norm"),
    "wall_time": ("f8", "s", "wall-clock time since the start of the analysis"),
}


@dataclass
class StepRecord:
    """One converged (or final) load step."""

    step: int
    control_displacement: float
    load: float
    load_factor: float
    iterations: int
    displacement_norm: float
    load_norm: float
    wall_time: float
    displacement: np.ndarray | None = None  # (n_nodes, 2) mm, or None if not stored
    gauss: dict[str, np.ndarray] = field(default_factory=dict)  # name -> (n_el, n_qp, k)
    scalars: dict[str, float | int] = field(default_factory=dict)  # extra history columns
    # other per-step fields, e.g. "interface/state" (n_pairs,): stored with the fields
    arrays: dict[str, np.ndarray] = field(default_factory=dict)
    # per-iteration convergence forensics (1-D), stored for every step under /forensics
    forensics: dict[str, np.ndarray] = field(default_factory=dict)


def check_name(name: str, what: str) -> None:
    if not isinstance(name, str) or not name or "/" in name or name in (".", ".."):
        raise ValueError(f"invalid {what} name {name!r} (non-empty, no '/')")


def finite_array(name: str, arr, shape: tuple | None = None) -> np.ndarray:
    a = np.asarray(arr)
    if a.dtype.kind not in "biuf":
        raise ValueError(f"{name}: unsupported dtype {a.dtype}")
    if a.dtype.kind == "f" and not np.isfinite(a).all():
        raise ValueError(f"{name}: contains NaN or inf")
    if shape is not None and (a.ndim != len(shape) or any(
            s is not None and s != n for s, n in zip(shape, a.shape, strict=True))):
        want = tuple("*" if s is None else s for s in shape)
        raise ValueError(f"{name}: shape {a.shape}, expected {want}")
    return a


def history_value(name: str, value, integer: bool | None = None) -> int | float:
    """Validate one history value; integer=True/False forces the column's kind."""
    if isinstance(value, bool | np.bool_):
        value = int(value)
    if isinstance(value, Integral) and integer is not False:
        return int(value)
    if not isinstance(value, Real):
        raise ValueError(f"{name}: not a real number: {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"{name}: non-finite value {value}")
    if integer:
        if not value.is_integer():
            raise ValueError(f"{name}: integer column got {value}")
        return int(value)
    return value


def validate_step(rec: StepRecord, last_step: int, n_nodes: int, n_cells: int,
                  columns: dict[str, bool]) -> tuple[dict, dict, dict, dict]:
    """(core history values, per-step arrays, extra history values, forensics) of `rec`, each
    checked: the step after `last_step`, displacement (n_nodes, 2), Gauss fields (n_cells, *, *),
    extra columns of the kind `columns` gives them (True: integer) where they exist."""
    core = {name: history_value(name, getattr(rec, name), integer=dtype == "i8")
            for name, (dtype, _, _) in CORE_COLUMNS.items()}
    if core["step"] < 1 or core["step"] <= last_step:
        raise ValueError(f"step: {core['step']} is not > previous step {last_step}")
    arrays = {}
    if rec.displacement is not None:
        arrays["displacement"] = finite_array("displacement", rec.displacement,
                                               (n_nodes, 2))
    for name, arr in rec.gauss.items():
        check_name(name, "gauss field")
        arrays["gauss/" + name] = finite_array(f"gauss[{name!r}]", arr,
                                                (n_cells, None, None))
    for name, arr in rec.arrays.items():
        parts = name.split("/")
        if len(parts) > 2 or parts[0] in ("gauss", "displacement"):
            raise ValueError(f"arrays[{name!r}]: use 'group/name' outside gauss/")
        for part in parts:
            check_name(part, "array")
        arrays[name] = finite_array(f"arrays[{name!r}]", arr)
    forensics = {}
    for name, arr in rec.forensics.items():
        check_name(name, "forensics array")
        forensics[name] = finite_array(f"forensics[{name!r}]", arr, (None,))
    extra = {}
    for name, val in rec.scalars.items():
        check_name(name, "history column")
        if name in CORE_COLUMNS:
            raise ValueError(f"scalars[{name!r}]: clashes with a core history column")
        extra[name] = history_value(f"scalars[{name!r}]", val, columns.get(name))
    return core, arrays, extra, forensics
