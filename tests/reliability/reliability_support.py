"""Helpers of the reliability corpus (issue 21): the decks, a CLI runner that separates stdout
and stderr, and the lines of stderr that report an error."""

from __future__ import annotations

from pathlib import Path

from click.testing import CliRunner

from icewall.cli import main

DECKS = Path(__file__).resolve().parents[2] / "decks"
CF4, TF1 = DECKS / "cf4.yaml", DECKS / "tf1.yaml"
LINEAR = ["analysis.solver=linear", "loads.control.target=2", "analysis.element_size=125"]


def invoke(*args, env: dict | None = None):
    """Run `icewall ARGS` in-process; the result has .exit_code, .stdout, .stderr."""
    return CliRunner().invoke(main, [str(a) for a in args], env=env)


def error_lines(result) -> list[str]:
    """The lines of stderr that report an error."""
    return [line for line in result.stderr.splitlines()
            if line.lower().startswith("error")]
