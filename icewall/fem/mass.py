"""Lumped mass of isoparametric elements by HRZ diagonal scaling.

Hinton, Rock & Zienkiewicz (1976): the diagonal of the consistent mass matrix
M_ab = sum_q rho N_a N_b dV, scaled per element so that it sums to the element's mass. Every
entry is positive for the 8-node quad, where row-sum lumping gives negative corner masses
(-1/12 of the element's mass each for a rectangle), and the element's total mass and centre of
mass are kept. Units: density t/mm^3, volume mm^3, mass t (with N, mm, s: 1 N = 1 t mm/s^2).
"""

from __future__ import annotations

import numpy as np

from icewall.fem.kinematics import ElementKinematics


def hrz_nodal_masses(kin: ElementKinematics, density: np.ndarray) -> np.ndarray:
    """(n_el, nn) lumped nodal masses of every element, for densities (n_el,) in t/mm^3."""
    rho = np.asarray(density, dtype=float)
    consistent_diagonal = np.einsum("qa,eq->ea", kin.N ** 2, kin.dV) * rho[:, None]
    element_mass = rho * kin.dV.sum(axis=1)
    scale = element_mass / np.maximum(consistent_diagonal.sum(axis=1), 1e-300)
    return consistent_diagonal * scale[:, None]


def lumped_mass_vector(kin: ElementKinematics, density: np.ndarray, n_dofs: int) -> np.ndarray:
    """(n_dofs,) diagonal of the lumped mass matrix on the equations of `kin.dofs` (each node's
    mass on both of its displacement dofs), summed over the elements."""
    nodal = hrz_nodal_masses(kin, density)
    per_dof = np.repeat(nodal, 2, axis=1)  # dofs are node-major: (x, y) per node
    return np.bincount(kin.dofs.ravel(), weights=per_dof.ravel(), minlength=n_dofs)
