"""Issue 21, items 7 and 8 (part B): no silent or misleading output. A linear-elastic result is
named as such and never presented as a prediction; an absurd preload is refused; a tampered
step count is an error, not dropped steps; YAML 1.2 exponent floats and merge keys are read;
a sweep ratio needs a peak; `plot -k all` draws what it can and names what it skipped; `make
run` stores the fields the crack-pattern plot needs."""

from __future__ import annotations

import json
import re
from pathlib import Path

import h5py
import pytest
from reliability_support import CF4, TF1, error_lines, invoke

from icewall.deck.load import load_deck, load_deck_text
from icewall.errors import DeckError, ResultError
from icewall.results.reader import open_result

ROOT = Path(__file__).resolve().parents[2]


# ---- the solver is named; a linear result is no prediction -----------------------------------

def test_summary_names_the_solver(linear_result, result_copy):
    result = invoke("summary", linear_result)
    assert result.exit_code == 0
    assert re.search(r"^solver\s+: linear \(linear-elastic, not a prediction\)$", result.stdout,
                     re.M)
    assert "ductility (CSA S474)   : not assessed" in result.stdout
    data = json.loads(invoke("summary", linear_result, "--json").stdout)
    assert data["solver"] == "linear" and data["ductility"].get("verdict") is None
    with h5py.File(result_copy, "a") as f:
        f.attrs["solver"] = "nonlinear"
    assert re.search(r"^solver\s+: nonlinear$", invoke("summary", result_copy).stdout, re.M)


def test_report_gives_a_linear_result_no_ratio(linear_result):
    from icewall.post.html_report import table_html, validation_row

    row = validation_row(linear_result)
    assert row["ultimate_test"] == pytest.approx(4.91)  # CF-4 has a test value to compare
    assert row["ult_ratio"] is None and row["res_ratio"] is None and row["verdict"] is None
    assert row["solver"] == "linear (linear-elastic, not a prediction)"
    assert "linear-elastic, not a prediction" in table_html([row])


# ---- range checks and deck reading -------------------------------------------------------------

@pytest.mark.parametrize("force", ["-1e15", "-1.5e7", "6e6"])
def test_an_absurd_preload_is_refused(force):
    result = invoke("check", TF1, "--set", f"loads.preload.axial_force={force}")
    assert result.exit_code == 2
    (line,) = error_lines(result)
    assert "loads.preload.axial_force" in line and "beyond the section's" in line


@pytest.mark.parametrize("deck", ["tf1", "tf2", "tf4", "tf5", "tf6", "tf7"])
def test_the_shipped_preloads_pass(deck):
    assert load_deck(ROOT / "decks" / f"{deck}.yaml").deck.loads.preload is not None


def test_yaml_exponent_floats_are_numbers():
    text = CF4.read_text().replace("E: 200000.0", "E: 2.0e5").replace("fy: 371.0", "fy: 371e0")
    deck = load_deck_text(text, "cf4.yaml", ["loads.control.target=4.0e1",
                                             "materials.concrete.fc=5.35E+1"]).deck
    assert deck.materials.steel.E == 200000.0 and deck.materials.steel.fy == 371.0
    assert deck.loads.control.target == 40.0 and deck.materials.concrete.fc == 53.5
    with pytest.raises(DeckError, match="expected a number, got 'e5'"):
        load_deck_text(text, "cf4.yaml", ["materials.steel.E=e5"])


def test_sweep_file_exponent_floats_are_numbers(tmp_path):
    from icewall.analysis.sweep import expand_jobs

    sweep_file = tmp_path / "sweep.yaml"
    sweep_file.write_text(f"decks: [{CF4}]\nvary: {{materials.steel.E: [2.0e5, 2.1e5]}}\n")
    jobs = expand_jobs(sweep_file=sweep_file, outdir=tmp_path)
    assert [load_deck(j.deck, j.overrides).deck.materials.steel.E for j in jobs] == [2.0e5,
                                                                                    2.1e5]


def test_yaml_merge_keys_are_read():
    text = CF4.read_text().replace("  interface:\n", "  bearing_plates: &elastic {E: 210000.0, "
                                   "nu: 0.3}\n  legs:\n    <<: *elastic\n    nu: 0.25\n"
                                   "  interface:\n")
    deck = load_deck_text(text, "cf4.yaml").deck
    assert deck.materials.legs.E == 210000.0 and deck.materials.legs.nu == 0.25
    twice = text.replace("    nu: 0.25\n", "    nu: 0.25\n    nu: 0.2\n")
    with pytest.raises(DeckError, match="duplicate key"):
        load_deck_text(twice, "cf4.yaml")


# ---- a tampered result file ----------------------------------------------------------------------

@pytest.mark.parametrize("n_steps", [1, 3, -1])
def test_a_tampered_step_count_is_an_error(result_copy, n_steps):
    with h5py.File(result_copy, "a") as f:
        assert f.attrs["n_steps"] == 2 and len(f["history/load"]) == 2
        f.attrs["n_steps"] = n_steps
    with pytest.raises(ResultError, match="corrupt result file, n_steps"):
        open_result(result_copy)
    result = invoke("summary", result_copy)
    assert result.exit_code == 2 and "n_steps" in error_lines(result)[0]


def test_a_run_killed_between_append_and_count_still_reads(result_copy):
    """The writer appends a step's history, then counts it: a running file may hold one
    value more than n_steps (readers trust n_steps), a finished one may not."""
    with h5py.File(result_copy, "a") as f:
        f.attrs["n_steps"] = 1
        f.attrs["status"] = "running"
    with open_result(result_copy) as r:
        assert len(r.history["load"]) == 1


# ---- sweep table: a ratio needs a peak -----------------------------------------------------------

def test_sweep_ratios_only_for_runs_that_peaked(tmp_path, monkeypatch):
    from icewall.analysis import sweep_table
    from icewall.analysis.sweep import expand_jobs

    jobs = expand_jobs([CF4], ["materials.concrete.fc=40,50,60"], outdir=tmp_path)
    peaks = {"40": (5.0, True), "50": (4.0, True), "60": (3.18, False)}  # 60: still rising
    results = {}
    for job in jobs:
        Path(job.output).touch()
        results[job.name] = {"name": job.name, "path": job.output, "status": "completed"}

    def measures(path):
        peak, peaked = peaks[re.search(r"fc=(\d+)", path).group(1)]
        return {"specimen": "CF-4", "status": "completed", "unit": "MPa", "peak": peak,
                "peaked": "yes" if peaked else "no", "residual_40": peak / 2}

    monkeypatch.setattr(sweep_table, "_measures", measures)
    rows = sweep_table.build_rows(jobs, results)
    by_fc = {re.search(r"fc=(\d+)", r["name"]).group(1): r for r in rows}
    assert by_fc["40"]["ult_test/pred"] == pytest.approx(4.91 / 5.0)
    assert by_fc["50"]["ult_test/pred"] == pytest.approx(4.91 / 4.0)
    assert all(by_fc["60"][c] is None for c in sweep_table.RATIOS)
    mean, cov, n = sweep_table.ratio_stats(rows)["ult_test/pred"]
    assert n == 2 and mean == pytest.approx((4.91 / 5.0 + 4.91 / 4.0) / 2)


# ---- plots ---------------------------------------------------------------------------------------

def test_plot_all_draws_what_it_can_and_names_what_it_skipped(linear_result, tmp_path):
    pytest.importorskip("matplotlib")
    result = invoke("plot", linear_result, "-k", "all", "-o", tmp_path, "--format", "png")
    assert result.exit_code == 0, result.output
    drawn = sorted(p.name for p in tmp_path.iterdir())
    assert drawn == ["cf4_lin_deformed_peak.png", "cf4_lin_plates_peak.png",
                     "cf4_lin_trajectories_peak.png", "curves.png"]
    skipped = [line for line in result.stderr.splitlines() if line.startswith("skipped ")]
    assert [line.split(":")[0] for line in skipped] == ["skipped cracks_peak",
                                                         "skipped interface_peak"]
    assert "state" in skipped[0]  # says why
    result = invoke("plot", linear_result, "-k", "cracks,plates", "-o", tmp_path / "two",
                    "--format", "png")
    assert result.exit_code == 2  # a kind asked for by name and not drawn is an error
    assert (tmp_path / "two" / "cf4_lin_plates_peak.png").exists()


def test_make_run_stores_the_state_fields():
    """The README's first command (`make run`) writes what the crack-pattern plot needs."""
    makefile = (ROOT / "Makefile").read_text()
    fields = re.search(r"^RUN_FIELDS \?= (.+)$", makefile, re.M).group(1)
    target = re.search(r"^run: .*\n\t(.+)$", makefile, re.M).group(1)
    assert "--set 'outputs.fields=$(RUN_FIELDS)'" in target
    deck = load_deck(CF4, [f"outputs.fields={fields}"]).deck
    assert set(deck.outputs.fields) == {"displacement", "stress", "strain", "state"}
