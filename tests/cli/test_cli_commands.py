"""The CLI as a user meets it: exit codes, one-line errors, files written."""

from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import yaml
from click.testing import CliRunner

from icewall.cli import main
from icewall.deck.jsonschema import deck_json_schema

ROOT = Path(__file__).resolve().parents[2]
DECKS = ROOT / "decks"


def invoke(*args: str):
    return CliRunner().invoke(main, list(args))


def test_check_ok_and_broken(tmp_path):
    ok = invoke("check", str(DECKS / "cf4.yaml"))
    assert ok.exit_code == 0, ok.output
    assert "ok" in ok.output
    broken = tmp_path / "bad.yaml"
    broken.write_text((DECKS / "cf4.yaml").read_text().replace("fc: 53.5", "fc: 53500"))
    result = invoke("check", str(broken))
    assert result.exit_code == 2
    assert "Traceback" not in result.output
    lines = result.output.strip().splitlines()
    assert len(lines) == 1
    assert lines[0].startswith(f"error: {broken}:")
    assert "materials.concrete.fc" in lines[0]


def test_run_then_summary(tmp_path):
    out = tmp_path / "cf4.h5"
    result = invoke("run", str(DECKS / "cf4.yaml"), "-o", str(out), "--quiet",
                    "--set", "analysis.solver=linear")
    assert result.exit_code == 0, result.output
    assert out.exists()
    assert not Path(str(out) + ".partial").exists()
    summary = invoke("summary", str(out), "--json")
    assert summary.exit_code == 0, summary.output
    data = json.loads(summary.output)
    assert data["status"] == "completed"
    assert data["n_steps"] == 40
    assert data["final_deflection"] == 40.0
    assert data["max_load"] == data["final_load"] > 0  # linear: the peak is at the end
    text = invoke("summary", str(out))
    assert "CF-4" in text.output


def test_summary_of_missing_file_is_a_clean_error(tmp_path):
    result = invoke("summary", str(tmp_path / "nope.h5"))
    assert result.exit_code == 2
    assert "Traceback" not in result.output


def test_mesh_writes_files_and_reports_spacing(tmp_path):
    result = invoke("mesh", str(DECKS / "cf4.yaml"), "--out", str(tmp_path))
    assert result.exit_code == 0, result.output
    for suffix in (".msh", ".vtu", ".xdmf"):
        assert (tmp_path / f"cf4{suffix}").exists()
    assert "h_c" in result.output and "core_1" in result.output
    import meshio

    m = meshio.read(tmp_path / "cf4.vtu")
    assert m.cells[0].type == "quad8"


def test_published_schema_is_current_and_accepts_shipped_decks():
    published = json.loads((ROOT / "docs" / "deck.schema.json").read_text())
    current = json.loads(json.dumps(deck_json_schema()))
    assert published == current, "run `make schema` to refresh docs/deck.schema.json"
    for path in DECKS.glob("*.yaml"):
        jsonschema.validate(yaml.safe_load(path.read_text()), published)


def test_schema_rejects_what_the_loader_rejects():
    schema = deck_json_schema()
    deck = yaml.safe_load((DECKS / "cf4.yaml").read_text())
    deck["geometry"]["depht"] = 1.0
    try:
        jsonschema.validate(deck, schema)
    except jsonschema.ValidationError as exc:
        assert "depht" in str(exc)
    else:
        raise AssertionError("the schema accepted an unknown key")


def test_unwritable_output_fails_before_computing(tmp_path, monkeypatch):
    blocker = tmp_path / "a_file"
    blocker.write_text("not a directory")
    called = []
    import icewall.pipeline as pipeline

    monkeypatch.setattr(pipeline, "build_mesh", lambda deck: called.append(deck))
    result = invoke("run", str(DECKS / "cf4.yaml"), "-o", str(blocker / "sub" / "r.h5"))
    assert result.exit_code == 2
    assert "cannot create the output directory" in result.output
    assert "Traceback" not in result.output
    assert called == []  # nothing was meshed or solved


def test_check_warns_when_the_newton_scheme_meets_a_tension_preload_without_fixed_points():
    """TF-5 (+1000 kN on the plates): under Newton every pair opens in the preload and the cores
    float (docs/solver.md item 11); `icewall check` says so in one line, and nothing of it for
    the secant scheme, a compression preload (TF-1) or with fixed points."""
    from pathlib import Path

    decks = Path(__file__).resolve().parents[2] / "decks"
    runner = CliRunner()

    def lines(deck, *sets):
        args = ["check", str(decks / deck)]
        for assignment in sets:
            args += ["--set", assignment]
        result = runner.invoke(main, args)
        assert result.exit_code == 0
        return [line for line in result.output.splitlines() if "tension preload" in line]

    unpinned = "materials.interface.fixed_points_per_core=0"
    warned = lines("tf5.yaml", "analysis.scheme=newton", unpinned)
    assert len(warned) == 1 and warned[0].startswith("warning: ") and "item 11" in warned[0]
    assert lines("tf5.yaml", unpinned) == []
    assert lines("tf1.yaml", "analysis.scheme=newton") == []
    assert lines("tf5.yaml", "analysis.scheme=newton") == []  # the deck's own station pins


def test_check_warns_when_the_newton_scheme_meets_the_sharp_mode_rules():
    """`icewall check` says, in one line, that Newton with the sharp mode rules of 3.2.5
    (mode_rule_band 0) need not converge (docs/solver.md items 7, 10, 18), and more under
    rule (b) read `equal`; with a band, or with the secant scheme, it says nothing of it."""
    from pathlib import Path

    deck = str(Path(__file__).resolve().parents[2] / "decks" / "cf4.yaml")
    runner = CliRunner()
    for rule in ("equal", "floor"):
        newton = runner.invoke(main, ["check", deck, "--set", "analysis.scheme=newton", "--set",
                                      f"materials.concrete.compression_tension_rule={rule}"])
        assert newton.exit_code == 0
        lines = [line for line in newton.output.splitlines() if "mode_rule_band" in line]
        assert len(lines) == 1 and lines[0].startswith("warning: ")
        assert ("confined" in lines[0]) == (rule == "equal")
    for extra in (["--set", "analysis.scheme=newton", "--set",
                   "materials.concrete.mode_rule_band=0.1"], []):
        quiet = runner.invoke(main, ["check", deck, *extra])
        assert quiet.exit_code == 0 and "mode_rule_band" not in quiet.output


def test_check_warns_when_the_newton_scheme_meets_moving_post_peak_strengths():
    """The same for post_peak_strength ray (docs/solver.md items 21-22): one line under the
    Newton scheme, none with peak or under the secant scheme."""
    from pathlib import Path

    deck = str(Path(__file__).resolve().parents[2] / "decks" / "cf4.yaml")
    runner = CliRunner()
    band = ["--set", "materials.concrete.mode_rule_band=0.1"]
    newton = runner.invoke(main, ["check", deck, "--set", "analysis.scheme=newton", *band])
    lines = [line for line in newton.output.splitlines() if "post_peak_strength" in line]
    assert newton.exit_code == 0 and len(lines) == 1 and lines[0].startswith("warning: ")
    for extra in (["--set", "analysis.scheme=newton", *band, "--set",
                   "materials.concrete.post_peak_strength=peak"], []):
        quiet = runner.invoke(main, ["check", deck, *extra])
        assert quiet.exit_code == 0 and "post_peak_strength" not in quiet.output


def test_check_warns_when_the_newton_scheme_runs_at_a_loose_tolerance():
    """A Newton deck with a tolerance above 1e-4 gets one warning line (its figures are not
    converged equilibria: docs/solver.md items 25, 27); none at its own 1e-4 or tighter, and
    none under the secant scheme, whose 0.05 is the thesis'."""
    from pathlib import Path

    deck = str(Path(__file__).resolve().parents[2] / "decks" / "cf4.yaml")
    runner = CliRunner()
    newton = ["--set", "analysis.scheme=newton", "--set", "materials.concrete.mode_rule_band=0.1",
              "--set", "materials.concrete.post_peak_strength=peak"]
    loose = runner.invoke(main, ["check", deck, *newton, "--set", "analysis.tolerance_load=1e-3"])
    lines = [line for line in loose.output.splitlines() if "a tolerance of 0.001" in line]
    assert loose.exit_code == 0 and len(lines) == 1 and lines[0].startswith("warning: ")
    for extra in (newton, [*newton, "--set", "analysis.tolerance_displacement=1e-6"], []):
        quiet = runner.invoke(main, ["check", deck, *extra])
        assert quiet.exit_code == 0 and "a tolerance of" not in quiet.output
