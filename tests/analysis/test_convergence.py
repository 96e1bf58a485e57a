"""icewall convergence: error estimates, Richardson extrapolation and the Pareto choice on
synthetic data with hand-computed answers; the ladder; one small end-to-end run."""

from __future__ import annotations

import csv
import math
import sys
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from icewall.analysis import convergence as cv
from icewall.analysis import convergence_table as ct
from icewall.cli import main
from icewall.errors import DeckError

DECKS = Path(__file__).resolve().parents[2] / "decks"
CF4 = str(DECKS / "cf4.yaml")


def test_relative_and_curve_errors():
    assert ct.relative_error(5.5, 5.0) == pytest.approx(0.1)
    assert ct.relative_error(-4.5, -5.0) == pytest.approx(0.1)
    assert ct.relative_error(None, 5.0) is None and ct.relative_error(1.0, 0.0) is None
    ref = (np.array([0.0, 10.0, 40.0]), np.array([0.0, 10.0, 4.0]))
    shifted = (ref[0], ref[1] + 0.5)  # 0.5 above everywhere: RMS 0.5, over the peak 10
    assert ct.curve_error(shifted, ref) == pytest.approx(0.05)
    # common range only: a curve that stops at 10 mm is compared on [0, 10]
    short = (np.array([0.0, 10.0]), np.array([0.0, 10.0]))
    assert ct.curve_error(short, ref) == pytest.approx(0.0)
    # a difference growing linearly from 0 to 2 over the range: RMS 2 / sqrt(3)
    tilted = (ref[0], ref[1] + ref[0] / 20.0)
    assert ct.curve_error(tilted, ref) == pytest.approx(2.0 / math.sqrt(3) / 10.0, rel=1e-3)


def test_richardson_known_answers():
    # f = 1 + 3 h^2 at h = 1, 2, 4 (ratio 2): order 2, limit 1
    r = ct.richardson([1.0, 2.0, 4.0], [4.0, 13.0, 49.0])
    assert r["order"] == pytest.approx(2.0) and r["extrapolated"] == pytest.approx(1.0)
    # unequal ratios (2, then 1.5): f = 1 + h^2 at h = 1, 2, 3
    r = ct.richardson([1.0, 2.0, 3.0], [2.0, 5.0, 10.0])
    assert r["order"] == pytest.approx(2.0) and r["extrapolated"] == pytest.approx(1.0)
    # f = 7 - 0.5 h at h = 0.5, 1, 2: order 1 from below, limit 7
    r = ct.richardson([0.5, 1.0, 2.0], [6.75, 6.5, 6.0])
    assert r["order"] == pytest.approx(1.0) and r["extrapolated"] == pytest.approx(7.0)


@pytest.mark.parametrize(("h", "f", "why"), [
    ([1.0, 2.0, 4.0], [1.0, 2.0, 1.5], "oscillatory"),
    ([1.0, 2.0, 4.0], [2.0, 2.0 + 64, 2.0 + 4096], "order > 5"),  # h^6
    ([1.0, 2.0, 4.0], [2.0, 2.2, 2.4], "order < 0.5"),  # no convergence with h
    ([1.0, 1.1, 2.0], [2.0, 2.21, 5.0], "ratio 1.10"),
    ([1.0, 2.0], [2.0, 5.0], "three"),
    ([1.0, 2.0, 4.0], [2.0, 2.0, 3.0], "no change"),
])
def test_richardson_not_applicable(h, f, why):
    r = ct.richardson(h, f)
    assert r["order"] is None and r["extrapolated"] is None
    assert r["note"].startswith("n/a") and why in r["note"]


def row(family, run, h, peak, cost=1.0, status="completed", value=None, first_peak=None):
    d = np.array([0.0, 10.0, 40.0])
    return {"family": family, "run": run, "h": h, "value": value or str(h), "status": status,
            "usable": status == "completed", "cost": cost, "peak": peak, "defl_peak": 10.0,
            "first_peak": peak if first_peak is None else first_peak, "defl_first_peak": 10.0,
            "residual": 0.5 * peak, "curve": (d, np.array([0.0, peak, 0.5 * peak]))}


def test_the_first_maximum_gets_errors_of_its_own():
    """A second hump that moves with the step (the largest load) while the first maximum
    stays: the peak's errors are large, the first maximum's small, and the Pareto choice
    for the first maximum is the cheapest run."""
    rows = [row("step", "s1", 1.0, 6.46, cost=1.0, first_peak=6.25),
            row("step", "s05", 0.5, 6.10, cost=2.0, first_peak=6.26),
            row("step", "s025", 0.25, 6.30, cost=4.0, first_peak=6.255)]
    ct.family_errors(rows)
    ct.total_errors(rows, "s1")
    by = {r["run"]: r for r in rows}
    assert by["s1"]["err_peak"] == pytest.approx(0.16 / 6.30)
    assert by["s1"]["err_first_peak"] == pytest.approx(-0.005 / 6.255)
    assert by["s05"]["err_defl_first_peak"] == 0.0
    table = {(p["threshold"], p["quantity"]): p for p in ct.pareto_rows(rows)}
    assert table[0.02, "first_peak"]["run"] == "s1"
    assert table[0.02, "peak"]["run"] == "s025"


def test_a_run_stopped_after_its_first_maximum_is_that_figure_s_reference():
    """The finest tolerance stopped in a drop after its first maximum: it has no peak or
    residual error, but it is the first maximum's reference; a run stopped before its first
    maximum settled has none."""
    rows = [row("tol", "t3", 1e-3, 6.46, first_peak=6.219),
            row("tol", "t4", 1e-4, 6.30, first_peak=6.255),
            row("tol", "t6", 1e-6, 6.27, first_peak=6.252, status="stopped"),
            row("tol", "t8", 1e-8, 6.10, first_peak=6.10, status="stopped")]
    rows[2]["usable_first_peak"] = True
    rows[3]["usable_first_peak"] = False
    family = ct.family_errors(rows)["tol"]
    by = {r["run"]: r for r in rows}
    assert family["reference"] == "t4" and family["first_peak_reference"] == "t6"
    assert by["t3"]["err_peak"] == pytest.approx(0.16 / 6.30)
    assert by["t3"]["err_first_peak"] == pytest.approx(-0.033 / 6.252)
    assert by["t4"]["err_first_peak"] == pytest.approx(0.003 / 6.252)
    assert by["t6"]["err_first_peak"] == 0.0 and by["t6"]["err_peak"] is None
    assert by["t8"]["err_first_peak"] is None
    assert family["richardson"]["first_peak"]["runs"] == ["t6", "t4", "t3"]
    assert ct.usable_for(by["t6"], "defl_first_peak") and not ct.usable_for(by["t6"], "peak")


def test_family_errors_against_finest_usable_run_and_richardson():
    # peak = 5 + 0.2 h^2 at h = 1, 2, 4; the run at h = 0.5 stopped early: excluded
    rows = [row("mesh", "m4", 4.0, 8.2), row("mesh", "m2", 2.0, 5.8), row("mesh", "m1", 1.0, 5.2),
            row("mesh", "m05", 0.5, 3.0, status="stopped")]
    family = ct.family_errors(rows)["mesh"]
    rich = family["richardson"]["peak"]
    by = {r["run"]: r for r in rows}
    assert {r["reference"] for r in rows} == {"m1"} == {family["reference"]}
    assert family["finer_unusable"] == ["m05"]  # the reference is not the finest level
    assert by["m2"]["err_peak"] == pytest.approx(0.6 / 5.2)
    assert by["m4"]["err_peak"] == pytest.approx(3.0 / 5.2)
    assert by["m1"]["err_peak"] == 0.0 and by["m1"]["err_curve"] == 0.0
    assert by["m05"]["err_peak"] is None and by["m05"]["rich_err_peak"] is None
    assert rich["order"] == pytest.approx(2.0) and rich["extrapolated"] == pytest.approx(5.0)
    assert rich["runs"] == ["m1", "m2", "m4"]
    assert by["m1"]["rich_err_peak"] == pytest.approx(0.04)
    # the curve is the peak times a fixed shape: its RMS error is m2's over m1's peak
    shape = np.sqrt(np.mean(np.interp(np.linspace(0, 40, ct.CURVE_POINTS), [0, 10, 40],
                                      [0, 1, 0.5]) ** 2))
    assert by["m2"]["err_curve"] == pytest.approx(0.6 * shape / 5.2)


def two_families():
    """Family a: base (cost 10, peak 10.5), a1 finer (cost 30, peak 10.05); family b: b2
    coarser (cost 4, peak 11.5), base, b05 finer (cost 25, peak 10.2). Base errors: a 4.48 %,
    b 2.94 %."""
    rows = [row("a", "base", 2.0, 10.5, cost=10.0, value="2"),
            row("a", "a1", 1.0, 10.05, cost=30.0, value="1"),
            row("b", "b2", 2.0, 11.5, cost=4.0, value="2"),
            row("b", "base", 1.0, 10.5, cost=10.0, value="1"),
            row("b", "b05", 0.5, 10.2, cost=25.0, value="0.5")]
    ct.family_errors(rows)
    ct.total_errors(rows, "base")
    return rows


def test_total_errors_add_the_other_families_base_errors():
    rows = two_families()
    by = {(r["family"], r["run"]): r for r in rows}
    e_a, e_b = 0.45 / 10.05, 0.3 / 10.2
    assert by["a", "base"]["total_err_peak"] == pytest.approx(e_a + e_b)
    assert by["b", "base"]["total_err_peak"] == pytest.approx(e_a + e_b)
    assert by["a", "a1"]["total_err_peak"] == pytest.approx(e_b)
    assert by["b", "b2"]["total_err_peak"] == pytest.approx(1.3 / 10.2 + e_a)
    assert by["b", "b05"]["total_err_peak"] == pytest.approx(e_a)


def test_pareto_front_and_cheapest_within():
    points = [(1.0, 0.2, "a"), (2.0, 0.08, "b"), (3.0, 0.09, "c"), (4.0, 0.01, "d"),
              (4.0, 0.03, "e")]
    assert [p[2] for p in ct.pareto_front(points)] == ["a", "b", "d"]
    assert ct.cheapest_within(points, 0.10)[2] == "b"
    assert ct.cheapest_within(points, 0.05)[2] == "d"
    assert ct.cheapest_within(points, 0.20)[2] == "a"
    assert ct.cheapest_within(points, 0.001) is None


def test_cheapest_runs_within_the_thresholds():
    rows = two_families()
    e_a = 0.45 / 10.05
    measured = {p[2]: p for p in ct.measured_points(rows, "peak")}
    assert set(measured) == {"base", "a1", "b2", "b05"}  # the shared base run counted once
    assert measured["b05"] == (25.0, pytest.approx(e_a), "b05")
    table = {(p["threshold"], p["quantity"]): p for p in ct.pareto_rows(rows)}
    assert table[0.10, "peak"]["run"] == "base"  # 7.4 % at 10 s
    assert table[0.05, "peak"]["run"] == "b05"  # 4.5 % at 25 s (a1: 2.9 % at 30 s)
    assert table[0.02, "peak"]["run"] is None
    assert table[0.05, "peak"]["cost_s"] == 25.0
    # "all": the largest of the peak, residual and curve errors (here all the same shape)
    assert table[0.05, "all"]["run"] == "b05"


def test_ladder_parsing_and_jobs(tmp_path):
    families = cv.parse_ladder(cv.DEFAULT_LADDER)
    assert [f.name for f in families] == ["element_size", "gauss", "increment", "tolerance"]
    assert families[3].keys == ("analysis.tolerance_displacement", "analysis.tolerance_load")
    levels, base, residual_at = cv.build_jobs(CF4, families, ["loads.control.target=16"],
                                              tmp_path)
    assert residual_at == 16.0
    assert len(levels) == 15 and len({lv["job"].name for lv in levels}) == 12
    assert [lv["job"] is base for lv in levels].count(True) == 4  # 75 mm, 3x3, x1, 0.05
    assert base.overrides == ("outputs.fields=[]", "loads.control.target=16")
    inc = [lv for lv in levels if lv["family"] == "increment"]
    assert [lv["value"] for lv in inc] == ["2", "1", "0.5"]  # factors on the deck's 1 mm
    assert inc[0]["job"].overrides[-1] == "loads.control.increment=2"
    gauss = [lv for lv in levels if lv["family"] == "gauss"]
    assert [lv["nominal"] for lv in gauss] == pytest.approx([0.5, 1 / 3, 0.25])
    bad = tmp_path / "ladder.yaml"
    bad.write_text("families:\n  mesh:\n    keys: analysis.element_size\n    values: [75, -1]\n")
    with pytest.raises(DeckError, match=r"ladder.yaml:2: families.mesh: .*positive"):
        cv.read_ladder(bad)
    result = CliRunner().invoke(main, ["convergence", CF4, "--ladder", str(bad)])
    assert result.exit_code == 2 and "Traceback" not in result.output
    assert len(result.output.strip().splitlines()) == 1
    typo = tmp_path / "typo.yaml"
    typo.write_text("families:\n  mesh: {keys: analysis.element_sise, values: [75, 50]}\n")
    with pytest.raises(DeckError, match="element_sise"):
        cv.build_jobs(CF4, cv.read_ladder(typo), (), tmp_path)


def test_quick_ladder_end_to_end(tmp_path, monkeypatch):
    """CF-4 to 4 mm: element size 150/75 and increment 2/1 mm (3 runs, the base shared)."""
    out = tmp_path / "conv"
    args = ["convergence", CF4, "--quick", "-o", str(out), "--set", "loads.control.target=4",
            "--set", "loads.control.increment=1", "--set", "analysis.element_size=75", "-q"]
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 0, result.output
    with open(out / "convergence_runs.csv", newline="") as f:
        reader = csv.DictReader(f)
        assert tuple(reader.fieldnames) == cv.COLUMNS
        rows = list(reader)
    assert [(r["family"], r["value"]) for r in rows] == [
        ("element_size", "150"), ("element_size", "75"), ("increment", "2"), ("increment", "1")]
    assert {r["status"] for r in rows} == {"completed"}
    for family in ("element_size", "increment"):
        members = [r for r in rows if r["family"] == family]
        finest = min(members, key=lambda r: float(r["h"]))
        assert finest["run"] == "cf4__base" and {r["reference"] for r in members} == {"cf4__base"}
        coarse = next(r for r in members if r is not finest)
        assert float(coarse["h"]) > float(finest["h"])
        assert float(coarse["err_peak"]) == pytest.approx(
            float(coarse["peak"]) / float(finest["peak"]) - 1.0, abs=1e-6)
        assert float(finest["err_peak"]) == 0.0 and float(coarse["err_curve"]) > 0.0
    # the base run's peak is the HDF5 file's largest load, the test error against Table 5.1
    from icewall.analysis.summary import summarize

    base = next(r for r in rows if r["run"] == "cf4__base")
    assert float(base["peak"]) == pytest.approx(summarize(out / "cf4__base.h5")["max_load"])
    assert float(base["test_err_peak"]) == pytest.approx(float(base["peak"]) / 4.91 - 1, rel=1e-4)
    assert float(base["first_peak"]) == pytest.approx(
        summarize(out / "cf4__base.h5")["first_max_load"])
    assert int(base["elements"]) > int(rows[0]["elements"])  # 75 mm is the finer mesh
    for name in ("families", "pareto", "curves"):
        assert (out / f"convergence_{name}.csv").stat().st_size > 0
    # resumed: nothing reruns; without matplotlib the plot is skipped, the tables written
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    (out / "convergence_runs.csv").unlink()
    lines: list[str] = []
    code = cv.convergence_command(CF4, quick=True, outdir=str(out), echo=lines.append,
                                  overrides=["loads.control.target=4",
                                             "loads.control.increment=1",
                                             "analysis.element_size=75"])
    assert code == 0 and (out / "convergence_runs.csv").exists()
    text = "\n".join(lines)
    assert text.count("skipped (completed earlier)") == 3
    assert "plot skipped: matplotlib is not installed" in text
    assert "element_size reference cf4__base" in text and "Cheapest run within" in text
    # --tables-only: results made by other code are tabled as they are, nothing reruns,
    # and a missing one is named
    monkeypatch.setattr("icewall.pipeline.code_version", lambda: "other")
    (out / "cf4__increment=2.h5").unlink()
    stamp = (out / "cf4__base.h5").stat().st_mtime_ns
    loud = [a for a in args if a != "-q"]
    result = CliRunner().invoke(main, [*loud, "--tables-only", "--no-plot"])
    assert result.exit_code == 0, result.output
    assert (out / "cf4__base.h5").stat().st_mtime_ns == stamp
    assert ("cf4__base: tabled from its file (the earlier result differs in code version)"
            in result.output)
    assert "cf4__increment=2: no result file: not tabled" in result.output
    with open(out / "convergence_runs.csv", newline="") as f:
        status = {(r["family"], r["value"]): r["status"] for r in csv.DictReader(f)}
    assert status["increment", "2"] == "missing" and status["increment", "1"] == "completed"
    both = CliRunner().invoke(main, [*args, "--tables-only", "--force"])
    assert both.exit_code == 2 and "not both" in both.output
