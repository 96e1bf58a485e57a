"""`icewall sweep` reuses a result only if deck text, overrides and code say it is the same run
(issue 21, item 2); every `icewall run` stores the stamp."""

from __future__ import annotations

import csv
import json
import os
import shutil

import h5py
import pytest
from reliability_helpers import CF4, icewall

from icewall.analysis import sweep as sweep_module
from icewall.analysis.sweep import Job, reuse_verdict, sweep_command

LIN = ["analysis.solver=linear", "loads.control.target=2"]


def _sweep(outdir, sets):
    lines: list[str] = []
    code = sweep_command([CF4], overrides=sets, outdir=str(outdir), echo=lines.append,
                         workers=1)
    with open(outdir / "sweep_summary.csv", newline="") as f:
        rows = {row["name"]: row for row in csv.DictReader(f) if row["name"]}
    return code, "\n".join(lines), rows


def _run(out, sets):
    done = icewall("run", CF4, *[a for s in sets for a in ("--set", s)], "-q", "-o", str(out))
    assert done.returncode == 0, done.stderr


def test_run_result_with_other_overrides_is_rerun(tmp_path):
    _run(tmp_path / "cf4.h5", LIN)
    code, lines, rows = _sweep(tmp_path, ["analysis.solver=linear", "loads.control.target=3"])
    assert code == 0
    assert "rerun: the earlier result differs in overrides" in lines
    assert "skipped (" not in lines
    with h5py.File(tmp_path / "cf4.h5") as f:
        assert json.loads(f.attrs["deck_overrides"])[-1] == "loads.control.target=3"
        assert float(f["history/control_displacement"][-1]) == pytest.approx(3.0)
    assert rows["cf4"]["n_steps"] == "3"


def test_run_result_with_the_same_settings_is_reused(tmp_path):
    _run(tmp_path / "cf4.h5", LIN)
    code, lines, _ = _sweep(tmp_path, LIN)
    assert code == 0 and "skipped (completed earlier)" in lines


def _job(tmp_path, overrides=tuple(LIN)) -> Job:
    return Job("cf4", CF4, tuple(overrides), (), str(tmp_path / "cf4.h5"))


def test_other_code_version_is_rerun(tmp_path, monkeypatch):
    _run(tmp_path / "cf4.h5", LIN)
    assert reuse_verdict(_job(tmp_path)) == ("completed", "")
    import icewall.pipeline

    monkeypatch.setattr(icewall.pipeline, "code_version", lambda: "0.0.0+other")
    status, why = reuse_verdict(_job(tmp_path))
    assert status is None and why == "the earlier result differs in code version"


def test_edited_deck_and_missing_stamp_are_rerun(tmp_path):
    _run(tmp_path / "cf4.h5", LIN)
    deck = tmp_path / "cf4.yaml"
    shutil.copy(CF4, deck)
    deck.write_text(deck.read_text() + "# edited\n")
    job = Job("cf4", str(deck), tuple(LIN), (), str(tmp_path / "cf4.h5"))
    assert reuse_verdict(job) == (None, "the earlier result differs in deck text")
    with h5py.File(tmp_path / "cf4.h5", "a") as f:
        del f.attrs["run_stamp"]
        f.attrs["sweep_overrides"] = json.dumps(LIN)  # an old sweep's stamp is not enough
    assert reuse_verdict(_job(tmp_path)) == (None, "the earlier result has no run stamp")
    assert sweep_module.finished_status(_job(tmp_path)) is None


def test_resume_refuses_a_run_of_other_code(tmp_path, monkeypatch):
    """--resume ends with the result an uninterrupted run gives: only with the same code."""
    import icewall.pipeline
    from icewall.deck.load import load_deck
    from icewall.errors import ResultError

    out = tmp_path / "cf4.h5"
    loaded = load_deck(CF4, ["analysis.solver=linear", "loads.control.target=1"])
    icewall.pipeline.run_deck(loaded, out)
    os.replace(out, str(out) + ".partial")  # as if interrupted
    monkeypatch.setattr(icewall.pipeline, "code_version", lambda: "0.0.0+other")
    with pytest.raises(ResultError, match="it was run by other code"):
        icewall.pipeline.run_deck(loaded, out, resume=True)
