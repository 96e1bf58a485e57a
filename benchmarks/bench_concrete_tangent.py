"""Cost and accuracy of the consistent concrete tangent on real CF-4 states (not part of the
test run).

Runs the deck with the shipped solver to --to mm, then, at the last converged step (committed
states of the step before, displacements of the last: what a Newton iteration sees at
convergence), times the concrete update against the update with its consistent tangent
(analytic and by differences; NumPy and, where installed, numba updates) and checks the
assembled tangent stiffness (`Structure.evaluate(tangent=True)`, gap elements not included)
against central differences of the internal forces.

Usage: python benchmarks/bench_concrete_tangent.py [--deck decks/cf4.yaml] [--to 8]
       [--set k=v ...] [--repeat 30]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from icewall.deck.load import load_deck
from icewall.materials import concrete_compiled
from icewall.materials.concrete import update_concrete
from icewall.materials.concrete_tangent import update_with_tangent
from icewall.mesh.build import build_mesh, region_materials
from icewall.model.build import build_model
from icewall.solve.nonlinear import run_nonlinear

ROOT = Path(__file__).resolve().parent.parent


def _best_ms(function, repeat: int) -> float:
    function()
    best = np.inf
    for _ in range(repeat):
        tic = time.perf_counter()
        function()
        best = min(best, time.perf_counter() - tic)
    return 1e3 * best


def _compiled(strain, state, params, formulation, trial_stress, with_moduli=False):
    stress, trial = concrete_compiled.compiled_update(strain, state, params, formulation,
                                                      trial_stress)
    return stress, None, trial


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--deck", default=str(ROOT / "decks" / "cf4.yaml"))
    parser.add_argument("--to", type=float, default=8.0, help="control displacement (mm)")
    parser.add_argument("--set", dest="overrides", action="append", default=[])
    parser.add_argument("--repeat", type=int, default=30)
    args = parser.parse_args()
    loaded = load_deck(args.deck, args.overrides)
    deck = loaded.deck
    model = build_model(deck, build_mesh(deck), region_materials(deck))
    previous = None
    for report in run_nonlinear(model):
        if report.increment.control_displacement >= args.to and previous is not None:
            break
        previous = report.increment.evaluation.states
    structure, u = report.structure, report.increment.u
    names = [g.name for g in structure.groups]
    k = names.index("concrete")
    group, committed = structure.groups[k], previous[k]
    formulation, trial_stress = deck.analysis.formulation, deck.materials.concrete.trial_stress
    strain = structure.evaluate(u, previous).strain[group.cells].reshape(-1, 4)
    print(f"{Path(args.deck).stem} at {report.increment.control_displacement:.2f} mm: "
          f"{strain.shape[0]} concrete points, {committed.cracked.any(axis=1).mean():.0%} "
          f"cracked, {committed.crushed.any(axis=1).mean():.0%} crushed; {formulation}, "
          f"{trial_stress} trial")

    p = group.law.params
    rows = [("update_concrete (no moduli)", lambda: update_concrete(
        strain, committed, p, formulation, trial_stress, with_moduli=False))]
    for method in ("analytic", "differences"):
        rows.append((f"update + tangent, {method}", lambda m=method: update_with_tangent(
            strain, committed, p, formulation, trial_stress, method=m)))
    if concrete_compiled.available(formulation, trial_stress):
        rows.append(("compiled update", lambda: _compiled(strain, committed, p, formulation,
                                                          trial_stress)))
        for method in ("analytic", "differences"):
            rows.append((f"compiled update + tangent, {method}",
                         lambda m=method: update_with_tangent(strain, committed, p, formulation,
                                                              trial_stress, _compiled, m)))
    rows.append(("Structure.evaluate (iteration moduli)", lambda: structure.evaluate(u, previous)))
    rows.append(("Structure.evaluate(tangent=True)",
                 lambda: structure.evaluate(u, previous, tangent=True)))
    print(f"{'':<42} {'ms (best of ' + str(args.repeat) + ')':>18}")
    for label, function in rows:
        print(f"{label:<42} {_best_ms(function, args.repeat):>18.2f}")

    _, analytic, _ = update_with_tangent(strain, committed, p, formulation, trial_stress)
    _, differenced, _ = update_with_tangent(strain, committed, p, formulation, trial_stress,
                                            method="differences")
    error = np.abs(analytic - differenced).max(axis=(1, 2)) / np.abs(differenced).max(axis=(1, 2))
    print(f"\nanalytic vs differences per point: median {np.median(error):.1e}, "
          f"99 % {np.quantile(error, 0.99):.1e}, max {error.max():.1e}, "
          f"{int(np.sum(error > 1e-6))} points above 1e-6 (kinks within the step)")

    K = structure.stiffness(structure.evaluate(u, previous, tangent=True))
    secant = structure.stiffness(structure.evaluate(u, previous))
    rng = np.random.default_rng(0)
    du = rng.normal(size=u.shape) * 1e-3
    for h in (1e-2, 1e-4, 1e-6):
        plus = structure.evaluate(u + h * du, previous).internal_force
        minus = structure.evaluate(u - h * du, previous).internal_force
        expected = (plus - minus) / (2.0 * h)
        size = np.linalg.norm(expected)
        print(f"h {h:.0e}: |K_t du - FD| / |FD| = {np.linalg.norm(K @ du - expected) / size:.2e}"
              f", iteration matrix {np.linalg.norm(secant @ du - expected) / size:.2e}")
    asymmetry = abs(K - K.T).max() / abs(K).max()
    print(f"tangent stiffness: {K.shape[0]} equations, max |K - K^T| / max |K| = {asymmetry:.1e}")


if __name__ == "__main__":
    main()
