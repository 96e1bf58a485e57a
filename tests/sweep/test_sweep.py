"""`icewall sweep`: job expansion, resumability, failures, the summary table, Dask.

Every run here is a tiny linear analysis (two steps to 2 mm): the sweep machinery is under test,
not the mechanics.
"""

from __future__ import annotations

import csv
import os
from pathlib import Path

import pytest

from icewall.analysis.sweep import expand_jobs, finished_status, split_values, sweep_command
from icewall.analysis.sweep_runners import run_job, run_local
from icewall.errors import DeckError

DECKS = Path(__file__).resolve().parents[2] / "decks"
CF4, TF1, VTT3 = str(DECKS / "cf4.yaml"), str(DECKS / "tf1.yaml"), str(DECKS / "vtt3.yaml")
TINY = ["analysis.solver=linear", "loads.control.target=2"]


def sweep(decks, outdir, sets=(), **kwargs):
    """Run sweep_command; returns (exit status, printed lines)."""
    lines: list[str] = []
    code = sweep_command(decks, overrides=[*TINY, *sets], outdir=str(outdir),
                         echo=lines.append, **kwargs)
    return code, "\n".join(lines).splitlines()


def read_table(outdir) -> dict[str, dict]:
    with open(Path(outdir) / "sweep_summary.csv", newline="") as f:
        return {row["name"]: row for row in csv.DictReader(f)}


# ---- job expansion ----------------------------------------------------------------------------

def test_split_values_respects_brackets_and_quotes():
    assert split_values("40,50, 60") == ["40", "50", "60"]
    assert split_values("[450, 750],[300, 750]") == ["[450, 750]", "[300, 750]"]
    assert split_values('"a, b"') == ['"a, b"']
    assert split_values("{x: 1, y: 2}") == ["{x: 1, y: 2}"]
    with pytest.raises(DeckError, match="empty value"):
        split_values("40,,50")


def test_cartesian_product_names_and_outputs(tmp_path):
    jobs = expand_jobs([CF4, VTT3], ["materials.concrete.fc=40,50", "analysis.gauss=2,3",
                                     "analysis.solver=linear"], outdir=tmp_path)
    assert len(jobs) == 8
    assert [j.name for j in jobs[:4]] == [
        "cf4__materials.concrete.fc=40__analysis.gauss=2",
        "cf4__materials.concrete.fc=40__analysis.gauss=3",
        "cf4__materials.concrete.fc=50__analysis.gauss=2",
        "cf4__materials.concrete.fc=50__analysis.gauss=3"]
    first = jobs[0]
    assert first.overrides == ("analysis.solver=linear", "materials.concrete.fc=40",
                               "analysis.gauss=2")
    assert first.varied == ("materials.concrete.fc=40", "analysis.gauss=2")
    assert first.output == str(tmp_path / f"{first.name}.h5")
    assert jobs[4].name.startswith("vtt3__") and jobs[4].deck == VTT3
    # no variation: the deck stem is the name; a list value stays one value
    only = expand_jobs([TF1], ["geometry.diaphragms.positions=[450, 750]"], outdir=tmp_path)
    assert [j.name for j in only] == ["tf1"]
    assert only[0].overrides == ("geometry.diaphragms.positions=[450, 750]",)
    lists = expand_jobs([CF4], ["geometry.diaphragms.positions=[450, 750],[300, 750]"])
    assert [j.name for j in lists] == ["cf4__geometry.diaphragms.positions=450_750",
                                       "cf4__geometry.diaphragms.positions=300_750"]


def test_sweep_file(tmp_path):
    (tmp_path / "sub").mkdir()
    path = tmp_path / "sub" / "study.yaml"
    path.write_text(f"decks: [{os.path.relpath(CF4, path.parent)}]\n"
                    "vary:\n  materials.concrete.fc: [40, 60.5]\n"
                    "  materials.interface.model: [gap, bonded]\n"
                    "fixed: {analysis.solver: linear, specimen.description: 'yes'}\n")
    jobs = expand_jobs([VTT3], ["analysis.gauss=2"], sweep_file=path, outdir=tmp_path)
    assert len(jobs) == 8  # 2 decks x 2 x 2
    assert jobs[0].deck == VTT3 and Path(jobs[-1].deck).resolve() == Path(CF4).resolve()
    assert jobs[-1].name == "cf4__materials.concrete.fc=60.5__materials.interface.model=bonded"
    assert jobs[-1].overrides == ("analysis.solver=linear", 'specimen.description="yes"',
                                  "analysis.gauss=2", "materials.concrete.fc=60.5",
                                  "materials.interface.model=bonded")
    with pytest.raises(DeckError, match="given twice"):
        expand_jobs([CF4], ["analysis.solver=linear,nonlinear", "analysis.solver=linear"])
    # a --set replaces the file's entry for its key
    jobs = expand_jobs([], ["materials.concrete.fc=30", "analysis.solver=nonlinear,linear"],
                       sweep_file=path)
    assert [j.name for j in jobs] == [
        "cf4__materials.interface.model=gap__analysis.solver=nonlinear",
        "cf4__materials.interface.model=gap__analysis.solver=linear",
        "cf4__materials.interface.model=bonded__analysis.solver=nonlinear",
        "cf4__materials.interface.model=bonded__analysis.solver=linear"]
    assert jobs[0].overrides[:2] == ('specimen.description="yes"', "materials.concrete.fc=30")
    path.write_text("decks: [a.yaml]\nvary: {analysis.gauss: [2, 3]}\nfixed: {analysis.gauss: 2}")
    with pytest.raises(DeckError, match="study.yaml: analysis.gauss both varied and fixed"):
        expand_jobs(sweep_file=path)
    with pytest.raises(DeckError, match="share the name"):
        expand_jobs([CF4, str(tmp_path / "cf4.yaml")])
    with pytest.raises(DeckError, match="no decks"):
        expand_jobs([], ["analysis.gauss=2,3"])
    path.write_text("decks: [a.yaml]\nvaries: {}\n")
    with pytest.raises(DeckError, match="mapping of decks, vary, fixed"):
        expand_jobs(sweep_file=path)


# ---- running ----------------------------------------------------------------------------------

def test_sweep_table_and_ratios(tmp_path):
    code, lines = sweep([CF4, TF1, VTT3], tmp_path)
    assert code == 0
    assert sum(line.startswith(("[1/3]", "[2/3]", "[3/3]")) for line in lines) == 3
    assert any(line.startswith("mean") for line in lines)
    rows = read_table(tmp_path)
    assert set(rows) == {"cf4", "tf1", "vtt3", "mean", "cov"}
    from icewall.analysis.reference import find_reference

    for name, specimen in (("cf4", "CF-4"), ("tf1", "TF-1"), ("vtt3", "VTT3")):
        row = rows[name]
        assert row["status"] == "completed" and row["specimen"] == specimen
        assert (tmp_path / f"{name}.h5").exists()
        ref = find_reference(specimen)
        assert row["unit"] == ref.unit and float(row["peak"]) > 0
        assert row["residual_40"] == ""  # never reached 40 mm
        # a linear run never peaks: no ratio (tests/reliability checks the ratios of runs
        # that did peak, and that only those enter the mean and CoV)
        assert row["peaked"] == "no" and row["ult_test/pred"] == ""
    # issue 20 §1 columns; a linear run has no history columns: from the stored stress field
    cf4 = rows["cf4"]
    assert 0.0 < float(cf4["plate_mid/fy"]) <= float(cf4["plate_max/fy"])
    assert cf4["residual_mechanism"].startswith("at 2 mm")
    assert rows["mean"]["ult_test/pred"] == rows["mean"]["res_test/pred"] == ""


def test_realizations_and_their_bands(tmp_path):
    code, lines = sweep([CF4, VTT3], tmp_path, realizations=3)
    assert code == 0
    rows = read_table(tmp_path)
    assert set(rows) == {"cf4", "cf4.r1", "cf4.r2", "vtt3", "vtt3.r1", "vtt3.r2", "mean", "cov"}
    # realization k widens the patches by k 1e-8: its overrides say so, its loads barely move
    assert rows["cf4.r2"]["overrides"].endswith(f"loads.patches.width={50 * (1 + 2e-8)!r}")
    peaks = [float(rows[n]["peak"]) for n in ("cf4", "cf4.r1", "cf4.r2")]
    assert max(peaks) / min(peaks) - 1 < 1e-6 and len(set(peaks)) > 1
    with open(tmp_path / "sweep_realizations.csv", newline="") as f:
        bands = {row["name"]: row for row in csv.DictReader(f)}
    assert set(bands) == {"cf4", "vtt3", "mean", "cov"}
    cf4 = bands["cf4"]
    assert cf4["realizations"] == "3" and cf4["statuses"] == "3 completed"
    assert float(cf4["peak_min"]) == min(peaks) and float(cf4["peak_max"]) == max(peaks)
    assert float(cf4["peak"]) == sorted(peaks)[1]  # the median
    assert cf4["residual_40"] == ""  # a linear run to 2 mm never reaches 40 mm
    assert [rows[n]["ult_test/pred"] for n in ("cf4", "cf4.r1", "cf4.r2")] == [""] * 3
    assert cf4["ult_test/pred"] == ""  # linear runs never peak: no ratio to take a median of
    assert any(line.startswith("over 3 round-off realizations") for line in lines)


def test_resume_force_and_partial(tmp_path):
    code, _ = sweep([CF4], tmp_path, ["materials.concrete.fc=40,50"], workers=2)
    assert code == 0
    names = ["cf4__materials.concrete.fc=40", "cf4__materials.concrete.fc=50"]
    files = [tmp_path / f"{n}.h5" for n in names]
    stamps = [f.stat().st_mtime_ns for f in files]
    code, lines = sweep([CF4], tmp_path, ["materials.concrete.fc=40,50"], quiet=True)
    assert code == 0 and not any(line.startswith("[") for line in lines)  # quiet: no progress
    assert [f.stat().st_mtime_ns for f in files] == stamps
    assert set(read_table(tmp_path)) >= set(names)  # skipped runs still in the table
    _, lines = sweep([CF4], tmp_path, ["materials.concrete.fc=40,50"])
    assert sum("skipped (completed earlier)" in line for line in lines) == 2
    # a crash leaves only the .partial: that run alone is rerun
    os.replace(files[1], str(files[1]) + ".partial")
    _, lines = sweep([CF4], tmp_path, ["materials.concrete.fc=40,50"])
    assert sum("skipped (" in line for line in lines) == 1
    assert any(names[1] in line and "completed" in line for line in lines)
    assert files[1].exists() and not Path(str(files[1]) + ".partial").exists()
    assert files[0].stat().st_mtime_ns == stamps[0]
    # other fixed settings, same names: rerun; --force: rerun
    _, lines = sweep([CF4], tmp_path, ["materials.concrete.fc=40,50", "analysis.gauss=2"])
    assert not any("skipped (" in line for line in lines)
    assert finished_status(expand_jobs([CF4], [*TINY, "materials.concrete.fc=40,50"],
                                       outdir=tmp_path)[0]) is None
    before = files[0].stat().st_mtime_ns
    _, lines = sweep([CF4], tmp_path, ["materials.concrete.fc=40,50", "analysis.gauss=2"],
                     force=True)
    assert not any("skipped (" in line for line in lines)
    assert files[0].stat().st_mtime_ns != before


def test_edited_deck_is_rerun(tmp_path):
    deck = tmp_path / "vtt3.yaml"
    deck.write_text(Path(VTT3).read_text())
    sweep([str(deck)], tmp_path)
    _, lines = sweep([str(deck)], tmp_path)
    assert any("skipped (completed earlier)" in line for line in lines)
    deck.write_text(Path(VTT3).read_text() + "# edited\n")
    _, lines = sweep([str(deck)], tmp_path)
    assert any(line.startswith("[1/1] vtt3") and "completed" in line for line in lines)


def test_failing_deck_does_not_stop_the_others(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text(Path(CF4).read_text().replace("fc: 53.5", "fc: 53500.0"))
    code, lines = sweep([str(bad), VTT3], tmp_path / "out")
    assert code == 1
    rows = read_table(tmp_path / "out")
    assert rows["vtt3"]["status"] == "completed"
    assert rows["bad"]["status"] == "failed"
    assert "bad.yaml" in rows["bad"]["reason"] and "53500" in rows["bad"]["reason"]
    assert any(line.startswith("bad: failed: ") for line in lines)  # listed under the table
    # an override that breaks one variation: the job fails with the deck's message
    code, _ = sweep([VTT3], tmp_path / "out2", ["materials.concrete.fc=40,-5"])
    rows = read_table(tmp_path / "out2")
    assert code == 1
    assert rows["vtt3__materials.concrete.fc=40"]["status"] == "completed"
    failed = rows["vtt3__materials.concrete.fc=-5"]
    assert failed["status"] == "failed" and "materials.concrete.fc" in failed["reason"]
    assert failed["peak"] == ""


def _crashing_runner(job):
    """Kills its worker process for one job (as a segfault or the OOM killer would)."""
    if "fc=99" in job.name:
        os._exit(3)
    return run_job(job)


def test_worker_crash_fails_only_its_job(tmp_path):
    jobs = expand_jobs([VTT3], [*TINY, "materials.concrete.fc=40,99,50"], outdir=tmp_path)
    results: dict[str, dict] = {}
    run_local(jobs, 2, lambda r: results.__setitem__(r["name"], r), runner=_crashing_runner)
    assert {n: r["status"] for n, r in results.items()} == {
        "vtt3__materials.concrete.fc=40": "completed",
        "vtt3__materials.concrete.fc=99": "failed",
        "vtt3__materials.concrete.fc=50": "completed"}
    assert "worker process died" in results["vtt3__materials.concrete.fc=99"]["reason"]


# ---- Dask -------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def dask_cluster():
    distributed = pytest.importorskip("dask.distributed")
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       host="127.0.0.1", dashboard_address=None)
    yield cluster
    cluster.close()


def _dask_missing() -> bool:
    try:
        import dask.distributed  # noqa: F401
    except ImportError:
        return True
    return False


@pytest.mark.skipif(_dask_missing(), reason="dask[distributed] not installed (cluster extra)")
def test_dask_cluster_on_loopback(tmp_path, dask_cluster):
    address = dask_cluster.scheduler_address
    assert address.startswith("tcp://127.0.0.1:")
    code, lines = sweep([CF4, VTT3], tmp_path, ["materials.concrete.fc=40,-5"],
                        scheduler=address)
    assert code == 1  # the fc=-5 runs fail, on the cluster, without stopping the sweep
    rows = read_table(tmp_path)
    assert rows["cf4__materials.concrete.fc=40"]["status"] == "completed"
    assert rows["vtt3__materials.concrete.fc=40"]["status"] == "completed"
    assert rows["cf4__materials.concrete.fc=-5"]["status"] == "failed"
    assert sum(line.startswith("[") for line in lines) == 4
    _, lines = sweep([CF4, VTT3], tmp_path, ["materials.concrete.fc=40,-5"],
                     scheduler=address)
    assert sum("skipped (" in line for line in lines) == 2  # the failed ones are retried


def test_local_path_does_not_import_dask(tmp_path):
    import subprocess
    import sys

    code = ("import sys; from icewall.analysis.sweep import sweep_command; "
            f"rc = sweep_command([{VTT3!r}], overrides={TINY!r}, outdir={str(tmp_path)!r}, "
            "workers=1, echo=lambda s: None); "
            "assert rc == 0 and 'dask' not in sys.modules and 'distributed' not in sys.modules")
    subprocess.run([sys.executable, "-c", code], check=True, timeout=120)
    assert (tmp_path / "vtt3.h5").exists()
