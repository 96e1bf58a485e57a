"""The nonlinear analysis of a model: material groups, constraints, path following, and what
each converged increment reports (counts, energies, forensics)."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from icewall.model.build import Model
from icewall.model.materials import MaterialGroup, build_groups
from icewall.model.structure import Evaluation, Structure
from icewall.solve.constraints import SupportConstraints
from icewall.solve.control import Increment, PathState, Problem, follow_path
from icewall.solve.energy import EnergyAccount, secant_elastic_energy
from icewall.solve.settings import solver_settings


@dataclass(frozen=True)
class StepReport:
    """One converged increment with everything the result file records."""

    increment: Increment
    counts: dict[str, int]
    energy: dict[str, float]
    displacement: np.ndarray  # (n_nodes, 2)
    arrays: dict[str, np.ndarray]  # per-pair interface state etc.
    structure: Structure

    def state_fields(self) -> dict[str, np.ndarray]:
        return state_fields(self.structure, self.increment.evaluation.states)


def point_flags(groups: tuple[MaterialGroup, ...], states) -> tuple[np.ndarray | None, ...]:
    """Per group, the crack/crush (concrete) or yield (steel) flags of each point, (n, k)."""
    flags = []
    for group, state in zip(groups, states, strict=True):
        if group.model == "rotating_crack":
            flags.append(np.concatenate([state.cracked, state.crushed], axis=1))
        elif group.model == "von_mises":
            flags.append(np.asarray(state.yielded).reshape(-1, 1))
        else:
            flags.append(None)
    return tuple(flags)


def state_counts(groups: tuple[MaterialGroup, ...], states) -> dict[str, int]:
    """Points cracked in plane / out of plane, crushed (softening), yielded."""
    counts = {}
    for group, state in zip(groups, states, strict=True):
        if group.model == "rotating_crack":
            counts["cracked_in_plane"] = int(np.count_nonzero(state.cracked_in_plane))
            counts["cracked_out_of_plane"] = int(np.count_nonzero(state.cracked_out_of_plane))
            counts["crushed"] = int(np.count_nonzero(state.crushed_any))
        elif group.model == "von_mises":
            counts["yielded"] = int(np.count_nonzero(state.yielded))
    return counts


def _elastic_energy(structure: Structure, ev: Evaluation) -> dict[str, float]:
    dV = structure.kinematics.dV
    energy = {}
    for group, state in zip(structure.groups, ev.states, strict=True):
        cells = group.cells
        eps = ev.strain[cells]
        if group.model == "von_mises":  # 1/2 sigma : (eps - eps_p)
            eps = eps - state.plastic_strain.reshape(eps.shape)
        energy[group.name] = secant_elastic_energy(ev.stress[cells], eps, dV[cells])
    return energy


def make_constraints(model: Model, structure: Structure):
    """Supports only when the interfaces are bonded or tied; gap elements otherwise."""
    mesh = model.mesh
    if model.deck.materials.interface.model == "gap" and len(mesh.interface_pairs):
        from icewall.solve.gap_constraints import GapConstraints

        return GapConstraints(model)
    return SupportConstraints(model.dof_map.n_equations, model.fixed)


def run_nonlinear(model: Model) -> Iterator[StepReport]:
    """Yield every converged increment of the deck's analysis."""
    deck = model.deck
    groups = build_groups(deck, model.cell_material, model.gauss_spacing,
                          model.kinematics.dV.shape[1])
    structure = Structure(model.kinematics, model.assembler, groups)
    constraints = make_constraints(model, structure)
    problem = Problem(structure, constraints, model.reference_load, model.preload,
                      model.control_equation, lambda states: point_flags(groups, states),
                      tuple(g.freezable for g in groups))
    settings = solver_settings(deck)
    initial = PathState(np.zeros(model.dof_map.n_equations), 0.0, structure.initial_states())
    energy = EnergyAccount()
    previous = structure.evaluate(initial.u, initial.states)
    previous_u, previous_load = initial.u, np.zeros_like(initial.u)
    preload = np.zeros_like(initial.u) if model.preload is None else model.preload
    for inc, _ in follow_path(problem, settings, initial):
        ev = inc.evaluation
        load = inc.load_factor * model.reference_load + inc.preload_factor * preload
        energy.add_external(previous_load, load, inc.u - previous_u)
        for group in groups:
            c = group.cells
            energy.add_internal(group.name, previous.stress[c], ev.stress[c], previous.strain[c],
                                ev.strain[c], structure.kinematics.dV[c])
        for name, value in _elastic_energy(structure, ev).items():
            energy.set_elastic(name, value)
        energy.friction_work += constraints.friction_work_increment()
        counts = {**state_counts(groups, ev.states), **constraints.counts()}
        yield StepReport(inc, counts, energy.record(), model.dof_map.expand(inc.u),
                         constraints.arrays(), structure)
        previous, previous_u, previous_load = ev, inc.u, load


def state_fields(structure: Structure, states) -> dict[str, np.ndarray]:
    """Material-state Gauss fields over all elements (zero outside the owning group):
    concrete_flags (cracked 1-3, crushed 1-3; int8), orthotropy_angle (rad),
    equivalent_plastic_strain (steel)."""
    n_el, nq = structure.n_elements, structure.n_gauss
    fields: dict[str, np.ndarray] = {}
    for group, state in zip(structure.groups, states, strict=True):
        shape = (group.cells.size, nq)
        if group.model == "rotating_crack":
            flags = fields.setdefault("concrete_flags", np.zeros((n_el, nq, 6), np.int8))
            flags[group.cells] = np.concatenate([state.cracked, state.crushed],
                                                axis=1).reshape(shape + (6,))
            angle = fields.setdefault("orthotropy_angle", np.zeros((n_el, nq, 1)))
            angle[group.cells] = state.angle.reshape(shape + (1,))
        elif group.model == "von_mises":
            peeq = fields.setdefault("equivalent_plastic_strain", np.zeros((n_el, nq, 1)))
            peeq[group.cells] = np.asarray(state.equivalent_plastic_strain).reshape(shape + (1,))
    return fields
