"""summarize() and format_summary() on synthetic load-deflection curves."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from icewall.analysis.summary import format_summary, summarize
from icewall.errors import ResultError
from icewall.mesh.mesh import Mesh, Region
from icewall.results import ResultWriter, StepRecord


def one_cell_mesh() -> Mesh:
    pts = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]])
    return Mesh(points=pts, cells=np.array([[0, 1, 2, 3]]), cell_type="quad4",
                cell_region=np.array([1]), regions=(Region("core", "concrete", 1),))


def curve_file(path, n=41, peak_at=25, *, finish=("stopped", "load below 80% of peak")):
    """Parabolic rise to a peak of 3.2 MPa at step `peak_at`, then softening."""
    w = ResultWriter(path, deck_text="deck", deck_path="s.yaml", mesh=one_cell_mesh(),
                     attrs={"specimen": "SCS-3", "load_measure": "w", "load_unit": "MPa"})
    delta = 0.2 * np.arange(1, n + 1)
    d_peak = 0.2 * peak_at
    load = 3.2 - 0.004 * (delta - d_peak) ** 2 - 0.01 * np.clip(delta - d_peak, 0, None)
    its = [2 + (i % 4) for i in range(n)]  # 2,3,4,5,2,...
    for i in range(n):
        w.write_step(StepRecord(i + 1, float(delta[i]), float(load[i]), float(load[i] / 3.2),
                                its[i], 1e-8, 1e-7, 0.1 * (i + 1)))
    if finish:
        w.finish(*finish)
    return w, delta, load, its


def test_summary_of_known_peak(tmp_path):
    _, delta, load, its = curve_file(tmp_path / "r.h5")
    s = summarize(tmp_path / "r.h5")
    assert s["specimen"] == "SCS-3" and s["status"] == "stopped"
    assert s["stop_reason"] == "load below 80% of peak"
    assert s["n_steps"] == 41
    assert s["max_load"] == pytest.approx(3.2)
    assert s["deflection_at_max_load"] == pytest.approx(5.0)  # step 25 * 0.2 mm
    assert s["final_load"] == pytest.approx(load[-1]) and s["final_load"] < 3.2
    assert s["final_deflection"] == pytest.approx(8.2)
    assert s["total_iterations"] == sum(its)
    assert s["iterations_per_step_median"] == pytest.approx(np.median(its))
    assert s["iterations_per_step_max"] == 5
    assert s["run_time_s"] >= 0
    assert (s["load_measure"], s["load_unit"]) == ("w", "MPa")
    assert json.loads(json.dumps(s)) == s  # plain JSON types only (for --json)


def test_format_summary_block(tmp_path):
    curve_file(tmp_path / "r.h5")
    text = format_summary(summarize(tmp_path / "r.h5"))
    lines = text.splitlines()
    assert len({line.index(" : ") for line in lines}) == 1  # aligned
    assert "max load (w)           : 3.2 MPa" in text
    assert "deflection at max load : 5 mm" in text
    assert "status                 : stopped" in text
    assert "iterations per step    : median 3, max 5" in text


def test_summary_of_empty_and_unfinished_runs(tmp_path):
    w, *_ = curve_file(tmp_path / "empty.h5", n=0, finish=None)
    s = summarize(str(tmp_path / "empty.h5") + ".partial")
    assert s["n_steps"] == 0 and s["max_load"] is None and s["status"] == "running"
    assert "killed" in s["stop_reason"]
    assert "max load (w)" in format_summary(s)
    w.finish()
    script = ("import sys, os; sys.path.insert(0, {d!r});"
              "from test_summary import curve_file;"
              "curve_file({p!r}, n=10, peak_at=4, finish=None); os._exit(3)")
    script = script.format(d=os.path.dirname(__file__), p=str(tmp_path / "killed.h5"))
    assert subprocess.run([sys.executable, "-c", script]).returncode == 3
    s = summarize(str(tmp_path / "killed.h5") + ".partial")
    assert s["n_steps"] == 10 and s["deflection_at_max_load"] == pytest.approx(0.8)
    with pytest.raises(ResultError):
        summarize(tmp_path / "killed.h5")


def test_summary_lists_accepted_snap_throughs(tmp_path):
    path = tmp_path / "snap.h5"
    w = ResultWriter(path, deck_text="deck", deck_path="s.yaml", mesh=one_cell_mesh(),
                     attrs={"specimen": "SCS-3", "load_measure": "w", "load_unit": "MPa"})
    for i, (d, load, snap) in enumerate([(1.0, 2.0, 0), (2.0, 3.0, 0), (2.0625, 1.0, 1),
                                         (3.0, 1.1, 0)]):
        w.write_step(StepRecord(i + 1, d, load, load, 3, 1e-8, 1e-7, 0.1,
                                scalars={"snap_back": snap}))
    w.finish("completed", "")
    s = summarize(path)
    assert s["snap_throughs"] == [pytest.approx(2.0625)]
    assert "snap-throughs          : at 2.062 mm" in format_summary(s)
    many = format_summary({**s, "snap_throughs": [5.0 + 0.5 * k for k in range(40)]})
    assert ("snap-throughs          : 40: at 5 mm, at 5.5 mm, at 6 mm, at 6.5 mm, at 7 mm, "
            "..., at 24.5 mm") in many
    curve_file(tmp_path / "none.h5")
    assert "snap-throughs          : none" in format_summary(summarize(tmp_path / "none.h5"))


def test_summary_says_whether_every_step_is_a_converged_equilibrium(tmp_path):
    """The equilibrium line reads the scheme and tolerances from the stored deck and the run's
    --set overrides (the Newton scheme's own 1e-4 where the deck leaves them out) and judges
    every stored step by the schemes' own test; an unreadable stored deck gives the norms
    alone."""
    from pathlib import Path

    deck_text = (Path(__file__).resolve().parents[2] / "decks" / "cf4.yaml").read_text()

    def result(name, overrides, load_norms, deck=deck_text, displacement_norm=3e-5):
        path = tmp_path / name
        w = ResultWriter(path, deck_text=deck, deck_path="cf4.yaml", mesh=one_cell_mesh(),
                         attrs={"specimen": "CF-4", "load_measure": "w", "load_unit": "MPa",
                                "deck_overrides": json.dumps(overrides)})
        for i, norm in enumerate(load_norms):
            w.write_step(StepRecord(i + 1, 1.0 + i, 2.0 + i, 1.0, 5, displacement_norm, norm,
                                    0.1))
        w.finish("completed", "")
        return format_summary(summarize(path))

    newton = ["analysis.scheme=newton"]
    assert ("equilibrium            : every step a converged equilibrium: 0.0001 (load), "
            "0.0001 (displacement), scheme newton; largest load norm 9e-05, displacement "
            "norm 3e-05") in result("converged.h5", newton, [2e-5, 9e-5])
    assert "not every step is an equilibrium to its tolerances (1 outside): 0.0001 (load)" in (
        result("one_off.h5", newton, [2e-5, 2e-4]))
    # the schemes' own test: a load norm 100x inside the tolerance passes a first correction
    assert "every step a converged equilibrium" in result("first.h5", newton, [5e-7],
                                                          displacement_norm=3e-3)
    assert "(1 outside)" in result("not_first.h5", newton, [5e-6], displacement_norm=3e-3)
    assert ("every step within loose tolerances (figures move with them): 0.05 (load), "
            "0.05 (displacement), scheme secant") in result("secant.h5", [], [0.04, 0.01])
    assert "every step within loose tolerances" in result(
        "1e-3.h5", [*newton, "analysis.tolerance_load=1e-3",
                    "analysis.tolerance_displacement=1e-3"], [9e-4])
    assert ("largest load norm 9e-05, displacement norm 3e-05 (the stored deck does not read: "
            "tolerances unknown)") in result("no_deck.h5", [], [9e-5], deck="deck")


def test_summary_gives_the_first_maximum_and_says_when_the_curve_climbs_past_it(tmp_path):
    """A curve with a second, higher hump (docs/solver.md item 29): the first maximum is the
    largest load before the curve first softens by 5 %, and the summary says that it climbs
    higher later; on a single hump the two are the same and nothing is added."""
    def result(name, loads):
        path = tmp_path / name
        w = ResultWriter(path, deck_text="", deck_path="cf4.yaml", mesh=one_cell_mesh(),
                         attrs={"specimen": "CF-4", "load_measure": "w", "load_unit": "MPa"})
        for i, load in enumerate(loads):
            w.write_step(StepRecord(i + 1, 1.0 + i, load, 1.0, 5, 1e-5, 1e-5, 0.1))
        w.finish("completed", "")
        return summarize(path)

    two = result("two.h5", [3.0, 6.25, 5.9, 6.46, 2.0])
    assert two["first_max_load"] == 6.25 and two["deflection_at_first_max_load"] == 2.0
    assert two["max_load"] == 6.46
    assert ("first maximum          : 6.25 MPa at 2 mm (before the curve first softens by "
            "5 %; it climbs higher later)") in format_summary(two)
    one = result("one.h5", [3.0, 6.25, 5.0])
    assert one["first_max_load"] == one["max_load"] == 6.25
    assert "first maximum          : 6.25 MPa at 2 mm\n" in format_summary(one)


def test_summary_gives_the_energy_balance_and_the_drops_numerical_dissipation(tmp_path):
    """The energy account at the last step: the imbalance as a fraction of the external work
    and, in a run that can take dynamic drops, beside it the numerical dissipation of their time
    integration (solve/energy.py); a file without the energy columns has no such line."""
    def result(name, scalars):
        path = tmp_path / name
        w = ResultWriter(path, deck_text="", deck_path="cf4.yaml", mesh=one_cell_mesh(),
                         attrs={"specimen": "CF-4", "load_measure": "w", "load_unit": "MPa"})
        for i, step in enumerate(scalars):
            w.write_step(StepRecord(i + 1, 1.0 + i, 2.0, 1.0, 5, 1e-5, 1e-5, 0.1,
                                    scalars=step))
        w.finish("completed", "")
        return summarize(path)

    static = result("static.h5", [{"external_work": 1.0e3, "energy_imbalance": 1.0},
                                  {"external_work": 4.0e6, "energy_imbalance": -2.0e3}])
    assert static["energy"] == {"external_work": 4.0e6, "energy_imbalance": -2.0e3,
                                "imbalance_fraction": -5e-4, "numerical_dissipation": None,
                                "numerical_fraction": None}
    assert ("energy balance         : external work 4e+06 N mm; of it imbalance -0.05 % "
            "(-2000 N mm)\n") in format_summary(static) + "\n"
    dynamic = result("dynamic.h5", [{"external_work": 8.0e6, "energy_imbalance": 4.0e3,
                                     "numerical_dissipation": 1.2e5}])
    assert dynamic["energy"]["numerical_fraction"] == pytest.approx(0.015)
    assert ("energy balance         : external work 8e+06 N mm; of it imbalance 0.05 % "
            "(4000 N mm), numerical dissipation of the dynamic drops 1.5 % (1.2e+05 N mm)"
            ) in format_summary(dynamic)
    assert json.loads(json.dumps(dynamic)) == dynamic
    curve_file(tmp_path / "none.h5")
    none = summarize(tmp_path / "none.h5")
    assert none["energy"] is None and "energy balance" not in format_summary(none)
