"""End-to-end linear runs: equilibrium, linearity, what the result file holds."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from icewall.deck.load import load_deck
from icewall.fem.kinematics import internal_force_blocks
from icewall.mesh.build import build_mesh, region_materials
from icewall.model.build import build_model
from icewall.pipeline import run_deck
from icewall.results.reader import open_result

DECKS = Path(__file__).resolve().parents[2] / "decks"
LINEAR = ["analysis.solver=linear"]


@pytest.fixture(scope="module")
def cf4_result(tmp_path_factory):
    loaded = load_deck(DECKS / "cf4.yaml", LINEAR)
    report = run_deck(loaded, tmp_path_factory.mktemp("run") / "cf4.h5")
    return loaded, report


def test_result_file_layout(cf4_result):
    loaded, report = cf4_result
    with open_result(report.path) as res:
        assert res.status == "completed"
        assert res.attrs["units"] == "N, mm, MPa"
        assert res.attrs["load_measure"] == "w"
        assert res.deck_text == loaded.text
        assert res.attrs["deck_overrides"] == '["analysis.solver=linear"]'
        assert res.steps == list(range(1, 41))
        assert res.mesh.n_nodes == report.n_nodes
        assert set(res.gauss_fields(1)) == {"stress", "strain"}
        assert np.isfinite(res.history["load"]).all()


def test_linear_load_is_proportional_to_deflection(cf4_result):
    _, report = cf4_result
    with open_result(report.path) as res:
        h = res.history
        ratio = h["load"] / h["control_displacement"]
        assert np.allclose(ratio, ratio[0], rtol=1e-10)
        u1, u40 = res.displacement(1), res.displacement(40)
        assert np.allclose(40.0 * u1, u40, rtol=1e-9, atol=1e-12)
        control = res.mesh.node_sets["control"][0]
        assert -u40[control, 1] == pytest.approx(40.0)


def test_stored_stresses_are_in_equilibrium_with_the_loads(cf4_result):
    """Internal forces of the stored stresses = P * reference load at the free equations, and
    the support reactions carry the whole applied load (2.5 P in the half model: half the
    midspan station, the one at L/5 and the one at the wall end)."""
    loaded, report = cf4_result
    deck = loaded.deck
    mesh = build_mesh(deck)
    model = build_model(deck, mesh, region_materials(deck))
    with open_result(report.path) as res:
        stress = res.gauss(10, "stress")
        P = res.history["load_factor"][9]
    f_int = model.assembler.vector(internal_force_blocks(model.kinematics, stress))
    free = np.setdiff1d(np.arange(model.dof_map.n_equations), model.fixed)
    residual = f_int[free] - P * model.reference_load[free]
    assert np.abs(residual).max() < 1e-8 * np.abs(P * model.reference_load).max()
    support_eq = model.dof_map.equations(mesh.node_sets["support_1"], 1)
    assert f_int[support_eq].sum() == pytest.approx(2.5 * P, rel=1e-9)


def test_outputs_not_asked_for_are_not_written(tmp_path):
    loaded = load_deck(DECKS / "cf4.yaml", LINEAR + ["outputs.fields=[displacement]",
                                                     "outputs.every=10"])
    report = run_deck(loaded, tmp_path / "cf4.h5")
    with open_result(report.path) as res:
        assert res.steps == [10, 20, 30, 40]
        assert res.gauss_fields(10) == []
        assert len(res.history["load"]) == 40


def test_preload_is_held_and_bonded_wall_has_no_pairs(tmp_path):
    loaded = load_deck(DECKS / "tf1.yaml", LINEAR + ["materials.interface.model=bonded"])
    report = run_deck(loaded, tmp_path)
    with open_result(report.path) as res:
        assert len(res.mesh.interface_pairs) == 0
        h = res.history
        # with the preload held, load and deflection are affine, not proportional
        slope = np.diff(h["load"]) / np.diff(h["control_displacement"])
        assert np.allclose(slope, slope[0])
