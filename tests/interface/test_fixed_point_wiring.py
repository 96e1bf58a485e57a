"""The deck's fixed-point placements reach the solver's constraint set (issue 20 §4)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from icewall.deck.load import load_deck
from icewall.interface.fixed_points import fixed_point_mask
from icewall.interface.gap import FIXED, FREE
from icewall.mesh.build import build_mesh, region_materials
from icewall.model.build import build_model
from icewall.solve.gap_constraints import GapConstraints

DECK = Path(__file__).resolve().parents[2] / "decks" / "cf4.yaml"


@pytest.mark.parametrize("placement", ["[top]", "[corners]", "[bottom_support]",
                                       "[top, corners]", "[station]"])
def test_placements_become_permanent_fixed_pairs(placement):
    deck = load_deck(DECK, ["materials.interface.fixed_points_per_core=2",
                            f"materials.interface.fixed_point_placement={placement}"]).deck
    mesh = build_mesh(deck)
    constraints = GapConstraints(build_model(deck, mesh, region_materials(deck)))
    expected = fixed_point_mask(mesh, deck.materials.interface)
    permanent = constraints.committed.permanent
    assert permanent.any() and np.array_equal(permanent, expected)
    assert np.all(constraints.committed.state[permanent] == FIXED)


def test_no_fixed_points_by_default():
    deck = load_deck(DECK).deck
    mesh = build_mesh(deck)
    constraints = GapConstraints(build_model(deck, mesh, region_materials(deck)))
    assert not constraints.committed.permanent.any()


def test_a_tension_preload_starts_from_separated_pairs():
    """Under an in-plane tension applied first the pairs start open (thesis 4.2.2: the
    concrete separates from the steel), the fixed points held; other walls start bonded."""
    deck = load_deck(DECK.parent / "tf5.yaml").deck
    assert deck.loads.preload.axial_force > 0.0
    mesh = build_mesh(deck)
    state = GapConstraints(build_model(deck, mesh, region_materials(deck))).committed
    assert state.permanent.sum() == 8
    assert np.all(state.state[state.permanent] == FIXED)
    assert np.all(state.state[~state.permanent] == FREE)
    cf4 = load_deck(DECK).deck
    cf4_mesh = build_mesh(cf4)
    bonded = GapConstraints(build_model(cf4, cf4_mesh, region_materials(cf4))).committed
    assert np.all(bonded.state == FIXED)
