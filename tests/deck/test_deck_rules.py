"""The rest of the broken-deck corpus (issue 6 §3): every cross-field rule of
icewall/deck/validate.py that test_deck_errors.py does not break, through the CLI: one line
naming file, line and key, exit code 2, no traceback."""

from __future__ import annotations

from pathlib import Path

import pytest
from click.testing import CliRunner

from icewall.cli import main

DECKS = Path(__file__).resolve().parents[2] / "decks"

# (name, deck, [(old, new), ...], key, text, line marker: first line containing it)
RULES = [
    ("end plate as long as the half wall", "cf4", [("  end_plate: 6.4", "  end_plate: 1083.0")],
     "geometry.end_plate", "as long as the half wall", "end_plate: 1083.0"),
    ("no support", "cf4", [("  supports:\n    - x: 750.0\n      bearing_plate_width: 75.0\n"
                            "      bearing_plate_thickness: 25.0\n      restraint: roller",
                            "  supports: []")],
     "geometry.supports", "at least one support", "supports: []"),
    ("bearing plate beyond the wall end", "cf4",
     [("bearing_plate_width: 75.0", "bearing_plate_width: 700.0")],
     "geometry.supports[0].bearing_plate_width", "beyond the wall end",
     "bearing_plate_width: 700.0"),
    ("overlapping bearing plates", "cf4",
     [("      restraint: roller\n", "      restraint: roller\n    - x: 800.0\n")],
     "geometry.supports[0]", "bearing plates overlap",
     "- x: 750.0"),
    ("leg beyond the wall end", "tf1", [("length: 50.0 ", "length: 500.0")],
     "geometry.legs[0]", "reaches beyond the wall end", "- x: 625.0"),
    ("overlapping legs", "tf1",
     [("      height: 420.0     # h_2\n",
       "      height: 420.0\n    - x: 550.0\n      length: 200.0\n      height: 100.0\n")],
     "geometry.legs[1]", "legs overlap", "- x: 550.0"),
    ("bearing plate over a leg", "tf1",
     [("bearing_plate_width: 0.0", "bearing_plate_width: 75.0")],
     "geometry.supports[0]", "overlaps a leg", "- x: 625.0          # roller"),
    ("no load patch", "cf4", [("positions: [0.0, 300.0, 1058.0]", "positions: []")],
     "loads.patches.positions", "at least one load patch", "positions: []"),
    ("load patch off the top plate", "cf4",
     [("positions: [0.0, 300.0, 1058.0]", "positions: [0.0, 300.0, 1070.0]")],
     "loads.patches.positions[2]", "runs off the top plate", "1070.0]"),
    ("control point off the wall", "cf4", [("    x: 0.0              # top", "    x: 1200.0 #")],
     "loads.control.x", "is off the wall", "x: 1200.0"),
    ("increment larger than the target", "cf4",
     [("    increment: 1.0      # thesis", "    increment: 50.0 #")],
     "loads.control.increment", "larger than the target", "increment: 50.0"),
    ("intensity without tributary length", "cf4",
     [("    tributary_length: 300.0   # L/5\n", "")],
     "loads.measure.tributary_length", "needs tributary_length", "  measure:"),
    ("axisymmetric full model", "cf4",
     [("  model: half", "  model: full"), ("restraint: roller", "restraint: pin"),
      ("formulation: plane_strain", "formulation: axisymmetric")],
     "geometry.model", "is a half model", "model: full"),
    ("plane-stress plates in an axisymmetric analysis", "cf4",
     [("formulation: plane_strain", "formulation: axisymmetric")],
     "materials.steel.formulation", "plane-strain (or plane-stress) analyses only",
     "    formulation: plane_stress"),
    ("field listed twice", "cf4",
     [("fields: [displacement, stress, strain]", "fields: [displacement, stress, stress]")],
     "outputs.fields", "listed twice", "fields: [displacement, stress, stress]"),
]


@pytest.mark.parametrize("rule", RULES, ids=[r[0] for r in RULES])
def test_broken_rule_is_one_line_with_file_line_and_key(rule, tmp_path):
    _, deck, edits, key, text, marker = rule
    broken = (DECKS / f"{deck}.yaml").read_text()
    for old, new in edits:
        assert old in broken, f"test fragment {old!r} not in {deck}.yaml"
        broken = broken.replace(old, new, 1)
    path = tmp_path / "broken.yaml"
    path.write_text(broken)
    line = next(i for i, s in enumerate(broken.splitlines(), start=1) if marker in s)
    result = CliRunner().invoke(main, ["check", str(path)])
    assert result.exit_code == 2
    assert result.output.startswith(f"error: {path}:{line}: {key}: "), result.output
    assert text in result.output and result.output.count("\n") == 1
    assert "Traceback" not in result.output
