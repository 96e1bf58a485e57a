"""Issue 6 §4, what a scene does not need is left out: asserted as structural facts (rows,
stages, state columns, calls, datasets, imported modules), never as timings."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

import icewall.materials.steel as steel
from icewall.deck.load import load_deck
from icewall.materials.concrete_law import ConcreteLaw
from icewall.mesh.build import build_mesh, region_materials
from icewall.model.build import build_model
from icewall.pipeline import run_deck
from icewall.solve.constraints import SupportConstraints
from icewall.solve.gap_constraints import GapConstraints
from icewall.solve.nonlinear import run_nonlinear
from icewall.solve.problem import make_constraints

DECKS = Path(__file__).resolve().parents[2] / "decks"
COARSE = ["analysis.element_size=150", "loads.control.target=2"]


def _model(deck: str, *overrides: str):
    loaded = load_deck(DECKS / deck, COARSE + list(overrides))
    mesh = build_mesh(loaded.deck)
    return build_model(loaded.deck, mesh, region_materials(loaded.deck))


def _constraints(model):
    return make_constraints(model)


def test_bonded_deck_has_no_gap_elements_and_no_multiplier_rows():
    gap = _model("cf4.yaml")
    bonded = _model("cf4.yaml", "materials.interface.model=bonded")
    assert isinstance(_constraints(gap), GapConstraints)
    assert _constraints(gap).n_multipliers == 2 * len(gap.mesh.interface_pairs) > 0
    constraints = _constraints(bonded)
    assert type(constraints) is SupportConstraints and constraints.n_multipliers == 0
    assert len(bonded.mesh.interface_pairs) == 0
    assert bonded.dof_map.n_equations < gap.dof_map.n_equations  # no double nodes either
    report = next(run_nonlinear(bonded))
    assert report.arrays == {} and not any(k.startswith("gap_") for k in report.counts)




def test_plane_stress_carries_no_out_of_plane_state():
    model = _model("cf4.yaml", "analysis.formulation=plane_stress", "loads.control.target=4")
    reports = list(run_nonlinear(model))
    ev = reports[-1].increment.evaluation
    group, concrete = next((g, s) for g, s in zip(reports[-1].structure.groups, ev.states,
                                                  strict=True) if isinstance(g.law, ConcreteLaw))
    assert reports[-1].counts["cracked_in_plane"] > 0  # the in-plane state does evolve
    assert np.all(ev.stress[..., 2] == 0.0)  # sigma_zz, every group
    assert not concrete.cracked[:, 2].any() and not concrete.crushed[:, 2].any()
    assert np.all(concrete.max_equivalent_uniaxial_strain[:, 2] == 0.0)
    assert np.all(concrete.secant_modulus[:, 2] == group.law.params.E0)  # virgin
    assert all(r.counts["cracked_out_of_plane"] == 0 for r in reports)
    strain = _model("cf4.yaml", "loads.control.target=1")  # plane strain does carry sigma_zz
    assert np.any(next(run_nonlinear(strain)).increment.evaluation.stress[..., 2] != 0.0)


def _count_return_mappings(monkeypatch) -> list[int]:
    calls: list[int] = []
    for name in ("_return_3d", "_return_plane_stress"):
        real = getattr(steel, name)

        def counted(trial, kappa, params, real=real):
            calls.append(len(trial))
            return real(trial, kappa, params)

        monkeypatch.setattr(steel, name, counted)
    return calls


@pytest.mark.parametrize("formulation", ["plane_strain", "plane_stress"])
def test_steel_return_mapping_only_at_yielding_points(monkeypatch, formulation):
    calls = _count_return_mappings(monkeypatch)
    params = steel.steel_parameters(200000.0, 0.3, 371.0, formulation=formulation)
    eps_y = 371.0 / 200000.0
    strain = np.zeros((6, 4))
    strain[:, 0] = eps_y * np.array([0.2, 0.5, 0.9, 1.5, 3.0, -2.0])  # uniaxial-ish
    state = steel.SteelState.initial(6)
    steel.update_steel(strain[:3], state.take(slice(0, 3)), params)
    assert calls == []  # all elastic: the yield check only
    _, _, trial = steel.update_steel(strain, state, params)
    assert calls == [int(np.count_nonzero(trial.yielded))] and 0 < calls[0] < 6


def test_no_preload_stage_and_no_return_mapping_where_none_is_needed(monkeypatch):
    """CF-4 to 1 mm: no in-plane load, so no load-control increment; its steel stays elastic,
    so the von Mises return mapping is never entered (the yield check only). (At 2 mm, on
    this 150 mm mesh, the top plate under the wall-end station reaches yield in an iteration.)"""
    calls = _count_return_mappings(monkeypatch)
    model = _model("cf4.yaml", "loads.control.target=1")
    assert model.preload is None and _model("tf1.yaml").preload is not None
    reports = list(run_nonlinear(model))
    assert [r.increment.kind for r in reports] == ["control"]  # 1 x 1 mm
    assert reports[-1].counts["yielded"] == 0 and calls == []


def test_outputs_not_asked_for_are_neither_computed_nor_written(tmp_path, monkeypatch):
    import icewall.solve.nonlinear as nonlinear

    def refuse(*args, **kwargs):
        raise AssertionError("computed an output the deck did not ask for")

    monkeypatch.setattr(nonlinear, "state_fields", refuse)
    monkeypatch.setattr(GapConstraints, "arrays", refuse)
    monkeypatch.setattr(nonlinear.StepReport, "displacement", property(refuse))
    loaded = load_deck(DECKS / "cf4.yaml", COARSE + ["outputs.fields=[]"])
    assert run_deck(loaded, tmp_path / "none.h5").status == "completed"
    with h5py.File(tmp_path / "none.h5", "r") as f:
        assert len(f["steps"]) == 0 and len(f["history/step"]) == 2
    monkeypatch.undo()
    loaded = load_deck(DECKS / "cf4.yaml", COARSE + ["outputs.fields=[stress]",
                                                     "loads.control.target=4",
                                                     "outputs.every=2"])
    run_deck(loaded, tmp_path / "stress.h5")
    with h5py.File(tmp_path / "stress.h5", "r") as f:
        assert sorted(f["steps"]) == ["00002", "00004"]
        assert [sorted(f["steps"][k]) for k in f["steps"]] == [["gauss"], ["gauss"]]
        assert list(f["steps/00002/gauss"]) == ["stress"]


@pytest.mark.parametrize("solver", ["nonlinear", "linear"])
def test_run_imports_neither_matplotlib_nor_dask(tmp_path, solver):
    """`icewall run` works with matplotlib, dask and numba made unimportable, and loads none
    of them (while the plotting commands stay registered; the concrete update falls back to
    its NumPy kernel)."""
    script = f"""
import sys
class Block:
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in ("matplotlib", "dask", "distributed", "numba"):
            raise ImportError("blocked: " + name)
sys.meta_path.insert(0, Block())
from icewall.cli import main
try:
    main(["run", {str(DECKS / "cf4.yaml")!r}, "-q", "-o", {str(tmp_path / "r.h5")!r},
          "--set", "analysis.element_size=150", "--set", "loads.control.target=1",
          "--set", "analysis.solver={solver}"])
except SystemExit as exc:
    assert not exc.code, exc.code
print(sorted(m for m in sys.modules if m.split(".")[0] in ("matplotlib", "dask", "numba")))
assert "icewall.cli_post" in sys.modules  # the plotting commands are still registered
"""
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                         timeout=300)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"
    assert (tmp_path / "r.h5").exists()
