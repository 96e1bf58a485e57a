"""Bilinear von Mises steel with linear isotropic hardening (thesis §3.4), batched over points.

Backward-Euler return mapping with the consistent (algorithmic) tangent (Simo & Hughes 1998,
Computational Inelasticity, Box 3.2 for 3D, §3.4 for plane stress). Strain/stress are
[xx, yy, zz, xy] with engineering shear strain; yield stress kappa = fy + H * eps_bar, where
eps_bar is the equivalent plastic strain and H the plastic (hardening) modulus, so that the
uniaxial tangent after yield is E H / (E + H).

Plane strain / axisymmetric: the 3D radial return restricted to the 4 components (eps_zz is the
given out-of-plane strain, 0 in plane strain, or the hoop strain). Plane stress: Simo-Taylor
projected return in the (xx, yy, xy) space with a scalar Newton on the consistency parameter;
sigma_zz = 0, eps_zz is solved and stored, the input eps_zz is ignored, and the moduli have a
zero zz row and column. Finite output for strains with |E * eps| below the float range.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from icewall.formulations import check_formulation
from icewall.materials.elastic import elastic_moduli
from icewall.materials.law import MaterialLaw, Update

YIELD_TOLERANCE = 1e-10  # relative overstress q / kappa - 1 below which a point stays elastic
NEWTON_TOLERANCE = 1e-13  # plane stress: |consistency residual| / kappa at convergence
NEWTON_MAX_ITERATIONS = 100  # monotone Newton from a lower bound; ~40 suffice for eps ~ 1e3 fy/E
_M = np.array([1.0, 1.0, 1.0, 0.0])  # trace vector m
_IDEV = np.diag([1.0, 1.0, 1.0, 0.5]) - np.outer(_M, _M) / 3.0  # deviatoric projector (Voigt)
_IN_PLANE = np.array([0, 1, 3])  # xx, yy, xy
ReturnMap = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]  # stress, C, d eps_p, d eps_bar


@dataclass(frozen=True)
class SteelParameters:
    """Elastic constants, yield stress fy (MPa), plastic modulus H = d kappa / d eps_bar (MPa)."""

    E: float
    nu: float
    fy: float
    hardening_modulus: float
    formulation: str = "plane_strain"

    def __post_init__(self) -> None:
        check_formulation(self.formulation)
        if not (self.E > 0.0 and -1.0 < self.nu < 0.5 and self.fy > 0.0):
            raise ValueError(f"need E > 0, -1 < nu < 0.5, fy > 0; got {self}")
        if not self.hardening_modulus >= 0.0:
            raise ValueError(f"hardening_modulus must be >= 0, got {self.hardening_modulus}")

    @property
    def shear_modulus(self) -> float:
        return self.E / (2.0 * (1.0 + self.nu))


def steel_parameters(E: float, nu: float, fy: float, hardening_ratio: float = 0.02,
                     formulation: str = "plane_strain",
                     fy_reduction: float = 0.0) -> SteelParameters:
    """Parameters with H = hardening_ratio * E (thesis §4.3.2: 0.02 E_s; errata: not 200 MPa).

    H is the plastic modulus d kappa / d eps_bar, so the uniaxial slope after yield is
    E H / (E + H) = 0.0196 E for 0.02; if the thesis' "hardening slope" is read as that tangent
    E_t instead, pass hardening_ratio = 0.02 / 0.98.

    `fy_reduction` lowers the yield stress to fy (1 - fy_reduction). The thesis (§5.3, CF-8) could
    not run plane-stress plates with plane-strain concrete and instead reduced fy by 11.1 % in a
    plane-strain run; `plane_strain_fy_reduction(nu)` gives that value (0.111 for nu = 0.3).
    """
    if not 0.0 <= fy_reduction < 1.0:
        raise ValueError(f"fy_reduction must lie in [0, 1), got {fy_reduction}")
    return SteelParameters(E=float(E), nu=float(nu), fy=float(fy) * (1.0 - fy_reduction),
                           hardening_modulus=float(hardening_ratio) * float(E),
                           formulation=formulation)


def plane_strain_fy_reduction(nu: float) -> float:
    """1 - sqrt(1 - nu + nu^2): a plane-strain plate in uniaxial in-plane stress (sigma_zz =
    nu sigma_xx) then yields elastically at sigma_xx = fy, as a plane-stress plate would."""
    return 1.0 - float(np.sqrt(1.0 - nu + nu * nu))


@dataclass(frozen=True)
class SteelState:
    """Committed (or trial) state of n points; all arrays have n rows.

    plastic_strain holds tensor components [xx, yy, zz] and the ENGINEERING plastic shear strain
    2 eps_p_xy in the xy slot (like the total strain), so sigma = D (strain - plastic_strain).
    """

    strain: np.ndarray  # (n, 4) total strain of the last update; zz solved in plane stress
    plastic_strain: np.ndarray  # (n, 4) plastic strain, trace-free
    equivalent_plastic_strain: np.ndarray  # (n,) eps_bar = int sqrt(2/3 deps_p : deps_p)
    yielded: np.ndarray  # (n,) bool: has yielded at some time (eps_bar > 0)
    out_of_plane_strain: np.ndarray  # (n,) total eps_zz (solved in plane stress; hoop if axisym.)

    @classmethod
    def initial(cls, n: int) -> SteelState:
        """Virgin, unstrained steel at n points."""
        return cls(strain=np.zeros((n, 4)), plastic_strain=np.zeros((n, 4)),
                   equivalent_plastic_strain=np.zeros(n), yielded=np.zeros(n, dtype=bool),
                   out_of_plane_strain=np.zeros(n))

    @property
    def n_points(self) -> int:
        return int(self.equivalent_plastic_strain.shape[0])

    def select(self, mask: np.ndarray, other: SteelState) -> SteelState:
        """Rows of `self` where mask (n,) is True, rows of `other` elsewhere."""
        mask = np.asarray(mask, dtype=bool)
        return SteelState(**{f.name: np.where(
            mask.reshape(mask.shape + (1,) * (getattr(self, f.name).ndim - 1)),
            getattr(self, f.name), getattr(other, f.name)) for f in fields(self)})

    def take(self, index: np.ndarray | slice) -> SteelState:
        """A state of the selected rows."""
        return SteelState(**{f.name: getattr(self, f.name)[index] for f in fields(self)})


def yield_stress(state: SteelState, params: SteelParameters) -> np.ndarray:
    """Current yield stress kappa = fy + H eps_bar, (n,)."""
    return params.fy + params.hardening_modulus * state.equivalent_plastic_strain


def von_mises_stress(stress: np.ndarray) -> np.ndarray:
    """Equivalent stress q = sqrt(3/2 s : s) of stresses (..., 4) [xx, yy, zz, xy]."""
    s = np.asarray(stress, dtype=float)
    xx, yy, zz, xy = s[..., 0], s[..., 1], s[..., 2], s[..., 3]
    return np.sqrt(0.5 * ((xx - yy) ** 2 + (yy - zz) ** 2 + (zz - xx) ** 2) + 3.0 * xy * xy)


def update_steel(strain: np.ndarray, state: SteelState, params: SteelParameters
                 ) -> tuple[np.ndarray, np.ndarray, SteelState]:
    """Stress (n, 4), consistent moduli (n, 4, 4) and trial state for total strains (n, 4).

    Pure: `state` (the committed state) is not modified. Only points whose trial von Mises stress
    exceeds the current yield stress get a return mapping.
    """
    strain = np.asarray(strain, dtype=float)
    if strain.ndim != 2 or strain.shape[1] != 4 or strain.shape[0] != state.n_points:
        raise ValueError(f"strain must be ({state.n_points}, 4), got {strain.shape}")
    kappa = yield_stress(state, params)
    D = elastic_moduli(params.E, params.nu, params.formulation)
    stress = (strain - state.plastic_strain) @ D  # D is symmetric
    moduli = np.repeat(D[None], strain.shape[0], axis=0)
    plastic_strain = state.plastic_strain.copy()
    eps_bar = state.equivalent_plastic_strain.copy()
    plastic = von_mises_stress(stress) > kappa * (1.0 + YIELD_TOLERANCE)
    idx = np.flatnonzero(plastic)
    if idx.size:
        _return = _return_plane_stress if params.formulation == "plane_stress" else _return_3d
        s, C, d_eps_p, d_eps_bar = _return(stress[idx], kappa[idx], params)
        stress[idx], moduli[idx] = s, C
        plastic_strain[idx] += d_eps_p
        eps_bar[idx] += d_eps_bar
    strain = strain.copy()
    if params.formulation == "plane_stress":
        elastic_zz = -params.nu / params.E * (stress[:, 0] + stress[:, 1])
        strain[:, 2] = elastic_zz + plastic_strain[:, 2]
    trial = SteelState(strain=strain, plastic_strain=plastic_strain,
                       equivalent_plastic_strain=eps_bar, yielded=state.yielded | plastic,
                       out_of_plane_strain=strain[:, 2].copy())
    return stress, moduli, trial


def _return_3d(trial: np.ndarray, kappa: np.ndarray, p: SteelParameters) -> ReturnMap:
    """Radial return of 3D trial stresses (m, 4): stress, moduli, d plastic strain, d eps_bar."""
    G, H = p.shear_modulus, p.hardening_modulus
    K = p.E / (3.0 * (1.0 - 2.0 * p.nu))
    dev = trial - trial[:, :3].mean(axis=1)[:, None] * _M
    q = von_mises_stress(trial)
    d_eps_bar = (q - kappa) / (3.0 * G + H)
    ratio = 3.0 * G * d_eps_bar / q  # 1 - theta: fraction of the trial deviator removed
    stress = trial - ratio[:, None] * dev
    flow = 1.5 * dev / q[:, None]  # d eps_p / d eps_bar (tensor components)
    flow[:, 3] *= 2.0  # engineering plastic shear
    normal = dev / (np.sqrt(2.0 / 3.0) * q)[:, None]  # unit deviator n (tensor components)
    theta, theta_bar = 1.0 - ratio, 3.0 * G / (3.0 * G + H) - ratio
    C = (K * np.outer(_M, _M) + 2.0 * G * theta[:, None, None] * _IDEV
         - 2.0 * G * theta_bar[:, None, None] * normal[:, :, None] * normal[:, None, :])
    return stress, C, d_eps_bar[:, None] * flow, d_eps_bar


def _return_plane_stress(trial: np.ndarray, kappa: np.ndarray, p: SteelParameters
                         ) -> ReturnMap:
    """Simo-Taylor plane-stress return of trial stresses (m, 4) with sigma_zz = 0.

    In the eigenbasis of the compliance and of P (sigma.P.sigma = 2/3 q^2) the stress is
    sigma(dg) = diag(1 / (1 + c_i dg)) sigma_trial, c1 = E / (3 (1 - nu)) for (xx + yy),
    c2 = 2G for (yy - xx) and xy. Newton solves g(dg) = q(dg) (1 - 2/3 H dg) - kappa = 0;
    g is convex and decreasing, and the start dg0 (exact if xx + yy = 0) bounds the root from
    below, so the iterates increase monotonically to it.
    """
    E, nu, G, H = p.E, p.nu, p.shear_modulus, p.hardening_modulus
    c1, c2, h = E / (3.0 * (1.0 - nu)), 2.0 * G, 2.0 / 3.0 * H
    xx, yy, xy = trial[:, 0], trial[:, 1], trial[:, 3]
    A = (xx + yy) ** 2 / 6.0  # mode contributions to sigma.P.sigma
    B = 0.5 * (yy - xx) ** 2 + 2.0 * xy * xy
    q_trial = np.sqrt(1.5 * (A + B))
    dg = (q_trial - kappa) / (c2 * kappa + h * q_trial)
    for _ in range(NEWTON_MAX_ITERATIONS):
        a1, a2 = 1.0 / (1.0 + c1 * dg), 1.0 / (1.0 + c2 * dg)
        q = np.sqrt(1.5 * (A * a1 * a1 + B * a2 * a2))
        g = q * (1.0 - h * dg) - kappa
        dq = -1.5 * (A * c1 * a1**3 + B * c2 * a2**3) / q
        dg = dg - g / (dq * (1.0 - h * dg) - h * q)
        if np.all(np.abs(g) <= NEWTON_TOLERANCE * kappa):
            break
    a1, a2 = 1.0 / (1.0 + c1 * dg), 1.0 / (1.0 + c2 * dg)
    s_sum, s_diff = (xx + yy) * a1, (yy - xx) * a2
    sigma = np.stack([0.5 * (s_sum - s_diff), 0.5 * (s_sum + s_diff), xy * a2], axis=1)
    n = np.stack([(2.0 * sigma[:, 0] - sigma[:, 1]) / 3.0,
                  (2.0 * sigma[:, 1] - sigma[:, 0]) / 3.0, 2.0 * sigma[:, 2]], axis=1)  # P sigma
    f2 = np.einsum("mi,mi->m", sigma, n)  # sigma.P.sigma = 2/3 q^2
    xi1, xi2 = E / (1.0 - nu) * a1, c2 * a2  # eigenvalues of Xi = (C^-1 + dg P)^-1
    Xi = np.zeros((dg.size, 3, 3))
    Xi[:, 0, 0] = Xi[:, 1, 1] = 0.5 * (xi1 + xi2)
    Xi[:, 0, 1] = Xi[:, 1, 0] = 0.5 * (xi1 - xi2)
    Xi[:, 2, 2] = 0.5 * xi2
    Xn = np.einsum("mij,mj->mi", Xi, n)
    beta = h * f2 / np.maximum(1.0 - h * dg, np.finfo(float).tiny)
    C3 = Xi - Xn[:, :, None] * Xn[:, None, :] / (np.einsum("mi,mi->m", n, Xn) + beta)[:, None, None]
    m = dg.size
    stress, C = np.zeros((m, 4)), np.zeros((m, 4, 4))
    stress[:, _IN_PLANE] = sigma
    C[:, _IN_PLANE[:, None], _IN_PLANE] = C3
    d_eps_p = np.zeros((m, 4))
    d_eps_p[:, _IN_PLANE] = dg[:, None] * n  # engineering shear: 2 dg sigma_xy
    d_eps_p[:, 2] = -(d_eps_p[:, 0] + d_eps_p[:, 1])
    return stress, C, d_eps_p, 2.0 / 3.0 * dg * np.sqrt(1.5 * f2)  # (2/3) dg q


@dataclass(frozen=True)
class SteelLaw(MaterialLaw):
    """Von Mises steel (`update_steel`): its moduli are its consistent tangent."""

    params: SteelParameters

    def initial_state(self, n: int) -> SteelState:
        return SteelState.initial(n)

    def update(self, strain: np.ndarray, state: SteelState, frozen: np.ndarray | None = None,
               returned_secant: bool = False, tangent: bool = False) -> Update:
        return update_steel(strain, state, self.params)

    def flags(self, state: SteelState) -> np.ndarray:
        """Yielded, (n, 1)."""
        return np.asarray(state.yielded).reshape(-1, 1)

    def counts(self, state: SteelState) -> dict[str, int]:
        return {"yielded": int(np.count_nonzero(state.yielded))}

    def elastic_strain(self, strain: np.ndarray, state: SteelState) -> np.ndarray:
        """eps - eps_p: the strain of sigma = D (eps - eps_p)."""
        return strain - state.plastic_strain

    def state_fields(self, state: SteelState) -> dict[str, np.ndarray]:
        return {"equivalent_plastic_strain":
                np.asarray(state.equivalent_plastic_strain).reshape(-1, 1)}

    def yielded(self, state: SteelState) -> np.ndarray:
        return state.yielded
