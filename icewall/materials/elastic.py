"""Isotropic linear elasticity in the [xx, yy, zz, xy] convention (engineering shear)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from icewall.formulations import check_formulation
from icewall.materials.law import MaterialLaw, Update


def elastic_moduli(E: float | np.ndarray, nu: float | np.ndarray,
                   formulation: str) -> np.ndarray:
    """Isotropic tangent moduli (..., 4, 4); (4, 4) for scalar E and nu.

    Plane strain and axisymmetric: the 3D isotropic law restricted to [xx, yy, zz, xy].
    Plane stress: sigma_zz = 0 condensed out, so the zz row and column are zero.
    """
    check_formulation(formulation)
    E, nu = np.broadcast_arrays(np.asarray(E, dtype=float), np.asarray(nu, dtype=float))
    mu = E / (2.0 * (1.0 + nu))
    D = np.zeros(E.shape + (4, 4))
    if formulation == "plane_stress":
        c = E / (1.0 - nu * nu)
        D[..., 0, 0] = D[..., 1, 1] = c
        D[..., 0, 1] = D[..., 1, 0] = c * nu
    else:
        lam = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
        D[..., :3, :3] = lam[..., None, None]
        for i in range(3):
            D[..., i, i] += 2.0 * mu
    D[..., 3, 3] = mu
    return D


def update_elastic(strain: np.ndarray, E: float | np.ndarray, nu: float | np.ndarray,
                   formulation: str) -> tuple[np.ndarray, np.ndarray]:
    """Stress (..., 4) and moduli (..., 4, 4) for strains (..., 4).

    E and nu are scalars or arrays broadcastable to strain.shape[:-1]. In plane stress the
    strain's zz component is ignored (see `plane_stress_strain_zz`); in plane strain
    sigma_zz = nu (sigma_xx + sigma_yy) follows from the moduli.
    """
    strain = np.asarray(strain, dtype=float)
    D = elastic_moduli(E, nu, formulation)
    D = np.broadcast_to(D, strain.shape[:-1] + (4, 4))
    stress = np.einsum("...ij,...j->...i", D, strain)
    return stress, np.array(D)


def plane_stress_strain_zz(strain: np.ndarray, nu: float | np.ndarray) -> np.ndarray:
    """Out-of-plane strain eps_zz = -nu / (1 - nu) (eps_xx + eps_yy) of plane stress, (...,)."""
    strain = np.asarray(strain, dtype=float)
    return -np.asarray(nu) / (1.0 - np.asarray(nu)) * (strain[..., 0] + strain[..., 1])


@dataclass(frozen=True)
class ElasticLaw(MaterialLaw):
    """Linear elasticity with fixed moduli: no state, the moduli are the tangent."""

    params: np.ndarray  # (4, 4) moduli

    @property
    def constant_moduli(self) -> np.ndarray:
        return self.params

    def update(self, strain: np.ndarray, state: None, frozen: np.ndarray | None = None,
               returned_secant: bool = False, tangent: bool = False) -> Update:
        moduli = np.broadcast_to(self.params, strain.shape[:-1] + (4, 4))
        return strain @ self.params.T, moduli, state
