"""A corpus of broken decks: each gives one DeckError naming file, line and key."""

from __future__ import annotations

import pytest

from icewall.deck.load import load_deck
from icewall.errors import DeckError


def _line_of(text: str, fragment: str) -> int:
    return next(i for i, line in enumerate(text.splitlines(), start=1) if fragment in line)


# (description, old fragment, new fragment, expected key in message, expected text, line marker)
CASES = [
    ("unknown key", "  depth: 250.0 ", "  depht: 250.0 ", "geometry.depht", "unknown key",
     "depht"),
    ("wrong type", "fc: 53.5", "fc: strong", "materials.concrete.fc", "expected a number",
     "fc: strong"),
    ("wrong units (Pa for MPa)", "fc: 53.5", "fc: 53500", "materials.concrete.fc",
     "above the maximum", "fc: 53500"),
    ("missing required", "    fy: 371.0", "    fy_: 371.0", "materials.steel.fy_", "unknown key",
     "fy_"),
    ("diaphragm outside", "positions: [450.0, 750.0]", "positions: [450.0, 1080.0]",
     "geometry.diaphragms.positions[1]", "outside the wall", "positions: [450.0, 1080.0]"),
    ("plates thicker than the depth", "  top_plate: 12.6 ", "  top_plate: 240.0 ",
     "geometry.top_plate", "thicker than the depth", "top_plate: 240.0"),
    ("overlapping patches", "positions: [0.0, 300.0, 1058.0]",
     "positions: [0.0, 300.0, 320.0, 916.5]", "loads.patches.positions[2]", "overlap",
     "positions: [0.0, 300.0, 320.0"),
    ("support off the wall", "    - x: 750.0", "    - x: 1200.0", "geometry.supports[0].x",
     "off the wall", "- x: 1200.0"),
    ("absurd element size", "element_size: 50.0", "element_size: 0.01",
     "analysis.element_size", "is the unit mm", "element_size: 0.01"),
    ("element larger than the wall", "element_size: 50.0", "element_size: 500.0",
     "analysis.element_size", "exceeds the wall depth", "element_size: 500.0"),
    ("bad choice", "formulation: plane_strain", "formulation: plain_strain",
     "analysis.formulation", "not one of", "plain_strain"),
    ("negative thickness", "  end_plate: 6.4", "  end_plate: -6.4", "geometry.end_plate",
     "below the minimum", "end_plate: -6.4"),
]


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_broken_deck_names_file_line_and_key(case, cf4_text, write_deck):
    _, old, new, key, text, marker = case
    assert old in cf4_text, f"test fragment {old!r} not in cf4.yaml"
    broken = cf4_text.replace(old, new, 1)
    path = write_deck(broken)
    with pytest.raises(DeckError) as info:
        load_deck(path)
    err = info.value
    message = str(err)
    assert err.exit_code == 2
    assert str(path) in message
    assert key in message
    assert text in message
    assert err.line == _line_of(broken, marker)


def test_missing_required_section(write_deck, cf4_text):
    start = cf4_text.index("materials:")
    end = cf4_text.index("loads:")
    path = write_deck(cf4_text[:start] + cf4_text[end:])
    with pytest.raises(DeckError, match="materials: required key is missing"):
        load_deck(path)


def test_duplicate_key(write_deck, cf4_text):
    broken = cf4_text.replace("  depth: 250.0", "  depth: 250.0\n  depth: 260.0", 1)
    path = write_deck(broken)
    with pytest.raises(DeckError, match="duplicate key") as info:
        load_deck(path)
    assert info.value.line == _line_of(broken, "depth: 260.0")


def test_yaml_syntax_error(write_deck, cf4_text):
    broken = cf4_text.replace("  width: 381.0", "  width: [381.0", 1)
    path = write_deck(broken)
    with pytest.raises(DeckError, match="YAML syntax error") as info:
        load_deck(path)
    assert info.value.line is not None


def test_empty_and_non_mapping_decks(write_deck):
    with pytest.raises(DeckError, match="empty"):
        load_deck(write_deck(""))
    with pytest.raises(DeckError, match="mapping"):
        load_deck(write_deck("- 1\n- 2\n"))
    with pytest.raises(DeckError, match="no such file"):
        load_deck("/nonexistent/deck.yaml")


def test_full_model_without_pin_is_refused(write_deck, cf4_text):
    path = write_deck(cf4_text.replace("model: half", "model: full", 1))
    with pytest.raises(DeckError, match="pin"):
        load_deck(path)


def test_half_patch_overlapping_its_mirror(write_deck, cf4_text):
    path = write_deck(cf4_text.replace("[0.0, 300.0, 1058.0]", "[10.0, 300.0]", 1))
    with pytest.raises(DeckError, match="mirror"):
        load_deck(path)



def test_unknown_fixed_point_placement_is_refused():
    from pathlib import Path

    deck = Path(__file__).resolve().parents[2] / "decks" / "cf4.yaml"
    with pytest.raises(DeckError, match="unknown fixed-point placement") as err:
        load_deck(deck, ["materials.interface.fixed_point_placement=[sides]"])
    assert "fixed_point_placement[0]" in str(err.value)
