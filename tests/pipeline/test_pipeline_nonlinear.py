"""The nonlinear CF-4 analysis end to end, checked from the stored result independently of the
solver: equilibrium of every stored step, interface laws, energy balance, a traced peak."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from icewall.deck.load import load_deck
from icewall.fem.kinematics import internal_force_blocks
from icewall.interface.gap import FIXED, FREE, SLIP, constraint_matrix
from icewall.mesh.build import build_mesh, region_materials
from icewall.model.build import build_model
from icewall.pipeline import run_deck
from icewall.results.reader import open_result

DECKS = Path(__file__).resolve().parents[2] / "decks"
# Plane stress traces the CF-4 peak within a short range (see the closing notes of issue 4).
# tolerance 0.02, not the thesis' 0.05: the energy balance below holds to the solver's
# tolerance (at 0.05 the imbalance of this run reaches 2.6 % of the external work, at 0.02 it
# stays under 0.7 %)
OVERRIDES = ["analysis.solver=nonlinear", "analysis.formulation=plane_stress",
             "loads.control.target=16", "outputs.fields=[displacement, stress, strain, state]",
             "analysis.tolerance_load=0.02", "analysis.tolerance_displacement=0.02"]


@pytest.fixture(scope="module")
def cf4_nonlinear(tmp_path_factory):
    loaded = load_deck(DECKS / "cf4.yaml", OVERRIDES)
    report = run_deck(loaded, tmp_path_factory.mktemp("nl") / "cf4.h5")
    deck = loaded.deck
    mesh = build_mesh(deck)
    model = build_model(deck, mesh, region_materials(deck))
    return deck, model, report


def test_runs_to_target_and_traces_a_peak(cf4_nonlinear):
    _, _, report = cf4_nonlinear
    assert report.status == "completed"
    with open_result(report.path) as res:
        h = res.history
        assert h["control_displacement"][-1] == pytest.approx(16.0)
        assert np.all(np.isfinite(h["load"]))
        peak = int(np.argmax(h["load"]))
        assert 0 < peak < len(h["load"]) - 1  # the load rises, peaks and falls within 16 mm
        assert h["cracked_in_plane"][-1] > 0 and h["yielded"][-1] >= 0


def test_every_stored_step_is_in_equilibrium(cf4_nonlinear):
    deck, model, report = cf4_nonlinear
    C = constraint_matrix(model.mesh.interface_pairs, model.mesh.interface_normals,
                          model.dof_map.node_equations, model.dof_map.n_equations)
    free = np.setdiff1d(np.arange(model.dof_map.n_equations), model.fixed)
    largest = 0.0  # eq. 4.5's reference as the solver takes it: never below the largest reached
    with open_result(report.path) as res:
        for step in res.steps:
            stress = res.gauss(step, "stress")
            lam = np.column_stack([res.array(step, "interface/lam_N"),
                                   res.array(step, "interface/lam_T")]).ravel()
            P = res.history["load_factor"][step - 1]
            f_int = model.assembler.vector(internal_force_blocks(model.kinematics, stress))
            residual = (P * model.reference_load - f_int - C.T @ lam)[free]
            reactions = f_int[model.fixed] + (C.T @ lam)[model.fixed]
            reference = np.sqrt(np.sum((P * model.reference_load) ** 2) + reactions @ reactions)
            largest = max(largest, reference)
            assert np.linalg.norm(residual) <= deck.analysis.tolerance_load * largest


def test_interface_laws_hold_at_converged_steps(cf4_nonlinear):
    deck, _, report = cf4_nonlinear
    mu = deck.materials.interface.friction
    with open_result(report.path) as res:
        for step in res.steps:
            state = res.array(step, "interface/state")
            lam_N = res.array(step, "interface/lam_N")
            lam_T = res.array(step, "interface/lam_T")
            scale = np.abs(lam_N).max()
            assert np.all(lam_N[state == FREE] == 0) and np.all(lam_T[state == FREE] == 0)
            slip = state == SLIP
            assert np.allclose(np.abs(lam_T[slip]), mu * np.abs(lam_N[slip]),
                               atol=0.05 * scale)
            assert set(np.unique(state)) <= {FIXED, SLIP, FREE}


def test_energy_balance(cf4_nonlinear):
    _, _, report = cf4_nonlinear
    with open_result(report.path) as res:
        h = res.history
        # trapezoidal work over 1 mm steps: the first steps (cracking and slip starting
        # within a step) carry an error of O(1e4) N mm that stays small against the total
        late = h["external_work"] > 0.2 * h["external_work"][-1]
        assert np.all(np.abs(h["energy_imbalance"][late]) <= 0.02 * h["external_work"][late])
        parts = (h["elastic_energy"] + h["concrete_dissipation"] + h["plastic_work"]
                 + h["friction_work"] + h["energy_imbalance"])
        assert np.allclose(parts, h["external_work"])
        assert np.all(h["friction_work"] >= -1e-6 * h["external_work"])


def test_mechanism_history_matches_the_stored_stress(cf4_nonlinear):
    """Issue 20 §1: the bottom-plate columns of the history agree with the plate stresses
    recomputed from the stored stress field (icewall.post.plate_stresses) and its plastic
    strain, and the crushed x range with the stored concrete flags."""
    from icewall.mesh.gauss import gauss_points_xy
    from icewall.post.plate_stresses import member_stresses

    _, model, report = cf4_nonlinear
    with open_result(report.path) as res:
        h = res.history
        assert {"tension_plate_stress_mid", "tension_plate_stress_max",
                "crushed_x_min"} <= set(h)
        for step in res.steps[::4]:
            _, stations, mean = member_stresses(res.mesh, res.gauss(step, "stress"),
                                                3)["bottom_plate"]
            i = step - 1
            assert h["tension_plate_stress_mid"][i] == pytest.approx(
                mean[np.argmin(np.abs(stations))], rel=1e-9, abs=1e-9)
            assert h["tension_plate_stress_max"][i] == pytest.approx(mean.max(), rel=1e-9)
            plate = res.mesh.cell_region == next(r.tag for r in res.mesh.regions
                                                 if r.name == "bottom_plate")
            peeq = res.gauss(step, "equivalent_plastic_strain")[plate]
            assert h["tension_plate_yielded"][i] == np.count_nonzero(peeq > 0)
            crushed = (res.gauss(step, "concrete_flags")[..., 3:6] != 0).any(axis=2)
            if crushed.any():
                x = gauss_points_xy(res.mesh, 3)[crushed][:, 0]
                assert h["crushed_x_min"][i] == pytest.approx(x.min())
                assert h["crushed_x_max"][i] == pytest.approx(x.max())
            else:
                assert np.isnan(h["crushed_x_min"][i])
        assert h["tension_plate_stress_mid"][-1] > 0.0  # tension at midspan
