"""History state of the concrete model at n material points (one array row per point).

Directions 1, 2 are the in-plane orthotropy axes (angle beta from x), 3 is zz (out-of-plane or
hoop). States are immutable: `update_concrete` returns a new trial state, and the caller commits
it only on a converged increment (`select` merges committed and trial rows).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any

import numpy as np


@dataclass(frozen=True)
class ConcreteState:
    """Committed (or trial) state of n points; all arrays have n rows."""

    strain: np.ndarray  # (n, 4) total strain; zz is solved and stored in plane stress
    stress: np.ndarray  # (n, 4) global stress [xx, yy, zz, xy]
    angle: np.ndarray  # (n,) orthotropy angle beta of direction 1 from x (rad, unwrapped)
    equivalent_uniaxial_strain: np.ndarray  # (n, 3) eps_iu, signed (Fig. 3.12 step 4)
    max_equivalent_uniaxial_strain: np.ndarray  # (n, 3) max |eps_iu| reached (load/unload)
    secant_modulus: np.ndarray  # (n, 3) E_i, secant (§3.2.6)
    poisson_ratio: np.ndarray  # (n, 3) nu_i (eqs. 3.19-3.20)
    shear_modulus: np.ndarray  # (n,) G12 (eq. 3.21)
    uniaxial_strength: np.ndarray  # (n, 3) sigma_ic, signed (§3.2.4-3.2.5)
    uniaxial_peak_strain: np.ndarray  # (n, 3) eps_ic, signed
    cracked: np.ndarray  # (n, 3) bool: reached the tensile softening branch in direction i
    crushed: np.ndarray  # (n, 3) bool: reached the compressive softening branch

    @classmethod
    def initial(cls, n: int, params: Any) -> ConcreteState:
        """Virgin, unstressed concrete: E_i = E0, nu_i = nu0, uniaxial compression parameters."""
        E0, nu0 = float(params.E0), float(params.nu0)
        return cls(
            strain=np.zeros((n, 4)),
            stress=np.zeros((n, 4)),
            angle=np.zeros(n),
            equivalent_uniaxial_strain=np.zeros((n, 3)),
            max_equivalent_uniaxial_strain=np.zeros((n, 3)),
            secant_modulus=np.full((n, 3), E0),
            poisson_ratio=np.full((n, 3), nu0),
            shear_modulus=np.full(n, E0 / (2.0 * (1.0 + nu0))),
            uniaxial_strength=np.full((n, 3), -float(params.fc)),
            uniaxial_peak_strain=np.full((n, 3), -float(params.eps_c)),
            cracked=np.zeros((n, 3), dtype=bool),
            crushed=np.zeros((n, 3), dtype=bool),
        )

    @property
    def n_points(self) -> int:
        return int(self.angle.shape[0])

    @property
    def cracked_in_plane(self) -> np.ndarray:
        """(n,) bool: a crack normal to direction 1 or 2 (in-plane tension softening)."""
        return self.cracked[:, 0] | self.cracked[:, 1]

    @property
    def cracked_out_of_plane(self) -> np.ndarray:
        """(n,) bool: a crack normal to direction 3 (zz / hoop)."""
        return self.cracked[:, 2].copy()

    @property
    def crushed_any(self) -> np.ndarray:
        """(n,) bool: compressive softening in any direction."""
        return self.crushed.any(axis=1)

    def select(self, mask: np.ndarray, other: ConcreteState) -> ConcreteState:
        """Rows of `self` where mask (n,) is True, rows of `other` elsewhere."""
        mask = np.asarray(mask, dtype=bool)
        merged = {}
        for f in fields(self):
            a, b = getattr(self, f.name), getattr(other, f.name)
            merged[f.name] = np.where(mask.reshape(mask.shape + (1,) * (a.ndim - 1)), a, b)
        return ConcreteState(**merged)

    def take(self, index: np.ndarray | slice) -> ConcreteState:
        """A state of the selected rows."""
        return ConcreteState(**{f.name: getattr(self, f.name)[index] for f in fields(self)})
