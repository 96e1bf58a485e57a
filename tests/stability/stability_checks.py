"""Checks of a result file made from the file alone (issue 6 §2): no NaN or inf, equilibrium of
every stored step rebuilt from the stored deck, mesh and state, a named outcome, and two runs
of one input that agree to the last bit."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np

from icewall.deck.load import load_deck, load_deck_text
from icewall.fem.kinematics import internal_force_blocks, strain
from icewall.interface.gap import FREE, constraint_matrix
from icewall.mesh.build import region_materials
from icewall.model.build import build_model
from icewall.pipeline import run_deck
from icewall.results.reader import open_result

DECKS = Path(__file__).resolve().parents[2] / "decks"
# the reasons a nonlinear run may stop with (icewall.solve.control, icewall.interface)
NAMED_REASONS = ("non-convergence", "snap-back", "singular system", "NaN")


@dataclass(frozen=True)
class Case:
    name: str
    deck: str  # file name in decks/
    overrides: tuple[str, ...]
    # fields every step: the equilibrium check needs stress and the interface forces (state)
    outputs: str = "outputs.fields=[displacement, stress, strain, state]"

    def run(self, path: Path):
        loaded = load_deck(DECKS / self.deck, list(self.overrides) + [self.outputs])
        return loaded, run_deck(loaded, path)


def assert_no_nan_or_inf(path: str) -> None:
    """Every numeric value in the file is finite, except a history column's documented fill
    (NaN before the step at which the column first appeared)."""
    bad = []

    def visit(name: str, obj) -> None:
        if not isinstance(obj, h5py.Dataset) or obj.dtype.kind != "f":
            return
        data = obj[()]
        if name.startswith("history/") and "first_step" in obj.attrs:
            data = data[int(obj.attrs["first_step"]) - 1:]
        if not np.all(np.isfinite(data)):
            bad.append(name)

    with h5py.File(path, "r") as f:
        f.visititems(visit)
        for name, value in f.attrs.items():
            if isinstance(value, float | np.floating) and not np.isfinite(value):
                bad.append(f"attribute {name}")
    assert not bad, f"non-finite values in {path}: {bad}"


def assert_equilibrium(path: str) -> int:
    """Rebuild the model from the file (deck text, --set overrides, mesh) and check every stored
    step: the out-of-balance force of the stored stresses, interface forces, load and preload
    factors, on the free equations, is within the run's load tolerance of the eq. 4.5 reference
    (applied loads and support reactions, the largest reached so far), as icewall.solve.control
    defines it. Also: strains follow from the stored displacements (B u), free pairs carry no
    force. Needs every step stored (outputs.every = 1). Returns the number of steps checked."""
    with open_result(path) as res:
        loaded = load_deck_text(res.deck_text, "stored deck",
                                json.loads(res.attrs["deck_overrides"]))
        deck = loaded.deck
        model = build_model(deck, res.mesh, region_materials(deck))
        n_eq = model.dof_map.n_equations
        pairs = res.mesh.interface_pairs
        C = constraint_matrix(pairs, res.mesh.interface_normals, model.dof_map.node_equations,
                              n_eq) if len(pairs) else None
        free = np.ones(n_eq, dtype=bool)
        free[model.fixed] = False
        preload = np.zeros(n_eq) if model.preload is None else model.preload
        h = res.history
        assert res.steps == [int(s) for s in h["step"]], "a step without stored fields"
        scale = 0.0
        for i, step in enumerate(res.steps):
            stress = res.gauss(step, "stress")
            f_int = model.assembler.vector(internal_force_blocks(model.kinematics, stress))
            external = h["load_factor"][i] * model.reference_load + \
                h["preload_factor"][i] * preload
            unbalance = external - f_int
            if C is not None:
                lam_N = res.array(step, "interface/lam_N")
                lam_T = res.array(step, "interface/lam_T")
                free_pairs = res.array(step, "interface/state") == FREE
                assert not np.any(lam_N[free_pairs]) and not np.any(lam_T[free_pairs])
                unbalance -= C.T @ np.column_stack([lam_N, lam_T]).ravel()
            reference = np.sqrt(np.sum(external[free] ** 2) + np.sum(f_int[~free] ** 2))
            scale = max(scale, reference)  # eq. 4.5: never less than the largest reached
            norm = np.linalg.norm(unbalance[free]) / scale
            assert norm <= deck.analysis.tolerance_load * (1 + 1e-9), \
                f"step {step}: load norm {norm:.3g} > {deck.analysis.tolerance_load}"
            u = model.dof_map.restrict(res.displacement(step).ravel())
            eps = strain(model.kinematics, u)
            stored = res.gauss(step, "strain")
            in_plane = [0, 1, 3]  # zz is solved by the material in plane stress
            assert np.allclose(eps[..., in_plane], stored[..., in_plane], rtol=1e-9,
                               atol=1e-12 * max(1.0, np.abs(stored).max()))
        return len(res.steps)


def assert_named_outcome(report, target: float, increment: float) -> str:
    """The run reached the target, or stopped with a named reason in a valid final file."""
    with open_result(report.path) as res:
        h = res.history
        assert len(h["step"]) == res.attrs["n_steps"] == report.n_steps
        assert np.all(np.diff(h["step"]) == 1)
        if report.status == "completed":
            assert res.status == "completed"
            assert abs(h["control_displacement"][-1] - target) <= 0.05 * increment
            return "reached target"
        assert report.status == res.status == "stopped", report.status
        reason = res.attrs["stop_reason"]
        assert reason.split(":")[0] in NAMED_REASONS, reason
        return reason.split(":")[0]


def assert_same_result(path_a: str, path_b: str) -> None:
    """Two runs of one input: every history column (but wall time) and every stored array
    equal to the last bit."""
    with open_result(path_a) as a, open_result(path_b) as b:
        assert a.status == b.status and a.attrs["stop_reason"] == b.attrs["stop_reason"]
        assert sorted(a.history) == sorted(b.history)
        for name, column in a.history.items():
            if name != "wall_time":
                np.testing.assert_array_equal(column, b.history[name], err_msg=name)
        assert a.steps == b.steps
    with h5py.File(path_a, "r") as fa, h5py.File(path_b, "r") as fb:
        names: list[str] = []
        fa["steps"].visititems(lambda n, o: names.append(n) if isinstance(o, h5py.Dataset)
                               else None)
        for name in names:
            np.testing.assert_array_equal(fa["steps"][name][()], fb["steps"][name][()],
                                          err_msg=name)
