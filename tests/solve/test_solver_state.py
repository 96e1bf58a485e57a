"""The solver state a checkpoint holds: the secant path's jumps over stalls survive a resume
(a resumed run makes no more than `analysis.max_jumps` in all), and the checkpoint carries
every number of the path's resume tuple."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from softening_bar import bar_problem, settings

import icewall.solve.control as control
from icewall.deck.load import load_deck
from icewall.errors import ConvergenceError
from icewall.mesh.build import build_mesh, region_materials
from icewall.model.build import build_model
from icewall.solve.control import StepFailed, follow_path
from icewall.solve.energy import EnergyAccount
from icewall.solve.nonlinear import restore_checkpoint, run_nonlinear

DECKS = Path(__file__).resolve().parents[2] / "decks"


def _never_converges(monkeypatch):
    def fail(*args, **kwargs):
        raise StepFailed("no convergence (test)", "non-convergence")

    monkeypatch.setattr(control, "_iterate", fail)


def _run(problem, initial, resume_tuple=None):
    s = replace(settings(1.0, 0.1, cuts=1), max_jumps=2)
    start = initial if resume_tuple is None else replace(initial, resume=resume_tuple)
    with pytest.raises(ConvergenceError) as info:
        list(follow_path(problem, s, start, resume=resume_tuple is not None))
    return str(info.value)


def test_a_resumed_run_keeps_its_jump_count(monkeypatch):
    problem, initial = bar_problem(100.0, 4)
    _never_converges(monkeypatch)
    assert "stepping over the stall (1 jumps)" in _run(problem, initial)
    # resumed after two jumps (max_jumps = 2): no third one
    message = _run(problem, initial, ("control", 0.0, 0.1, 0.0, 2.0))
    assert "stepping over the stall" not in message and "step cuts" in message


def test_the_checkpoint_carries_the_whole_resume_tuple():
    """The first converged step of a coarse CF-4: its checkpoint restores the path state with
    every number of its resume tuple (jumps included)."""
    loaded = load_deck(DECKS / "cf4.yaml", ["analysis.element_size=150",
                                            "loads.control.target=1"])
    deck = loaded.deck
    report = next(run_nonlinear(build_model(deck, build_mesh(deck), region_materials(deck))))
    path = report.checkpoint.args[0]
    assert path.resume[0] == "control" and len(path.resume) == 5
    data = report.checkpoint()
    restored, stress, _ = restore_checkpoint(data, report.structure, report.constraints,
                                             EnergyAccount())
    assert restored.resume == path.resume
    assert restored.load_factor == path.load_factor and np.array_equal(restored.u, path.u)
    assert np.array_equal(stress, path.evaluation.stress)
