"""The stability matrix (case, outcome, steps, time) is printed at the end of a run."""

from __future__ import annotations

import pytest

MATRIX: list[tuple[str, str, int, float]] = []


@pytest.fixture
def matrix_row():
    """Record one row of the stability matrix: (case, outcome, steps, seconds per run)."""
    return MATRIX.append


def pytest_terminal_summary(terminalreporter):
    if MATRIX:
        terminalreporter.section("stability matrix")
        terminalreporter.write_line(f"{'case':32s} {'outcome':34s} {'steps':>5s} {'s/run':>7s}")
        for name, outcome, steps, seconds in MATRIX:
            terminalreporter.write_line(f"{name:32s} {outcome:34s} {steps:5d} {seconds:7.1f}")
