"""Issue 21, item 6: bad input never gives a traceback. Each case of the probe that leaked one
goes through the command line: one clear error line on stderr, exit code 2 (bad input) or 1,
no traceback, no "internal error" (the catch-all is not the fix), no stray file."""

from __future__ import annotations

import h5py
import pytest
from reliability_support import CF4, LINEAR, error_lines, invoke

from icewall.cli import main


def _deck_text(**replace: str) -> str:
    text = CF4.read_text()
    for old, new in replace.items():
        assert old in text
        text = text.replace(old, new)
    return text


def _no_history_load(path):
    with h5py.File(path, "a") as f:
        del f["history/load"]
    return path


def _cases():
    """id -> (build(tmp, unwritable, result_copy) -> argv, env, expected exit, message part)."""
    deck = str(CF4)
    return {
        "mesh-unwritable": (lambda t, u, r: ["mesh", deck, "--out", u], None, 2, "Not a directory"),
        "plot-unwritable": (lambda t, u, r: ["plot", r, "-o", u, "--format", "png"], None, 2,
                            "Not a directory"),
        "export-unwritable": (lambda t, u, r: ["export", r, "-o", u / "x.pvd"], None, 2,
                              "Not a directory"),
        "report-unwritable": (lambda t, u, r: ["report", r, "-o", u / "r.html"], None, 2,
                              "a_file"),
        "schema-unwritable": (lambda t, u, r: ["schema", "-o", u / "s.json"], None, 2,
                              "Not a directory"),
        "point-csv-unwritable": (lambda t, u, r: ["point", "--fc", "40", "--steps", "5", "--csv",
                                                  u / "p.csv"], None, 2, "Not a directory"),
        "mesh-format-foo": (lambda t, u, r: ["mesh", deck, "--out", t / "m", "--format", "foo"],
                            None, 2, "unknown mesh format"),
        "fc-huge-integer": (lambda t, u, r: ["check", deck, "--set",
                                             "materials.concrete.fc=" + "9" * 400], None, 2,
                            "too large for a number"),
        "yaml-nested-5000": (lambda t, u, r: ["check", _write(t / "deep.yaml", _deck_text() +
                                                              "extra: " + "[" * 5000 + "]" * 5000
                                                              + "\n")], None, 2, "nested"),
        "yaml-mapping-nested-3000": (lambda t, u, r: ["check", _write(
            t / "deep2.yaml", _deck_text() + "".join("  " * i + f"k{i}:\n" for i in range(3000))
            + "  " * 3000 + "v: 1\n")], None, 2, "nested"),
        "sweep-file-nested-5000": (lambda t, u, r: ["sweep", "-f", _write(
            t / "sweep.yaml", "decks: " + "[" * 5000 + "]" * 5000 + "\n"), "--dry-run"], None,
                                   2, "nested"),
        "nul-in-specimen-name": (lambda t, u, r: [
            "run", _write(t / "nul.yaml", _deck_text(**{"name: CF-4": 'name: "CF\\0-4"'})),
            *_sets(LINEAR), "-q", "-o", t / "out"], None, 2, "NUL"),
        "point-max-strain-0": (lambda t, u, r: ["point", "--fc", "40", "--max-strain", "0"],
                               None, 2, "max-strain"),
        "point-fc-1e308": (lambda t, u, r: ["point", "--fc", "1e308"], None, 2, "--fc"),
        "env-sparse-solver": (lambda t, u, r: ["run", deck, *_sets(LINEAR), "-q", "-o",
                                               t / "out"],
                              {"ICEWALL_SPARSE_SOLVER": "foo"}, 2, "ICEWALL_SPARSE_SOLVER"),
        "env-superlu-ordering": (lambda t, u, r: ["run", deck, *_sets(LINEAR), "-q", "-o",
                                                  t / "out"],
                                 {"ICEWALL_SUPERLU_ORDERING": "foo"}, 2,
                                 "ICEWALL_SUPERLU_ORDERING"),
        "env-concrete-kernel": (lambda t, u, r: ["check", deck],
                                {"ICEWALL_CONCRETE_KERNEL": "fortran"}, 2,
                                "ICEWALL_CONCRETE_KERNEL"),
        "summary-no-history-load": (lambda t, u, r: ["summary", _no_history_load(r)], None, 2,
                                    "history/load missing"),
        "plot-no-history-load": (lambda t, u, r: ["plot", _no_history_load(r), "-o", t / "p",
                                                  "--format", "png"], None, 2,
                                 "history/load missing"),
        "export-no-history-load": (lambda t, u, r: ["export", _no_history_load(r), "-o",
                                                    t / "x.pvd"], None, 2, "history/load missing"),
    }


def _write(path, text: str):
    path.write_text(text)
    return path


def _sets(overrides: list[str]) -> list[str]:
    return [arg for o in overrides for arg in ("--set", o)]


CASES = _cases()


@pytest.mark.parametrize("case", list(CASES))
def test_bad_input_is_one_clear_line(case, tmp_path, unwritable, result_copy):
    pytest.importorskip("matplotlib") if case.startswith(("plot", "report")) else None
    build, env, exit_code, message = CASES[case]
    work = tmp_path / "work"
    work.mkdir()
    argv = build(work, unwritable, result_copy)
    before = sorted(p.name for p in work.rglob("*"))
    result = invoke(*argv, env=env)
    assert result.exit_code == exit_code, (result.exit_code, result.output)
    assert result.exception is None or isinstance(result.exception, SystemExit)
    assert "Traceback" not in result.output and "internal error" not in result.output
    lines = error_lines(result)
    assert len(lines) == 1 and message in lines[0], result.stderr
    after = sorted(p.name for p in work.rglob("*"))
    assert after == before, "a stray file was left"
    assert not unwritable.exists()


def test_every_command_goes_through_the_error_handling():
    """Every command's callback is wrapped by icewall.cli._handle_errors."""
    unwrapped = [name for name, command in main.commands.items()
                 if getattr(command.callback, "__wrapped__", None) is None]
    assert unwrapped == []


def test_an_unexpected_exception_is_one_line_too(monkeypatch):
    """The catch-all: a bug still gives one line and exit 1, and ICEWALL_TRACEBACK=1 shows it."""
    import icewall.deck.load

    def broken(*args, **kwargs):
        raise KeyError("boom")

    monkeypatch.setattr(icewall.deck.load, "load_deck", broken)
    result = invoke("check", CF4)
    assert result.exit_code == 1 and "Traceback" not in result.output
    assert error_lines(result) == ["error: internal error (KeyError: 'boom'); please report it "
                                   "(ICEWALL_TRACEBACK=1 shows where)"]
    result = invoke("check", CF4, env={"ICEWALL_TRACEBACK": "1"})
    assert isinstance(result.exception, KeyError)


def test_environment_values_match_where_they_are_read(monkeypatch):
    """icewall.environment accepts exactly what the solver and the kernel accept."""
    from icewall.environment import VARIABLES
    from icewall.materials.concrete_compiled import KERNELS
    from icewall.sparse import BACKENDS

    assert set(VARIABLES["ICEWALL_SPARSE_SOLVER"][0]) == {"auto", *BACKENDS}
    assert set(VARIABLES["ICEWALL_CONCRETE_KERNEL"][0]) == {"auto", *KERNELS}
    result = invoke("check", CF4, env={"ICEWALL_SUPERLU_ORDERING": "colamd",
                                       "ICEWALL_SPARSE_SOLVER": " Auto "})
    assert result.exit_code == 0, result.output
