"""Energy bookkeeping per step: external work = stored elastic energy + concrete cracking and
crushing dissipation + steel plastic work + interface friction work (+ imbalance)."""

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
        return {"external_work": self.external_work, "elastic_energy": stored,
                "concrete_dissipation": concrete, "plastic_work": steel,
                "friction_work": self.friction_work,
                "energy_imbalance": self.external_work - work - self.friction_work}


def secant_elastic_energy(stress: np.ndarray, strain: np.ndarray, dV: np.ndarray) -> float:
    """1/2 sigma : eps, the energy recovered by secant unloading to the origin (concrete,
    Fig. 3.13; elastic groups)."""
    return float(0.5 * np.sum(np.einsum("eqi,eqi->eq", stress, strain) * dV))
