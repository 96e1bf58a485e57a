"""Two runs on one output, planted symbolic links, output names: icewall never touches a file
it does not own and never writes through a link (issue 21, items 1, 4 and 8)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys

import h5py
import numpy as np
import pytest
from reliability_helpers import (
    CF4,
    LINEAR,
    digest,
    icewall,
    one_error_line,
    start_icewall,
    wait_for,
)

from icewall.analysis.sweep import expand_jobs
from icewall.analysis.sweep_runners import run_job
from icewall.errors import ResultError
from icewall.results.checkpoint import write_checkpoint
from icewall.results.output_safety import OutputLock
from icewall.results.reader import open_result
from icewall.results.writer import ResultWriter


def _steps_on_disk(partial) -> int:
    try:
        with open_result(partial) as res:
            return len(res.history["load"])
    except Exception:  # noqa: BLE001 - being created
        return 0


def test_second_run_is_refused_and_the_first_finishes_intact(tmp_path):
    out = tmp_path / "same.h5"
    first = start_icewall("run", CF4, "--set", "loads.control.target=4", "--set",
                          "loads.control.increment=0.5", "-q", "-o", str(out))
    partial = tmp_path / "same.h5.partial"
    wait_for(lambda: _steps_on_disk(partial) >= 1, 120, "the first run's first step", first)
    # held still while the second runs: without this the first could finish (and release the
    # lock) before the second starts, and the second would rightly run (a flaky failure)
    first.send_signal(signal.SIGSTOP)
    try:
        second = icewall("run", CF4, *LINEAR, "-o", str(out))
    finally:
        first.send_signal(signal.SIGCONT)
    assert second.returncode == 2
    assert "being written by another icewall run" in one_error_line(second.stderr)
    _, err = first.communicate(timeout=300)
    assert first.returncode == 0, err
    with open_result(out) as res:  # the first run's result, whole and readable
        assert res.status == "completed" and res.attrs["solver"] == "nonlinear"
        assert len(res.history["load"]) == 8
    assert not (tmp_path / "same.h5.lock").exists()


def test_held_lock_leaves_the_partial_untouched(tmp_path):
    out = tmp_path / "cf4.h5"
    partial = tmp_path / "cf4.h5.partial"
    partial.write_bytes(b"first run's data" * 1000)
    before = digest(partial)
    with OutputLock(out):
        refused = icewall("run", CF4, *LINEAR, "-o", str(out))
    assert refused.returncode == 2, refused.stderr
    assert f"pid {os.getpid()}" in one_error_line(refused.stderr)
    assert digest(partial) == before and not out.exists()


def test_a_dead_holder_does_not_block(tmp_path):
    out = tmp_path / "cf4.h5"
    holder = subprocess.Popen([sys.executable, "-c",
                               "import sys, time\nfrom icewall.results.output_safety import "
                               "OutputLock\nOutputLock(sys.argv[1]).acquire()\nprint('held', "
                               "flush=True)\ntime.sleep(600)", str(out)],
                              stdout=subprocess.PIPE, text=True)
    assert holder.stdout.readline().strip() == "held"
    holder.send_signal(signal.SIGKILL)
    holder.wait(timeout=30)
    assert (tmp_path / "cf4.h5.lock").exists()  # left behind by the killed holder
    done = icewall("run", CF4, *LINEAR, "-q", "-o", str(out))
    assert done.returncode == 0, done.stderr
    assert out.exists() and not (tmp_path / "cf4.h5.lock").exists()


def test_sweep_rerun_while_an_orphaned_worker_writes(tmp_path):
    job = expand_jobs([CF4], ["analysis.solver=linear", "loads.control.target=2"],
                      outdir=tmp_path)[0]
    partial = tmp_path / f"{job.name}.h5.partial"
    partial.write_bytes(b"orphan's steps" * 1000)
    before = digest(partial)
    with OutputLock(job.output):  # the orphaned worker
        result = run_job(job)
    assert result["status"] == "failed"
    assert "being written by another icewall run" in result["reason"]
    assert digest(partial) == before and not os.path.exists(job.output)


@pytest.mark.parametrize("suffix", [".partial", "", ".lock", ".checkpoint.npz"])
def test_planted_symlink_is_refused(tmp_path, suffix):
    victim = tmp_path / "victim.txt"
    victim.write_text("precious")
    out = tmp_path / "cf4.h5"
    os.symlink(victim, str(out) + suffix)
    refused = icewall("run", CF4, *LINEAR, "-o", str(out))
    assert refused.returncode == 2, refused.stderr
    assert "symbolic link" in one_error_line(refused.stderr)
    assert victim.read_text() == "precious"


def test_checkpoint_temporary_link_is_not_followed(tmp_path):
    victim = tmp_path / "victim.txt"
    victim.write_text("precious")
    ckpt = tmp_path / "cf4.h5.checkpoint.npz"
    os.symlink(victim, str(ckpt) + ".tmp")
    write_checkpoint(ckpt, {"u": np.arange(3.0), "step": 1})
    assert victim.read_text() == "precious"
    with np.load(ckpt) as data:
        assert data["u"].tolist() == [0.0, 1.0, 2.0]


@pytest.mark.parametrize("name", ["run.hdf5", "RUN.H5", "run.HDF5"])
def test_hdf5_suffix_is_a_file_name(tmp_path, name):
    done = icewall("run", CF4, *LINEAR, "-q", "-o", str(tmp_path / name))
    assert done.returncode == 0, done.stderr
    assert (tmp_path / name).is_file()
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]


def test_empty_specimen_name_uses_the_deck_stem(tmp_path):
    done = icewall("run", CF4, *LINEAR, "--set", 'specimen.name=""', "-q", "-o", str(tmp_path))
    assert done.returncode == 0, done.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cf4.h5"]
    with h5py.File(tmp_path / "cf4.h5") as f:
        assert f.attrs["specimen"] == ""



def test_a_hard_linked_partial_is_never_written_into(tmp_path):
    out = tmp_path / "cf4.h5"
    victim = tmp_path / "victim.h5"
    sets = [*LINEAR, "--set", "loads.control.target=1"]
    assert icewall("run", CF4, *sets, "-q", "-o", str(victim)).returncode == 0
    before = digest(victim)
    os.link(victim, str(out) + ".partial")
    with pytest.raises(ResultError, match="hard link"):
        ResultWriter.reopen(out, 0)  # what --resume of a nonlinear run opens
    done = icewall("run", CF4, *sets, "-q", "--resume", "-o", str(out))  # linear: anew
    assert done.returncode == 0, done.stderr
    assert digest(victim) == before and out.exists()
