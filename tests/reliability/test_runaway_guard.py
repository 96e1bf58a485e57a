"""Issue 21, item 5: a run that cannot finish on this machine is refused up front (one line,
exit 2) by `icewall check` and `icewall run`, unless analysis.allow_large says the user means
it; a long one is warned about; a sweep of 1e7 runs is refused before any job is listed.
Machine-dependent limits (memory, free disk) are exercised with the machine figures patched."""

from __future__ import annotations

import pytest
from reliability_support import CF4, LINEAR, error_lines, invoke

import icewall.analysis.sweep as sweep_module
import icewall.deck.resources as resources
from icewall.analysis.sweep import expand_jobs
from icewall.deck.load import load_deck
from icewall.errors import DeckError
from icewall.mesh.build import build_mesh

RUNAWAY = {
    "increment-1e-9": ("loads.control.increment=1.0e-9", "steps"),
    "target-1e9": ("loads.control.target=1.0e9", "steps"),
    "element-size-0.6": ("analysis.element_size=0.6", "elements"),
    "element-size-1e-300": ("analysis.element_size=1e-300", "elements"),  # inf elements
    "increment-1e-320": ("loads.control.increment=1e-320", "steps"),  # inf steps
}


@pytest.mark.parametrize("case", list(RUNAWAY))
def test_check_refuses_a_runaway_deck(case):
    override, what = RUNAWAY[case]
    result = invoke("check", CF4, "--set", override)
    assert result.exit_code == 2, result.output
    (line,) = error_lines(result)
    assert what in line and "analysis.allow_large: true" in line


@pytest.mark.parametrize("case", list(RUNAWAY))
def test_allow_large_turns_the_refusal_into_a_warning(case):
    override, what = RUNAWAY[case]
    result = invoke("check", CF4, "--set", override, "--set", "analysis.allow_large=true")
    assert result.exit_code == 0, result.output
    warnings = [line for line in result.stderr.splitlines() if line.startswith("warning:")]
    assert any(what in line and "allowed by analysis.allow_large" in line for line in warnings)


def test_run_is_refused_before_it_starts(tmp_path, monkeypatch):
    def no_meshing(*args, **kwargs):
        raise AssertionError("the runaway deck was meshed")

    monkeypatch.setattr("icewall.pipeline.build_mesh", no_meshing)
    out = tmp_path / "out"
    result = invoke("run", CF4, "--set", "analysis.solver=linear", "--set",
                    "loads.control.increment=1e-9", "-o", out)
    assert result.exit_code == 2 and "steps" in error_lines(result)[0]
    assert not out.exists()  # nothing meshed, nothing written


def test_memory_above_the_available_is_refused(monkeypatch):
    monkeypatch.setattr(resources, "available_memory", lambda: 1e6)
    result = invoke("check", CF4)
    assert result.exit_code == 2
    (line,) = error_lines(result)
    assert "of memory, this machine has 1 MB available" in line
    monkeypatch.setattr(resources, "available_memory", lambda: None)  # unknown: no refusal
    assert invoke("check", CF4).exit_code == 0


def test_output_above_the_free_disk_is_refused(monkeypatch, tmp_path):
    monkeypatch.setattr(resources, "free_disk", lambda directory: 1e3)
    result = invoke("check", CF4)
    assert result.exit_code == 2 and "free" in error_lines(result)[0]
    result = invoke("run", CF4, *[a for o in LINEAR for a in ("--set", o)], "-q",
                    "-o", tmp_path / "r.h5")
    assert result.exit_code == 2 and "the result needs about" in error_lines(result)[0]
    assert not (tmp_path / "r.h5").exists() and not (tmp_path / "r.h5.partial").exists()
    result = invoke("check", CF4, "--set", "analysis.allow_large=true")
    assert result.exit_code == 0 and "allowed by analysis.allow_large" in result.stderr


def test_a_long_run_is_warned_about():
    """4000 steps of 0.01 mm: accepted, with one warning line on stderr."""
    result = invoke("check", CF4, "--set", "loads.control.increment=0.01")
    assert result.exit_code == 0, result.output
    warnings = [line for line in result.stderr.splitlines() if line.startswith("warning:")]
    assert len(warnings) == 1 and "expect about" in warnings[0] and " h" in warnings[0]
    assert invoke("check", CF4).stderr == ""  # the shipped deck: no warning


def test_the_estimate_is_of_the_right_order():
    """Elements and equations of the shipped CF-4 against its mesh: the grid estimate is a
    lower bound within a factor 2 (it does not follow every plate and patch edge)."""
    loaded = load_deck(CF4)
    est = resources.estimate(loaded.deck)
    mesh = build_mesh(loaded.deck)
    assert est.n_steps == 40 and est.n_steps_with_cuts == 40 * 2 ** 4
    assert est.n_elements <= mesh.n_cells <= 2 * est.n_elements
    assert est.n_equations <= 2 * mesh.n_nodes <= 2 * est.n_equations
    assert 1e5 < est.output_bytes < 1e8 and est.memory_bytes < 1e9 and est.hours < 1


def test_a_sweep_of_1e7_runs_is_refused_up_front(tmp_path, monkeypatch):
    values = ",".join(f"{40 + 0.001 * i:g}" for i in range(3163))  # 3163^2 = 1.0e7 runs
    sets = [f"materials.concrete.fc={values}", f"materials.steel.fy={values}"]
    listed = []
    monkeypatch.setattr(sweep_module, "Job", lambda *args: listed.append(args))
    with pytest.raises(DeckError, match="1e\\+07 runs"):
        expand_jobs([CF4], sets, outdir=tmp_path)
    assert listed == []  # refused before one job was listed (listing 1e7 took gigabytes)
    monkeypatch.undo()
    result = invoke("sweep", CF4, *[a for s in sets for a in ("--set", s)], "-o",
                    tmp_path / "sw")
    assert result.exit_code == 2 and "analysis.allow_large=true" in error_lines(result)[0]
    assert not (tmp_path / "sw").exists()
    jobs = expand_jobs([CF4], ["materials.concrete.fc=40,50"], outdir=tmp_path)
    assert len(jobs) == 2  # a normal sweep is untouched
