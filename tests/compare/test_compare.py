"""icewall compare: unit tests on synthetic records, and the CI comparison of the CI variants
against the stored baseline (tests/compare/baseline_ci.yaml)."""

from __future__ import annotations

import copy
from pathlib import Path

import pytest

from icewall.analysis import ci_gate
from icewall.analysis import compare as cmp
from icewall.errors import ResultError

HERE = Path(__file__).resolve().parent
BASELINE = HERE / "baseline_ci.yaml"
WIDE = (0.0, 10.0)  # a band that never fails: tests of the per-run checks


def record(peak=5.0, residual=3.0, status="completed", specimen="CF-4", **extra) -> dict:
    rec = {"specimen": specimen, "deck": "decks/cf4.yaml", "overrides": ["loads.control.target=16"],
           "status": status, "stop_reason": "" if status == "completed" else "snap-back",
           "unit": "MPa", "peak_load": peak, "deflection_at_peak": 10.0, "peaked": True,
           "final_deflection": 16.0 if status == "completed" else 12.0,
           "residual_deflection": 16.0,
           "residual_load": residual if status == "completed" else None}
    rec.update(extra)
    return rec


def baseline_of(records: dict, band=WIDE) -> dict:
    return cmp.make_baseline(records, command="test", ratio_band=band)


def verdicts(report, quantity: str) -> dict[str, str]:
    return {r.run: r.verdict for r in report.rows if r.quantity.startswith(quantity)}


def test_peak_moved_5_percent_fails_at_3_percent():
    base = baseline_of({"cf4": record(peak=5.0), "cf5": record(peak=4.0, specimen="CF-5")})
    now = {"cf4": record(peak=5.25), "cf5": record(peak=4.0 * 1.02, specimen="CF-5")}
    report = cmp.compare(now, base, peak_tol=0.03, ratio_band=WIDE)
    assert verdicts(report, "peak") == {"cf4": "FAIL", "cf5": "ok"}
    assert not report.passed
    row = next(r for r in report.rows if r.run == "cf4" and r.quantity == "peak")
    assert row.change == pytest.approx(0.05)
    assert "FAIL" in cmp.format_report(report).splitlines()[-1]
    # the same 5 % passes a stated 6 % tolerance
    assert cmp.compare(now, base, peak_tol=0.06, ratio_band=WIDE).passed


def test_residual_within_10_percent_passes_beyond_fails():
    base = baseline_of({"cf4": record(residual=3.0)})
    within = cmp.compare({"cf4": record(residual=3.0 * 0.92)}, base, residual_tol=0.10,
                         ratio_band=WIDE)
    assert within.passed and verdicts(within, "res@16mm") == {"cf4": "ok"}
    beyond = cmp.compare({"cf4": record(residual=3.0 * 1.12)}, base, residual_tol=0.10,
                         ratio_band=WIDE)
    assert verdicts(beyond, "res@16mm") == {"cf4": "FAIL"} and not beyond.passed


def test_completed_run_that_now_stops_fails_and_vice_versa():
    base = baseline_of({"cf4": record(), "tf2": record(status="stopped", specimen="TF-2")})
    now = {"cf4": record(status="stopped"), "tf2": record(status="completed", specimen="TF-2")}
    report = cmp.compare(now, base, ratio_band=WIDE)
    status = {r.run: r for r in report.rows if r.quantity == "status"}
    assert status["cf4"].verdict == "FAIL" and "now stops" in status["cf4"].note
    assert status["tf2"].verdict == "FAIL" and "now completes" in status["tf2"].note
    # the residual of a run that stopped short has no value: reported, and failed
    assert verdicts(report, "res@") == {"cf4": "FAIL", "tf2": "FAIL"}


def test_stopped_in_both_is_a_valid_state():
    base = baseline_of({"cf4": record(status="stopped")})
    report = cmp.compare({"cf4": record(status="stopped")}, base, ratio_band=WIDE)
    assert report.passed
    assert verdicts(report, "res@") == {"cf4": "ok"}  # no value on either side


def test_missing_new_and_other_overrides():
    base = baseline_of({"cf4": record(), "cf5": record(specimen="CF-5")})
    now = {"cf4": record(overrides=["loads.control.target=20"]), "vtt3": record(specimen="VTT3")}
    report = cmp.compare(now, base, ratio_band=WIDE)
    by = {(r.run, r.quantity): r.verdict for r in report.rows}
    assert by[("cf5", "run")] == "FAIL"  # in the baseline, not in the results
    assert by[("vtt3", "run")] == "new"  # reported, does not fail by itself
    assert by[("cf4", "overrides")] == "FAIL"


def test_mean_test_over_predicted_ratio_band():
    # CF-4 test 4.91 MPa, CF-5 test 3.82 MPa (reference_data.yaml); a blind deck has no test
    recs = {"cf4": record(peak=4.91), "cf5": record(peak=3.82 / 0.9, specimen="CF-5"),
            "cf6": record(peak=9.0, specimen="CF-6")}
    mean, n = cmp.mean_ratio(recs)
    assert n == 2 and mean == pytest.approx(0.95)
    base = baseline_of(recs)
    assert cmp.compare(recs, base, ratio_band=(0.93, 1.07)).passed
    low = cmp.compare(recs, base, peak_tol=1.0, ratio_band=(0.96, 1.07))
    ratio_row = low.rows[-1]
    assert ratio_row.verdict == "FAIL" and "outside" in ratio_row.note and not low.passed
    # every peak 10 % higher: the per-run check and the band (0.93) both catch it
    higher = {k: {**v, "peak_load": v["peak_load"] * 1.1} for k, v in recs.items()}
    report = cmp.compare(higher, base, peak_tol=0.03, ratio_band=(0.93, 1.07))
    assert report.rows[-1].verdict == "FAIL"
    assert verdicts(report, "peak") == {"cf4": "FAIL", "cf5": "FAIL", "cf6": "FAIL"}


def test_baseline_file_round_trip_and_command(tmp_path):
    recs = {"cf4": record(), "cf5": record(peak=4.0, specimen="CF-5")}
    path = tmp_path / "base.yaml"
    cmp.write_baseline(path, cmp.make_baseline(recs, command="icewall compare x --update",
                                               peak_tol=0.02, ratio_band=(0.5, 2.0)))
    text = path.read_text()
    assert "# Written by: icewall compare x --update" in text
    data = cmp.read_baseline(path)
    assert "not validation data" in data["note"] and data["command"] == "icewall compare x --update"
    assert data["tolerances"] == {"peak": 0.02, "curve": 0.01, "residual": 0.10,
                                  "ratio_band": [0.5, 2.0]}
    assert data["runs"]["cf5"]["peak_load"] == 4.0 and data["icewall_version"]
    lines: list[str] = []
    # the header's tolerances apply when none is given: 2.5 % fails at the stated 2 %
    moved = copy.deepcopy(recs)
    moved["cf4"]["peak_load"] = 5.0 * 1.025
    assert cmp.compare_command(moved, path, echo=lines.append) == 1
    assert cmp.compare_command(moved, path, peak_tol=0.03, echo=lines.append) == 0
    assert lines[0].split()[:5] == ["run", "quantity", "baseline", "now", "change"]
    # --update rewrites it from the results
    assert cmp.compare_command(moved, path, update=True, command="update", echo=lines.append) == 0
    assert cmp.read_baseline(path)["runs"]["cf4"]["peak_load"] == pytest.approx(5.125)
    assert cmp.compare_command(moved, path, echo=lines.append) == 0


def test_missing_baseline_is_an_error(tmp_path):
    with pytest.raises(ResultError, match="--update"):
        cmp.compare_command({"cf4": record()}, tmp_path / "none.yaml", echo=print)
    with pytest.raises(ResultError, match="not found"):
        cmp.compare_command(tmp_path / "nothing", tmp_path / "none.yaml", echo=print)


def test_band_of_the_realizations_widened_by_the_tolerance():
    # three realizations of one run: peaks 5.0-5.1, residuals 2.0-2.5 (bands within half the
    # tolerances below, so both are gated)
    group = [record(peak=5.0, residual=2.0), record(peak=5.1, residual=2.5),
             record(peak=5.05, residual=2.2)]
    base = cmp.make_baseline({"cf4": group[0]}, command="test", ratio_band=WIDE,
                             realizations={"cf4": group})
    run = base["runs"]["cf4"]
    assert run["peak_band"] == [5.0, 5.1] and run["residual_band"] == [2.0, 2.5]
    assert run["realizations"] == 3 and run["statuses"] == ["completed"]
    checks = {  # peak, residual -> verdicts (peak 5 %, residual 60 % beyond the band edges)
        (5.1, 2.5): ("ok", "ok"), (5.35, 3.95): ("ok", "ok"), (4.76, 0.81): ("ok", "ok"),
        (5.36, 2.2): ("FAIL", "ok"), (4.74, 2.2): ("FAIL", "ok"), (5.0, 4.05): ("ok", "FAIL"),
        (5.0, 0.79): ("ok", "FAIL")}
    for (peak, residual), expected in checks.items():
        report = cmp.compare({"cf4": record(peak=peak, residual=residual)}, base,
                             peak_tol=0.05, residual_tol=0.60, ratio_band=WIDE)
        got = (verdicts(report, "peak")["cf4"], verdicts(report, "res@")["cf4"])
        assert got == expected, (peak, residual, got)
    row = next(r for r in cmp.compare({"cf4": record(peak=5.4)}, base, peak_tol=0.05,
                                      ratio_band=WIDE).rows if r.quantity == "peak")
    assert row.change == pytest.approx(5.4 / 5.1 - 1) and "band [5, 5.1]" in row.note


def test_a_status_any_realization_ended_with_is_no_change():
    # one realization of three stopped short (non-convergence): a stop is then no change,
    # and neither is the residual it lacks; without that realization the stop fails
    group = [record(), record(status="stopped"), record(residual=3.1)]
    base = cmp.make_baseline({"cf8": group[0]}, command="test", ratio_band=WIDE,
                             realizations={"cf8": group})
    assert base["runs"]["cf8"]["statuses"] == ["completed", "stopped"]
    assert base["runs"]["cf8"]["residual_band"] == [3.0, 3.1]  # over those with a value
    assert cmp.compare({"cf8": record(status="stopped")}, base, ratio_band=WIDE).passed
    alone = cmp.make_baseline({"cf8": group[0]}, command="test", ratio_band=WIDE)
    assert not cmp.compare({"cf8": record(status="stopped")}, alone, ratio_band=WIDE).passed


def test_realizations_perturb_only_the_patch_width(tmp_path):
    jobs = {j.name: j for j in ci_gate.ci_jobs(tmp_path, {"cf4": ("loads.control.target=15",)},
                                           realizations=3)}
    assert sorted(jobs) == ["cf4", "cf4.r1", "cf4.r2"]
    assert jobs["cf4"].overrides == ("loads.control.target=15",)
    widths = [float(jobs[n].overrides[-1].split("=")[1]) for n in ("cf4.r1", "cf4.r2")]
    assert widths == pytest.approx([50.0 * (1 + 1e-8), 50.0 * (1 + 2e-8)], rel=1e-15)
    assert widths[0] != 50.0 and jobs["cf4.r2"].output == str(tmp_path / "cf4.r2.h5")


def test_stored_baseline_matches_the_ci_variants():
    data = cmp.read_baseline(BASELINE)
    assert set(data["runs"]) == set(ci_gate.CI_VARIANTS)
    for name, run in data["runs"].items():
        assert run["overrides"] == list(ci_gate.CI_VARIANTS[name])
        assert run["deck"] == f"decks/{name}.yaml"
        # the round-off realizations and the same variant on other platforms (--platform)
        assert run["realizations"] >= ci_gate.REALIZATIONS
        assert len(run["curve_bands"]) == len(run["curve_deflections"]) > 0
        assert run["status"] in run["statuses"]
        if run["peak_load"] is not None:  # the run itself is one of the realizations
            assert run["peak_band"][0] <= run["peak_load"] <= run["peak_band"][1]
    assert "not validation data" in data["note"]


def test_ci_comparison_of_the_ci_variants(tmp_path):
    """Runs the eight CI variants (about 2 minutes on 2 cores) and compares them with the
    stored baseline: must pass on the current code."""
    lines: list[str] = []
    status = ci_gate.run_ci_comparison(tmp_path / "ci", BASELINE, workers=2, echo=lines.append)
    assert status == 0, "\n".join(lines)
    assert lines[-1].splitlines()[-1] == "PASS"
    assert len(list((tmp_path / "ci").glob("*.h5"))) == len(ci_gate.CI_VARIANTS)


def test_a_figure_whose_band_is_wider_than_its_tolerance_is_reported_not_gated():
    # peaks spread 4 % over the realizations (> half of 3 %): any peak is reported; the residual is
    # reported when the baseline's tolerance is null (README, "Round-off")
    group = [record(peak=5.0, residual=2.0), record(peak=5.2, residual=3.0)]
    base = cmp.make_baseline({"cf4": group[0]}, command="test", ratio_band=WIDE,
                             realizations={"cf4": group})
    report = cmp.compare({"cf4": record(peak=9.0, residual=9.0)}, base, peak_tol=0.03,
                         residual_tol=None, ratio_band=WIDE)
    rows = {r.quantity: r for r in report.rows if r.run == "cf4"}
    assert rows["peak"].verdict == "info" and "span 4.0% > 0.5 x 3.0%" in rows["peak"].note
    assert rows["res@16mm"].verdict == "info" and "not gated" in rows["res@16mm"].note
    assert report.passed
    # the same peak against a narrow band (1 %, under half the tolerance) fails
    narrow = cmp.make_baseline({"cf4": group[0]}, command="test", ratio_band=WIDE,
                               realizations={"cf4": [group[0], record(peak=5.05)]})
    assert not cmp.compare({"cf4": record(peak=9.0)}, narrow, peak_tol=0.03,
                           residual_tol=None, ratio_band=WIDE).passed


def test_pre_peak_loads_are_gated_against_their_bands():
    group = [record(curve_deflections=[1.0, 2.0], curve_loads=[1.0, 2.0]),
             record(curve_deflections=[1.0, 2.0], curve_loads=[1.001, 2.002])]
    base = cmp.make_baseline({"cf4": group[0]}, command="test", ratio_band=WIDE,
                             realizations={"cf4": group})
    assert base["runs"]["cf4"]["curve_bands"] == [[1.0, 1.001], [2.0, 2.002]]

    def curve_verdicts(loads):
        report = cmp.compare({"cf4": record(curve_deflections=[1.0, 2.0], curve_loads=loads)},
                             base, curve_tol=0.01, ratio_band=WIDE)
        rows = [r for r in report.rows if r.quantity.startswith("load@")]
        return [(r.quantity, r.verdict) for r in rows]

    assert curve_verdicts([1.005, 1.99]) == [("load@1mm", "ok"), ("load@2mm", "ok")]
    assert curve_verdicts([1.02, 2.0]) == [("load@1mm", "FAIL"), ("load@2mm", "ok")]
    assert curve_verdicts([1.0, None]) == [("load@1mm", "ok"), ("load@2mm", "FAIL")]


@pytest.mark.parametrize("change", ["fc103", "mu103", "leg103"])
def test_a_3_percent_model_change_fails_the_ci_gate(change):
    """Issue 18: the gate must catch a real change of the model. The CI variants were run with
    f'c, the friction coefficient or the TF leg width 3 % larger (tests/compare/
    model_changes.yaml, measured); against the stored baseline each fails on a gated pre-peak
    load, named with its band (0.5 % beyond it, ci_gate.CI_TOLERANCES)."""
    import yaml

    data = yaml.safe_load((HERE / "model_changes.yaml").read_text())[change]
    base = cmp.read_baseline(BASELINE)
    runs = {name: base["runs"][name] for name in data["runs"]}
    report = cmp.compare(data["runs"], {**base, "runs": runs},
                         **_ci_tolerances(base), ratio_band=(0.0, 10.0))
    loads = [r for r in report.failures if r.quantity.startswith("load@")]
    assert loads and all("moved more than 0.5%" in r.note for r in loads)
    # anything else that fails is a run that now stops (f'c: CF-13), never a silent pass
    assert all(r.quantity.startswith("load@") or r.run == "cf13" for r in report.failures)


def _ci_tolerances(base: dict) -> dict:
    t = base["tolerances"]
    return {"peak_tol": t["peak"], "curve_tol": t["curve"], "residual_tol": t["residual"]}


def test_the_ci_baseline_gates_what_is_reproducible_and_reports_the_rest():
    base = cmp.read_baseline(BASELINE)
    assert base["tolerances"]["residual"] is None  # post-peak: reported only
    gated = 0
    for run in base["runs"].values():
        for band in run["curve_bands"]:
            lo, hi = band
            gated += hi / lo - 1 <= cmp.GATE_FRACTION * base["tolerances"]["curve"]
    # of 24 pre-peak loads: 23 when written with the readings of issue 20 and realizations that
    # keep the mesh (14 while they changed it, 17 before issue 20; README, "Round-off")
    assert gated >= 22
