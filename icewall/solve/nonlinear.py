"""The nonlinear analysis of a model: material groups, constraints, path following, and what
each converged increment reports (counts, energies, forensics)."""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterator
from dataclasses import dataclass, fields, replace
from typing import Any

import numpy as np

from icewall.errors import ResultError
from icewall.model.build import Model
from icewall.model.materials import MaterialGroup
from icewall.model.structure import Evaluation, Structure
from icewall.solve.control import Increment, PathState, follow_path
from icewall.solve.energy import EnergyAccount, secant_elastic_energy
from icewall.solve.path import follow_path as follow_newton_path
from icewall.solve.problem import build_problem
from icewall.solve.settings import solver_settings


@dataclass(frozen=True)
class StepReport:
    """One converged increment with everything the result file records; the per-step fields
    (displacement, interface arrays, state fields, checkpoint) are computed only when asked
    for, and only while the generator stands at this step."""

    increment: Increment
    counts: dict[str, int]
    energy: dict[str, float]
    structure: Structure
    constraints: Any
    dof_map: Any
    checkpoint: Callable[[], dict[str, np.ndarray]]  # full solver state, for --resume

    @property
    def displacement(self) -> np.ndarray:
        """(n_nodes, 2) nodal displacements."""
        return self.dof_map.expand(self.increment.u)

    @property
    def arrays(self) -> dict[str, np.ndarray]:
        """Per-pair interface state (empty without gap elements)."""
        return self.constraints.arrays()

    def state_fields(self) -> dict[str, np.ndarray]:
        return state_fields(self.structure, self.increment.evaluation.states)


def state_counts(groups: tuple[MaterialGroup, ...], states) -> dict[str, int]:
    """Points in each named condition of every law (cracked, crushed, yielded)."""
    counts = {}
    for group, state in zip(groups, states, strict=True):
        counts.update(group.law.counts(state))
    return counts


def _elastic_energy(structure: Structure, ev: Evaluation) -> dict[str, float]:
    """Per group, 1/2 sigma : eps_e of the law's elastic strain (for steel eps - eps_p)."""
    dV = structure.kinematics.dV
    energy = {}
    for group, state in zip(structure.groups, ev.states, strict=True):
        cells = group.cells
        eps = ev.strain[cells]
        eps = group.law.elastic_strain(eps.reshape(-1, 4), state).reshape(eps.shape)
        energy[group.name] = secant_elastic_energy(ev.stress[cells], eps, dV[cells])
    return energy


def run_nonlinear(model: Model, resume: dict[str, np.ndarray] | None = None
                  ) -> Iterator[StepReport]:
    """Yield every converged increment of the deck's analysis; with `resume` (a checkpoint of
    an interrupted run of the same model) from the step it was taken at."""
    settings = solver_settings(model.description)
    problem = build_problem(model, settings.scheme)
    structure, constraints = problem.structure, problem.constraints
    groups = structure.groups
    energy = EnergyAccount()
    if resume is None:
        start = PathState(np.zeros(model.dof_map.n_equations), 0.0, structure.initial_states())
        first = structure.evaluate(start.u, start.states)
        stress, strain = first.stress, first.strain
    else:
        start, stress, strain = restore_checkpoint(resume, structure, constraints, energy)
    preload = np.zeros_like(start.u) if model.preload is None else model.preload
    previous_u = start.u
    previous_load = start.load_factor * model.reference_load + start.preload_factor * preload
    follow = follow_newton_path if settings.scheme == "newton" else follow_path
    energy.dynamic = problem.mass is not None
    for inc, path in follow(problem, settings, start, resume=resume is not None):
        ev = inc.evaluation
        load = inc.load_factor * model.reference_load + inc.preload_factor * preload
        if inc.path_energy is not None:  # a dynamic drop: its terms over its time steps
            energy.add_drop(inc.path_energy)
        else:
            energy.add_external(previous_load, load, inc.u - previous_u)
            for group in groups:
                c = group.cells
                energy.add_internal(group.name, stress[c], ev.stress[c], strain[c],
                                    ev.strain[c], structure.kinematics.dV[c])
            energy.friction_work += constraints.friction_work_increment()
        for name, value in _elastic_energy(structure, ev).items():
            energy.set_elastic(name, value)
        counts = {**state_counts(groups, ev.states), **constraints.counts()}
        snapshot = functools.partial(take_checkpoint, path, constraints, energy)
        yield StepReport(inc, counts, energy.record(), structure, constraints, model.dof_map,
                         snapshot)
        stress, strain, previous_u, previous_load = ev.stress, ev.strain, inc.u, load


def take_checkpoint(path: PathState, constraints, energy: EnergyAccount
                    ) -> dict[str, np.ndarray]:
    """The full solver state after a converged step, as named arrays: path (displacements,
    load and preload factors, eq. 4.5 reference, where the path goes on), the Gauss-point
    states of every group, the interface pair states and the energy account."""
    ev = path.evaluation
    stage, *where = path.resume  # the path's own counters too (control.py, path.py)
    out: dict[str, np.ndarray] = {
        "path/u": path.u, "path/load_factor": path.load_factor,
        "path/preload_factor": path.preload_factor, "path/load_scale": path.load_scale,
        "path/stage": np.array(stage), "path/where": np.array(where, dtype=float),
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
                       energy: EnergyAccount) -> tuple[PathState, np.ndarray, np.ndarray]:
    """Set `constraints` and `energy` to a checkpoint; returns the path state to go on from
    and the stress and strain of the checkpoint's step (the start of the next increment)."""
    try:
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
        resume = (str(data["path/stage"]), *map(float, data["path/where"]))
        last = data["path/last_increment"]
        path = PathState(u, float(data["path/load_factor"]), tuple(states), None,
                         float(data["path/preload_factor"]), float(data["path/load_scale"]),
                         resume, last if last.size else None)
        return path, data["previous/stress"], data["previous/strain"]
    except KeyError as exc:
        raise ResultError(f"the checkpoint lacks {exc.args[0]!r}: not one of this model") from None


def _same_shape(value: np.ndarray, like, name: str) -> np.ndarray:
    like = np.asarray(like)
    if value.shape != like.shape:
        raise ResultError(f"the checkpoint's {name} has shape {value.shape}, the model's "
                          f"{like.shape}: it is not a checkpoint of this model")
    return value.astype(like.dtype, copy=True)


def state_fields(structure: Structure, states) -> dict[str, np.ndarray]:
    """Material-state Gauss fields of every law over all elements (zero outside the owning
    group): concrete_flags (cracked 1-3, crushed 1-3; int8), orthotropy_angle (rad),
    equivalent_plastic_strain (steel)."""
    n_el, nq = structure.n_elements, structure.n_gauss
    fields: dict[str, np.ndarray] = {}
    for group, state in zip(structure.groups, states, strict=True):
        for name, value in group.law.state_fields(state).items():
            field = fields.setdefault(name, np.zeros((n_el, nq) + value.shape[1:], value.dtype))
            field[group.cells] = value.reshape((group.cells.size, nq) + value.shape[1:])
    return fields
