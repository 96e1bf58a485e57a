"""The problem every solution scheme solves, built in one place from a model."""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

import numpy as np

from icewall import sparse
from icewall.fem.mass import lumped_mass_vector
from icewall.model.build import Model
from icewall.model.materials import build_groups
from icewall.model.structure import Structure
from icewall.solve.constraints import SupportConstraints
from icewall.solve.gap_constraints import GapConstraints


@dataclass(frozen=True)
class Problem:
    structure: Structure
    constraints: Any  # SupportConstraints or GapConstraints
    reference_load: np.ndarray  # (n_eq,) the load pattern the load factor scales (R*)
    preload: np.ndarray | None  # in-plane load vector (n_eq,), held during control
    control_equation: int  # deflection = -u[control_equation]
    mass: np.ndarray | None = None  # (n_eq,) lumped mass diagonal, t (dynamic drops)

    def point_flags(self, states) -> tuple[np.ndarray | None, ...]:
        """Per group, the (n, k) flags of each point whose switching within an increment
        counts as chatter (the law's `flags`: crack, crush, yield), or None."""
        return tuple(group.law.flags(state)
                     for group, state in zip(self.structure.groups, states, strict=True))


def build_problem(model: Model, scheme=None) -> Problem:
    """The material groups, structure and constraints of `model`, set up for `scheme` (an
    icewall.solve.schemes object; None: the constraints as built, no mass): the one place a
    Problem is made from a model."""
    groups = build_groups(model.description, model.cell_material, model.gauss_spacing,
                          model.kinematics.dV.shape[1])
    structure = Structure(model.kinematics, model.assembler, groups)
    constraints = make_constraints(model)
    mass = None
    if scheme is not None:
        scheme.prepare(constraints)
        mass = scheme.mass(model)
    return Problem(structure, constraints, model.reference_load, model.preload,
                   model.control_equation, mass)


def wall_mass(model: Model) -> np.ndarray:
    """(n_eq,) HRZ-lumped mass of every material's density (fem.mass), plus the loading
    head's (loads.control.head_mass) on the loaded equations in proportion to their load."""
    density = np.zeros(len(model.cell_material))
    for key, section in model.description.materials.items():
        density[model.cell_material == key] = getattr(section, "density", 0.0)
    mass = lumped_mass_vector(model.kinematics, density, model.dof_map.n_equations)
    head = getattr(model.description.control, "head_mass", 0.0)
    if head > 0.0:
        share = np.abs(model.reference_load)
        mass = mass + head * share / share.sum()
    return mass


def make_constraints(model: Model):
    """Supports only when the interfaces are bonded or tied; gap elements otherwise."""
    if model.description.interface.model == "gap" and len(model.mesh.interface_pairs):
        return GapConstraints(model)
    return SupportConstraints(model.dof_map.n_equations, model.fixed)


def newton_constraints(constraints: SupportConstraints) -> None:
    """Set the constraint set up as the Newton scheme uses it."""
    if not os.environ.get(sparse.ENVIRONMENT_VARIABLE):
        # the fastest factorisation for the size (docs/solver_backends.md); the secant
        # scheme keeps the old call, which reproduces its earlier results bit for bit
        constraints.sparse_backend = "auto"
    if hasattr(constraints, "stabilization"):
        # Newton solves the contact conditions with the displacements: no pair is frozen,
        # and no spring stands in the matrix that is not in the residual (it would make the
        # tangent inexact: CF-4's elastic step then converged linearly, 1 % per iteration);
        # a pair that keeps switching between held and open is decided semismoothly instead
        constraints.stabilization = 0.0
        constraints.settle_cycles = True
        constraints.max_changes = np.iinfo(np.int64).max
