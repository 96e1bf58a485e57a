"""The thesis profile meshes every analysed wall at Table 4.4's h_c (analysis.thesis_mesh)."""

from __future__ import annotations

import pytest

from icewall.analysis.thesis_mesh import (
    ANALYSED,
    TABLE_4_4_H_C,
    concrete_spacing,
    nearest_element_size,
)
from icewall.deck.load import load_deck


@pytest.mark.parametrize("name", sorted(ANALYSED))
def test_the_profile_gives_table_4_4_h_c(name):
    deck = f"decks/{ANALYSED[name]}.yaml"
    spacing = concrete_spacing(deck, [], "thesis")
    # within 4 %: VTT3 18.57 against 18.0, the others within 3 %
    assert spacing.area_mean == pytest.approx(TABLE_4_4_H_C[name], rel=0.04)
    assert spacing.area_mean > concrete_spacing(deck, []).area_mean  # the decks' finer mesh


def test_nearest_element_size_picks_the_closest_area_mean():
    sizes = (50.0, 87.0, 100.0)
    best = nearest_element_size("decks/cf4.yaml", 24.5, "thesis", sizes)
    assert best.element_size == 87.0
    assert load_deck("decks/cf4.yaml", [], "thesis").deck.analysis.element_size == 87.0
