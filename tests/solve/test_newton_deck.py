"""analysis.scheme=newton on a shipped deck, up to first cracking: the contact conditions are
solved with the displacements (no frozen pair, no stabilisation spring), and every stored step
is an equilibrium to the tight tolerance, checked from the result file."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from icewall.deck.load import load_deck
from icewall.pipeline import run_deck
from icewall.results.reader import open_result

DECKS = Path(__file__).resolve().parents[2] / "decks"
NEWTON = ["analysis.scheme=newton", "analysis.tolerance_load=0.0001",
          "analysis.tolerance_displacement=0.0001", "analysis.max_iterations=40",
          "outputs.fields=[]"]
# before any concrete cracks: 0.02 mm bonded (composite action cracks the core by 0.1 mm),
# 0.2 mm with gap elements
TARGET = {"bonded": 0.02, "gap": 0.2}


@pytest.mark.parametrize("interface", ["bonded", "gap"])
def test_newton_elastic_steps_converge_tightly(tmp_path, interface):
    target = TARGET[interface]
    loaded = load_deck(DECKS / "cf4.yaml", [*NEWTON, f"materials.interface.model={interface}",
                                            f"loads.control.target={target}",
                                            f"loads.control.increment={target / 2}"])
    report = run_deck(loaded, tmp_path / "cf4.h5")
    assert report.status == "completed"
    with open_result(report.path) as res:
        h = res.history
        assert h["control_displacement"][-1] == pytest.approx(target)
        assert np.all(np.asarray(h["load_norm"]) <= 1e-4)
        iterations = np.asarray(h["iterations"])
        assert np.all(iterations < 40)
        if interface == "bonded":  # from the virgin state the first step is nearly linear
            assert iterations[0] <= 2
            load = np.asarray(h["load"])
            # nearly proportional (the concrete curves are nonlinear from zero; with gap
            # elements slip and opening make the response stiffen less than proportionally)
            assert load[1] == pytest.approx(2 * load[0], rel=0.02)
