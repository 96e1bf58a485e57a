"""Equivalent-uniaxial strengths and peak strains of a principal stress state: thesis §3.2.4's
ray to the ultimate surface (`ultimate_surface.strength_scale`) and the mode rules of §3.2.5
read with signed stresses (errata §3), sharp or blended over a band; peak strains per errata
§2.4. Conventions: tension positive, f'c > 0 a magnitude, units MPa.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from icewall.materials.concrete_formulas import (
    MAX_SCALE,
    ZERO_TOLERANCE,
    mode_rule_strength,
    mode_rule_weight,
    peak_strain,
    zero_component,
)
from icewall.materials.ultimate_surface import strength_scale

if TYPE_CHECKING:
    from icewall.materials.parameters import ConcreteParameters


def equivalent_uniaxial_strengths(principal: ArrayLike, params: ConcreteParameters, *,
                                  strain_sign: ArrayLike | None = None,
                                  zero_tol: float = ZERO_TOLERANCE,
                                  max_scale: float = MAX_SCALE) -> np.ndarray:
    """Signed sigma_ic (n,3) (negative = compression), in the columns' own order.

    sigma_ic = s sigma_i on the proportional ray (§3.2.4), then the §3.2.5 mode rules read
    with signed stresses (errata §3 "Sign convention"): (a) triaxial compression: from the
    surface; (b) compression-tension: tension from the surface, compression equal to f'c
    (params.compression_tension_rule "equal") or at least f'c in magnitude ("floor");
    (c) all-tension: tension at least f't; with ``params.mode_rule_band`` > 0 rules (b) and
    (c) blend in over a band of the other components' stresses (`mode_rule_weights`).
    Components with |sigma_i| <= zero_tol
    max|sigma| (e.g. sigma3 = 0 in plane stress) and all components of a zero state
    (max|sigma| <= 1e-12 f'c) fall back to the uniaxial values (errata §3, "Using the strength
    surface"): -f'c where ``strain_sign`` (e.g. sign of eps_iu) or else the stress is negative,
    +f't otherwise. Mode counts use only the non-fallback components.
    """
    p = np.atleast_2d(np.asarray(principal, dtype=float))
    fc, ft = params.fc, params.ft
    printed_lode = "eq3.13" in getattr(params, "printed_forms", ())
    s = np.asarray(strength_scale(p, fc, params.surface, max_scale=max_scale,
                                  printed_lode=printed_lode))
    zero = zero_component(p, np.max(np.abs(p), axis=1, keepdims=True), fc, zero_tol)
    hint = p if strain_sign is None else np.broadcast_to(np.asarray(strain_sign, float), p.shape)
    any_tension = ((p > 0.0) & ~zero).any(axis=1, keepdims=True)
    any_compression = ((p < 0.0) & ~zero).any(axis=1, keepdims=True)
    banded = params.mode_rule_band > 0.0  # the rules blend in over the band
    in_tension, in_compression = mode_rule_weights(p, zero, params) if banded else (0.0, 0.0)
    # rule (b): "the compressive strength/strain is set equal to the uniaxial strength/strain
    # ... if the calculated values from the ultimate surfaces are greater": read in magnitudes
    # a cap, read signed (errata §3) a floor; "equal" applies both, "floor" the errata's
    out = mode_rule_strength(p, s[:, None] * p, zero, hint, any_tension, any_compression,
                             in_tension, in_compression, fc, ft,
                             params.compression_tension_rule == "equal", banded)
    if params.compression_tension_rule == "cap":  # read in magnitudes: at most f'c
        compressive, scaled = (p < 0.0) & ~zero, s[:, None] * p
        weight = in_tension if banded else any_tension.astype(float)
        out = np.where(compressive, (1.0 - weight) * scaled
                       + weight * np.maximum(scaled, -fc), out)
    return out


def mode_rule_weights(principal: np.ndarray, zero: np.ndarray, params: ConcreteParameters
                      ) -> tuple[np.ndarray, np.ndarray]:
    """How far rules (b) and (c) of §3.2.5 apply, (n, 1) each, with a band of width
    b = ``params.mode_rule_band`` f't: rule (b) (a compressive component in a compression-
    tension state) by min(t / b, 1), t the largest tension; rule (c) (a tensile component in
    all-tension) by 1 - min(c / b, 1), c the largest compression (zero components count
    neither). With b = 0 the thesis' sharp rules, whose strengths jump where a principal
    stress changes sign (docs/solver.md items 7, 10 and 18); the band makes them continuous
    and leaves every state with no principal stress of the other sign within b unchanged."""
    band = params.mode_rule_band * params.ft
    nonzero = np.where(zero, 0.0, principal)
    tension = np.max(np.maximum(nonzero, 0.0), axis=1, keepdims=True)
    compression = np.max(np.maximum(-nonzero, 0.0), axis=1, keepdims=True)
    return mode_rule_weight(tension, band), 1.0 - mode_rule_weight(compression, band)


def equivalent_uniaxial_peak_strains(sigma_ic: ArrayLike, params: ConcreteParameters
                                     ) -> np.ndarray:
    """Signed eps_ic (n,3) for the signed strengths sigma_ic (errata §2.4 substitute for the
    lost Elwi-Murray strain surface).

    Compression, R = |sigma_ic|/f'c: eps_ic/eps_c = 1 + m (R - 1) for R >= 1 (m =
    ``params.peak_strain_slope`` = 3: 3R - 2) and -1.6R^3 + 2.25R^2 + 0.35R for R < 1
    (Darwin & Pecknold 1977 as quoted in errata §2.4; not re-verified). Tension:
    eps_ic = eps_t sigma_ic / f't (linear branch). Finally |eps_ic| >= |sigma_ic|/E0, so that
    R_E = E0 eps_ic / sigma_ic >= 1 (errata §2.4); where clamped the ascending branch is linear.
    """
    return peak_strain(np.atleast_2d(np.asarray(sigma_ic, dtype=float)), params.fc, params.ft,
                       params.eps_c, params.eps_t, params.E0, params.peak_strain_slope)
