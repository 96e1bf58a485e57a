"""Consistent tangent d sigma / d eps of the rotating-crack concrete update (thesis Fig. 3.12).

At a fixed committed state the update returns a stress coaxial with the total strain: with
theta the principal-strain angle and e the principal strains (e_3 = zz),

    sigma = T(theta)^T [s(e, theta), 0],     s = (s_1, s_2, s_3) the principal stresses.

Its derivative has the rotating-crack structure (Rots 1988; Feenstra 1993; de Borst et al.,
Nonlinear Finite Element Analysis of Solids and Structures, ch. 7): in the principal axes,
with the engineering shear gamma_12,

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

The principal moduli d s_i / d e_j are analytic for the corotational (deck default) and total
trial stresses (`principal_moduli`): d s / d trial on the branch each direction took, times
d trial / d e = C_l(E_i, nu_i) of the committed state (plane stress: condensed). Unloading:
s_i = trial_i. Loading onto the envelope: the slope of eqs. 3.9-3.11 in eps_iu = trial_i / E_i
plus its slope in sigma_ic (directly and through eps_ic, errata §2.4), where sigma_ic = s trial_i
moves with the whole trial stress on the strength surface (d s / d trial by implicit
differentiation of eq. 3.15, `ultimate_surface.strength_scale_gradient`), unless a §3.2.5 rule
or the uniaxial fallback fixes it. At a kink (the loading test, a mode rule switching) that is
the derivative of the branch the update took: a zero increment unloads, so the tangent at the
committed state is its unloading (secant) one.

For the incremental trial (rotated committed stress, sub-stepped in the structure) the
principal moduli and d s / d theta are central differences in the principal frame: each
perturbation keeps the axes (or turns them by ANGLE_STEP), so the differences see the update's
own branches, whichever `update` is passed (NumPy, sub-stepped or compiled); all perturbations
of all points are one batched call. Near kinks they average the two sides.

Cost on 1125 CF-4-like points (plane strain, 70 % cracked; min of 40 runs, 2-core machine):
`update_concrete` 1.6 ms, with the analytic tangent 3.2 ms (numba update: 1.8 ms); by
differences 7.6 ms (numba update: 2.9 ms). Both agree to ~1e-9 away from kinks.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from icewall.materials.concrete import (
    _envelope,
    loading_directions,
    past_peak,
    update_concrete,
)
from icewall.materials.concrete_state import ConcreteState
from icewall.materials.envelope_slopes import envelope_slopes, scaled_slopes
from icewall.materials.mode_rules import mode_rule_weights
from icewall.materials.orthotropic import (
    condense_plane_stress,
    global_strain,
    local_normal_components,
    orthotropic_normal_stiffness,
    strain_rotation,
)
from icewall.materials.parameters import take_parameters
from icewall.materials.rotation import continuous_axes, resolved_moduli
from icewall.materials.ultimate_surface import strength_scale, strength_scale_gradient

RELATIVE_STEP = 1e-6
"""Central-difference step on the principal strains, relative to the point's strain size (at
least the cracking strain f't / E0): truncation ~(k h)^2 on a softening branch exp(-k eps)."""
ANGLE_STEP = 1e-6
"""Central-difference step on the principal angle (rad), incremental trial only."""
EQUAL_STRAIN_TOLERANCE = 1e-8
"""|e_1 - e_2| below this fraction of the strain size takes the limit of G (round-off of the
quotient ~1e-16 / tolerance, error of the limit ~tolerance)."""

MAX_SCALE = 100.0
"""`equivalent_uniaxial_strengths`' cap on the strength ray (max_scale, times f'c)."""

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


def _trial_jacobian(state: ConcreteState, formulation: str) -> np.ndarray:
    """d trial / d e (n, 3, 3): the committed C_l(E_i, nu_i) of Fig. 3.12 step 3 (errata §3);
    plane strain: e_3 fixed; plane stress: sigma_3t = 0 condensed (row and column 3 zero)."""
    stiffness = orthotropic_normal_stiffness(state.secant_modulus, state.poisson_ratio)
    if formulation == "plane_stress":
        return condense_plane_stress(stiffness)
    if formulation == "plane_strain":
        stiffness[:, :, 2] = 0.0
    return stiffness


def _strength_jacobian(trial: np.ndarray, strength: np.ndarray, loading: np.ndarray,
                       params: Any) -> np.ndarray:
    """d sigma_ic / d trial (m, 3, 3) of `equivalent_uniaxial_strengths` for the `loading`
    directions, whose sigma_ic (`strength`) the update computed: s sigma_i on the ray of the
    trial stress (§3.2.4), or constant where a §3.2.5 mode rule or the uniaxial fallback set
    it. The scale s is read back from a direction on the ray (s = sigma_ic / sigma_i) instead
    of solving the surface again."""
    largest = np.abs(trial).max(axis=1, keepdims=True)
    zero = (np.abs(trial) <= 1e-6 * largest) | (largest <= 1e-12 * params.fc)
    if params.mode_rule_band > 0.0:
        return _blended_strength_jacobian(trial, strength, zero, loading, params)
    tension, compression = (trial > 0.0) & ~zero, (trial < 0.0) & ~zero
    any_tension = tension.any(axis=1, keepdims=True)
    any_compression = compression.any(axis=1, keepdims=True)
    reading = params.compression_tension_rule
    rule_b = (np.zeros_like(zero) if reading == "equal" else strength > -params.fc
              if reading == "cap" else strength < -params.fc)  # floor: min(s sigma, -f'c)
    follows = np.where(compression & any_tension, rule_b,
                       np.where(tension & ~any_compression, strength > params.ft, True))
    follows &= loading & ~zero
    derivative = np.zeros(trial.shape + (3,))
    rows = np.nonzero(follows.any(axis=1))[0]
    if rows.size:
        p = trial[rows]
        first = np.argmax(follows[rows], axis=1)
        scale = (np.take_along_axis(strength[rows], first[:, None], axis=1)
                 / np.take_along_axis(p, first[:, None], axis=1))[:, 0]
        capped = scale * np.abs(p).max(axis=1) >= (1.0 - 1e-9) * MAX_SCALE * params.fc
        gradient = strength_scale_gradient(p, scale, params.fc, params.surface, capped)
        derivative[rows] = scale[:, None, None] * np.eye(3) + p[:, :, None] * gradient[:, None, :]
    return derivative * follows[:, :, None]


def _blended_strength_jacobian(trial: np.ndarray, strength: np.ndarray, zero: np.ndarray,
                               loading: np.ndarray, params: Any) -> np.ndarray:
    """`_strength_jacobian` with the mode rules blended over a band (`mode_rule_weights`):
    sigma_ic = (1 - w) s sigma_i + w rule_i, so d sigma_ic = (1 - w + w [rule_i follows the
    ray]) d(s sigma_i) + (rule_i - s sigma_i) dw, w a clipped linear function of the largest
    tension (rule (b)) or compression (rule (c)). The scale s is read back from a component
    whose sigma_ic is on the ray (weight 0, or weight 1 with the rule following the ray), and
    solved again only for rows without one."""
    fc, ft, band = params.fc, params.ft, params.mode_rule_band * params.ft
    active = loading & ~zero
    derivative = np.zeros(trial.shape + (3,))
    rows = np.nonzero(active.any(axis=1))[0]
    if rows.size == 0:
        return derivative
    p, nil, given = trial[rows], zero[rows], strength[rows]
    compression = (p < 0.0) & ~nil  # the rest: tension (zero components are not active)
    in_tension, in_compression = mode_rule_weights(p, nil, params)
    weight = np.where(compression, in_tension, in_compression)
    reading = params.compression_tension_rule
    equal = reading == "equal"
    followed_b = False if equal else (given > -fc if reading == "cap" else given < -fc)
    ray_followed = np.where(compression, followed_b, given > ft)
    # (only a loading direction's sigma_ic is the update's for this trial stress)
    readable = active[rows] & ((weight == 0.0) | ((weight == 1.0) & ray_followed))
    scale = np.empty(p.shape[0])
    has = readable.any(axis=1)
    first = np.argmax(readable, axis=1)[has]
    scale[has] = given[has, first] / p[has, first]
    if not has.all():
        scale[~has] = strength_scale(p[~has], fc, params.surface, max_scale=MAX_SCALE)
    capped = scale * np.abs(p).max(axis=1) >= (1.0 - 1e-9) * MAX_SCALE * fc
    on_ray = p * scale[:, None]
    ray_slope = (scale[:, None, None] * np.eye(3)
                 + p[:, :, None] * strength_scale_gradient(p, scale, fc, params.surface,
                                                           capped)[:, None, :])
    rule = np.where(compression, -fc if equal else np.minimum(on_ray, -fc),
                    np.maximum(on_ray, ft))
    follows = np.where(compression, False if equal else on_ray < -fc, on_ray > ft)
    # dw / d sigma_j: at the largest tension (rule (b)) or compression (rule (c)), in the band
    nonzero = np.where(nil, 0.0, p)
    by_tension = np.zeros_like(p)
    by_compression = np.zeros_like(p)
    index = np.arange(p.shape[0])
    inside = (in_tension[:, 0] > 0.0) & (in_tension[:, 0] < 1.0)
    by_tension[index, np.argmax(nonzero, axis=1)] = np.where(inside, 1.0 / band, 0.0)
    inside = (in_compression[:, 0] > 0.0) & (in_compression[:, 0] < 1.0)
    by_compression[index, np.argmax(-nonzero, axis=1)] = np.where(inside, 1.0 / band, 0.0)
    weight_slope = np.where(compression[:, :, None], by_tension[:, None, :],
                            by_compression[:, None, :])
    blended = (((1.0 - weight) + weight * follows)[:, :, None] * ray_slope
               + (rule - on_ray)[:, :, None] * weight_slope)
    derivative[rows] = blended
    return derivative * active[:, :, None]


def principal_moduli(trial_state: ConcreteState, state: ConcreteState, params: Any,
                     formulation: str) -> np.ndarray:
    """d s_i / d e_j (n, 3, 3) at fixed axes of the corotational (or total) update whose trial
    state is `trial_state`, on the branches it took (Fig. 3.12 steps 3-6).

    Unloading (and a direction held on its secant): s_i = trial_i. Loading onto the envelope:
    s_i = sign(eps_iu) sigma_env(|eps_iu|; sigma_ic, eps_ic), eps_iu = trial_i / E_i, with
    sigma_ic on the ray of the whole trial stress (the strength surface couples the
    directions) and eps_ic(sigma_ic). Then d s / d e = (d s / d trial) C_l.
    """
    E = state.secant_modulus
    eps_u = trial_state.equivalent_uniaxial_strain
    trial = eps_u * E  # eps_iu = trial / E_i (step 4)
    loading, sign_change = loading_directions(trial, eps_u, state, params)
    response = np.tile(np.eye(3), (trial.shape[0], 1, 1))  # d s / d trial
    rows = np.nonzero(loading.any(axis=1))[0]
    if rows.size:  # a loading direction's sigma_ic, eps_ic are in the trial state
        strength = trial_state.uniaxial_strength[rows]
        peak_strain = trial_state.uniaxial_peak_strain[rows]
        kept = past_peak(eps_u[rows], state.cracked[rows], state.crushed[rows],
                         sign_change[rows], params)  # their sigma_ic is a constant
        strength_slope = _strength_jacobian(trial[rows], strength, loading[rows] & ~kept,
                                            params)
        here, secant = _envelope(eps_u[rows], strength, peak_strain, params, rows)
        by_eps, by_strength = envelope_slopes(eps_u[rows], strength, peak_strain, params, rows)
        if getattr(params, "fallen_strength", "envelope") == "scaled":
            secant, by_eps, by_strength = scaled_slopes(
                eps_u[rows], strength, peak_strain, here, secant, by_eps, by_strength,
                state.max_equivalent_uniaxial_strain[rows], E[rows], sign_change[rows],
                params, rows, loading[rows])
        heal = ~sign_change[rows] & (secant > E[rows])  # loads along its secant: s = trial
        on_envelope = loading[rows] & ~heal
        loaded = ((by_eps / E[rows])[:, :, None] * np.eye(3)
                  + (np.sign(eps_u[rows]) * np.sign(strength) * by_strength)[:, :, None]
                  * strength_slope)
        response[rows] = np.where(on_envelope[:, :, None], loaded, response[rows])
    if formulation == "plane_stress":
        response[:, 2, :] = 0.0
    return np.matmul(response, _trial_jacobian(state, formulation))


def _differenced_moduli(strain: np.ndarray, state: ConcreteState, params: Any,
                        formulation: str, trial_stress: str, update: Update,
                        angle: np.ndarray, principal: np.ndarray, size: np.ndarray
                        ) -> np.ndarray:
    """Local tangent (n, 4, 4) without G: d s / d e by central differences in the principal
    frame and, for the incremental trial, the column (d s / d theta) / (2 (e_1 - e_2))."""
    n = strain.shape[0]
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
    if rotate:  # d s / d theta, d theta = d gamma_12 / (2 (e_1 - e_2))
        difference = principal[:, 0] - principal[:, 1]
        distinct = np.abs(difference) > EQUAL_STRAIN_TOLERANCE * size
        by_angle = (local[-2] - local[-1]) / (2.0 * ANGLE_STEP)
        L[:, :3, 3] = np.where(distinct[:, None], by_angle, 0.0) / (
            2.0 * np.where(distinct, difference, 1.0))[:, None]
    return L


def update_with_tangent(strain: np.ndarray, state: ConcreteState, params: Any,
                        formulation: str, trial_stress: str = "corotational",
                        update: Update = update_concrete, method: str = "auto"
                        ) -> tuple[np.ndarray, np.ndarray, ConcreteState]:
    """Stress (n, 4), consistent tangent (n, 4, 4) and trial state of `update` at `strain`.

    `update(strain, state, params, formulation, trial_stress=, with_moduli=False)` is the
    stress update the solver calls (`update_concrete`, its sub-stepped or compiled form). The
    tangent is d sigma / d eps of that map at the fixed committed `state` (`tangent_of_update`).
    """
    strain = np.asarray(strain, dtype=float).reshape(-1, 4)
    stress, _, trial = update(strain, state, params, formulation, trial_stress=trial_stress,
                              with_moduli=False)
    return stress, tangent_of_update(strain, stress, trial, state, params, formulation,
                                     trial_stress, update, method), trial


def tangent_of_update(strain: np.ndarray, stress: np.ndarray, trial: ConcreteState,
                      state: ConcreteState, params: Any, formulation: str,
                      trial_stress: str = "corotational", update: Update = update_concrete,
                      method: str = "auto") -> np.ndarray:
    """Consistent tangent (n, 4, 4) of `update` at `strain`, where it gave `stress` and the
    trial state `trial` from the committed `state` (no second update on the analytic path).

    Unsymmetric in general and indefinite on softening branches; no floor or secant option
    applies to it. plane_strain: eps_zz is not an input (column zz zero); plane_stress:
    sigma_zz = 0 is condensed (row and column zz zero); axisymmetric: all four components.

    `method`: "analytic" principal moduli (`principal_moduli`; corotational and total trial
    stresses, which are not sub-stepped), "differences" (any trial stress and update: `update`
    is called again at perturbed strains), or "auto": analytic unless the trial stress is
    incremental.
    """
    strain = np.asarray(strain, dtype=float).reshape(-1, 4)
    angle = trial.angle
    principal = local_normal_components(trial.strain, angle, 1.0)
    principal_stress = local_normal_components(stress, angle, 2.0)
    size = _strain_size(trial.strain, params)
    if method == "auto":
        method = "differences" if trial_stress == "incremental" else "analytic"
    if method == "analytic":
        if trial_stress == "incremental":
            raise ValueError("the analytic concrete tangent covers the corotational and total "
                             "trial stresses; use method='differences'")
        L = np.zeros((strain.shape[0], 4, 4))
        L[:, :3, :3] = principal_moduli(trial, state, params, formulation)
        if continuous_axes(params):  # the cone taken out of the returned stress (rotation.py)
            L[:, :3, :3] = resolved_moduli(L[:, :3, :3], trial, state, params, formulation,
                                           update, trial_stress)
    elif method == "differences":
        L = _differenced_moduli(strain, state, params, formulation, trial_stress, update, angle,
                                principal, size)
    else:
        raise ValueError(f"unknown tangent method {method!r}; expected auto, analytic or "
                         "differences")
    L[:, 3, 3] = _shear_modulus(principal_stress, principal, L, size)
    if formulation == "plane_stress":
        L[:, 2, :] = 0.0
    T = strain_rotation(angle)
    return np.matmul(T.transpose(0, 2, 1), np.matmul(L, T))


def consistent_tangent(strain: np.ndarray, state: ConcreteState, params: Any, formulation: str,
                       trial_stress: str = "corotational", update: Update = update_concrete,
                       method: str = "auto") -> np.ndarray:
    """d sigma / d eps (n, 4, 4) of `update` at fixed committed state (`update_with_tangent`)."""
    return update_with_tangent(strain, state, params, formulation, trial_stress, update,
                               method)[1]
