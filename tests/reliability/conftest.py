"""Fixtures of the reliability corpus (issue 21): a tiny linear result, a copy of it to damage,
and a path no one can write to (under a regular file, so it holds for root too)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from reliability_support import CF4, LINEAR

from icewall.deck.load import load_deck
from icewall.pipeline import run_deck


@pytest.fixture(scope="session")
def linear_result(tmp_path_factory) -> Path:
    """CF-4, linear solver, two 1 mm steps, 125 mm elements: about 0.2 s."""
    report = run_deck(load_deck(CF4, LINEAR), tmp_path_factory.mktemp("rel") / "cf4_lin.h5")
    return Path(report.path)


@pytest.fixture
def result_copy(linear_result, tmp_path) -> Path:
    """A copy of the linear result to damage."""
    return Path(shutil.copy(linear_result, tmp_path / "copy.h5"))


@pytest.fixture
def unwritable(tmp_path) -> Path:
    """A directory path that cannot be created: its parent is a regular file."""
    blocker = tmp_path / "a_file"
    blocker.write_text("not a directory\n")
    return blocker / "out"
