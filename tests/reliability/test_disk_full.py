"""Disk full (issue 21, item 3): one clear line, exit 1, every converged step kept in the
`.partial`, no stray checkpoint temporary, the checkpoint kept, and `--resume` finishing the run
once there is space again. On a real size-limited filesystem (a tmpfs mounted with `size=`,
which needs root); the checkpoint's own handling also with a simulated ENOSPC."""

from __future__ import annotations

import errno
import os
import subprocess
import sys

import numpy as np
import pytest
from reliability_helpers import CF4, icewall

from icewall.results import checkpoint as checkpoint_module
from icewall.results.checkpoint import read_checkpoint, write_checkpoint
from icewall.results.output_safety import DiskFullError
from icewall.results.reader import open_result

# allow_large: the up-front estimate (icewall.deck.resources) refuses a result larger than the
# free disk before the run starts (tests/reliability/test_runaway_guard.py); here the disk runs
# full during the run, the case the estimate cannot foresee, so the refusal is turned into a
# warning
GUARD_OFF = ["--set", "analysis.allow_large=true"]
NONLINEAR = ["--set", "loads.control.target=6", "--set", "loads.control.increment=0.5",
             *GUARD_OFF]
LINEAR = ["--set", "analysis.solver=linear", *GUARD_OFF]


def _mount(path, size: str) -> None:
    subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(path)],
                   check=True, capture_output=True, text=True)


@pytest.fixture
def small_disk(tmp_path):
    """A 2 MiB tmpfs; `grow()` remounts it at 64 MiB (space freed)."""
    disk = tmp_path / "disk"
    disk.mkdir()
    if os.geteuid() != 0:
        pytest.skip("mounting a size-limited tmpfs needs root")
    try:
        _mount(disk, "2m")
    except (OSError, subprocess.CalledProcessError) as exc:
        reason = getattr(exc, "stderr", "") or str(exc)
        pytest.skip(f"cannot mount a size-limited tmpfs here: {reason.strip()}")

    def grow() -> None:
        subprocess.run(["mount", "-o", "remount,size=64m", str(disk)], check=True)

    try:
        yield disk, grow
    finally:
        subprocess.run(["umount", "-l", str(disk)], check=False)


def _disk_full_line(result: subprocess.CompletedProcess) -> str:
    assert result.returncode == 1, (result.returncode, result.stderr)
    assert "Traceback" not in result.stderr
    # (the allowed estimate's one warning line aside)
    lines = [line for line in result.stderr.splitlines()
             if line.strip() and not line.startswith("warning: ")]
    assert len(lines) == 1 and lines[0].startswith("error: disk full"), result.stderr
    return lines[0]


def _history(path) -> np.ndarray:
    with open_result(path) as res:
        return np.column_stack([res.history["control_displacement"], res.history["load"]])


@pytest.mark.parametrize("solver", ["linear", "nonlinear"])
def test_full_disk_stops_cleanly_and_resume_finishes(small_disk, tmp_path, solver):
    small_disk, grow = small_disk
    sets = LINEAR if solver == "linear" else NONLINEAR
    out = small_disk / "cf4.h5"
    full = icewall("run", CF4, *sets, "-q", "-o", str(out))
    line = _disk_full_line(full)
    partial = small_disk / "cf4.h5.partial"
    assert "converged steps are kept in" in line and str(partial) in line
    with open_result(partial) as res:
        assert res.status == "failed" and res.attrs["stop_reason"].startswith("disk full")
        kept = len(res.history["load"])
    assert kept >= 1
    assert not list(small_disk.glob("*.tmp")) and not out.exists()
    if solver == "nonlinear":
        assert int(read_checkpoint(str(out) + ".checkpoint.npz")["step"]) == kept
    grow()
    resumed = icewall("run", CF4, *sets, "-q", "--resume", "-o", str(out))
    assert resumed.returncode == 0, resumed.stderr
    assert sorted(p.name for p in small_disk.iterdir()) == ["cf4.h5"]
    reference = tmp_path / "reference.h5"
    assert icewall("run", CF4, *sets, "-q", "-o", str(reference)).returncode == 0
    np.testing.assert_array_equal(_history(out), _history(reference))


def test_hdf5_write_failing_unforeseen_does_not_crash(small_disk):
    """The free-space check bypassed (a disk filled by someone else meanwhile): HDF5's own
    write fails; one error line and exit 1, not a segfault at exit."""
    small_disk, _ = small_disk
    script = ("import sys\nfrom icewall.results import writer\n"
              "writer.ensure_space = lambda *a, **k: None\nfrom icewall.cli import main\n"
              "sys.argv = ['icewall', *sys.argv[1:]]\nmain()")
    out = small_disk / "cf4.h5"
    done = subprocess.run([sys.executable, "-c", script, "run", CF4, *LINEAR, "-q", "-o",
                           str(out)], capture_output=True, text=True, timeout=300)
    assert done.returncode == 1, done.stderr[-2000:]
    errors = [line for line in done.stderr.splitlines() if line.startswith("error: ")]
    assert len(errors) == 1 and errors[0].startswith("error: disk full writing step ")
    assert f" to {out}.partial (" in errors[0]
    assert not list(small_disk.glob("*.tmp")) and not (small_disk / "cf4.h5.lock").exists()


def test_checkpoint_write_failing_with_enospc(tmp_path, monkeypatch):
    path = tmp_path / "cf4.h5.checkpoint.npz"
    write_checkpoint(path, {"u": np.zeros(3), "step": 1})

    def no_space(file, **arrays):
        file.write(b"PK half")
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(checkpoint_module.np, "savez", no_space)
    with pytest.raises(DiskFullError, match="disk full writing the checkpoint"):
        write_checkpoint(path, {"u": np.ones(3), "step": 2})
    assert sorted(p.name for p in tmp_path.iterdir()) == [path.name]
    assert int(read_checkpoint(path)["step"]) == 1

