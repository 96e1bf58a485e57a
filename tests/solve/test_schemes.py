"""The iteration schemes as objects chosen once from the deck (solve/schemes.py): each owns its
settings and the defaults of the limits a deck leaves out, and gives the stages the one
path-following loop (solve/path.py) drives."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest
from softening_bar import bar_problem, settings

from icewall.deck.load import load_deck
from icewall.model.description import ModelDescription
from icewall.schemes import NEWTON, SECANT
from icewall.solve.control import SecantStage
from icewall.solve.newton_stages import NewtonControl, NewtonPreload
from icewall.solve.schemes import Dynamic, Newton, Secant
from icewall.solve.settings import solver_settings

DECKS = Path(__file__).resolve().parents[2] / "decks"


def _settings(deck: str, *overrides: str):
    return solver_settings(ModelDescription.of_deck(load_deck(DECKS / deck,
                                                              list(overrides)).deck))


def test_the_deck_chooses_the_scheme_object_with_its_own_settings_and_defaults():
    secant = _settings("cf4.yaml", "analysis.max_jumps=2")
    assert isinstance(secant.scheme, Secant) and secant.scheme.max_jumps == 2
    assert secant.scheme.defaults == SECANT.defaults and secant.tolerance_load == 0.05
    newton = _settings("tf1.yaml", "analysis.scheme=newton", "analysis.trace_snap_backs=true")
    assert type(newton.scheme) is Newton and newton.scheme.trace_snap_backs
    assert newton.scheme.drop_held == "stroke"  # the TF decks hold the loading head's stroke
    assert newton.tolerance_load == NEWTON.defaults["tolerance_load"] == 1e-4
    dynamic = _settings("cf4.yaml", "analysis.scheme=newton", "analysis.drops=dynamic",
                        "analysis.time_step_scale=0.5")
    assert isinstance(dynamic.scheme, Dynamic) and dynamic.scheme.inertia
    assert dynamic.scheme.time_step_scale == 0.5 and dynamic.scheme.name == "newton"
    assert not hasattr(secant.scheme, "time_step_scale")  # no scheme reads another's options


def test_each_scheme_gives_its_stages():
    problem, initial = bar_problem(100.0, 4)
    assert Secant().stages(problem) == Newton().stages(problem) == ("control",)
    secant = settings(1.0, 0.1)
    assert isinstance(Secant().stage("control", problem, secant, initial), SecantStage)
    newton = replace(secant, scheme=Newton())
    assert isinstance(Newton().stage("preload", problem, newton, initial), NewtonPreload)
    assert isinstance(Newton().stage("control", problem, newton, initial), NewtonControl)
    with pytest.raises(ValueError, match="mass"):  # the bar has none
        Dynamic().stage("control", problem, replace(secant, scheme=Dynamic()), initial)
