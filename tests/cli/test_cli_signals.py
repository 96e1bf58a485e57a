"""A run stopped by SIGTERM or SIGINT keeps every finished step and records why it stopped."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from icewall.results.reader import open_result

DECKS = Path(__file__).resolve().parents[2] / "decks"


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT])
def test_signal_mid_run_leaves_a_valid_partial_file(tmp_path, signum):
    out = tmp_path / "cf4.h5"
    proc = subprocess.Popen(
        [sys.executable, "-m", "icewall.cli", "run", str(DECKS / "cf4.yaml"), "-o", str(out),
         "--set", "loads.control.target=40", "--set", "analysis.max_iterations=400"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    partial = Path(str(out) + ".partial")
    deadline = time.time() + 120
    while time.time() < deadline:  # wait until at least two steps are on disk
        if partial.exists():
            try:
                with open_result(partial) as res:
                    if len(res.history["load"]) >= 2:
                        break
            except Exception:  # the file is being created
                pass
        if proc.poll() is not None:
            break
        time.sleep(0.2)
    assert proc.poll() is None, "the run ended before it could be interrupted"
    proc.send_signal(signum)
    _, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 128 + signum
    assert f"interrupted by {signal.Signals(signum).name}" in stderr
    assert "Traceback" not in stderr
    with open_result(partial) as res:
        assert res.status == "failed"
        assert res.attrs["stop_reason"] == f"interrupted by {signal.Signals(signum).name}"
        assert len(res.history["load"]) >= 2
