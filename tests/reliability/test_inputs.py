"""Issue 38, item 5: every input file goes through the deck's error path: one line naming the
file, the line or key and what is wrong, exit 2; never the internal-error catch-all (exit 1),
never a traceback. Decks, sweep files, ladders, --set values, compare baselines; and a result
file whose stored deck no longer loads gets one rule from every reader."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys

import h5py
import pytest
from reliability_support import CF4, error_lines, invoke


def _one_line(result, exit_code: int = 2) -> str:
    assert result.exit_code == exit_code, (result.exit_code, result.output)
    assert result.exception is None or isinstance(result.exception, SystemExit)
    assert "Traceback" not in result.output and "internal error" not in result.output
    lines = error_lines(result)
    assert len(lines) == 1, result.stderr
    return lines[0]


def _deck(tmp_path, old: str, new: str):
    text = CF4.read_text()
    assert old in text
    path = tmp_path / "deck.yaml"
    path.write_text(text.replace(old, new, 1))
    return path


# -- control characters --------------------------------------------------------------------------
def test_a_control_character_in_a_deck(tmp_path):
    path = _deck(tmp_path, "fc: 53.5", "fc: 5\x013.5")
    line_no = next(i for i, line in enumerate(path.read_text().splitlines(), 1) if "\x01" in line)
    line = _one_line(invoke("check", path))
    assert f"{path}:{line_no}:" in line and "U+0001" in line


def test_a_control_character_in_a_set_value():
    line = _one_line(invoke("check", CF4, "--set", "materials.concrete.fc=4\x010"))
    assert "--set materials.concrete.fc" in line and "U+0001" in line


def test_a_control_character_in_a_sweep_file(tmp_path):
    sweep = tmp_path / "sweep.yaml"
    sweep.write_text(f"decks: [{CF4}]\nvary: {{materials.concrete.fc: [40\x02, 50]}}\n")
    line = _one_line(invoke("sweep", "-f", sweep, "--dry-run", "-o", tmp_path / "o"))
    assert f"{sweep}:2:" in line and "U+0002" in line


def test_a_control_character_in_a_ladder(tmp_path):
    ladder = tmp_path / "ladder.yaml"
    ladder.write_text("families:\n  gauss: {keys: analysis.gauss, values: [2, 3\x1b]}\n")
    line = _one_line(invoke("convergence", CF4, "--ladder", ladder, "--tables-only", "-o",
                            tmp_path / "c"))
    assert f"{ladder}:2:" in line and "U+001B" in line


# -- compare baselines ------------------------------------------------------------------------
@pytest.fixture
def baseline(linear_result, tmp_path):
    runs = tmp_path / "runs"
    runs.mkdir()
    shutil.copy(linear_result, runs / "cf4.h5")
    path = tmp_path / "b.yaml"
    assert invoke("compare", runs, "--baseline", path, "--update").exit_code == 0
    return runs, path


def _set_line(path, key: str, value: str) -> int:
    lines = path.read_text().splitlines()
    at = next(i for i, line in enumerate(lines) if line.strip().startswith(f"{key}:"))
    lines[at] = f"{lines[at].split(':')[0]}: {value}"
    path.write_text("\n".join(lines) + "\n")
    return at + 1


@pytest.mark.parametrize(("key", "value", "message"), [
    ("peak_load", "abc", "expected a number, got 'abc'"),
    ("peak_load", "9" * 400, "too large for a number"),
    ("curve_loads", "[1.0, x]", "item 1: expected a number"),
    ("overrides", "5", "expected a list"),
    ("peaked", "maybe", "expected true or false"),
    ("ratio_band", "[1.1, 0.9]", "LO > HI"),
    ("status", "[completed]", "expected a string"),
])
def test_a_malformed_baseline_value_names_its_line_and_key(baseline, key, value, message):
    runs, path = baseline
    at = _set_line(path, key, value)
    line = _one_line(invoke("compare", runs, "--baseline", path))
    assert f"{path}:{at}:" in line and message in line and key in line


@pytest.mark.parametrize(("name", "content", "message"), [
    ("binary", b"\x89PNG\r\n\x1a\n\x00\x00\xff\xfe", "not a text file"),
    ("nul", b"runs: {}\n\x00\n", "NUL byte"),
    ("control", b"runs:\n  cf4: {peak_load: 1\x07}\n", "U+0007"),
    ("nested-3000", b"runs: " + b"[" * 3000 + b"]" * 3000 + b"\n", "nested more than 64"),
    ("mapping-nested-3000", b"".join(b"  " * i + b"k%d:\n" % i for i in range(3000)), "nested"),
    ("huge-integer", b"runs: {}\ntolerances: {peak: " + b"9" * 5000 + b"}\n", "cannot read"),
    ("not-a-mapping", b"- 1\n- 2\n", "not a baseline file"),
    ("runs-a-list", b"runs: [1, 2]\n", "not a baseline file"),
    ("run-a-number", b"runs: {cf4: 5}\n", "runs.cf4: expected a mapping"),
    ("duplicate-key", b"runs: {}\nruns: {}\n", "duplicate key"),
])
def test_a_malformed_baseline_file_is_one_line(linear_result, tmp_path, name, content,
                                               message):
    runs = tmp_path / "runs"
    runs.mkdir()
    shutil.copy(linear_result, runs / "cf4.h5")
    path = tmp_path / "b.yaml"
    path.write_bytes(content)
    line = _one_line(invoke("compare", runs, "--baseline", path))
    assert str(path) in line and message in line


def test_the_shipped_ci_baseline_reads():
    from icewall.analysis.ci_gate import BASELINE_CI
    from icewall.analysis.compare import read_baseline

    assert len(read_baseline(BASELINE_CI)["runs"]) >= 8


# -- a result whose stored deck no longer loads: one rule for every reader ---------------------
def _with_deck(result, tmp_path, deck) -> str:
    copy = tmp_path / "runs" / "cf4.h5"
    copy.parent.mkdir(exist_ok=True)
    shutil.copy(result, copy)
    with h5py.File(copy, "r+") as f:
        del f["deck"]
        f.create_dataset("deck", data=deck)
    return str(copy)


BROKEN_DECKS = {"garbage": "{{{ not yaml", "control-character": "version: 1\x01\n",
                "a-list": "[1, 2]", "missing-keys": "version: 1\n", "not-text": [1, 2, 3]}
READERS = {
    "summary": lambda p, t: ["summary", p],
    "summary-json": lambda p, t: ["summary", "--json", p],
    "plot": lambda p, t: ["plot", p, "-o", t / "plots", "--format", "png"],
    "export": lambda p, t: ["export", p, "-o", t / "x.pvd"],
    "report": lambda p, t: ["report", p, "-o", t / "r.html"],
    "compare": lambda p, t: ["compare", t / "runs", "--baseline", t / "b.yaml", "--update"],
}


@pytest.mark.parametrize("reader", list(READERS))
@pytest.mark.parametrize("deck", list(BROKEN_DECKS))
def test_every_reader_reads_a_file_whose_deck_does_not_load(linear_result, tmp_path, reader,
                                                            deck):
    """The rule (results.reader.ResultFile.stored_deck): such a file is read for what its
    history and fields hold; what needs the deck (f_y, tolerances, reference, target) is
    unknown, and summary says why."""
    pytest.importorskip("matplotlib") if reader in ("plot", "report") else None
    path = _with_deck(linear_result, tmp_path, BROKEN_DECKS[deck])
    result = invoke(*READERS[reader](path, tmp_path))
    assert result.exit_code == 0, result.output
    assert "Traceback" not in result.output and not error_lines(result)
    if reader == "summary":
        assert "stored deck" in result.stdout and "does not load" in result.stdout
    if reader == "summary-json":
        assert json.loads(result.stdout)["stored_deck_problem"]


def test_a_damaged_overrides_attribute_is_named(linear_result, tmp_path):
    path = _with_deck(linear_result, tmp_path, CF4.read_text())
    with h5py.File(path, "r+") as f:
        f.attrs["deck_overrides"] = "{not json"
    line = _one_line(invoke("compare", tmp_path / "runs", "--baseline", tmp_path / "b.yaml",
                            "--update"))
    assert path in line and "deck_overrides" in line


# -- what the second probe of issue 38 found besides ------------------------------------------
def test_an_escaped_lone_surrogate_in_a_deck_string(tmp_path):
    """json.dumps("CF-4 \U0001f9ca") writes "\\ud83e\\uddca", which YAML reads as two lone
    surrogates: the result file could not be written (an internal UnicodeEncodeError)."""
    path = _deck(tmp_path, "name: CF-4", 'name: "CF-4 \\ud83e\\uddca"')
    line = _one_line(invoke("check", path))
    assert "specimen.name" in line and "surrogate" in line


def test_a_specimen_name_too_long_for_a_file_name(tmp_path):
    line = _one_line(invoke("check", _deck(tmp_path, "name: CF-4", "name: " + "x" * 300)))
    assert "specimen.name" in line and "300 characters" in line


def _damaged_attr(result, tmp_path, name, value) -> str:
    copy = tmp_path / "r.h5"
    shutil.copy(result, copy)
    with h5py.File(copy, "r+") as f:
        f.attrs[name] = value
    return str(copy)


@pytest.mark.parametrize(("attr", "value"), [("status", "\x1b[31mcompleted"),
                                             ("specimen", "x" * 100000),
                                             ("specimen", "CF\x1b[2J-4")])
@pytest.mark.parametrize("reader", ["summary", "plot", "report"])
def test_a_tampered_label_is_one_line_in_every_reader(linear_result, tmp_path, attr, value,
                                                      reader):
    """A 100000-character specimen name made plot and report lay out their title for ever;
    an escape sequence in the status reached the terminal."""
    path = _damaged_attr(linear_result, tmp_path, attr, value)
    args = {"summary": [], "plot": ["-o", str(tmp_path / "p"), "--format", "png"],
            "report": ["-o", str(tmp_path / "r.html")]}[reader]
    done = subprocess.run([sys.executable, "-m", "icewall.cli", reader, path, *args],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 2, done.stderr
    lines = [line for line in done.stderr.splitlines() if line.strip()]
    assert len(lines) == 1, done.stderr
    assert ("attribute specimen" if attr == "specimen" else "status") in lines[0]
    assert "\x1b" not in done.stdout + done.stderr


def test_a_fifo_named_as_a_result_does_not_block(tmp_path):
    fifo = tmp_path / "r.h5"
    os.mkfifo(fifo)
    done = subprocess.run([sys.executable, "-m", "icewall.cli", "summary", str(fifo)],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 2 and "not a regular file" in done.stderr


@pytest.mark.parametrize(("args", "hint"), [(["--path", "biaxial:nan"], "--path"),
                                            (["--path", "biaxial:1e308"], "--path"),
                                            (["--unload-at", "nan"], "--unload-at"),
                                            (["--unload-at", "-1"], "--unload-at")])
def test_point_refuses_a_ratio_or_unloading_strain_it_would_ignore(args, hint):
    """A NaN stress ratio gave zero stresses, 1e308 printed NumPy's overflow warnings, an
    unloading strain off the path was dropped without a word."""
    line = _one_line(invoke("point", "--fc", "40", "--steps", "20", *args))
    assert hint in line


def test_an_empty_output_directory_in_a_deck_is_refused():
    line = _one_line(invoke("check", CF4, "--set", "outputs.directory=''"))
    assert "outputs.directory" in line
