"""Helpers for deck tests: write a mutated copy of a shipped deck."""

from __future__ import annotations

from pathlib import Path

import pytest

DECKS = Path(__file__).resolve().parents[2] / "decks"


@pytest.fixture
def cf4_text() -> str:
    return (DECKS / "cf4.yaml").read_text()


@pytest.fixture
def write_deck(tmp_path):
    def write(text: str, name: str = "deck.yaml") -> Path:
        path = tmp_path / name
        path.write_text(text)
        return path

    return write
