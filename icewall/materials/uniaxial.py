"""Equivalent-uniaxial stress-strain curves of concrete (thesis §3.2.3, §3.2.7).

All functions take broadcastable arrays and work in MAGNITUDES: strains and stresses are >= 0
(the sign of a negative strain is ignored); the caller attaches the sign of the direction.

- ascending branch: Saenz (1964), eqs. 3.9-3.10, with the secant capped at E0 (errata §3,
  "Saenz branch with the thesis' inputs": R_E = E0 eps_c / f'c < 2 for f'c > 30.25 MPa, so the
  raw curve starts convex and its secant exceeds E0). With ``peak_strain = peak/E0`` (R_E = 1,
  the tension choice of errata §3 "Tension peak strain is undefined") the capped curve is
  exactly linear up to the peak.
- descending branch: exponential decay from the peak, eq. 3.11 corrected per errata §1.1
  (magnitudes, and the peak strain of the branch itself, eps_t in tension).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from icewall.materials import concrete_formulas as formulas
from icewall.materials.concrete_formulas import decay_exponent

#: Lower bound of the returned secant modulus, as a fraction of E0 (keeps stiffness matrices
#: non-singular far down the softening branch). It applies to the secant only: use the returned
#: stress, not ``secant * strain``, which would exceed the stress there.
SECANT_FLOOR = 1.0e-6


def _mag(x: ArrayLike) -> np.ndarray:
    return np.abs(np.asarray(x, dtype=float))


def saenz_secant(strain: ArrayLike, E0: ArrayLike, peak_stress: ArrayLike,
                 peak_strain: ArrayLike, *, cap: bool = True) -> np.ndarray:
    """Secant modulus sigma/eps of the Saenz curve (eq. 3.9), E0 at eps = 0.

    sigma/eps = E0 / (1 + (R_E - 2) x + x^2), x = eps/eps_peak, R_E = E0 eps_peak / sigma_peak
    (eq. 3.10). R_E is clamped to >= 1 (below 1 the denominator can vanish; errata §2.4 asks
    R_E >= 1). With ``cap`` the secant is limited to E0 (errata §3, "Saenz branch").
    """
    E0a = np.asarray(E0, dtype=float)
    sec = formulas.saenz_secant(_mag(strain), E0a, np.asarray(peak_stress, dtype=float),
                                np.asarray(peak_strain, dtype=float))
    return np.minimum(sec, E0a) if cap else sec


def saenz_stress(strain: ArrayLike, E0: ArrayLike, peak_stress: ArrayLike,
                 peak_strain: ArrayLike, *, cap: bool = False) -> np.ndarray:
    """Saenz ascending branch, eq. 3.9: sigma = E0 eps / (1 + (R_E - 2) x + x^2).

    Valid for 0 <= eps <= peak_strain; sigma(peak_strain) = peak_stress with zero slope there.
    ``cap=True`` returns the curve with the secant capped at E0 (what the envelopes use).
    """
    return saenz_secant(strain, E0, peak_stress, peak_strain, cap=cap) * _mag(strain)


def softening_stress(strain: ArrayLike, peak_stress: ArrayLike, peak_strain: ArrayLike,
                     decay: ArrayLike) -> np.ndarray:
    """Descending branch sigma = peak exp(-decay (eps - eps_peak)), for eps >= eps_peak.

    Eq. 3.11a/b corrected per errata §1.1: written in magnitudes and measured from the peak
    strain of the branch itself (eps_t in tension, not eps_c). Strains below the peak are
    clipped to it (returns the peak).
    """
    with np.errstate(over="ignore"):
        arg = decay_exponent(_mag(strain), np.asarray(peak_strain, dtype=float),
                             np.asarray(decay, dtype=float))
    return np.asarray(peak_stress, dtype=float) * np.exp(-arg)


def softening_energy(peak_stress: ArrayLike, decay: ArrayLike) -> np.ndarray:
    """Area under the descending branch, integrated from the peak to infinity: peak/decay.

    Eqs. 3.26-3.27 corrected per errata §1.1 (lower limit eps_peak, not 0; sigma_t/k_t in
    tension). Equals G_f/h_c (3.28) or G_cr/h_c (3.30). Infinite for decay = 0.
    """
    peak = np.asarray(peak_stress, dtype=float)
    k = np.asarray(decay, dtype=float)
    with np.errstate(divide="ignore"):
        return np.where(k > 0.0, peak / np.where(k > 0.0, k, 1.0), np.inf)


def _envelope(strain: ArrayLike, E0: ArrayLike, peak_stress: ArrayLike, peak_strain: ArrayLike,
              decay: ArrayLike, decay_start: ArrayLike | None = None, linear: bool = False
              ) -> tuple[np.ndarray, np.ndarray]:
    eps, eps_p = _mag(strain), np.asarray(peak_strain, dtype=float)
    start = eps_p if decay_start is None else np.maximum(np.asarray(decay_start, float), eps_p)
    with np.errstate(over="ignore"):
        exponent = decay_exponent(eps, start, np.asarray(decay, dtype=float))
        # linear (App. A, Fig. A.5): 1 - k (eps - eps_p) / 2, zero at eps_p + 2 / k: the same
        # area sigma / k as the exponential branch (eqs. 3.26-3.27 corrected)
        decayed = np.maximum(1.0 - 0.5 * exponent, 0.0) if linear else np.exp(-exponent)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # clipped below
        return formulas.envelope(eps, np.asarray(peak_stress, dtype=float), eps_p,
                                 np.asarray(E0, dtype=float), decayed, SECANT_FLOOR)


def compression_envelope(strain: ArrayLike, E0: ArrayLike, peak_stress: ArrayLike,
                         peak_strain: ArrayLike, decay: ArrayLike, linear: bool = False
                         ) -> tuple[np.ndarray, np.ndarray]:
    """Monotone compression envelope (magnitudes): capped Saenz to the peak, then eq. 3.11b
    (``linear``: the straight branch of App. A, Fig. A.5, of the same area).

    Returns ``(stress, secant)``; secant = stress/strain, E0 at strain 0, clipped into
    [SECANT_FLOOR * E0, E0] so it is always positive and finite (never NaN, for any strain >= 0).
    """
    return _envelope(strain, E0, peak_stress, peak_strain, decay, linear=linear)


def tension_envelope(strain: ArrayLike, E0: ArrayLike, peak_stress: ArrayLike,
                     peak_strain: ArrayLike, decay: ArrayLike,
                     decay_start: ArrayLike | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Monotone tension envelope (magnitudes); same form as :func:`compression_envelope`.

    With ``peak_strain = peak_stress / E0`` (the default eps_t) the ascending branch is linear
    (errata §3, "Tension peak strain is undefined"); descending branch eq. 3.11a corrected.
    ``decay_start``: eq. 3.11a as printed, the decay measured from eps_c (errata §1.1), the
    stress held at the peak up to it.
    """
    return _envelope(strain, E0, peak_stress, peak_strain, decay, decay_start)
