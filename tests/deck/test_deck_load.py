"""Deck loading: shipped decks are valid, overrides apply, derived defaults are right."""

from __future__ import annotations

from pathlib import Path

import pytest

from icewall.deck.load import load_deck
from icewall.errors import DeckError

DECKS = Path(__file__).resolve().parents[2] / "decks"


@pytest.mark.parametrize("name", sorted(p.name for p in DECKS.glob("*.yaml")))
def test_shipped_decks_are_valid(name):
    loaded = load_deck(DECKS / name)
    assert loaded.deck.version == 1
    assert loaded.deck.geometry.supports


def test_cf4_reading_of_table_4_1():
    deck = load_deck(DECKS / "cf4.yaml").deck
    geo = deck.geometry
    # Table 4.1: h = 250, b = 381, t_f = 12.6, t_d = 6.4, L = 1500, S1 = 300, S2 = 333.
    assert (geo.depth, geo.width, geo.top_plate, geo.span, geo.overhang) == (
        250.0, 381.0, 12.6, 1500.0, 333.0)
    assert geo.diaphragms.positions == (450.0, 750.0)  # L/2 - S1, L/2
    assert geo.half_length == pytest.approx(1083.0)
    assert deck.loads.measure.tributary_length == 300.0  # L/5
    assert deck.materials.concrete.fc == 53.5


def test_defaults_fill_unset_options():
    deck = load_deck(DECKS / "cf4.yaml").deck
    assert deck.materials.concrete.eps_c == 0.0025  # thesis 4.3.1
    assert deck.materials.concrete.Gf == 0.10
    assert deck.materials.steel.E == 200000.0
    assert deck.materials.interface.friction == pytest.approx(0.5773)


def test_set_override_changes_value_and_is_validated():
    deck = load_deck(DECKS / "cf4.yaml", ["materials.concrete.fc=40", "analysis.gauss=2"]).deck
    assert deck.materials.concrete.fc == 40.0
    assert deck.analysis.gauss == 2
    with pytest.raises(DeckError, match="analysis.gauss.*not one of"):
        load_deck(DECKS / "cf4.yaml", ["analysis.gauss=5"])
    with pytest.raises(DeckError, match="unknown key"):
        load_deck(DECKS / "cf4.yaml", ["materials.concrete.strength=40"])
    with pytest.raises(DeckError, match="key.path=value"):
        load_deck(DECKS / "cf4.yaml", ["materials.concrete.fc"])


def test_sequences_become_tuples_and_decks_are_frozen():
    deck = load_deck(DECKS / "cf4.yaml").deck
    assert isinstance(deck.loads.patches.positions, tuple)
    with pytest.raises(AttributeError):
        deck.geometry.depth = 1.0  # type: ignore[misc]


def test_deck_text_from_a_result_file_loads_the_same_deck():
    from icewall.deck.load import load_deck_text

    loaded = load_deck(DECKS / "cf4.yaml")
    again = load_deck_text(loaded.text, "result:/deck", ["analysis.gauss=2"])
    assert again.deck.geometry == loaded.deck.geometry
    assert again.deck.analysis.gauss == 2
    with pytest.raises(DeckError, match="result:/deck"):
        load_deck_text(loaded.text.replace("fc: 53.5", "fc: -1"), "result:/deck")


def test_scheme_defaults_fill_the_solver_limits_a_deck_leaves_out():
    """analysis.tolerance_*, max_iterations and max_step_cuts left out of a deck take the
    scheme's defaults (the thesis' 5 % under secant, 1e-4 under newton); given ones are kept,
    whatever the scheme; a directly built Analysis resolves them the same way."""
    from icewall.deck.analysis_options import SCHEME_DEFAULTS, Analysis

    limits = ("tolerance_displacement", "tolerance_load", "max_iterations", "max_step_cuts")
    for scheme, overrides in (("secant", []), ("newton", ["analysis.scheme=newton"])):
        analysis = load_deck(DECKS / "cf4.yaml", overrides).deck.analysis
        assert {k: getattr(analysis, k) for k in limits} == SCHEME_DEFAULTS[scheme]
        assert {k: getattr(Analysis(scheme=scheme), k) for k in limits} == SCHEME_DEFAULTS[scheme]
    assert SCHEME_DEFAULTS["newton"] == {"tolerance_displacement": 1e-4, "tolerance_load": 1e-4,
                                         "max_iterations": 40, "max_step_cuts": 6}
    assert SCHEME_DEFAULTS["secant"] == {"tolerance_displacement": 0.05, "tolerance_load": 0.05,
                                         "max_iterations": 200, "max_step_cuts": 4}
    given = load_deck(DECKS / "cf4.yaml", ["analysis.scheme=newton", "analysis.tolerance_load=0.01",
                                           "analysis.max_step_cuts=2"]).deck.analysis
    assert (given.tolerance_load, given.max_step_cuts) == (0.01, 2)
    assert (given.tolerance_displacement, given.max_iterations) == (1e-4, 40)
    kept = load_deck(DECKS / "cf4.yaml", ["analysis.max_iterations=40"]).deck.analysis
    assert (kept.max_iterations, kept.tolerance_load) == (40, 0.05)
