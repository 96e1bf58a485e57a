"""Slopes of the envelope stress of a loading direction (concrete._envelope: eqs. 3.9-3.11 with
errata 1.1 and §3) in |eps_iu| and in |sigma_ic| (through eps_ic, errata §2.4), and of the
envelope scaled through the committed point (`fallen_strength: scaled`); used by
concrete_tangent's analytic principal moduli."""

from __future__ import annotations

from typing import Any

import numpy as np

from icewall.materials.concrete import _envelope, _point_column
from icewall.materials.concrete_formulas import FALLEN_RANGE, scaled_envelope
from icewall.materials.uniaxial import SECANT_FLOOR


def peak_strain_slope(strength: np.ndarray, params: Any) -> np.ndarray:
    """d |eps_ic| / d |sigma_ic| of `equivalent_uniaxial_peak_strains` (errata §2.4)."""
    magnitude = np.abs(strength)
    R = magnitude / params.fc
    slope_m = params.peak_strain_slope
    compression = strength < 0.0
    ratio = np.where(R >= 1.0, 1.0 + slope_m * (R - 1.0), (-1.6 * R + 2.25) * R * R + 0.35 * R)
    ratio_slope = np.where(R >= 1.0, slope_m, (-4.8 * R + 4.5) * R + 0.35)
    raw = np.where(compression, ratio * params.eps_c, magnitude * params.eps_t / params.ft)
    slope = np.where(compression, ratio_slope * params.eps_c / params.fc,
                     params.eps_t / params.ft)
    return np.where(magnitude / params.E0 > raw, 1.0 / params.E0, slope)


def envelope_slopes(eps_u: np.ndarray, strength: np.ndarray, peak_strain: np.ndarray,
                     params: Any, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Slopes of the envelope stress magnitude (concrete._envelope, eqs. 3.9-3.11 with errata
    1.1 and §3) in |eps_iu| and in |sigma_ic| (through eps_ic as well), (m, 3) each."""
    E0 = float(params.E0)
    eps, peak, peak_eps = np.abs(eps_u), np.abs(strength), np.abs(peak_strain)
    decay = np.where(eps_u > 0.0, _point_column(params.k_t, rows),
                     _point_column(params.k_c, rows))
    rising = eps <= peak_eps
    # Saenz (eq. 3.9): sigma = E0 eps / D, D = 1 + (R_E - 2) x + x^2, capped at the line E0 eps
    raw_ratio = E0 * peak_eps / peak
    R_E = np.maximum(raw_ratio, 1.0)
    x = np.minimum(eps, peak_eps) / peak_eps
    D = 1.0 + (R_E - 2.0) * x + x * x
    capped = D <= 1.0
    steep = raw_ratio > 1.0  # R_E not clamped at 1 (eq. 3.10)
    dD_deps = (R_E - 2.0 + 2.0 * x) / peak_eps
    dD_dpeak_eps = x * np.where(steep, E0 / peak, 0.0) - (R_E - 2.0 + 2.0 * x) * x / peak_eps
    dD_dpeak = x * np.where(steep, -raw_ratio / peak, 0.0)
    a = E0 * eps / (D * D)
    rise = (np.where(capped, E0, E0 / D - a * dD_deps), np.where(capped, 0.0, -a * dD_dpeak),
            np.where(capped, 0.0, -a * dD_dpeak_eps))
    # decay (eq. 3.11 corrected): sigma = sigma_ic exp(-k (eps - eps_ic))
    with np.errstate(over="ignore"):
        fall_stress = peak * np.exp(-decay * np.clip(eps - peak_eps, 0.0, 1e300))
    fall = (-decay * fall_stress, fall_stress / peak, decay * fall_stress)
    by_eps, by_peak, by_peak_eps = (np.where(rising, r, f) for r, f in zip(rise, fall,
                                                                             strict=True))
    return by_eps, by_peak + by_peak_eps * peak_strain_slope(strength, params)


def scaled_slopes(eps_u: np.ndarray, strength: np.ndarray, peak_strain: np.ndarray,
                   here: np.ndarray, secant: np.ndarray, by_eps: np.ndarray,
                   by_strength: np.ndarray, max_eps_u: np.ndarray, E: np.ndarray,
                   sign_change: np.ndarray, params: Any, rows: np.ndarray,
                   loading: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(secant, slope in |eps_iu|, slope in |sigma_ic|) of the envelope scaled through the
    committed point (`fallen_strength: scaled`, concrete_formulas.scaled_envelope): s = c
    sigma_env(eps), c = E_i max / sigma_env(max), both envelopes moving with sigma_ic. Only the
    `loading` directions are scaled (the others' slopes are not used): far down a branch the
    envelope at max |eps_iu| underflows, and its quotient would overflow for nothing."""
    signed_max = np.copysign(max_eps_u, eps_u)
    at_max, _ = _envelope(signed_max, strength, peak_strain, params, rows)
    at_max = np.where(loading, at_max, 0.0)  # 0: not fallen, the envelope as it is
    line = E * max_eps_u
    _, scaled_secant = scaled_envelope(here, secant, at_max, line, sign_change, SECANT_FLOOR,
                                       _point_column(params.E0, rows))
    fallen = ~sign_change & (at_max > FALLEN_RANGE * line) & (line > at_max)
    at_max_safe = np.where(fallen, at_max, 1.0)
    scale = np.where(fallen, line / at_max_safe, 1.0)
    _, by_strength_at_max = envelope_slopes(signed_max, strength, peak_strain, params, rows)
    by_strength = scale * (by_strength - np.where(fallen, here / at_max_safe, 0.0)
                           * by_strength_at_max)
    return scaled_secant, scale * by_eps, by_strength
