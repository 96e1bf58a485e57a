"""The solver state a checkpoint holds, as named arrays (docs/hdf5_layout.md, "Resuming"): the
committed path state (displacements, load and preload factors, the eq. 4.5 reference, the last
increment), the cursor of the scheme's stage field by field (`path/cursor` names its type,
`path/<type>/<field>` holds each field: `path/mode/size`), the Gauss-point states of every
group, the interface pair states and the energy account.

A checkpoint of the positional layout before the typed cursors (`path/where`) is refused with
an error naming its file: the pipeline resumes only a run of the same code (its `run_stamp`),
so no such checkpoint reaches a resume of this code."""

from __future__ import annotations

from dataclasses import MISSING, fields, replace

import numpy as np

from icewall.errors import ResultError
from icewall.model.structure import Structure
from icewall.solve.energy import EnergyAccount
from icewall.solve.mode import Mode
from icewall.solve.state import PathState, PreloadCursor, SecantCursor

CURSORS = {cursor.kind: cursor for cursor in (SecantCursor, PreloadCursor, Mode)}
"""The typed cursors by their names in a checkpoint."""
_READ = {"float": float, "int": int, "bool": bool, "str": str}


def cursor_arrays(cursor) -> dict[str, np.ndarray]:
    """`path/cursor` (the cursor's type) and `path/<type>/<field>` for each field it keeps."""
    if cursor is None:
        return {}
    out = {"path/cursor": np.asarray(cursor.kind), "path/stage": np.asarray(cursor.stage)}
    for f in fields(cursor):
        if not f.metadata.get("transient"):
            out[f"path/{cursor.kind}/{f.name}"] = np.asarray(getattr(cursor, f.name))
    return out


def read_cursor(data: dict[str, np.ndarray], source: str):
    """The typed cursor of a checkpoint (None where it has none); a field it lacks takes its
    default. ResultError, naming `source`, for a cursor of an unknown type, a field without a
    default missing, or the positional layout of older checkpoints."""
    if "path/where" in data and "path/cursor" not in data:
        raise ResultError(f"{_named(source)} has the positional solver state of an "
                          "older icewall (path/where); this one reads only named fields: run "
                          "it anew without --resume")
    if "path/cursor" not in data:
        return None
    kind = str(data["path/cursor"])
    cursor = CURSORS.get(kind)
    if cursor is None:
        raise ResultError(f"{_named(source)} has a solver state of unknown type "
                          f"{kind!r} (known: {', '.join(CURSORS)})")
    values = {}
    for f in fields(cursor):
        key = f"path/{kind}/{f.name}"
        if key in data:
            values[f.name] = _READ[f.type](data[key])
        elif f.default is MISSING and f.default_factory is MISSING:
            raise ResultError(f"{_named(source)} lacks {key!r}")
    return cursor(**values)


def _named(source: str) -> str:
    return f"the checkpoint {source}" if source else "the checkpoint"


def take_checkpoint(path: PathState, constraints, energy: EnergyAccount
                    ) -> dict[str, np.ndarray]:
    """The full solver state after a converged step, as named arrays."""
    ev = path.evaluation
    out: dict[str, np.ndarray] = {
        "path/u": path.u, "path/load_factor": path.load_factor,
        "path/preload_factor": path.preload_factor, "path/load_scale": path.load_scale,
        **cursor_arrays(path.cursor),
        "previous/stress": ev.stress, "previous/strain": ev.strain,
        "path/last_increment": (np.zeros(0) if path.last_increment is None
                                else path.last_increment),
        "energy/external_work": energy.external_work,
        "energy/friction_work": energy.friction_work,
        "energy/damping_work": energy.damping_work,
        "energy/kinetic_lost": energy.kinetic_lost,
        "energy/numerical_dissipation": energy.numerical_dissipation}
    for kind in ("internal_work", "elastic_energy"):
        for name, value in getattr(energy, kind).items():
            out[f"energy/{kind}/{name}"] = value
    for k, state in enumerate(path.states):
        if state is not None:
            out.update({f"group{k}/{f.name}": getattr(state, f.name) for f in fields(state)})
    gap = getattr(constraints, "committed", None)
    if gap is not None:
        out.update({f"gap/{f.name}": getattr(gap, f.name) for f in fields(gap)
                    if f.name != "transitions" and getattr(gap, f.name) is not None})
    if getattr(constraints, "augmentation", None) is not None:  # fixed for the whole run
        out["constraints/augmentation"] = constraints.augmentation
    return {name: np.asarray(value) for name, value in out.items()}


def restore_checkpoint(data: dict[str, np.ndarray], structure: Structure, constraints,
                       energy: EnergyAccount, source: str = ""
                       ) -> tuple[PathState, np.ndarray, np.ndarray]:
    """Set `constraints` and `energy` to a checkpoint (read from the file `source`); returns
    the path state to go on from and the stress and strain of the checkpoint's step (the start
    of the next increment)."""
    try:
        cursor = read_cursor(data, source)
        states = []
        for k, initial in enumerate(structure.initial_states()):
            if initial is None:
                states.append(None)
                continue
            states.append(type(initial)(**{f.name: _same_shape(
                data[f"group{k}/{f.name}"], getattr(initial, f.name), f"group{k}/{f.name}")
                for f in fields(initial)}))
        if getattr(constraints, "committed", None) is not None:
            gap = constraints.committed
            constraints.committed = replace(gap, transitions={}, **{
                f.name: _same_shape(data[f"gap/{f.name}"], getattr(gap, f.name), f.name)
                for f in fields(gap) if f.name != "transitions"
                and getattr(gap, f.name) is not None})
            constraints.state = constraints.committed
        if "constraints/augmentation" in data:
            constraints.augmentation = float(data["constraints/augmentation"])
        energy.external_work = float(data["energy/external_work"])
        energy.friction_work = float(data["energy/friction_work"])
        energy.damping_work = float(data.get("energy/damping_work", 0.0))
        energy.kinetic_lost = float(data.get("energy/kinetic_lost", 0.0))
        energy.numerical_dissipation = float(data.get("energy/numerical_dissipation", 0.0))
        for name, value in data.items():
            kind, _, group = name.removeprefix("energy/").partition("/")
            if name.startswith("energy/") and group:
                getattr(energy, kind)[group] = float(value)
        u = _same_shape(data["path/u"], np.zeros(structure.assembler.n_dofs), "path/u")
        last = data["path/last_increment"]
        path = PathState(u, float(data["path/load_factor"]), tuple(states), None,
                         float(data["path/preload_factor"]), float(data["path/load_scale"]),
                         cursor, last if last.size else None)
        return path, data["previous/stress"], data["previous/strain"]
    except KeyError as exc:
        raise ResultError(f"{_named(source)} lacks {exc.args[0]!r}: not one of this "
                          "model") from None


def _same_shape(value: np.ndarray, like, name: str) -> np.ndarray:
    like = np.asarray(like)
    if value.shape != like.shape:
        raise ResultError(f"the checkpoint's {name} has shape {value.shape}, the model's "
                          f"{like.shape}: it is not a checkpoint of this model")
    return value.astype(like.dtype, copy=True)
