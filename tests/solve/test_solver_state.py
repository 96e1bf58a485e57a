"""The solver state a checkpoint holds: the secant path's jumps over stalls survive a resume
(a resumed run makes no more than `analysis.max_jumps` in all), the checkpoint carries the
path's typed cursor field by field, and a checkpoint of the older positional layout is refused
with an error that names its file."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from softening_bar import bar_problem, settings

import icewall.solve.control as control
from icewall.deck.load import load_deck
from icewall.errors import ConvergenceError, ResultError
from icewall.mesh.build import build_mesh, region_materials
from icewall.model.build import build_model
from icewall.solve.checkpoint import restore_checkpoint
from icewall.solve.energy import EnergyAccount
from icewall.solve.mode import Mode
from icewall.solve.nonlinear import run_nonlinear
from icewall.solve.path import follow_path
from icewall.solve.state import SecantCursor, StepFailed

DECKS = Path(__file__).resolve().parents[2] / "decks"


def _never_converges(monkeypatch):
    def fail(*args, **kwargs):
        raise StepFailed("no convergence (test)", "non-convergence")

    monkeypatch.setattr(control, "_iterate", fail)


def _run(problem, initial, cursor=None):
    s = settings(1.0, 0.1, cuts=1, max_jumps=2)
    start = initial if cursor is None else replace(initial, cursor=cursor)
    with pytest.raises(ConvergenceError) as info:
        list(follow_path(problem, s, start, resume=cursor is not None))
    return str(info.value)


def test_a_resumed_run_keeps_its_jump_count(monkeypatch):
    problem, initial = bar_problem(100.0, 4)
    _never_converges(monkeypatch)
    assert "stepping over the stall (1 jumps)" in _run(problem, initial)
    # resumed after two jumps (max_jumps = 2): no third one
    message = _run(problem, initial, SecantCursor("control", 0.0, 0.1, 0.0, jumps=2))
    assert "stepping over the stall" not in message and "step cuts" in message


def _first_step(overrides):
    loaded = load_deck(DECKS / "cf4.yaml", ["analysis.element_size=150", *overrides])
    deck = loaded.deck
    return next(run_nonlinear(build_model(deck, build_mesh(deck), region_materials(deck))))


def test_the_checkpoint_carries_the_whole_cursor():
    """The first converged step of a coarse CF-4: its checkpoint holds the path's cursor by
    named fields (path/secant/jumps, ...), and restores the path state with all of them."""
    report = _first_step(["loads.control.target=1"])
    path = report.checkpoint.args[0]
    assert isinstance(path.cursor, SecantCursor) and path.cursor.stage == "control"
    data = report.checkpoint()
    assert str(data["path/cursor"]) == "secant" and "path/where" not in data
    assert {name for name in data if name.startswith("path/secant/")} == {
        "path/secant/stage", "path/secant/position", "path/secant/size", "path/secant/peak",
        "path/secant/jumps"}
    restored, stress, _ = restore_checkpoint(data, report.structure, report.constraints,
                                             EnergyAccount())
    assert restored.cursor == path.cursor
    assert restored.load_factor == path.load_factor and np.array_equal(restored.u, path.u)
    assert np.array_equal(stress, path.evaluation.stress)


def test_the_newton_mode_is_restored_field_by_field():
    """The Newton control stage's `Mode` (every field but the transient halt) goes through
    the checkpoint bit for bit, NaNs included; a field a checkpoint lacks takes its default."""
    report = _first_step(["loads.control.target=1", "analysis.scheme=newton"])
    path = report.checkpoint.args[0]
    assert isinstance(path.cursor, Mode)
    data = report.checkpoint()
    assert "path/mode/halt" not in data and str(data["path/stage"]) == "control"
    restored, _, _ = restore_checkpoint(data, report.structure, report.constraints,
                                        EnergyAccount())
    for name in ("name", "size", "release", "damping", "ceiling", "slope", "peak", "omega",
                 "kinked", "unstable", "held", "stagnant"):
        assert np.array_equal(getattr(restored.cursor, name), getattr(path.cursor, name),
                              equal_nan=isinstance(getattr(path.cursor, name), float)), name
    del data["path/mode/held"]
    assert restore_checkpoint(data, report.structure, report.constraints,
                              EnergyAccount())[0].cursor.held == 1


def test_a_checkpoint_of_the_positional_layout_is_refused_naming_its_file():
    report = _first_step(["loads.control.target=1"])
    data = {name: value for name, value in report.checkpoint().items()
            if not name.startswith("path/secant/") and name != "path/cursor"}
    data["path/where"] = np.array([1.0, 1.0, 2.5e5, 0.0])  # (position, size, peak, jumps)
    with pytest.raises(ResultError, match=r"the checkpoint old\.npz has the positional"):
        restore_checkpoint(data, report.structure, report.constraints, EnergyAccount(),
                           "old.npz")
    data["path/cursor"] = np.array("spiral")
    with pytest.raises(ResultError, match="unknown type 'spiral'"):
        restore_checkpoint(data, report.structure, report.constraints, EnergyAccount(),
                           "old.npz")
