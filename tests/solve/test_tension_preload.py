"""A wall whose first load is an in-plane tension (TF-5 to TF-7): under the converged scheme
the preload is carried, every step an equilibrium, and it goes through the plates (thesis
4.2.2: "the concrete separates from the steel"), checked against the plates' own stretch."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from newton_runs import MAKEFILE_NEWTON, assert_every_step_converged

from icewall.deck.load import load_deck
from icewall.pipeline import run_deck
from icewall.results.reader import open_result

DECKS = Path(__file__).resolve().parents[2] / "decks"


def test_tf5_carries_its_tension_through_the_plates_under_newton(tmp_path):
    """TF-5 (N = 1000 kN) under the Makefile's Newton settings to 0.05 mm: before the cores
    were held at one station and started separated, its first preload step stalled at every
    size (the first step of an elastic preload from zero gaps is scale-free: docs/solver.md
    item 50). With the tension in the plates alone, the top plate stretches by N / (2 t b E)
    (plane-stress plates, 6.4 mm each, b = 799 mm): 4.89e-4, 0.377 mm from the symmetry line
    to the end cap's face at 770 mm; the cores, pinned at one station each, can only stiffen
    it a little (measured 0.94 of it: the box's deformation squeezes them), where bonded
    cores (E_c A_c about 3.5 times the plates' E A) would leave about a quarter."""
    loaded = load_deck(DECKS / "tf5.yaml", [
        *MAKEFILE_NEWTON, "outputs.fields=[displacement]", "loads.control.target=0.05",
        "loads.control.increment=0.05"])
    report = run_deck(loaded, tmp_path / "tf5.h5")
    assert report.status == "completed"
    with open_result(report.path) as res:
        h = res.history
        assert_every_step_converged(h)
        preload = np.flatnonzero(np.asarray(h["preload_stage"]) == 1)
        assert np.asarray(h["preload_factor"])[preload[-1]] == pytest.approx(1.0)
        u = res.displacement(int(preload[-1]) + 1)  # fields are stored from step 1
        points = res.mesh.points
    top = np.isclose(points[:, 1], points[:, 1].max())
    at = {x: u[top & np.isclose(points[:, 0], x), 0].mean() for x in (0.0, 770.0)}
    plates_alone = 1.0e6 / (2 * 6.4 * 799.0 * 200_000.0) * 770.0
    assert 0.9 * plates_alone < at[770.0] - at[0.0] <= 1.001 * plates_alone
