"""`fallen_strength: scaled`: a direction that loads again where the envelope on its new ray has
fallen below its secant line follows that envelope scaled through its committed point
(concrete_formulas.scaled_envelope), against Fig. 3.12 step 6's jump onto the new envelope
("envelope"; docs/solver.md items 21-22 and 37)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from test_concrete_post_peak import RAY, _committed, _reload
from test_concrete_tangent import random_damaged_points

from icewall.materials.concrete import update_concrete

SCALED = dataclasses.replace(RAY, fallen_strength="scaled")
DAMAGED = dataclasses.replace(RAY, post_peak_strength="peak", compression_tension_rule="floor",
                              mode_rule_band=0.1)


def test_reloading_through_a_fallen_envelope_is_continuous():
    """Item 21's path: a cracked direction reloaded beside 40 MPa of new lateral compression.
    On the new ray its strength has fallen; "envelope" drops sigma_x by more than a third at
    the committed max, "scaled" moves by at most twice its steady step and keeps softening."""
    x, sigma = _reload(SCALED)
    step = np.abs(np.diff(sigma))
    assert step.max() <= 2.0 * np.median(step) + 1e-12
    assert np.all(np.diff(sigma[x > 6.0 * x[0] / 5.5]) < 0.0)  # past the max: softening
    _, jumping = _reload(RAY)
    assert np.abs(np.diff(jumping)).max() > 0.3 * jumping.min()


def test_the_scaled_branch_decays_as_eq_3_11_from_the_stress_it_has():
    """Past its peak the scaled branch is c sigma_ic exp(-k (eps - eps_ic)): its logarithmic
    slope is -k_t whatever the ray's strength, so the energy left below it is sigma / k_t, the
    crack band's of eqs. 3.26-3.30."""
    x, sigma = _reload(SCALED)
    beyond = x > 6.0 * x[0] / 5.5 * (1 + 1e-3)
    slope = np.diff(np.log(sigma[beyond])) / np.diff(x[beyond])
    np.testing.assert_allclose(slope, -RAY.k_t, rtol=1e-6)


def test_on_a_fixed_ray_the_scaled_law_is_the_thesis_law():
    """Paths whose ray cannot turn (plane stress, equal biaxial compression and tension, out
    to the descending branch) give the same stresses under both readings, to round-off: the
    envelope on an unchanged ray passes through the committed point, so the scale is 1."""
    for size in (-RAY.eps_c, 0.05 * RAY.eps_c):
        path = [[t * size, t * size, 0.0, 0.0] for t in np.linspace(0.05, 3.0, 60)]
        a = _committed(RAY, path, "plane_stress")
        b = _committed(SCALED, path, "plane_stress")
        assert a[-1].cracked.any() or a[-1].crushed.any()
        for left, right in zip(a, b, strict=True):
            np.testing.assert_allclose(right.stress, left.stress, rtol=1e-13, atol=1e-12)


@pytest.mark.parametrize("formulation", ["plane_strain", "plane_stress", "axisymmetric"])
def test_continuous_at_the_committed_strain_of_random_damaged_points(formulation):
    """On random damaged points, along random strain directions through the committed strain,
    the stress moves by no more than the tangent allows over +-h (no jump where a direction
    turns from unloading to loading); under "envelope" some of them (2-10 %) jump."""
    n, h = 400, 1e-9
    jumps = {}
    for reading in ("envelope", "scaled"):
        params = dataclasses.replace(DAMAGED, fallen_strength=reading)
        state, _ = random_damaged_points(params, formulation, n, np.random.default_rng(3))
        d = np.random.default_rng(5).normal(size=(n, 4))
        if formulation == "plane_strain":
            d[:, 2] = 0.0
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        below, above = (update_concrete(state.strain + s * h * d, state, params, formulation,
                                        "corotational", with_moduli=False)[0]
                        for s in (-1.0, 1.0))
        scale = np.abs(state.stress).max(axis=1) / np.abs(state.strain).max(axis=1)
        jumps[reading] = int(np.sum(np.abs(above - below).max(axis=1) > 1e3 * h * scale))
    assert jumps["scaled"] == 0
    assert jumps["envelope"] >= n // 50


def test_the_reading_is_checked_and_reaches_the_law():
    from pathlib import Path

    from icewall.deck.load import load_deck
    from icewall.model.materials import concrete_parameters

    with pytest.raises(ValueError, match="fallen_strength must be 'envelope' or 'scaled'"):
        dataclasses.replace(RAY, fallen_strength="kept")
    deck = Path(__file__).resolve().parents[2] / "decks" / "cf4.yaml"
    for overrides, expected in (([], "envelope"),
                                (["materials.concrete.fallen_strength=scaled"], "scaled")):
        loaded = load_deck(deck, overrides).deck
        assert concrete_parameters(loaded.materials.concrete, 50.0).fallen_strength == expected


def test_a_crack_opened_far_down_its_branch_raises_no_floating_point_error():
    """A crack opened to eps_iu ~ 0.6 (hundreds of decay lengths: its envelope at max |eps_iu|
    underflows) and then loaded across in compression: the update and its consistent tangent
    make no overflow or invalid operation (the scale line / envelope overflowed, and NumPy's
    errors were reported on runs whose results were finite: CF-4 to 40 mm, 11 321 invalid and
    11 070 overflow), and return finite stresses and moduli."""
    from icewall.materials.concrete_state import ConcreteState
    from icewall.materials.concrete_tangent import consistent_tangent
    from icewall.materials.parameters import derive_concrete_parameters

    params = derive_concrete_parameters(53.5, 50.0, compression_tension_rule="floor",
                                        mode_rule_band=0.1, post_peak_strength="peak",
                                        fallen_strength="scaled")
    state = ConcreteState.initial(1, params)
    with np.errstate(over="raise", invalid="raise", divide="raise"):
        for x in np.linspace(0.0, 1.2, 61)[1:]:
            stress, _, state = update_concrete(np.array([[x, 0.0, 0.0, 0.0]]), state, params,
                                               "plane_strain", "corotational")
        strain = np.array([[1.19, -2e-3, 0.0, 1e-4]])
        tangent = consistent_tangent(strain, state, params, "plane_strain")
    assert state.max_equivalent_uniaxial_strain[0, 0] > 0.5
    assert np.all(np.isfinite(stress)) and np.all(np.isfinite(tangent))
