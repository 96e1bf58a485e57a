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
