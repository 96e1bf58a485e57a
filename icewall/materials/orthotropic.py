"""Orthotropic kernels of the concrete model (thesis §3.2.2, §3.2.6, Fig. 3.12), batched.

Local axes: 1, 2 in the plane at angle beta (axis 1 at beta from x), 3 = zz (out-of-plane or hoop).
Strain/stress 4-vectors [xx, yy, zz, xy], engineering shear, tension positive.
"""

from __future__ import annotations

import numpy as np

from icewall.materials import concrete_formulas as formulas
from icewall.materials.concrete_formulas import (
    add_shear_stress,
    local_normal,
    principal_angle,
)

PHI_MIN = 1e-3
"""Floor on the determinant phi of eq. 3.3d (errata §3: guard phi -> 0 as nu -> 0.5)."""
ANGLE_TOLERANCE = 1e-9
"""In-plane principal-strain radius, relative to the strain size, below which beta is kept."""
AXIS_PERIODS = {"nearest": 0.5 * np.pi, "continuous": np.pi}
"""`rotating_axes` -> the period of principal_angle's labelling: the labelling nearest the
committed axes (pi/2), or direction 1 on the major principal strain (pi)."""
ROTATION_SLACK = 1e-9
"""The bound on the rotating crack's shear stiffness (`rotating_axes: continuous`) acts beyond
this fraction above G0: an isotropic elastic point, at G0 exactly, is left as it is."""


def major_strain_angle(strain: np.ndarray) -> np.ndarray:
    """Direction (n,) of the major in-plane principal strain, 0.5 atan2(xy / 2, (xx - yy) / 2)."""
    return 0.5 * np.arctan2(0.5 * strain[:, 3], 0.5 * (strain[:, 0] - strain[:, 1]))


def principal_strain_angle(strain: np.ndarray, previous_angle: np.ndarray,
                          rotating_axes: str = "nearest") -> np.ndarray:
    """Orthotropy angle beta (n,) of the in-plane principal strain axes (rotating crack, §3.2.2).

    "nearest": of the two axis labellings (beta, beta + pi/2) the one nearest `previous_angle`
    (mod pi) is kept, so directions 1 and 2 keep their damage as the axes rotate (and swap it
    where they turn by 45 degrees within an increment); "continuous": direction 1 on the major
    principal strain. The angle is stored unwrapped. Where the in-plane strain is (nearly)
    isotropic the previous angle is kept.
    """
    return principal_angle(strain[:, 0], strain[:, 1], strain[:, 3], previous_angle,
                           major_strain_angle(strain), ANGLE_TOLERANCE,
                           AXIS_PERIODS[rotating_axes])


def strain_rotation(angle: np.ndarray) -> np.ndarray:
    """T_eps (n, 4, 4): local strain = T_eps @ global strain (engineering shear).

    The stress rotation is T_sigma = T_eps^-T, so sigma_g = T_eps^T sigma_l and
    C_g = T_eps^T C_l T_eps (Fig. 3.12 steps 2 and 8 as corrected in errata §1.3).
    """
    c, s = np.cos(angle), np.sin(angle)
    cc, ss, cs = c * c, s * s, c * s
    T = np.zeros(angle.shape + (4, 4))
    T[:, 0, 0], T[:, 0, 1], T[:, 0, 3] = cc, ss, cs
    T[:, 1, 0], T[:, 1, 1], T[:, 1, 3] = ss, cc, -cs
    T[:, 2, 2] = 1.0
    T[:, 3, 0], T[:, 3, 1], T[:, 3, 3] = -2.0 * cs, 2.0 * cs, cc - ss
    return T


def local_normal_components(vector: np.ndarray, angle: np.ndarray, shear_factor: float
                            ) -> np.ndarray:
    """Normal components (n, 3) of a global 4-vector in the local axes.

    shear_factor = 1 for engineering strain (T_eps rows 1-3), 2 for stress (T_sigma rows 1-3).
    """
    c, s = np.cos(angle), np.sin(angle)
    return np.stack(local_normal(vector[:, 0], vector[:, 1], vector[:, 2], vector[:, 3], c, s,
                                 shear_factor), axis=1)


def local_shear_strain(strain: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Engineering shear strain (n,) in the local axes (T_eps row 4); zero in principal axes."""
    c, s = np.cos(angle), np.sin(angle)
    return formulas.local_shear_strain(strain[:, 0], strain[:, 1], strain[:, 3], c, s)


def global_stress(principal: np.ndarray, angle: np.ndarray,
                  shear: np.ndarray | None = None) -> np.ndarray:
    """sigma_g = T_eps^T [s1, s2, s3, tau] (n, 4); the local shear stress tau (n,) is zero
    unless given (reset to zero for each increment, §3.2.6)."""
    c, s = np.cos(angle), np.sin(angle)
    stress = np.stack(formulas.global_stress(principal[:, 0], principal[:, 1], principal[:, 2],
                                             c, s), axis=1)
    if shear is not None:
        stress[:, 0], stress[:, 1], stress[:, 3] = add_shear_stress(
            stress[:, 0], stress[:, 1], stress[:, 3], shear, c, s)
    return stress


def global_strain(principal: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Global strain (n, 4), engineering shear, with principal strains (n, 3) along angle."""
    strain = global_stress(principal, angle)
    strain[:, 3] *= 2.0
    return strain


def orthotropic_normal_stiffness(modulus: np.ndarray, poisson: np.ndarray,
                                 printed: tuple[str, ...] = ()) -> np.ndarray:
    """Normal block (n, 3, 3) of the local stiffness, eq. 3.2 with the 1/phi prefactor.

    Eq. 3.2 / errata 1.1: the printed matrix must be divided by phi.
    Eq. 3.3a-c: eta_ij^2 = nu_i nu_j. Eq. 3.3d / errata 1.1: phi = 1 - eta12^2 - eta23^2 -
    eta31^2 - 2 eta12 eta23 eta31 (printed 2 eta31^3); floored at PHI_MIN (errata §3).
    `printed` (deck printed_forms): "eq3.2" the matrix as printed, without 1/phi; "eq3.3d"
    the 1/phi of the printed phi (2 eta31^3).
    """
    C = np.empty(modulus.shape[:1] + (3, 3))
    (C[:, 0, 0], C[:, 1, 1], C[:, 2, 2], C[:, 0, 1], C[:, 0, 2],
     C[:, 1, 2]) = formulas.normal_stiffness(modulus[:, 0], modulus[:, 1], modulus[:, 2],
                                             poisson[:, 0], poisson[:, 1], poisson[:, 2],
                                             PHI_MIN)
    C[:, 1, 0], C[:, 2, 0], C[:, 2, 1] = C[:, 0, 1], C[:, 0, 2], C[:, 1, 2]
    if "eq3.2" in printed or "eq3.3d" in printed:
        C *= _printed_phi_factor(poisson, printed)[:, None, None]
    return C


def _printed_phi_factor(poisson: np.ndarray, printed: tuple[str, ...]) -> np.ndarray:
    """phi / phi_printed of the printed forms (eq. 3.2 without 1/phi: phi; eq. 3.3d's phi
    with 2 eta31^3: phi over it), each phi floored at PHI_MIN as in normal_stiffness."""
    n1, n2, n3 = poisson[:, 0], poisson[:, 1], poisson[:, 2]
    e12, e23, e31 = np.sqrt(n1 * n2), np.sqrt(n2 * n3), np.sqrt(n3 * n1)
    squares = e12 * e12 + e23 * e23 + e31 * e31
    phi = np.maximum(1.0 - squares - 2.0 * e12 * e23 * e31, PHI_MIN)
    used = np.maximum(1.0 - squares - 2.0 * e31 ** 3, PHI_MIN) if "eq3.3d" in printed else phi
    return phi if "eq3.2" in printed else phi / used


def uniaxial_coupling_matrix(modulus: np.ndarray, poisson: np.ndarray) -> np.ndarray:
    """B (n, 3, 3) of eq. 3.4, B_ij = C_ij / E_i, so that d eps_iu = sum_j B_ij d eps_j.

    Eq. 3.4 row 3 / errata 1.1: row 3 is E3 B31, E3 B32, E3 B33 (B is not symmetric).
    Eq. 3.7a / errata 1.1: d eps_iu = B_i1 d eps_1 + B_i2 d eps_2 + B_i3 d eps_3, without E_i.
    """
    return orthotropic_normal_stiffness(modulus, poisson) / modulus[:, :, None]


def condense_plane_stress(normal_stiffness: np.ndarray) -> np.ndarray:
    """Normal block with sigma_3 = 0 condensed out; row and column 3 set to zero (errata §3)."""
    C = normal_stiffness
    coupling = C[:, :, 2] / C[:, 2:3, 2]  # (n, 3): C_a3 / C_33
    condensed = C - coupling[:, :, None] * C[:, None, 2, :]
    condensed[:, 2, :] = 0.0
    condensed[:, :, 2] = 0.0
    return condensed


def global_moduli(normal_stiffness: np.ndarray, shear_modulus: np.ndarray, angle: np.ndarray
                  ) -> np.ndarray:
    """C_g = T_eps^T C_l T_eps (n, 4, 4) (Fig. 3.12 step 8, errata §1.3)."""
    local = np.zeros(angle.shape + (4, 4))
    local[:, :3, :3] = normal_stiffness
    local[:, 3, 3] = shear_modulus
    T = strain_rotation(angle)
    return np.matmul(T.transpose(0, 2, 1), np.matmul(local, T))
