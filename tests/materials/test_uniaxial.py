"""Uniaxial curves: Saenz (3.9-3.10), exponential softening (3.11 corrected), energies."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad

from icewall.materials.parameters import derive_concrete_parameters
from icewall.materials.uniaxial import (
    SECANT_FLOOR,
    compression_envelope,
    saenz_secant,
    saenz_stress,
    softening_energy,
    softening_stress,
    tension_envelope,
)

P = derive_concrete_parameters(53.5, 24.5)  # CF-4 3x3 (Table 4.4)


def comp(e: float | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return compression_envelope(e, P.E0, P.fc, P.eps_c, P.k_c)


def tens(e: float | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return tension_envelope(e, P.E0, P.ft, P.eps_t, P.k_t)


@pytest.mark.parametrize("fc", [20.0, 30.0, 53.5, 120.0])
def test_saenz_peak_value_slope_and_initial_slope(fc: float) -> None:
    p = derive_concrete_parameters(fc, 25.0)
    ec, h = p.eps_c, 1e-7
    assert saenz_stress(ec, p.E0, fc, ec) == pytest.approx(fc, rel=1e-12)
    slope = (saenz_stress(ec, p.E0, fc, ec) - saenz_stress(ec - h, p.E0, fc, ec)) / h
    assert abs(slope) < 1e-3 * p.E0  # zero slope at the peak (one-sided, O(h))
    assert saenz_stress(1e-9, p.E0, fc, ec) / 1e-9 == pytest.approx(p.E0, rel=1e-5)
    assert saenz_secant(0.0, p.E0, fc, ec) == pytest.approx(p.E0)


def test_saenz_secant_cap_errata() -> None:
    """errata §3 "Saenz branch": R_E = 11/sqrt(f'c) < 2, raw secant peaks at 1.066 E0 for
    f'c = 53.5 (errata value); capped secant never exceeds E0."""
    e = np.linspace(0.0, P.eps_c, 2001)
    raw = saenz_secant(e, P.E0, P.fc, P.eps_c, cap=False)
    assert raw.max() / P.E0 == pytest.approx(1.066, abs=2e-3)
    assert np.all(saenz_secant(e, P.E0, P.fc, P.eps_c) <= P.E0)
    s, _ = comp(e)
    assert np.all(np.diff(s) >= 0.0) and s[-1] == pytest.approx(P.fc)


def test_continuity_at_peak_and_monotone_envelopes() -> None:
    for env, peak, ep in ((comp, P.fc, P.eps_c), (tens, P.ft, P.eps_t)):
        below, _ = env(ep * (1 - 1e-10))
        above, _ = env(ep * (1 + 1e-10))
        assert below == pytest.approx(peak, rel=1e-6) and above == pytest.approx(peak, rel=1e-6)
        e = np.linspace(0.0, 50 * ep, 5001)
        s, sec = env(e)
        i = int(np.argmax(s))
        assert np.all(np.diff(s[: i + 1]) >= -1e-12) and np.all(np.diff(s[i:]) <= 1e-12)
        assert np.all(np.diff(sec) <= 1e-9 * P.E0)  # secant non-increasing (damage grows)


def test_tension_branch_is_linear_to_peak() -> None:
    """errata §3 "Tension peak strain is undefined": eps_t = f't/E0, linear branch."""
    e = np.linspace(0.0, P.eps_t, 50)
    s, sec = tens(e)
    assert np.allclose(s, P.E0 * e) and np.allclose(sec, P.E0)


@pytest.mark.parametrize("which", ["tension", "compression"])
def test_softening_energy_matches_numerical_integral(which: str) -> None:
    """eqs. 3.26-3.30 corrected (errata §1.1): area from the peak = G_f/h_c and G_cr/h_c."""
    if which == "tension":
        peak, ep, k, target = P.ft, P.eps_t, P.k_t, P.Gf / P.h_c
        env = tens
    else:
        peak, ep, k, target = P.fc, P.eps_c, P.k_c, P.G_cr / P.h_c
        env = comp
    area, _ = quad(lambda e: float(env(e)[0]), ep, ep + 60.0 / k, limit=200)
    assert area == pytest.approx(target, rel=1e-6)
    assert softening_energy(peak, k) == pytest.approx(target, rel=1e-12)
    # errata §1.1 eq. 3.26: integrating eq. 3.11 from 0 (printed limit) overshoots
    from_zero = peak / k * np.exp(k * ep)
    assert from_zero / target - 1.0 > {"tension": 0.04, "compression": 0.17}[which]


def test_eq_3_11_printed_peak_strain_and_sign_fail() -> None:
    """errata §1.1 eq. 3.11a: the tensile branch must start at eps_t, not eps_c."""
    assert softening_stress(P.eps_t, P.ft, P.eps_t, P.k_t) == pytest.approx(P.ft)
    printed = P.ft * np.exp(-P.k_t * (P.eps_t - P.eps_c))  # as printed: eps_c in 3.11a
    assert printed > 4 * P.ft  # exp(k_t (eps_c - eps_t)) = 4.2
    # signed strains in 3.11b (compression negative) grow without bound beyond the peak
    signed = P.fc * np.exp(-P.k_c * (-2 * P.eps_c - (-P.eps_c)))
    assert signed > P.fc
    assert softening_stress(2 * P.eps_c, P.fc, P.eps_c, P.k_c) < P.fc


def test_extreme_strains_finite_positive() -> None:
    e = np.array([0.0, 1e-300, 1e-12, 1e-3, 1.0, 1e3, 1e300, np.finfo(float).max])
    for env in (comp, tens):
        s, sec = env(e)
        assert np.all(np.isfinite(s)) and np.all(np.isfinite(sec))
        assert np.all(s >= 0.0) and np.all(sec > 0.0)
        assert sec[0] == P.E0
        assert sec[-1] == pytest.approx(SECANT_FLOOR * P.E0)
    s, sec = comp(-2 * P.eps_c)  # magnitudes: sign ignored
    assert s == pytest.approx(comp(2 * P.eps_c)[0])


def test_broadcasting_over_directions() -> None:
    e = np.array([[1e-4, 3e-3, 1e-2], [0.0, 2e-3, 5e-3]])
    peaks = np.array([P.fc, 1.2 * P.fc, 0.5 * P.fc])
    strains = np.array([P.eps_c, 1.6 * P.eps_c, 0.8 * P.eps_c])
    s, sec = compression_envelope(e, P.E0, peaks, strains, P.k_c)
    assert s.shape == sec.shape == (2, 3)
    for i in range(2):
        for j in range(3):
            sj, _ = compression_envelope(e[i, j], P.E0, peaks[j], strains[j], P.k_c)
            assert s[i, j] == pytest.approx(sj)


def test_softening_energy_zero_decay_is_inf() -> None:
    assert np.isinf(softening_energy(2.0, 0.0))
