"""Where one global iteration of a full nonlinear run goes, and ratio (a): time per global
iteration / one bare sparse LU factorisation + two-RHS solve of the same iteration matrix,
both measured in this one run (not part of the test run).

Usage: python benchmarks/bench_iteration.py [--deck decks/cf4.yaml] [--set k=v ...]
       [--sample-every 10] [--backends superlu pardiso] [--name iteration]
Writes benchmarks/out/<name>_phases.csv (one row per phase) and <name>_summary.csv.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from common import OUT, PhaseTimer, environment, median, peak_memory_mb, print_table, write_csv

from icewall.deck.load import load_deck
from icewall.pipeline import run_deck
from icewall.results import open_result

try:
    from icewall import sparse
except ImportError:  # a checkout before the sparse backends (a "before" measurement)
    sparse = None

ROOT = Path(__file__).resolve().parent.parent


def iterations_after_cracking(path: Path) -> tuple[list[int], int]:
    """Iterations of every step after the first one with in-plane cracking, and that step."""
    with open_result(path) as result:
        history = result.history
        iterations = np.asarray(history["iterations"])
        cracked = np.asarray(history.get("cracked_in_plane", np.zeros_like(iterations)))
    first = int(np.argmax(cracked > 0)) if np.any(cracked > 0) else len(iterations)
    return iterations[first + 1:].tolist(), first + 1


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--deck", default=str(ROOT / "decks" / "cf4.yaml"))
    parser.add_argument("--set", dest="overrides", action="append", default=[])
    parser.add_argument("--sample-every", type=int, default=10)
    parser.add_argument("--backends", nargs="+", default=None,
                        help="backends timed bare on the sampled matrices (default: installed)")
    parser.add_argument("--name", default="iteration", help="prefix of the CSV files written")
    args = parser.parse_args()
    backends = tuple(args.backends or (sparse.available_backends() if sparse else ["superlu"]))
    loaded = load_deck(args.deck, args.overrides)
    OUT.mkdir(parents=True, exist_ok=True)
    output = OUT / f"{Path(args.deck).stem}.h5"
    timer = PhaseTimer(sample_every=args.sample_every, backends=backends)
    tic = time.perf_counter()
    with timer.installed():
        report = run_deck(loaded, output)
    wall = time.perf_counter() - tic
    bare_time = timer.sampling_seconds
    solve_time = report.timings["solve"] - bare_time
    n = max(timer.factorisations, 1)
    per_iteration = solve_time / n
    after, first_cracked = iterations_after_cracking(Path(report.path))
    in_phases = sum(timer.per_iteration(p) for p in timer.times)
    rows = [{"phase": p, "ms_per_iteration": 1e3 * timer.per_iteration(p),
             "share": timer.per_iteration(p) / per_iteration} for p in
            ("constitutive", "assembly", "matrix", "lu", "solves", "interface")]
    rows.append({"phase": "other (control loop, norms, commits)",
                 "ms_per_iteration": 1e3 * (per_iteration - in_phases),
                 "share": (per_iteration - in_phases) / per_iteration})
    rows.append({"phase": "I/O (HDF5, per iteration)",
                 "ms_per_iteration": 1e3 * report.timings["write"] / n,
                 "share": report.timings["write"] / n / per_iteration})
    rows.append({"phase": "global iteration (solve time / factorisations)",
                 "ms_per_iteration": 1e3 * per_iteration, "share": 1.0})
    print_table(rows, f"{loaded.deck.specimen.name}: one global iteration, {n} iterations, "
                      f"matrix {timer.matrix_size[0]} unknowns, {timer.matrix_size[1]} non-zeros")
    summary = {"deck": Path(args.deck).name, "overrides": " ".join(args.overrides),
               "status": report.status, "steps": report.n_steps, "global_iterations": n,
               "unknowns": timer.matrix_size[0], "nonzeros": timer.matrix_size[1],
               "ms_per_iteration": 1e3 * per_iteration,
               "median_iterations_per_step_after_cracking": median(after),
               "first_cracked_step": first_cracked,
               "run_time_s": report.timings["total"] - bare_time, "wall_with_sampling_s": wall,
               "io_s": report.timings["write"], "peak_memory_mb": peak_memory_mb(),
               "sparse_backend": sparse.choose_backend() if sparse else "superlu"}
    ratio_rows = []
    for backend, times in timer.bare.items():
        bare = median(times)
        summary[f"bare_factor_solve_ms_{backend}"] = 1e3 * bare
        summary[f"ratio_a_{backend}"] = per_iteration / bare
        ratio_rows.append({"backend": backend, "sampled_matrices": len(times),
                           "bare_factor+2_solves_ms": 1e3 * bare,
                           "iteration_ms": 1e3 * per_iteration,
                           "ratio_a": per_iteration / bare})
    if ratio_rows:
        print_table(ratio_rows, "(a) time per global iteration / bare LU + solve of the same "
                                "matrices, this run (target <= 1.3)")
    print_table([{k: summary[k] for k in ("steps", "global_iterations", "run_time_s",
                                          "median_iterations_per_step_after_cracking",
                                          "peak_memory_mb")}], "run")
    summary.update(environment())
    phases, summary_csv = OUT / f"{args.name}_phases.csv", OUT / f"{args.name}_summary.csv"
    write_csv(phases, rows)
    write_csv(summary_csv, [summary])
    print(f"\nwritten: {phases}, {summary_csv}")


if __name__ == "__main__":
    main()
