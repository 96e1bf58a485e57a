"""Consistent tangent d sigma / d eps of the rotating-crack concrete update (thesis Fig. 3.12).

At a fixed committed state the update returns a stress coaxial with the total strain: with
theta the principal-strain angle and e the principal strains (e_3 = zz),

    sigma = T(theta)^T [s(e, theta), 0],     s = (s_1, s_2, s_3) the principal stresses.

Its derivative has the rotating-crack structure (Rots 1988, §4.4; Feenstra 1993, §3.5;
de Borst et al. 2012, §7.3): in the principal axes, with the engineering shear gamma_12,

    d [s_1, s_2, s_3, tau_12] = L d [e_1, e_2, e_3, gamma_12],

    L = | d s_i / d e_j    (d s_i / d theta) / (2 (e_1 - e_2)) |
        |      0           G = (s_1 - s_2) / (2 (e_1 - e_2))   |

(d theta = d gamma_12 / (2 (e_1 - e_2)): a shear strain in the principal axes rotates them and
the principal stresses with them), and d sigma / d eps = T^T L T. The corotational and total
trial stresses depend on e only (d s / d theta = 0); the incremental one rotates the committed
stress into the new axes and also depends on theta.

Where e_1 -> e_2 the quotient G is replaced by its limit (d s_1/d e_1 - d s_1/d e_2 - d s_2/d e_1
+ d s_2/d e_2) / 4, the derivative of s_1 - s_2 along e_1 - e_2 (exact where the two directions
share their history, e.g. an uncracked isotropic point; elsewhere s_1 - s_2 does not vanish
with e_1 - e_2 and the update is not differentiable there); the theta column is dropped.

The principal moduli d s_i / d e_j (and d s / d theta) are central differences in the
principal frame: each perturbation keeps the axes (or turns them by a small angle), so the
differences see a smooth function of 2-3 variables whose branches (loading, unloading,
softening, the strength surface on the ray of the trial stress, plane-stress condensation) are
all those of the update itself, whichever `update` is passed (NumPy, sub-stepped or compiled).
All perturbations of all points are one batched call.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from icewall.materials.concrete import take_parameters, update_concrete
from icewall.materials.concrete_state import ConcreteState
from icewall.materials.orthotropic import global_strain, local_normal_components, strain_rotation

RELATIVE_STEP = 1e-6
"""Central-difference step on the principal strains, relative to the point's strain size (at
least the cracking strain f't / E0): truncation ~(k h)^2 on a softening branch exp(-k eps)."""
ANGLE_STEP = 1e-6
"""Central-difference step on the principal angle (rad), incremental trial only."""
EQUAL_STRAIN_TOLERANCE = 1e-8
"""|e_1 - e_2| below this fraction of the strain size takes the limit of G (round-off of the
quotient ~1e-16 / tolerance, error of the limit ~tolerance)."""

Update = Callable[..., tuple[np.ndarray, Any, ConcreteState]]


def _strain_size(strain: np.ndarray, params: Any) -> np.ndarray:
    """Per-point strain scale (n,): the largest component, at least the cracking strain."""
    return np.maximum(np.abs(strain).max(axis=1), float(params.ft) / float(params.E0))


def _perturbations(strain: np.ndarray, angle: np.ndarray, columns: list[int], step: np.ndarray,
                   principal: np.ndarray, rotate: bool) -> np.ndarray:
    """Perturbed strains (2k, n, 4): +- step along each principal column, then (with `rotate`)
    the principal strains turned by +- ANGLE_STEP."""
    perturbed = []
    for j in columns:
        unit = np.zeros_like(principal)
        unit[:, j] = 1.0
        direction = step[:, None] * global_strain(unit, angle)
        perturbed += [strain + direction, strain - direction]
    if rotate:
        for sign in (1.0, -1.0):
            turned = global_strain(principal, angle + sign * ANGLE_STEP)
            turned[:, 2] = strain[:, 2]
            perturbed.append(turned)
    return np.stack(perturbed)


def _shear_modulus(principal_stress: np.ndarray, principal_strain: np.ndarray,
                   moduli: np.ndarray, size: np.ndarray) -> np.ndarray:
    """G = (s_1 - s_2) / (2 (e_1 - e_2)), its limit where e_1 ~ e_2 (module docstring)."""
    difference = principal_strain[:, 0] - principal_strain[:, 1]
    distinct = np.abs(difference) > EQUAL_STRAIN_TOLERANCE * size
    quotient = (principal_stress[:, 0] - principal_stress[:, 1]) / (
        2.0 * np.where(distinct, difference, 1.0))
    limit = 0.25 * (moduli[:, 0, 0] - moduli[:, 0, 1] - moduli[:, 1, 0] + moduli[:, 1, 1])
    return np.where(distinct, quotient, limit)


def update_with_tangent(strain: np.ndarray, state: ConcreteState, params: Any,
                        formulation: str, trial_stress: str = "corotational",
                        update: Update = update_concrete
                        ) -> tuple[np.ndarray, np.ndarray, ConcreteState]:
    """Stress (n, 4), consistent tangent (n, 4, 4) and trial state of `update` at `strain`.

    `update(strain, state, params, formulation, trial_stress=, with_moduli=False)` is the
    stress update the solver calls (`update_concrete`, its sub-stepped or compiled form). The
    tangent is d sigma / d eps of that map at the fixed committed `state`, unsymmetric in
    general and indefinite on softening branches; no floor or secant option applies to it.
    plane_strain: eps_zz is not an input (column zz zero); plane_stress: sigma_zz = 0 is
    condensed (row and column zz zero); axisymmetric: all four components.
    """
    strain = np.asarray(strain, dtype=float).reshape(-1, 4)
    n = strain.shape[0]
    stress, _, trial = update(strain, state, params, formulation, trial_stress=trial_stress,
                              with_moduli=False)
    angle = trial.angle
    principal = local_normal_components(trial.strain, angle, 1.0)
    principal_stress = local_normal_components(stress, angle, 2.0)
    size = _strain_size(trial.strain, params)
    step = RELATIVE_STEP * size
    columns = [0, 1, 2] if formulation == "axisymmetric" else [0, 1]
    rotate = trial_stress == "incremental"
    perturbed = _perturbations(strain, angle, columns, step, principal, rotate)
    copies = perturbed.shape[0]
    index = np.tile(np.arange(n), copies)
    response, _, _ = update(perturbed.reshape(-1, 4), state.take(index),
                            take_parameters(params, index, n), formulation,
                            trial_stress=trial_stress, with_moduli=False)
    local = local_normal_components(response, np.tile(angle, copies), 2.0).reshape(copies, n, 3)

    L = np.zeros((n, 4, 4))
    for k, j in enumerate(columns):
        L[:, :3, j] = (local[2 * k] - local[2 * k + 1]) / (2.0 * step[:, None])
    L[:, 3, 3] = _shear_modulus(principal_stress, principal, L, size)
    if rotate:  # d s / d theta, d theta = d gamma_12 / (2 (e_1 - e_2))
        difference = principal[:, 0] - principal[:, 1]
        distinct = np.abs(difference) > EQUAL_STRAIN_TOLERANCE * size
        by_angle = (local[-2] - local[-1]) / (2.0 * ANGLE_STEP)
        L[:, :3, 3] = np.where(distinct[:, None], by_angle, 0.0) / (
            2.0 * np.where(distinct, difference, 1.0))[:, None]
    if formulation == "plane_stress":
        L[:, 2, :] = 0.0
    T = strain_rotation(angle)
    return stress, np.matmul(T.transpose(0, 2, 1), np.matmul(L, T)), trial


def consistent_tangent(strain: np.ndarray, state: ConcreteState, params: Any, formulation: str,
                       trial_stress: str = "corotational", update: Update = update_concrete
                       ) -> np.ndarray:
    """d sigma / d eps (n, 4, 4) of `update` at fixed committed state (`update_with_tangent`)."""
    return update_with_tangent(strain, state, params, formulation, trial_stress, update)[1]
