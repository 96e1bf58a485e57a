"""Whether the converged states of a deck's Newton path are stable under the held deflection
(a diagnostic for docs/solver.md item 30, not a benchmark).

At every converged state between two control deflections: the smallest eigenvalues of the
symmetrised consistent tangent with the held gap pairs as penalties (PENALTY x its largest
diagonal) and the supports and the control deflection held. All positive: no disturbance at
that deflection lowers the energy to second order, so a stroke-controlled test can stay on
the path. The state is the one the path was committed with (the tangent of its loading
branches: a softer comparison than the unloading one).

    python benchmarks/path_stability.py decks/cf4.yaml 6.3 7.4 --set loads.control.increment=0.25
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import scipy.sparse.linalg as spla

from icewall.deck.load import load_deck
from icewall.interface.augmented import active_rows
from icewall.mesh.build import build_mesh, region_materials
from icewall.model.build import build_model
from icewall.solve.path import follow_path
from icewall.solve.problem import Problem, build_problem
from icewall.solve.settings import SolverSettings, solver_settings
from icewall.solve.state import PathState

NEWTON = ("analysis.scheme=newton", "outputs.fields=[]", "materials.concrete.mode_rule_band=0.1",
          "materials.concrete.post_peak_strength=peak")  # as docs/solver.md items 22-30
PENALTY = 10.0
SHIFT = -1.0  # N/mm: eigenvalues nearest this, negative ones included
EIGENVALUES = 4


def newton_problem(deck_path: str, sets: list[str]
                   ) -> tuple[Problem, PathState, np.ndarray, SolverSettings]:
    """The deck's Newton problem (as icewall.solve.nonlinear.run_nonlinear builds it), its
    initial state, the equations neither supported nor the control's, the settings."""
    deck = load_deck(deck_path, [*NEWTON, *sets]).deck
    mesh = build_mesh(deck)
    model = build_model(deck, mesh, region_materials(deck))
    problem = build_problem(model, solver_settings(model.description).scheme)
    start = PathState(np.zeros(model.dof_map.n_equations), 0.0,
                      problem.structure.initial_states())
    free = np.ones(model.dof_map.n_equations, dtype=bool)
    free[problem.constraints.fixed] = False
    free[model.control_equation] = False
    return problem, start, np.flatnonzero(free), solver_settings(model.description)


def smallest_eigenvalues(problem: Problem, state: PathState, free: np.ndarray) -> np.ndarray:
    """The EIGENVALUES eigenvalues nearest SHIFT of the held, symmetrised tangent at `state`."""
    s, c = problem.structure, problem.constraints
    K = s.stiffness(s.with_tangent(state.evaluation)).tocsr()
    C = getattr(c, "C", None)
    if C is not None:
        held = C[np.flatnonzero(active_rows(c.committed))]
        K = K + PENALTY * float(abs(K.diagonal()).max()) * (held.T @ held)
    symmetric = (0.5 * (K + K.T)).tocsc()[free][:, free]
    return np.sort(spla.eigsh(symmetric, k=EIGENVALUES, sigma=SHIFT, which="LM",
                              return_eigenvectors=False))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("deck")
    parser.add_argument("start", type=float, help="first control deflection checked (mm)")
    parser.add_argument("end", type=float, help="last control deflection checked (mm)")
    parser.add_argument("--set", dest="sets", action="append", default=[],
                        help="deck override, as icewall run --set")
    args = parser.parse_args()
    problem, start, free, settings = newton_problem(args.deck, args.sets)
    tic = time.perf_counter()
    print("deflection mm, jack load N, drop, iterations, smallest eigenvalues N/mm")
    for inc, state in follow_path(problem, settings, start):
        deflection = -float(state.u[problem.control_equation])
        if deflection < args.start:
            continue
        values = smallest_eigenvalues(problem, state, free)
        print(f"{deflection:8.4f}  {inc.load_factor:11.1f}  {int(inc.snap_back)}  "
              f"{inc.iterations:4d}  " + " ".join(f"{v:10.4g}" for v in values)
              + f"  ({time.perf_counter() - tic:.0f} s)", flush=True)
        if deflection >= args.end:
            break


if __name__ == "__main__":
    main()
