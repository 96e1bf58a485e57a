"""Rotating axes the strain resolves (`rotating_axes: continuous`), batched over points.

The axes of orthotropy follow the principal strain axes (thesis 3.2.2: "co-axiality of stresses
and strains is maintained"). Where a point's directions carry different damage (a crack in one,
crushing in another), its principal stresses differ however close its principal strains come:
at an isotropic in-plane strain the stress depends on axes the strain does not define. The
update is a cone there (its shear stiffness (s1 - s2) / (2 (e1 - e2)) without bound: 1e4 E0 on
CF-4, thousands of E0 per step on lines through isotropy), and the labelling nearest the
committed axes swaps the directions' damage where the axes turn by 45 degrees: no Newton
iteration settles at either (docs/solver.md items 42, 45).

Under `continuous` direction 1 is the major principal strain (`orthotropic.AXIS_PERIODS`), and
the returned stress takes out the cone within a strain resolution delta (RESOLUTION cracking
strains). With m, r = (e1 + e2) / 2, |e1 - e2| / 2 and D0(m, e3) = s1 - s2 of the update at the
isotropic strain (m, m, e3) (the cone's height there; its derivatives by central differences
of the update), the returned principal stresses are the gradient of W - D0(m, e3) phi(r),
phi(r) = r (1 - r / delta)^2 (phi'(0) = 1, zero with its slope from delta on), W the update's
own potential where the point unloads:

    s1 - s2 -> s1 - s2 - D0 phi'(r),   s1 + s2 -> s1 + s2 - dD0/dm phi(r),
    s3 -> s3 - dD0/de3 phi(r)   (axisymmetric: the hoop strain does work).

At r = 0 the difference vanishes (the stress is isotropic in the plane, whatever the axes), so
the stress is continuous; its rotation stiffness stays finite (of order D0 / delta); from r =
delta on it is the update's. Where the point unloads it is the gradient of a potential of the
strain, so no closed strain path makes energy (a correction of the difference alone does:
item 45 measured one that made 64 % of CF-4's external work in a drop). The law itself runs at
the strain asked for: its loading tests, damage and state are the thesis'. A point with the
same properties in directions 1 and 2 has D0 = 0 and is left as it is. Both kernels call this
after their own update, with their own update for D0 (the same bits); frozen points (the secant
scheme's held axes) are left as they are.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np

from icewall.materials.concrete_state import ConcreteState
from icewall.materials.orthotropic import global_strain, global_stress, local_normal_components
from icewall.materials.parameters import take_parameters

RESOLUTION = 2.0
"""delta, the strain below which the axes of the in-plane strain deviator are not resolved, in
cracking strains f't / E0."""


def continuous_axes(params: Any) -> bool:
    """Whether the law resolves its axes (`rotating_axes: continuous`)."""
    return getattr(params, "rotating_axes", "nearest") == "continuous"


def resolution(params: Any) -> float:
    """delta: RESOLUTION cracking strains f't / E0."""
    return RESOLUTION * float(params.ft) / float(params.E0)


def _phi(r: np.ndarray, delta: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """phi, phi', phi'' of r (each (n,)): r (1 - r / delta)^2 below delta, 0 from it on."""
    inside = r < delta
    x = np.where(inside, r / delta, 1.0)
    phi = np.where(inside, r * (1.0 - x) ** 2, 0.0)
    slope = np.where(inside, (1.0 - x) * (1.0 - 3.0 * x), 0.0)
    curvature = np.where(inside, (6.0 * x - 4.0) / delta, 0.0)
    return phi, slope, curvature


DIFFERENCE_STEP = 1e-6
"""Central-difference step of D0's derivatives, in cracking strains."""

Update = Callable[..., tuple[np.ndarray, Any, ConcreteState]]


def _inside(trial: ConcreteState, committed: ConcreteState, params: Any,
            frozen: np.ndarray | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(rows (k,) of the points within delta whose directions 1 and 2 differ in the committed
    state, their r (k,), their principal strains (k, 3))."""
    e = local_normal_components(trial.strain, trial.angle, 1.0)
    r = 0.5 * np.abs(e[:, 0] - e[:, 1])
    inside = r < resolution(params)
    if frozen is not None:
        inside &= ~np.asarray(frozen, dtype=bool)
    differ = ((committed.secant_modulus[:, 0] != committed.secant_modulus[:, 1])
              | (committed.poisson_ratio[:, 0] != committed.poisson_ratio[:, 1])
              | (committed.max_equivalent_uniaxial_strain[:, 0]
                 != committed.max_equivalent_uniaxial_strain[:, 1]))
    rows = np.nonzero(inside & differ)[0]
    return rows, r[rows], e[rows]


def _cone(rows: np.ndarray, e: np.ndarray, trial: ConcreteState, committed: ConcreteState,
          params: Any, formulation: str, update: Update, trial_stress: str
          ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """D0, dD0/dm, dD0/de3 (each (k,)) of the points `rows`: s1 - s2 of `update` from the
    committed state to their isotropic strains (m, m, e3) in their axes, and its central
    differences in m (e1 and e2 together) and, axisymmetric, in e3."""
    k, h = rows.size, DIFFERENCE_STEP * float(params.ft) / float(params.E0)
    mean = 0.5 * (e[:, 0] + e[:, 1])
    shifts = [(0.0, 0.0), (h, 0.0), (-h, 0.0)]
    if formulation == "axisymmetric":
        shifts += [(0.0, h), (0.0, -h)]
    principal = np.concatenate([np.stack([mean + dm, mean + dm, e[:, 2] + d3], axis=1)
                                for dm, d3 in shifts])
    angle = np.tile(trial.angle[rows], len(shifts))
    strain = global_strain(principal, angle)
    if formulation == "plane_stress":  # the update solves it
        strain[:, 2] = np.tile(committed.strain[rows, 2], len(shifts))
    index = np.tile(rows, len(shifts))
    base = replace(take_parameters(params, index, committed.n_points), rotating_axes="nearest")
    stress, _, at = update(strain, committed.take(index), base, formulation,
                           trial_stress=trial_stress, with_moduli=False)
    # in the update's own axes (the committed ones: the strain is isotropic)
    s = local_normal_components(stress, at.angle, 2.0).reshape(len(shifts), k, 3)
    height = s[:, :, 0] - s[:, :, 1]
    by_mean = (height[1] - height[2]) / (2.0 * h)
    by_zz = (height[3] - height[4]) / (2.0 * h) if len(shifts) == 5 else np.zeros(k)
    return height[0], by_mean, by_zz


def resolved_stress(trial: ConcreteState, committed: ConcreteState, params: Any,
                    formulation: str, update: Update, trial_stress: str = "corotational",
                    frozen: np.ndarray | None = None) -> np.ndarray:
    """The returned stress (n, 4) of the update (`update`, with its signature) that gave
    `trial` from `committed`: the trial's stress less the cone (module docstring) at the points
    within delta whose directions differ; the trial's stress itself (the same bits)
    elsewhere."""
    rows, r, e = _inside(trial, committed, params, frozen)
    if rows.size == 0:
        return trial.stress
    height, by_mean, by_zz = _cone(rows, e, trial, committed, params, formulation, update,
                                   trial_stress)
    phi, slope, _ = _phi(r, resolution(params))
    s = local_normal_components(trial.stress[rows], trial.angle[rows], 2.0)
    mean = 0.5 * (s[:, 0] + s[:, 1]) - 0.5 * by_mean * phi
    half = 0.5 * (s[:, 0] - s[:, 1] - height * slope)
    s[:, 0], s[:, 1] = mean + half, mean - half
    s[:, 2] = s[:, 2] - by_zz * phi
    out = trial.stress.copy()
    out[rows] = global_stress(s, trial.angle[rows])
    return out


def resolved_moduli(moduli: np.ndarray, trial: ConcreteState, committed: ConcreteState,
                    params: Any, formulation: str, update: Update,
                    trial_stress: str = "corotational") -> np.ndarray:
    """d s / d e (n, 3, 3) of the returned principal stresses from the update's (`moduli`, in
    the axes of `trial`): the cone's correction differentiated through r, m and e3 (D0's own
    second derivatives left out: zero where the point unloads)."""
    rows, r, e = _inside(trial, committed, params, None)
    if rows.size == 0:
        return moduli
    height, by_mean, by_zz = _cone(rows, e, trial, committed, params, formulation, update,
                                   trial_stress)
    sign = np.where(e[:, 0] >= e[:, 1], 1.0, -1.0)  # +1: direction 1 on the major strain
    phi, slope, curvature = _phi(r, resolution(params))
    L = moduli[rows]
    dr = np.zeros((rows.size, 3))  # d r / d e
    dr[:, 0], dr[:, 1] = 0.5 * sign, -0.5 * sign
    d_height = np.zeros((rows.size, 3))  # d D0 / d e = dD0/dm d m / d e + dD0/de3 d e3 / d e
    d_height[:, 0] = d_height[:, 1] = 0.5 * by_mean
    d_height[:, 2] = by_zz
    d_mean = (0.5 * (L[:, 0, :] + L[:, 1, :]) - 0.5 * (by_mean * slope)[:, None] * dr)
    d_half = 0.5 * ((L[:, 0, :] - L[:, 1, :]) - slope[:, None] * d_height
                    - (height * curvature)[:, None] * dr)
    out = moduli.copy()
    out[rows, 0, :], out[rows, 1, :] = d_mean + d_half, d_mean - d_half
    out[rows, 2, :] = L[:, 2, :] - (by_zz * slope)[:, None] * dr
    return out
