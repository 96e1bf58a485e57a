"""Shared helpers of the reliability corpus: run the CLI in a subprocess, watch processes."""

from __future__ import annotations

import hashlib
import subprocess
import sys
import time
from pathlib import Path

import pytest

DECKS = Path(__file__).resolve().parents[2] / "decks"
CF4 = str(DECKS / "cf4.yaml")
LINEAR = ["--set", "analysis.solver=linear", "--set", "loads.control.target=2"]


def icewall(*args: str, timeout: float = 300) -> subprocess.CompletedProcess:
    """Run `icewall ARGS` to its end; stdout and stderr as text."""
    return subprocess.run([sys.executable, "-m", "icewall.cli", *args], capture_output=True,
                          text=True, timeout=timeout)


def start_icewall(*args: str) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "icewall.cli", *args],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def digest(path: Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def alive(pid: int) -> bool:
    """Whether process `pid` runs (a zombie nobody reaped has ended)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, IndexError):
        return False
    return state not in ("Z", "X")


def wait_for(condition, timeout: float, what: str, proc: subprocess.Popen | None = None):
    """Poll `condition()` until true; fail naming `what` (or when `proc` ended first)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = condition()
        if value:
            return value
        if proc is not None and proc.poll() is not None:
            out, err = proc.communicate()
            pytest.fail(f"the process ended before {what}: rc {proc.returncode}\n{out}\n{err}")
        time.sleep(0.1)
    pytest.fail(f"timed out waiting for {what}")


def one_error_line(stderr: str) -> str:
    """The single 'error: ...' line of a refused command (no traceback)."""
    assert "Traceback" not in stderr, stderr
    lines = [line for line in stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), stderr
    return lines[0]
