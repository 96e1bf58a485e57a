"""Killing a sweep (issue 21, item 8): SIGKILL leaves no worker running on; SIGTERM stops the
runs, writes the table of the runs finished so far and exits 143."""

from __future__ import annotations

import csv
import signal

from reliability_helpers import CF4, alive, start_icewall, wait_for

from icewall.results.reader import open_result


def _worker_pid(lock) -> int | None:
    try:
        text = lock.read_text().strip()
    except FileNotFoundError:
        return None
    return int(text) if text.isdigit() else None


def _steps_on_disk(partial) -> int:
    try:
        with open_result(partial) as res:
            return len(res.history["load"])
    except Exception:  # noqa: BLE001 - not there yet, or being created
        return 0


def test_sigkill_of_a_sweep_kills_its_workers(tmp_path):
    sweep = start_icewall("sweep", CF4, "--set", "loads.control.target=40", "-j", "1", "-q",
                          "-o", str(tmp_path))
    worker = wait_for(lambda: _worker_pid(tmp_path / "cf4.h5.lock"), 120, "the run's lock",
                      sweep)
    assert worker != sweep.pid and alive(worker)
    sweep.send_signal(signal.SIGKILL)
    sweep.wait(timeout=30)  # (its pipes stay open while any helper process lives)
    wait_for(lambda: not alive(worker), 30, f"the worker {worker} to die with the sweep")


def test_sigterm_of_a_sweep_writes_the_finished_runs(tmp_path):
    sweep = start_icewall("sweep", CF4, "--set", "analysis.solver=linear,nonlinear", "--set",
                          "loads.control.target=40", "-j", "2", "-o", str(tmp_path))
    fast, slow = "cf4__analysis.solver=linear", "cf4__analysis.solver=nonlinear"
    for line in sweep.stdout:  # progress lines, flushed as each run ends
        if fast in line and "completed" in line:
            break
    else:
        raise AssertionError(f"the linear run did not complete: {sweep.communicate()}")
    worker = wait_for(lambda: _worker_pid(tmp_path / f"{slow}.h5.lock"), 120,
                      "the nonlinear run's lock", sweep)
    wait_for(lambda: _steps_on_disk(tmp_path / f"{slow}.h5.partial") >= 1, 120,
             "the nonlinear run's first step", sweep)
    sweep.send_signal(signal.SIGTERM)
    out, err = sweep.communicate(timeout=60)
    assert sweep.returncode == 143, err
    assert "Traceback" not in err and "interrupted by SIGTERM" in err
    assert "interrupted: 1 of 2 runs in the table" in out
    with open(tmp_path / "sweep_summary.csv", newline="") as f:
        rows = {row["name"]: row for row in csv.DictReader(f) if row["name"]}
    assert rows[fast]["status"] == "completed" and slow not in rows
    wait_for(lambda: not alive(worker), 30, "the nonlinear worker to stop")
    with open_result(tmp_path / f"{slow}.h5.partial") as res:
        assert res.status == "failed"
        assert res.attrs["stop_reason"] == "interrupted by SIGTERM"
