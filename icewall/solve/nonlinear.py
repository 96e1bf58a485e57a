"""The nonlinear analysis of a model: material groups, constraints, path following, and what
each converged increment reports (counts, energies, forensics)."""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

from icewall.model.build import Model
from icewall.model.materials import MaterialGroup
from icewall.model.structure import Evaluation, Structure
from icewall.solve.checkpoint import restore_checkpoint, take_checkpoint
from icewall.solve.energy import EnergyAccount, secant_elastic_energy
from icewall.solve.path import follow_path
from icewall.solve.problem import build_problem
from icewall.solve.settings import solver_settings
from icewall.solve.state import Increment, PathState


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


def run_nonlinear(model: Model, resume: dict[str, np.ndarray] | None = None,
                  source: str = "") -> Iterator[StepReport]:
    """Yield every converged increment of the deck's analysis; with `resume` (a checkpoint of
    an interrupted run of the same model, read from the file `source`) from the step it was
    taken at."""
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
        start, stress, strain = restore_checkpoint(resume, structure, constraints, energy,
                                                   source)
    preload = np.zeros_like(start.u) if model.preload is None else model.preload
    previous_u = start.u
    previous_load = start.load_factor * model.reference_load + start.preload_factor * preload
    energy.dynamic = problem.mass is not None
    for inc, path in follow_path(problem, settings, start, resume=resume is not None):
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
