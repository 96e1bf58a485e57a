"""The thesis' printed forms of errata §1 corrections (materials.concrete.printed_forms), the
linear descending branch of App. A, the Poisson limit of 3.2.6 and the surface calibrations
(issue 37): each option changes what it says and nothing when left at its default."""

from __future__ import annotations

import math

import numpy as np
import pytest

from icewall.deck.load import load_deck
from icewall.materials.concrete import update_concrete
from icewall.materials.concrete_state import ConcreteState
from icewall.materials.parameters import derive_concrete_parameters, printed_lower_limit_decay
from icewall.materials.ultimate_surface import (
    SET_A_ELWI_MURRAY,
    elwi_murray_refit,
    strength_scale,
    unit_ray,
)
from icewall.materials.uniaxial import compression_envelope, tension_envelope
from icewall.model.materials import _concrete_law, concrete_parameters, concrete_point_parameters

CF4 = "decks/cf4.yaml"


def test_defaults_are_the_corrected_forms():
    p = derive_concrete_parameters(53.5, 24.5)
    assert p.printed_forms == () and p.compression_branch == "exponential"
    assert p.k_t == pytest.approx(591.37, abs=0.01)  # eq. 3.29 (Table 4.4: 592.3)
    assert p.k_c == pytest.approx(66.27, abs=0.01)  # eq. 3.34 corrected (Table 4.4: 66.3)


def test_eq_3_34_printed_drops_the_exponent():
    p = derive_concrete_parameters(53.5, 24.5, printed_forms=("eq3.34",))
    bracket = 0.015 * p.alpha - 0.667 * p.eps_c
    assert p.k_c == pytest.approx(24.5 / (209.2 * 53.5**0.25 * bracket), rel=1e-12)
    assert p.k_c == pytest.approx(15.29, abs=0.01)
    assert p.G_cr == pytest.approx(53.5 * 24.5 / p.k_c)


def test_eq_3_26_printed_integrates_from_zero():
    """(sigma / k) exp(k eps_peak) = G / h_c: k exp(-k eps_peak) = the corrected k."""
    q = derive_concrete_parameters(53.5, 24.5)
    p = derive_concrete_parameters(53.5, 24.5, printed_forms=("eq3.26",))
    assert p.k_t * math.exp(-p.k_t * p.eps_t) == pytest.approx(q.k_t, rel=1e-10)
    assert p.k_c * math.exp(-p.k_c * p.eps_c) == pytest.approx(q.k_c, rel=1e-10)
    assert p.k_t > q.k_t and p.k_c == pytest.approx(81.18, abs=0.01)
    # per Gauss point at another h_c the same relation holds (not a linear scaling)
    h = np.array([12.0, 24.5, 40.0])
    points = concrete_point_parameters(p, h, {})
    corrected = [derive_concrete_parameters(53.5, hc).k_c for hc in h]
    assert np.allclose(points.k_c * np.exp(-points.k_c * p.eps_c), corrected, rtol=1e-10)
    with pytest.raises(ValueError):
        printed_lower_limit_decay(200.0, 0.0025)  # k eps >= 1/e: no root


def test_eq_3_11a_printed_holds_f_t_up_to_eps_c():
    E0, ft, k = 32183.0, 2.414, 591.4
    eps_t = ft / E0
    strain = np.array([eps_t, 0.001, 0.0025, 0.0025 + 1.0 / k])
    stress, _ = tension_envelope(strain, E0, ft, eps_t, k, decay_start=0.0025)
    assert np.allclose(stress, [ft, ft, ft, ft / math.e])
    corrected, _ = tension_envelope(strain, E0, ft, eps_t, k)
    assert corrected[1] == pytest.approx(ft * math.exp(-k * (0.001 - eps_t)))


def test_linear_branch_has_the_exponential_area():
    fc, eps_c, k = 53.5, 0.0025, 66.3
    end = eps_c + 2.0 / k
    strain = np.linspace(eps_c, end + 0.01, 200001)
    stress, _ = compression_envelope(strain, 32183.0, fc, eps_c, k, linear=True)
    assert stress[-1] == 0.0 and stress[0] == pytest.approx(fc)
    area = float(np.sum(0.5 * (stress[1:] + stress[:-1]) * np.diff(strain)))
    assert area == pytest.approx(fc / k, rel=1e-6)  # eqs. 3.26-3.27 corrected
    middle = compression_envelope(np.array([eps_c + 1.0 / k]), 32183.0, fc, eps_c, k, True)[0]
    assert middle[0] == pytest.approx(0.5 * fc)


def test_eq_3_13_printed_swaps_the_meridians():
    """Printed, uniaxial compression (theta 60 deg) is read on r1, the tensile meridian."""
    p = derive_concrete_parameters(53.5, 24.5)
    state = np.array([[0.0, 0.0, -53.5]])
    assert strength_scale(state, 53.5, p.surface)[0] == pytest.approx(1.0, abs=1e-9)
    s = strength_scale(state, 53.5, p.surface, printed_lode=True)[0]
    sb, tb, *_ = unit_ray(np.array([0.0]), np.array([0.0]), np.array([-1.0]))
    r1, _ = p.surface.meridians(s * sb)
    assert s * tb[0] == pytest.approx(float(r1[0]), rel=1e-9)
    assert s < 0.2  # far below f'c: App. A "attain ultimate strength equivalent to f'c" fails


def _biaxial_update(params):
    state = ConcreteState.initial(1, params)
    strain = np.array([[-0.0004, -0.0004, 0.0, 0.0]])  # equal biaxial, loading
    return update_concrete(strain, state, params, "plane_stress", "incremental")[2]


def test_fig_3_12_step5_printed_reads_the_committed_stress():
    p = derive_concrete_parameters(53.5, 24.5)
    trial = _biaxial_update(p)
    assert trial.uniaxial_strength[0, 0] < -1.1 * 53.5  # the trial stress's biaxial ray
    printed = _biaxial_update(derive_concrete_parameters(53.5, 24.5,
                                                         printed_forms=("fig3.12_step5",)))
    # the committed (virgin, zero) stress has no ray: the uniaxial f'c (errata §3 fallback)
    assert printed.uniaxial_strength[0, 0] == pytest.approx(-53.5)


def test_deck_options_reach_the_law():
    deck = load_deck(CF4, ["materials.concrete.nu_max=0.5",
                           "materials.concrete.printed_forms=[eq3.34, eq3.11a]",
                           "materials.concrete.compression_branch=linear"]).deck
    c = deck.materials.concrete
    p = concrete_parameters(c, 24.5)
    assert (p.nu_max, p.printed_forms, p.compression_branch) == (0.5, ("eq3.34", "eq3.11a"),
                                                                  "linear")
    law = _concrete_law(c, deck.analysis, p, np.full(9, 24.5))
    assert law.kernel == "numpy"  # the point forms are written in NumPy only
    plain = load_deck(CF4, ["materials.concrete.printed_forms=[eq3.34]"]).deck
    assert concrete_parameters(plain.materials.concrete, 24.5).compression_branch == \
        "exponential"
    with pytest.raises(Exception, match="not one of"):
        load_deck(CF4, ["materials.concrete.printed_forms=[eq3.16]"])


def test_poisson_limit_caps_nu_in_compression():
    for limit in (0.49, 0.5):
        p = derive_concrete_parameters(53.5, 24.5, nu_max=limit)
        state = ConcreteState.initial(1, p)
        strain = np.array([[0.0, -0.0024, 0.0, 0.0]])
        trial = update_concrete(strain, state, p, "plane_stress", "incremental")[2]
        assert trial.poisson_ratio.max() == pytest.approx(limit)


def test_surface_calibrations():
    for calibration, expected in (("A_refit", elwi_murray_refit(0.33 / math.sqrt(53.5))),
                                  ("A", SET_A_ELWI_MURRAY)):
        deck = load_deck(CF4, [f"materials.concrete.surface.calibration={calibration}"]).deck
        surface = concrete_parameters(deck.materials.concrete, 24.5).surface
        assert np.allclose(surface.a, expected.a) and np.allclose(surface.b, expected.b)
    default = concrete_parameters(load_deck(CF4).deck.materials.concrete, 24.5).surface
    assert default.name.startswith("B")


def test_eq_3_2_and_3_3d_printed():
    """errata §1.1's numbers: isotropic E 30 000, nu 0.2: C11 28 800 printed, 33 333 corrected;
    eta = (0.2, 0.3, 0.45): phi 0.485 printed (2 eta31^3), 0.614 corrected."""
    from icewall.materials.orthotropic import orthotropic_normal_stiffness

    E, nu = np.full((1, 3), 30000.0), np.full((1, 3), 0.2)
    assert orthotropic_normal_stiffness(E, nu)[0, 0, 0] == pytest.approx(33333.33, abs=0.01)
    assert orthotropic_normal_stiffness(E, nu, ("eq3.2",))[0, 0, 0] == pytest.approx(28800.0)
    nu3 = np.array([[0.3, 0.04 / 0.3, 0.2025 / 0.3]])  # eta12 0.2, eta23 0.3, eta31 0.45
    ratio = (orthotropic_normal_stiffness(E, nu3, ("eq3.3d",))
             / orthotropic_normal_stiffness(E, nu3))
    assert np.allclose(ratio, 0.6135 / 0.48525, rtol=1e-9)  # 1 - 0.3325 - 0.054, - 0.18225
    # through the update: eps_iu of step 4 from the printed matrix is phi times the corrected
    # one (errata: "Without 1/phi ... dε_1u = 0.864 dε_1"), phi = (1 + nu)^2 (1 - 2 nu)
    strain = np.array([[-0.0002, 0.0, 0.0, 0.0]])
    p = derive_concrete_parameters(53.5, 24.5, printed_forms=("eq3.2",))
    printed = update_concrete(strain, ConcreteState.initial(1, p), p, "plane_strain",
                              "incremental")[2].equivalent_uniaxial_strain
    corrected = update_concrete(strain, ConcreteState.initial(1, PARAMS_53), PARAMS_53,
                                "plane_strain", "incremental")[2].equivalent_uniaxial_strain
    assert np.allclose(printed, corrected * 1.2**2 * 0.6, rtol=1e-12)


PARAMS_53 = derive_concrete_parameters(53.5, 24.5)


def test_rule_b_readings_equal_floor_cap():
    """3.2.5 (b) in a compression-tension state: equal = f'c; floor (signed) = at least f'c;
    cap (magnitudes) = at most f'c."""
    from icewall.materials.mode_rules import equivalent_uniaxial_strengths

    confined = np.array([[0.5, -20.0, -60.0]])  # small tension, confined strut: surface > f'c
    weakened = np.array([[2.0, 0.0, -10.0]])  # large tension: surface < f'c
    values = {}
    for rule in ("equal", "floor", "cap"):
        p = derive_concrete_parameters(53.5, 24.5, compression_tension_rule=rule)
        values[rule] = [equivalent_uniaxial_strengths(s, p)[0, 2] for s in (confined, weakened)]
    surface = derive_concrete_parameters(53.5, 24.5, compression_tension_rule="floor")
    assert values["equal"] == [pytest.approx(-53.5), pytest.approx(-53.5)]
    assert values["floor"][0] < -53.5 and values["floor"][1] == pytest.approx(-53.5)
    assert values["cap"][0] == pytest.approx(-53.5) and values["cap"][1] > -53.5
    del surface
    deck = load_deck(CF4, ["materials.concrete.compression_tension_rule=cap"]).deck
    c = deck.materials.concrete
    law = _concrete_law(c, deck.analysis, concrete_parameters(c, 24.5), np.full(9, 24.5))
    assert law.kernel == "numpy"
