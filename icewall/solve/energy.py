"""Energy bookkeeping per step: external work = stored elastic energy + concrete cracking and
crushing dissipation + steel plastic work + interface friction work + the dynamic drops'
viscous damping and the kinetic energy left where they ended (+ imbalance)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


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
        """The work terms of a dynamic drop (solve.dynamic.DropEnergy), summed over its time
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
