"""`post_peak_strength: peak`: a principal direction past its peak keeps the sigma_ic, eps_ic it
had when it passed it (docs/solver.md item 22), against the thesis' reading again on the ray of
the trial stress at every update ("ray", errata 1.3 step 5)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from test_concrete_tangent import random_damaged_points

from icewall.materials.concrete import update_concrete
from icewall.materials.concrete_state import ConcreteState
from icewall.materials.concrete_tangent import consistent_tangent
from icewall.materials.parameters import derive_concrete_parameters
from icewall.materials.uniaxial import softening_stress

RAY = derive_concrete_parameters(53.5, 50.0)
PEAK = dataclasses.replace(RAY, post_peak_strength="peak")
ET, EC = RAY.ft / RAY.E0, RAY.eps_c
# cracked in x beside a small lateral compression, then x unloaded a little and y compressed
# to about 40 MPa: on the ray of the new stress the tensile strength is far lower
PATH = [[ET, -0.02 * EC, 0.0, 0.0], [3 * ET, -0.04 * EC, 0.0, 0.0], [6 * ET, -0.05 * EC, 0.0, 0.0],
        [5.5 * ET, -0.5 * EC, 0.0, 0.0]]


def _committed(params, path=PATH, formulation="plane_strain") -> list[ConcreteState]:
    states = [ConcreteState.initial(1, params)]
    for row in path:
        states.append(update_concrete(np.array([row]), states[-1], params, formulation,
                                      "corotational")[2])
    return states[1:]


def _reload(params) -> tuple[np.ndarray, np.ndarray]:
    """sigma_x over eps_x from 5.5 to 7 e_t at the committed end of PATH (the committed max of
    |eps_xu| lies at 6 e_t)."""
    state = _committed(params)[-1]
    x = np.linspace(5.5 * ET, 7.0 * ET, 3001)
    strain = np.zeros((x.size, 4))
    strain[:, 0], strain[:, 1] = x, -0.5 * EC
    stress = update_concrete(strain, state.take(np.zeros(x.size, dtype=int)), params,
                             "plane_strain", "corotational", with_moduli=False)[0]
    return x, stress[:, 0]


def test_reloading_past_the_peak_is_continuous_with_the_kept_strength():
    """On reloading through its committed max |eps_iu| a cracked direction meets its own
    envelope: sigma_x moves by at most twice its steady step between neighbouring samples.
    Read on the ray of the trial stress (beside 40 MPa of lateral compression) the strength
    has fallen, and sigma_x drops by more than a third at the committed max (item 21)."""
    for params, continuous in ((PEAK, True), (RAY, False)):
        x, sigma = _reload(params)
        step = np.abs(np.diff(sigma))
        assert sigma.min() > 0.3 and np.all(np.isfinite(sigma))
        if continuous:
            assert step.max() <= 2.0 * np.median(step) + 1e-12
        else:
            where = int(np.argmax(step))
            assert step[where] > 0.3 * sigma[where]
            assert x[where] == pytest.approx(6.0 * ET, rel=1e-3)


def test_a_cracked_direction_keeps_the_strength_it_passed_its_peak_with():
    """The tensile sigma_ic, eps_ic set in the update that cracks x stay through the later
    loading steps under a changing lateral stress; the softening stress is eq. 3.11 from that
    peak. On the ray they move with the lateral stress."""
    cracked_at = next(k for k, s in enumerate(_committed(PEAK)) if s.cracked[0, 0])
    states = _committed(PEAK)
    kept = states[cracked_at].uniaxial_strength[0, 0]
    for state in states[cracked_at:]:
        assert state.uniaxial_strength[0, 0] == kept
        assert state.uniaxial_peak_strain[0, 0] == states[cracked_at].uniaxial_peak_strain[0, 0]
    loaded = states[2]  # loading at 6 e_t
    expected = softening_stress(loaded.equivalent_uniaxial_strain[0, 0], kept,
                                loaded.uniaxial_peak_strain[0, 0], RAY.k_t)
    local = loaded.stress[0, 0]  # no shear: x is a principal axis
    assert local == pytest.approx(float(expected), rel=1e-12)
    on_ray = [s.uniaxial_strength[0, 0] for s in _committed(RAY)[cracked_at:3]]
    assert len(set(on_ray)) == len(on_ray)


@pytest.mark.parametrize("fallen", ["envelope", "scaled"])
@pytest.mark.parametrize("formulation", ["plane_strain", "plane_stress", "axisymmetric"])
def test_tangent_and_zero_increment_over_random_damaged_states(formulation, fallen):
    """Over many random damaged points the analytic tangent equals the differenced one (except
    at the few whose loading test flips within the difference step) and a zero increment
    returns the committed stress; under both readings of a fallen strength (`scaled`: the
    tangent carries the scale's derivative through sigma_ic)."""
    rng = np.random.default_rng(3)
    n = 400
    params = dataclasses.replace(PEAK, compression_tension_rule="floor", mode_rule_band=0.1,
                                 fallen_strength=fallen)
    state, strain = random_damaged_points(params, formulation, n, rng)
    assert state.cracked.any(axis=1).mean() > 0.5 and state.crushed.any()
    stress, _, trial = update_concrete(strain, state, params, formulation, "corotational")
    again = update_concrete(trial.strain, trial, params, formulation, "corotational")[0]
    np.testing.assert_allclose(again, stress, rtol=0.0, atol=1e-12 * np.abs(stress).max())
    analytic = consistent_tangent(strain, state, params, formulation, method="analytic")
    differenced = consistent_tangent(strain, state, params, formulation, method="differences")
    error = (np.abs(analytic - differenced).max(axis=(1, 2))
             / np.abs(differenced).max(axis=(1, 2)))
    assert np.sum(error > 1e-6) <= 0.005 * n, np.sort(error)[-5:]


def test_unknown_reading_is_refused():
    with pytest.raises(ValueError, match="post_peak_strength must be 'ray' or 'peak'"):
        dataclasses.replace(RAY, post_peak_strength="frozen")


def test_the_deck_option_reaches_the_law():
    """`materials.concrete.post_peak_strength` of a deck sets the parameters every concrete
    point of the model gets (model.materials.concrete_parameters); the decks keep "ray"."""
    from pathlib import Path

    from icewall.deck.load import load_deck
    from icewall.model.materials import concrete_parameters

    deck = Path(__file__).resolve().parents[2] / "decks" / "cf4.yaml"
    for overrides, expected in (([], "ray"),
                                (["materials.concrete.post_peak_strength=peak"], "peak")):
        loaded = load_deck(deck, overrides).deck
        assert concrete_parameters(loaded.materials.concrete, 50.0).post_peak_strength == expected
