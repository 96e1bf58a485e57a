"""(d) Scaling of the time per global iteration with the number of unknowns (not part of the
test run): the CF-4 wall meshed from 10^3 to 10^5 equations (analysis.element_size), a few
global iterations of its nonlinear path (cracking in the first 2 mm increment: concrete
update + assembly + augmented matrix + LU + two solves + gap update), each iteration matrix
also factorised and solved bare; fits t ~ n^p. Every size runs in a fresh process.

Usage: python benchmarks/bench_scaling.py [--sizes 75 30 15 10 7 5 4] [--iterations 4]
       [--backends superlu superlu:COLAMD umfpack] [--csv scaling.csv]
(ICEWALL_SPARSE_SOLVER / ICEWALL_SUPERLU_ORDERING choose the solver of the iterations.)
With the default SuperLU ordering an iteration takes ~7 s at 2e4 unknowns and grows ~n^1.9:
finer meshes are skipped once an iteration exceeds --budget-s.
Writes benchmarks/out/scaling.csv.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
from common import (
    OUT,
    PhaseTimer,
    StopBenchmark,
    environment,
    peak_memory_mb,
    print_table,
    write_csv,
)
from common import median as median_of

ROOT = Path(__file__).resolve().parent.parent


def one_size(element_size: float, iterations: int, backends: tuple[str, ...]) -> dict:
    """Time `iterations` global iterations of CF-4 meshed at `element_size` (this process)."""
    from icewall.deck.load import load_deck
    from icewall.mesh.build import build_mesh, region_materials
    from icewall.model.build import build_model
    from icewall.solve.nonlinear import run_nonlinear

    deck = load_deck(ROOT / "decks" / "cf4.yaml", [
        f"analysis.element_size={element_size}", "loads.control.increment=2.0",
        "loads.control.target=40.0"]).deck
    model = build_model(deck, (mesh := build_mesh(deck)), region_materials(deck))
    timer = PhaseTimer(sample_every=1, backends=backends, stop_after=iterations)
    with timer.installed():
        try:
            for _ in run_nonlinear(model):
                pass
        except StopBenchmark:
            pass
    totals = timer.iteration_totals()
    row = {"element_size": element_size, "equations": model.dof_map.n_equations,
           "unknowns": timer.matrix_size[0], "nonzeros": timer.matrix_size[1],
           "elements": mesh.n_cells, "iterations": timer.factorisations,
           "iteration_ms": 1e3 * median_of(totals)}
    phases = timer.per_iteration_phases()
    for phase in ("constitutive", "assembly", "matrix", "lu", "solves", "interface"):
        row[f"{phase}_ms"] = 1e3 * median_of(phases.get(phase, [np.nan]))
    for backend, times in timer.bare.items():
        row[f"bare_{backend}_ms"] = 1e3 * median_of(times)
        row[f"ratio_a_{backend}"] = median_of(totals) / median_of(times)
    row["peak_memory_mb"] = peak_memory_mb()
    return row


def fit_exponent(n: np.ndarray, t: np.ndarray) -> float:
    """p of the least-squares fit log t = p log n + c."""
    return float(np.polyfit(np.log(n), np.log(t), 1)[0])


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--sizes", type=float, nargs="+", default=[75, 30, 15, 10, 7, 5, 4])
    parser.add_argument("--iterations", type=int, default=4)
    parser.add_argument("--backends", nargs="+", default=["superlu"])
    parser.add_argument("--csv", default="scaling.csv", help="file name under benchmarks/out")
    parser.add_argument("--budget-s", type=float, default=15.0,
                        help="skip the finer meshes once an iteration took longer than this")
    parser.add_argument("--one", type=float, help=argparse.SUPPRESS)  # worker: one size
    args = parser.parse_args()
    if args.one is not None:
        print(json.dumps(one_size(args.one, args.iterations, tuple(args.backends))))
        return
    rows = []
    for size in args.sizes:
        if rows and rows[-1]["iteration_ms"] > 1e3 * args.budget_s:
            print(f"element size {size:g}: skipped (last iteration above {args.budget_s} s)")
            continue
        done = subprocess.run([sys.executable, __file__, "--one", str(size), "--iterations",
                               str(args.iterations), "--backends", *args.backends],
                              capture_output=True, text=True, check=False)
        if done.returncode != 0:
            print(f"element size {size}: failed\n{done.stderr[-2000:]}", file=sys.stderr)
            continue
        rows.append(json.loads(done.stdout.strip().splitlines()[-1]))
        print(f"element size {size:g}: {rows[-1]['unknowns']} unknowns, "
              f"{rows[-1]['iteration_ms']:.1f} ms per iteration", flush=True)
    if len(rows) < 2:
        sys.exit("fewer than two sizes finished")
    n = np.array([r["unknowns"] for r in rows], dtype=float)
    fits = {"iteration_ms": fit_exponent(n, np.array([r["iteration_ms"] for r in rows]))}
    for key in [k for k in rows[0] if k.startswith("bare_") or k.endswith("_ms")]:
        fits[key] = fit_exponent(n, np.array([r[key] for r in rows]))
    shown = ["unknowns", "nonzeros", "iteration_ms", "constitutive_ms", "assembly_ms",
             "matrix_ms", "lu_ms", "solves_ms", "interface_ms"]
    shown += [k for k in rows[0] if k.startswith(("bare_", "ratio_a_"))] + ["peak_memory_mb"]
    print_table([{k: r[k] for k in shown} for r in rows],
                "(d) time per global iteration against problem size (CF-4, medians over "
                f"{args.iterations} iterations)")
    print_table([{"quantity": k, "exponent_p (t ~ n^p)": v} for k, v in fits.items()],
                f"fitted exponents over {int(n.min())}..{int(n.max())} unknowns")
    env = environment()
    for row in rows:
        row.update({f"exponent_{k}": v for k, v in fits.items()})
        row.update(env)
    write_csv(OUT / args.csv, rows)
    print(f"\nwritten: {OUT / args.csv}")


if __name__ == "__main__":
    main()
