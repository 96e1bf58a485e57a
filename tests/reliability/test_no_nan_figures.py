"""Issue 38, items 2 and 3: a NaN or an infinity is never a figure, and compare's mean
test/predicted ratio leaves out the runs that never peaked, as sweep's does. A non-finite value
in a result file is one line naming the file, the dataset and the step (exit 2) in every reader;
one in a baseline is one line naming the file, the line and the key; a baseline written by
--update from a set of results passes against that same set."""

from __future__ import annotations

import json
import math
import shutil

import h5py
import numpy as np
import pytest
from reliability_support import CF4, LINEAR, error_lines, invoke

from icewall.analysis.compare import compare, compare_command, mean_ratio
from icewall.errors import ResultError


def _tampered(result, tmp_path, dataset: str, index: int, value: float):
    copy = tmp_path / "results" / "cf4.h5"
    copy.parent.mkdir()
    shutil.copy(result, copy)
    with h5py.File(copy, "r+") as f:
        data = f[dataset][...]
        data.reshape(-1)[index] = value
        f[dataset][...] = data
    return copy


def _step(linear_result, index: int) -> int:
    with h5py.File(linear_result) as f:
        return int(f["history/step"][index])


READERS = {
    "summary": lambda p, t: ["summary", p],
    "summary-json": lambda p, t: ["summary", "--json", p],
    "plot": lambda p, t: ["plot", p, "-o", t / "plots", "--format", "png"],
    "export": lambda p, t: ["export", p, "-o", t / "x.pvd"],
    "report": lambda p, t: ["report", p, "-o", t / "r.html"],
    "compare": lambda p, t: ["compare", p.parent, "--baseline", t / "b.yaml", "--update"],
}
DAMAGE = {  # dataset, flat index, value
    "nan-load": ("history/load", 1, math.nan),
    "inf-load-factor": ("history/load_factor", 0, math.inf),
    "nan-deflection": ("history/control_displacement", 1, math.nan),
}


@pytest.mark.parametrize("reader", list(READERS))
@pytest.mark.parametrize("damage", list(DAMAGE))
def test_a_non_finite_history_value_is_a_named_error(linear_result, tmp_path, reader, damage):
    dataset, index, value = DAMAGE[damage]
    path = _tampered(linear_result, tmp_path, dataset, index, value)
    result = invoke(*READERS[reader](path, tmp_path))
    assert result.exit_code == 2, result.output
    lines = error_lines(result)
    assert len(lines) == 1, result.stderr
    assert f"{path}" in lines[0] and dataset in lines[0]
    assert f"at step {_step(linear_result, index)}" in lines[0]
    assert "nan" not in result.stdout.lower() and not (tmp_path / "b.yaml").exists()


def test_a_non_finite_field_is_a_named_error(tmp_path):
    out = tmp_path / "cf4.h5"
    assert invoke("run", CF4, *(a for o in LINEAR for a in ("--set", o)), "-q", "-o",
                  out).exit_code == 0
    with h5py.File(out, "r+") as f:
        step = sorted(f["steps"])[-1]
        u = f[f"steps/{step}/displacement"]
        u[0, 0] = np.nan
    result = invoke("export", out, "-o", tmp_path / "x.pvd")
    assert result.exit_code == 2
    (line,) = error_lines(result)
    assert f"steps/{step}/displacement" in line and f"at step {int(step)}" in line


def test_summary_json_is_strict_json(linear_result):
    result = invoke("summary", "--json", linear_result)
    assert result.exit_code == 0
    json.loads(result.stdout, parse_constant=lambda name: pytest.fail(f"{name} in the JSON"))


def test_an_undefined_derived_figure_is_none():
    from icewall.analysis.summary import finite_figures

    assert finite_figures({"a": math.inf, "b": [math.nan, 1.5], "c": {"d": -math.inf},
                           "e": "nan"}) == {"a": None, "b": [None, 1.5], "c": {"d": None},
                                            "e": "nan"}


# -- baselines --------------------------------------------------------------------------------
def _baseline(tmp_path, linear_result, replace: tuple[str, str] | None = None):
    runs = tmp_path / "runs"
    runs.mkdir()
    shutil.copy(linear_result, runs / "cf4.h5")
    base = tmp_path / "b.yaml"
    assert invoke("compare", runs, "--baseline", base, "--update").exit_code == 0
    if replace:
        text = base.read_text()
        assert replace[0] in text
        base.write_text(text.replace(replace[0], replace[1], 1))
    return runs, base


@pytest.mark.parametrize(("key", "value"), [("peak_load", ".nan"), ("peak_load", ".inf"),
                                            ("final_deflection", "-.inf")])
def test_compare_rejects_a_non_finite_baseline_value(linear_result, tmp_path, key, value):
    runs, base = _baseline(tmp_path, linear_result)
    lines = base.read_text().splitlines()
    at = next(i for i, line in enumerate(lines) if line.strip().startswith(f"{key}:"))
    lines[at] = f"{lines[at].split(':')[0]}: {value}"
    base.write_text("\n".join(lines) + "\n")
    result = invoke("compare", runs, "--baseline", base)
    assert result.exit_code == 2, result.output
    (line,) = error_lines(result)
    assert f"{base}:{at + 1}: runs.cf4.{key}:" in line and "not a finite number" in line


def test_compare_rejects_a_non_finite_tolerance(linear_result, tmp_path):
    runs, base = _baseline(tmp_path, linear_result, ("peak: 0.03", "peak: .nan"))
    result = invoke("compare", runs, "--baseline", base)
    assert result.exit_code == 2 and "tolerances.peak" in error_lines(result)[0]


# -- the mean ratio: runs that peaked only ----------------------------------------------------
def _record(peak: float, peaked: bool, specimen: str = "CF-4") -> dict:
    return {"specimen": specimen, "deck": "decks/cf4.yaml", "overrides": [],
            "status": "completed", "stop_reason": "", "unit": "MPa", "peak_load": peak,
            "deflection_at_peak": 10.0, "peaked": peaked, "final_deflection": 15.0,
            "residual_deflection": 15.0, "residual_load": 2.0, "curve_deflections": [],
            "curve_loads": []}


def test_a_run_that_never_peaked_stays_out_of_the_mean_ratio():
    # CF-4's test ultimate is 4.91 MPa: 1.0 for the run that peaked; the other, still rising
    # at its end (its largest load no ultimate), would pull the mean to 0.75
    records = {"cf4": _record(4.91, True), "cf4_short": _record(9.82, False)}
    assert mean_ratio(records) == (pytest.approx(1.0), 1)
    assert mean_ratio({"short": _record(9.82, False)}) == (None, 0)


def test_a_baseline_written_by_update_passes_against_its_results(tmp_path):
    records = {"cf4": _record(4.91, True), "cf4_short": _record(9.82, False)}
    base = tmp_path / "b.yaml"
    assert compare_command(records, base, update=True, echo=lambda text: None) == 0
    assert compare_command(records, base, echo=lambda text: None) == 0
    assert compare(records, base).passed


def test_update_refuses_a_baseline_that_would_fail_at_once(tmp_path):
    records = {"cf4": _record(4.91 / 0.5, True)}  # test/predicted 0.5, outside 0.93-1.07
    base = tmp_path / "b.yaml"
    with pytest.raises(ResultError, match="would fail against the results it is made from"):
        compare_command(records, base, update=True, echo=lambda text: None)
    assert not base.exists()
    assert compare_command(records, base, update=True, band=(0.4, 1.1),
                           echo=lambda text: None) == 0
    assert compare_command(records, base, echo=lambda text: None) == 0


def test_update_then_compare_of_a_sweep_that_never_peaked(linear_result, tmp_path):
    """The issue's case on the command line: a linear run (it never peaks) with a test value."""
    runs, base = _baseline(tmp_path, linear_result)
    result = invoke("compare", runs, "--baseline", base)
    assert result.exit_code == 0, result.output
    assert result.stdout.rstrip().endswith("PASS")
