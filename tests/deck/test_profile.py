"""Deck profiles (`--profile NAME`): overlays under --set, errors at the profile's line, the
record in the result file and the sweep's reuse."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from icewall.analysis.sweep import sweep_command
from icewall.cli import main
from icewall.deck.load import load_deck, load_deck_text
from icewall.deck.profile import find_profile, load_profile
from icewall.errors import DeckError
from icewall.results.reader import open_result

DECKS = Path(__file__).resolve().parents[2] / "decks"
CF4, VTT3 = str(DECKS / "cf4.yaml"), str(DECKS / "vtt3.yaml")
TINY = ["analysis.solver=linear", "loads.control.target=2", "outputs.fields=[]"]

PROFILE = """\
profile: demo
description: test overlay
overlay:
  analysis: {gauss: 2, element_size: 80.0}
  materials:
    steel: {hardening: 0.02, formulation: same}
series:
  CF:
    analysis: {element_size: 70.0}
specimens:
  CF-4:
    analysis: {element_size: 87.0}
    materials: {interface: {fixed_points_per_core: 2}}
"""


@pytest.fixture
def profile(tmp_path) -> Path:
    path = tmp_path / "demo.yaml"
    path.write_text(PROFILE)
    return path


def test_overlay_series_specimen_then_set(profile):
    deck = load_deck(CF4, [], profile).deck
    assert (deck.analysis.gauss, deck.analysis.element_size) == (2, 87.0)  # specimen wins
    assert deck.materials.steel.hardening == 0.02 and deck.materials.steel.formulation == "same"
    assert deck.materials.interface.fixed_points_per_core == 2
    assert deck.materials.steel.fy == 371.0  # untouched keys stay the deck's
    vtt = load_deck(VTT3, [], profile).deck  # no VTT section: the overlay alone
    assert vtt.analysis.element_size == 80.0
    over = load_deck(CF4, ["analysis.element_size=60", "analysis.gauss=4"], profile).deck
    assert (over.analysis.gauss, over.analysis.element_size) == (4, 60.0)  # --set wins


def test_stored_overrides_rebuild_the_deck(profile):
    """A result stores the profile's assignments among its overrides: the readers that rebuild
    a deck from the stored text and overrides see what the run saw."""
    loaded = load_deck(CF4, ["analysis.gauss=4"], profile)
    assert loaded.overrides[-1] == "analysis.gauss=4"
    assert "analysis.element_size=87.0" in loaded.overrides
    again = load_deck_text(loaded.text, "stored", loaded.overrides).deck
    assert again == loaded.deck
    assert load_deck(CF4).deck != loaded.deck


def test_a_bad_value_names_the_profile_file_and_line(tmp_path, profile):
    bad = tmp_path / "bad.yaml"
    bad.write_text("profile: bad\noverlay:\n  analysis:\n    gauss: 5\n")
    with pytest.raises(DeckError) as err:
        load_deck(CF4, [], bad)
    assert (err.value.file, err.value.line, err.value.key) == (str(bad), 4, "analysis.gauss")
    typo = tmp_path / "typo.yaml"
    typo.write_text("overlay:\n  analysis:\n    elemnt_size: 80\n")
    with pytest.raises(DeckError) as err:
        load_deck(CF4, [], typo)
    assert (err.value.file, err.value.line) == (str(typo), 3)
    # a --set of the same key replaces the profile's value: the error is the --set's
    with pytest.raises(DeckError) as err:
        load_deck(CF4, ["analysis.gauss=7"], bad)
    assert err.value.file == CF4
    wrong = tmp_path / "wrong.yaml"
    wrong.write_text("profile: wrong\noverlays: {}\n")
    with pytest.raises(DeckError, match="unknown key") as err:
        load_profile(str(wrong))
    assert err.value.line == 2


def test_cli_profile_errors_are_one_line_exit_2(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("overlay:\n  materials:\n    concrete: {fc: -3}\n")
    runner = CliRunner()
    for command in ("check", "run"):
        result = runner.invoke(main, [command, CF4, "--profile", str(bad)])
        assert result.exit_code == 2, result.output
        assert f"{bad}:3: materials.concrete.fc" in result.output
    result = runner.invoke(main, ["check", CF4, "--profile", "no-such-profile"])
    assert result.exit_code == 2 and "unknown profile 'no-such-profile'" in result.output


def test_the_shipped_thesis_profile_is_found_by_name():
    assert find_profile("thesis").name == "thesis.yaml"
    assert load_deck(CF4, [], "thesis").profile.name == "thesis"


def test_run_records_the_profile_and_a_sweep_reruns_on_another(tmp_path, profile):
    out = tmp_path / "sweep"
    lines: list[str] = []
    assert sweep_command([CF4], overrides=TINY, outdir=str(out), workers=1,
                         echo=lines.append, profile=str(profile)) == 0
    with open_result(out / "cf4.h5") as res:
        assert res.attrs["profile"] == "demo" and res.attrs["profile_text"] == PROFILE
        assert json.loads(res.attrs["run_stamp"])["profile"].startswith("demo ")
        assert "analysis.element_size=87.0" in json.loads(res.attrs["deck_overrides"])
    lines.clear()
    sweep_command([CF4], overrides=TINY, outdir=str(out), workers=1, echo=lines.append,
                  profile=str(profile))
    assert any("skipped" in line for line in lines)
    other = tmp_path / "other.yaml"
    other.write_text(PROFILE.replace("gauss: 2", "gauss: 3"))
    lines.clear()
    sweep_command([CF4], overrides=TINY, outdir=str(out), workers=1, echo=lines.append,
                  profile=str(other))
    assert any("rerun: the earlier result differs in profile" in line for line in lines)
    lines.clear()
    sweep_command([CF4], overrides=TINY, outdir=str(out), workers=1, echo=lines.append)
    assert any("rerun: the earlier result differs in profile" in line for line in lines)
