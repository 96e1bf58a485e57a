"""Energy bookkeeping per step: external work = stored elastic energy + concrete cracking and
crushing dissipation + steel plastic work + interface friction work + the dynamic drops'
viscous damping and the kinetic energy left where they ended (+ imbalance)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from icewall.solve.control import Increment, PathState
    from icewall.solve.integrator import Motion, TimeStep
    from icewall.solve.problem import Problem


@dataclass
class EnergyAccount:
    """Cumulative energies in N mm; `record()` gives the per-step history columns."""

    external_work: float = 0.0
    internal_work: dict[str, float] = field(default_factory=dict)  # per material group
    friction_work: float = 0.0
    elastic_energy: dict[str, float] = field(default_factory=dict)
    damping_work: float = 0.0  # viscous damping of the dynamic drops
    kinetic_lost: float = 0.0  # what the vibration held where a drop ended (solve.dynamic)
    dynamic: bool = False  # the run can take dynamic drops: record their columns

    def add_drop(self, drop) -> None:
        """The work terms of a dynamic drop (DropEnergy), summed over its time
        steps."""
        self.external_work += drop.external
        for group, work in drop.internal.items():
            self.internal_work[group] = self.internal_work.get(group, 0.0) + work
        self.friction_work += drop.friction
        self.damping_work += drop.damping
        self.kinetic_lost += drop.kinetic

    def add_external(self, load_old: np.ndarray, load_new: np.ndarray, du: np.ndarray) -> None:
        """Trapezoidal work of the applied loads over a converged increment."""
        self.external_work += float(0.5 * (load_old + load_new) @ du)

    def add_internal(self, group: str, stress_old: np.ndarray, stress_new: np.ndarray,
                     strain_old: np.ndarray, strain_new: np.ndarray, dV: np.ndarray) -> None:
        """Trapezoidal stress work over the increment of a group's points (n_el, nq, 4)."""
        density = np.einsum("eqi,eqi->eq", 0.5 * (stress_old + stress_new),
                            strain_new - strain_old)
        self.internal_work[group] = self.internal_work.get(group, 0.0) + float(
            np.sum(density * dV))

    def set_elastic(self, group: str, energy: float) -> None:
        self.elastic_energy[group] = float(energy)

    def record(self) -> dict[str, float]:
        stored = sum(self.elastic_energy.values())
        work = sum(self.internal_work.values())
        concrete = self.internal_work.get("concrete", 0.0) - self.elastic_energy.get(
            "concrete", 0.0)
        steel = self.internal_work.get("steel", 0.0) - self.elastic_energy.get("steel", 0.0)
        imbalance = (self.external_work - work - self.friction_work - self.damping_work
                     - self.kinetic_lost)
        out = {"external_work": self.external_work, "elastic_energy": stored,
               "concrete_dissipation": concrete, "plastic_work": steel,
               "friction_work": self.friction_work, "energy_imbalance": imbalance}
        if self.dynamic:
            out.update(damping_work=self.damping_work, kinetic_energy_lost=self.kinetic_lost)
        return out


def secant_elastic_energy(stress: np.ndarray, strain: np.ndarray, dV: np.ndarray) -> float:
    """1/2 sigma : eps, the energy recovered by secant unloading to the origin (concrete,
    Fig. 3.13; elastic groups)."""
    return float(0.5 * np.sum(np.einsum("eqi,eqi->eq", stress, strain) * dV))


@dataclass
class DropEnergy:
    """Work terms of one drop summed over its time steps (N mm)."""

    external: float = 0.0
    internal: dict[str, float] = field(default_factory=dict)
    friction: float = 0.0
    damping: float = 0.0
    kinetic: float = 0.0  # at the end
    largest_kinetic: float = 0.0
    seeded: float = 0.0  # the kinetic energy of the imperfections seeded (counted external)

    def add(self, problem: Problem, before: Increment | PathState, after: Increment,
            step: TimeStep, motion: Motion, F_pre: np.ndarray) -> None:
        """A committed time step: the trapezoidal work of the loads, the stresses and the
        damping, the friction work and the kinetic energy at its end."""
        self._static_terms(problem, before, after, F_pre)
        v_mean = 0.5 * (step.start.v + motion.v)
        self.damping += float(problem.constraints.restrict(step.damping * v_mean)
                              @ (after.u - before.u))
        self.kinetic = 0.5 * float(motion.v @ (step.mass * motion.v))
        self.largest_kinetic = max(self.largest_kinetic, self.kinetic)

    def close(self, problem: Problem, before: Increment, after: Increment,
              F_pre: np.ndarray) -> None:
        """The static step that ends the drop: its work terms; `kinetic` becomes what it took
        out of the account (the kinetic energy left and the work of the forces the inertia
        held)."""
        self.kinetic += self.net_work(problem, before, after, F_pre)
        self._static_terms(problem, before, after, F_pre)

    def net_work(self, problem: Problem, before: Increment, after: Increment,
                 F_pre: np.ndarray) -> float:
        """Trapezoidal work of the loads less that of the stresses from `before` to `after`."""
        probe = DropEnergy()
        probe._static_terms(problem, before, after, F_pre, friction=False)
        return probe.external - sum(probe.internal.values())

    def _static_terms(self, problem: Problem, before: Increment | PathState, after: Increment,
                      F_pre: np.ndarray, friction: bool = True) -> None:
        R, du = problem.reference_load, after.u - before.u
        self.external += float((0.5 * (before.load_factor + after.load_factor) * R + F_pre)
                               @ du)
        dV = problem.structure.kinematics.dV
        s0, s1 = before.evaluation.stress, after.evaluation.stress
        e0, e1 = before.evaluation.strain, after.evaluation.strain
        for group in problem.structure.groups:
            cells = group.cells
            density = np.einsum("eqi,eqi->eq", 0.5 * (s0[cells] + s1[cells]), e1[cells] -
                                e0[cells])
            self.internal[group.name] = self.internal.get(group.name, 0.0) + float(
                np.sum(density * dV[cells]))
        if friction:
            self.friction += float(problem.constraints.friction_work_increment())
