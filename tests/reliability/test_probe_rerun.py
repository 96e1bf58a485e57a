"""What the rerun of the hostile-input probe (issue 21) still found, each now held: damaged
result files are one line and exit 2, a step whose fields are missing is named, a sweep checks
every run's deck before it lists or runs one, an empty -o is refused, click's own usage errors
are one line too, and a sweep worker notices a parent that is a zombie."""

from __future__ import annotations

import subprocess
import time

import h5py
import numpy as np
import pytest
from reliability_helpers import CF4, LINEAR, icewall, one_error_line

from icewall.analysis.sweep_runners import _alive

FIELDS = ["--set", "outputs.fields=[displacement, stress, strain, state]"]


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    path = tmp_path_factory.mktemp("probe") / "cf4.h5"
    done = icewall("run", CF4, *LINEAR, *FIELDS, "-q", "-o", str(path))
    assert done.returncode == 0, done.stderr
    return path


def _damaged(result, tmp_path, damage) -> str:
    copy = tmp_path / "damaged.h5"
    copy.write_bytes(result.read_bytes())
    with h5py.File(copy, "r+") as f:
        damage(f)
    return str(copy)


def _step_group_misnamed(f):
    f["steps"].move(sorted(f["steps"])[0], "first")


def _no_cells(f):
    del f["mesh/cells"]


def _short_displacement(f):
    step = sorted(f["steps"])[-1]
    del f[f"steps/{step}/displacement"]
    f.create_dataset(f"steps/{step}/displacement", data=np.zeros((3, 3)))


# (a stored deck that is text but no longer loads is read by every reader alike, the figures
# that need it unknown: test_inputs.py::test_every_reader_reads_a_file_whose_deck_does_not_load)
@pytest.mark.parametrize(("command", "damage"), [("summary", _step_group_misnamed),
                                                 ("summary", _no_cells),
                                                 ("export", _short_displacement)])
def test_a_damaged_result_is_one_line_and_exit_2(result, tmp_path, command, damage):
    path = _damaged(result, tmp_path, damage)
    args = [command, path] + (["-o", str(tmp_path / "x.pvd")] if command == "export" else [])
    done = icewall(*args)
    assert done.returncode == 2, done.stderr
    assert "damaged result file" in one_error_line(done.stderr)


def test_export_names_a_step_whose_fields_are_missing(result, tmp_path):
    path = _damaged(result, tmp_path, lambda f: f.__delitem__(f"steps/{sorted(f['steps'])[0]}"))
    done = icewall("export", path, "-o", str(tmp_path / "x.pvd"))
    assert done.returncode == 0, done.stderr
    warning = [line for line in done.stderr.splitlines() if line.startswith("warning: ")]
    assert len(warning) == 1 and "step(s) 1 should store fields" in warning[0]


@pytest.mark.parametrize("value", ["40,abc", "40,1.0e999"])
def test_a_dry_run_checks_every_run(tmp_path, value):
    # (a real sweep runs the good variations and fails the bad one with the same message:
    # tests/sweep/test_sweep.py::test_failing_deck_does_not_stop_the_others)
    done = icewall("sweep", CF4, "--set", f"materials.concrete.fc={value}", "--dry-run",
                   "-o", str(tmp_path / "sw"))
    assert done.returncode == 2, done.stdout + done.stderr
    line = one_error_line(done.stderr)
    assert "materials.concrete.fc" in line and "(in run cf4__" in line
    assert not (tmp_path / "sw").exists()


def test_an_empty_output_is_refused():
    done = icewall("run", CF4, *LINEAR, "-o", "")
    assert done.returncode == 2 and "-o/--output" in one_error_line(done.stderr)


@pytest.mark.parametrize("args", [["frobnicate"], ["point", "--max-strain", "0"],
                                  ["mesh", CF4, "--format", "foo"], ["run"]])
def test_usage_errors_are_one_line(args):
    done = icewall(*args)
    assert done.returncode == 2
    one_error_line(done.stderr)


def test_a_zombie_parent_counts_as_dead():
    child = subprocess.Popen(["sleep", "0"])
    deadline = time.monotonic() + 10
    while _alive(child.pid) and time.monotonic() < deadline:  # ended, not yet reaped
        time.sleep(0.05)
    assert not _alive(child.pid)
    child.wait()
    assert not _alive(child.pid)
    running = subprocess.Popen(["sleep", "30"])
    try:
        assert _alive(running.pid)
    finally:
        running.kill()
        running.wait()
