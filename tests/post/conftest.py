"""Small result files shared by the post-processing tests (one nonlinear run of a coarse CF-4
with the state fields, one linear run without them)."""

from __future__ import annotations

from pathlib import Path

import pytest

from icewall.deck.load import load_deck
from icewall.pipeline import run_deck

DECKS = Path(__file__).resolve().parents[2] / "decks"
# Coarse plane-stress CF-4 to 16 mm in 2 mm steps: about 3 s, cracks, crushing and slip.
SMALL = ["analysis.formulation=plane_stress", "loads.control.target=16",
         "loads.control.increment=2", "analysis.element_size=125",
         "outputs.fields=[displacement, stress, strain, state]"]
LINEAR = ["analysis.solver=linear", "loads.control.target=2", "analysis.element_size=125"]


@pytest.fixture(scope="session")
def small_result(tmp_path_factory) -> str:
    report = run_deck(load_deck(DECKS / "cf4.yaml", SMALL),
                      tmp_path_factory.mktemp("post") / "cf4_small.h5")
    assert report.status == "completed"
    return report.path


@pytest.fixture(scope="session")
def linear_result(tmp_path_factory) -> str:
    report = run_deck(load_deck(DECKS / "cf4.yaml", LINEAR),
                      tmp_path_factory.mktemp("post_linear") / "cf4_linear.h5")
    return report.path
