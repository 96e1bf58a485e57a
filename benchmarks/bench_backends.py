"""The sparse direct solvers on the Newton iteration matrices: factorisation and two-RHS solve
time, ratio to the fastest backend on the same matrix, and the backward error of each solution.

Two stages (not part of the test run):
  capture: run a deck with the Newton scheme and save every `--every`-th augmented matrix that
           icewall factorises, with the two right-hand sides solved with it (reference load and
           unbalance), into benchmarks/out/matrices/NAME/ (scipy .npz + .npy);
  time:    time every backend on every saved matrix, interleaved per matrix (the order rotates
           each repeat), median of the repeats; writes benchmarks/out/backends.csv (one row per
           matrix and backend) and backends_summary.csv (per case and backend), prints tables.

Usage: python benchmarks/bench_backends.py capture --name cf4 --deck decks/cf4.yaml
           [--set k=v ...] [--every 10] [--max 12]
       python benchmarks/bench_backends.py time [--cases cf4 tf1] [--repeats 5]
           [--backends superlu:MMD_AT_PLUS_A pardiso ...] [--natural-limit 5000]
Backends: superlu:ORDERING (icewall's SuperLU options with that permc_spec), pardiso (one kept
handle, as icewall: analysis + factorisation each time), pardiso-numeric (the analysis of the
same pattern done before, outside the timing, on the previous matrix of the case when the
pattern is the same), umfpack and umfpack-numeric likewise (if scikit-umfpack works). Ratios
are to the fastest backend on the same matrix other than the *-numeric variants (icewall's
Newton matrices change their pattern from one iteration to the next).
`time` also passes every matrix through icewall's own path (icewall.interface.augmented
.factorize and its checked, refined solve) with each installed backend and auto:
backends_product.csv says whether icewall accepts the factors (PARDISO rejects perturbed pivots).
Set MKL_NUM_THREADS (1 on a shared machine: oversubscribed MKL threads spin).
"""

from __future__ import annotations

import argparse
import time
from functools import cache

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from common import OUT, SUPERLU_OPTIONS, environment, median, print_table, write_csv

import icewall.interface.augmented as augmented
from icewall import sparse
from icewall.deck.load import load_deck
from icewall.pipeline import run_deck

MATRICES = OUT / "matrices"
ORDERINGS = ("MMD_AT_PLUS_A", "COLAMD", "MMD_ATA", "NATURAL")


class StopCapture(Exception):
    """Enough matrices saved."""


def capture(name: str, deck: str, overrides: list[str], every: int, limit: int) -> None:
    """Run `deck` and save every `every`-th augmented matrix with its two right-hand sides."""
    folder = MATRICES / name
    folder.mkdir(parents=True, exist_ok=True)
    for old in folder.glob("*.np[yz]"):
        old.unlink()
    calls, saved, pending = [0], [0], {}
    original_factorize, original_solve = augmented.sparse_factorize, augmented.AugmentedFactor.solve

    def factorize(A, *args, **kwargs):
        calls[0] += 1
        if (calls[0] - 1) % every == 0:
            if saved[0] >= limit:
                raise StopCapture
            index = saved[0]
            sp.save_npz(folder / f"A{index:03d}.npz", sp.csc_matrix(A))
            pending[id(A)] = index
            saved[0] += 1
        return original_factorize(A, *args, **kwargs)

    def solve(self, rhs):
        b = np.asarray(rhs, dtype=float)
        index = pending.get(id(self.A))
        if index is not None:  # load control (a preload) solves one right-hand side
            np.save(folder / f"b{index:03d}.npy", b.reshape(b.shape[0], -1))
            del pending[id(self.A)]
        return original_solve(self, rhs)

    augmented.sparse_factorize, augmented.AugmentedFactor.solve = factorize, solve
    try:
        run_deck(load_deck(deck, overrides), OUT / f"backends_{name}.h5")
    except StopCapture:
        pass
    finally:
        augmented.sparse_factorize = original_factorize
        augmented.AugmentedFactor.solve = original_solve
    print(f"{name}: {calls[0]} factorisations, {saved[0]} matrices saved in {folder}")


class Timed:
    """One backend's factorisation of A, timed: `factor()` returns seconds, then `solve(B)`."""

    def __init__(self, backend: str, A: sp.csc_matrix, previous: sp.csc_matrix | None) -> None:
        self.backend, self.A = backend, A
        same = previous is not None and previous.shape == A.shape and np.array_equal(
            previous.indptr, A.indptr) and np.array_equal(previous.indices, A.indices)
        self.analysed_on = previous if same else A  # for the *-numeric variants
        self.pattern_reused = same
        self._solve = None

    def prepare(self) -> None:
        """Untimed set-up: the symbolic analysis of the *-numeric variants."""
        if self.backend == "pardiso-numeric":
            self.solver = _pardiso_handle("numeric")
            self.solver.set_phase(11)
            csr = self.analysed_on.tocsr()
            self.solver._call_pardiso(csr, np.zeros((csr.shape[0], 1)))
        elif self.backend == "umfpack-numeric":
            from scikits import umfpack

            self.context = umfpack.UmfpackContext("di")
            self.context.control[umfpack.UMFPACK_IRSTEP] = 0
            self.context.symbolic(_int32(self.analysed_on))

    def factor(self) -> float:
        A, name = self.A, self.backend
        tic = time.perf_counter()
        if name.startswith("superlu:"):
            lu = spla.splu(A, **{**SUPERLU_OPTIONS, "permc_spec": name.split(":")[1]})
            self._solve = lu.solve
        elif name == "pardiso":
            solver, csr = _pardiso_handle("full"), A.tocsr()
            solver.factorize(csr)  # analysis + numeric factorisation (phase 12)
            self._solve = lambda B: _pardiso_solve(solver, csr, B)
        elif name == "pardiso-numeric":
            csr = A.tocsr()
            self.solver.set_phase(22)
            self.solver._call_pardiso(csr, np.zeros((csr.shape[0], 1)))
            self._solve = lambda B: _pardiso_solve(self.solver, csr, B)
        elif name in ("umfpack", "umfpack-numeric"):
            from scikits import umfpack

            if name == "umfpack":
                self.context = umfpack.UmfpackContext("di")
                self.context.control[umfpack.UMFPACK_IRSTEP] = 0
            A32 = _int32(A)
            self.context.numeric(A32)
            self._solve = lambda B: np.column_stack([self.context.solve(
                umfpack.UMFPACK_A, A32, np.ascontiguousarray(c), autoTranspose=True)
                for c in B.T])
        else:
            raise ValueError(f"unknown backend {name!r}")
        return time.perf_counter() - tic

    def solve(self, B: np.ndarray) -> tuple[float, np.ndarray]:
        tic = time.perf_counter()
        x = self._solve(B)
        return time.perf_counter() - tic, x


@cache
def _pardiso_handle(purpose: str):
    """One pypardiso handle per purpose, kept like icewall keeps its one (creating a handle
    costs ~0.2 s: it looks the MKL library up)."""
    import pypardiso

    return pypardiso.PyPardisoSolver(mtype=11)


def _int32(A: sp.csc_matrix) -> sp.csc_matrix:
    return sp.csc_matrix((A.data, A.indices.astype(np.int32), A.indptr.astype(np.int32)),
                         shape=A.shape)


def _pardiso_solve(solver, csr: sp.csr_matrix, B: np.ndarray) -> np.ndarray:
    solver.set_phase(33)  # solve with the stored factors (no hash of the matrix)
    return solver._call_pardiso(csr, np.asfortranarray(B))


def backward_error(A: sp.csc_matrix, B: np.ndarray, X: np.ndarray) -> float:
    """max over columns of |A x - b| / (|A| |x| + |b|) (max norms), as icewall checks it."""
    if not np.all(np.isfinite(X)):
        return float("nan")
    residual = np.abs(B - A @ X).max(axis=0)
    scale = np.abs(A.data).max() * np.abs(X).max(axis=0) + np.abs(B).max(axis=0)
    ratio = np.divide(residual, scale, out=np.where(residual > 0.0, np.inf, 0.0),
                      where=scale > 0.0)
    return float(np.max(ratio))


def relative_residual(A: sp.csc_matrix, B: np.ndarray, X: np.ndarray) -> float:
    """max over columns of ||A x - b||_2 / ||b||_2 (NaN if x is not finite)."""
    if not np.all(np.isfinite(X)):
        return float("nan")
    r, b = np.linalg.norm(B - A @ X, axis=0), np.linalg.norm(B, axis=0)
    return float(np.max(np.divide(r, b, out=np.where(r > 0.0, np.inf, 0.0), where=b > 0.0)))


def time_case(case: str, backends: list[str], repeats: int, natural_limit: int
              ) -> tuple[list[dict], list[dict]]:
    """Timing rows (one per matrix and backend) of the case's saved matrices, and the rows of
    icewall's own path (product_check)."""
    rows, previous = [], None
    checks = []
    for path in sorted((MATRICES / case).glob("A*.npz")):
        A = sp.csc_matrix(sp.load_npz(path))
        A.sum_duplicates()
        rhs = path.with_name("b" + path.name[1:]).with_suffix(".npy")
        B = np.load(rhs) if rhs.exists() else np.zeros((A.shape[0], 0))
        if B.shape[1] < 2:  # pad to two right-hand sides with a random one
            B = np.column_stack([B, np.random.default_rng(0).random((A.shape[0], 2 - B.shape[1]))])
        names = [b for b in backends if not (b == "superlu:NATURAL" and A.shape[0] > natural_limit)]
        factor_s = {b: [] for b in names}
        solve_s = {b: [] for b in names}
        errors, residuals, reused = {}, {}, False
        for r in range(repeats):
            for b in names[r % len(names):] + names[:r % len(names)]:
                timed = Timed(b, A, previous)
                timed.prepare()
                factor_s[b].append(timed.factor())
                seconds, X = timed.solve(B)
                solve_s[b].append(seconds)
                errors[b], reused = backward_error(A, B, X), timed.pattern_reused
                residuals[b] = relative_residual(A, B, X)
        usable = [b for b in names if not b.endswith("-numeric")]  # patterns change
        best = min(median(factor_s[b]) for b in usable)
        best_total = min(median(factor_s[b]) + median(solve_s[b]) for b in usable)
        for b in names:
            f, s = median(factor_s[b]), median(solve_s[b])
            rows.append({"case": case, "matrix": path.stem, "unknowns": A.shape[0],
                         "nonzeros": A.nnz, "backend": b, "factor_ms": 1e3 * f,
                         "solve2_ms": 1e3 * s, "ratio_factor": f / best,
                         "ratio_total": (f + s) / best_total, "backward_error": errors[b],
                         "relative_residual": residuals[b],
                         "pattern_of_previous": reused, "real_rhs": rhs.exists()})
        previous = A
        checks += product_check(case, path, A, B)
        print(f"  {case} {path.stem}: n={A.shape[0]}, " + ", ".join(
            f"{b} {1e3 * median(factor_s[b]):.1f}" for b in names) + " ms")
    return rows, checks


def product_check(case: str, path, A: sp.csc_matrix, B: np.ndarray) -> list[dict]:
    """icewall's own factorisation and checked solve of A with each backend (and auto)."""
    rows = []
    for backend in ("auto", *sparse.available_backends()):
        tic, outcome, error = time.perf_counter(), "accepted", float("nan")
        try:
            factor = augmented.factorize(A, backend)
            X = factor.solve(B)
            error = relative_residual(A, B, X)
            chosen = factor.lu.backend
        except Exception as exc:  # noqa: BLE001 (recorded, not raised)
            outcome, chosen = f"{type(exc).__name__}: {str(exc)[:60]}", "-"
        rows.append({"case": case, "matrix": path.stem, "unknowns": A.shape[0],
                     "backend": backend, "chosen": chosen, "outcome": outcome,
                     "relative_residual": error,
                     "factor_solve_ms": 1e3 * (time.perf_counter() - tic)})
    return rows


def summarise(rows: list[dict]) -> list[dict]:
    """Per case and backend: medians over the matrices, worst backward error."""
    out = []
    for case in dict.fromkeys(r["case"] for r in rows):
        for b in dict.fromkeys(r["backend"] for r in rows if r["case"] == case):
            mine = [r for r in rows if r["case"] == case and r["backend"] == b]
            out.append({"case": case, "unknowns": int(median(r["unknowns"] for r in mine)),
                        "backend": b, "matrices": len(mine),
                        "factor_ms": median(r["factor_ms"] for r in mine),
                        "solve2_ms": median(r["solve2_ms"] for r in mine),
                        "ratio_factor": median(r["ratio_factor"] for r in mine),
                        "ratio_total": median(r["ratio_total"] for r in mine),
                        "worst_backward_error": max(r["backward_error"] for r in mine),
                        "worst_relative_residual": max(r["relative_residual"] for r in mine)})
    return out


def main() -> None:
    parser = argparse.ArgumentParser()
    commands = parser.add_subparsers(dest="command", required=True)
    cap = commands.add_parser("capture")
    cap.add_argument("--name", required=True)
    cap.add_argument("--deck", required=True)
    cap.add_argument("--set", dest="overrides", action="append", default=[])
    cap.add_argument("--every", type=int, default=10)
    cap.add_argument("--max", type=int, default=12)
    tim = commands.add_parser("time")
    tim.add_argument("--cases", nargs="+", default=None)
    tim.add_argument("--repeats", type=int, default=5)
    tim.add_argument("--backends", nargs="+", default=None)
    tim.add_argument("--natural-limit", type=int, default=5000,
                     help="skip SuperLU's NATURAL ordering above this many unknowns")
    args = parser.parse_args()
    if args.command == "capture":
        capture(args.name, args.deck, args.overrides, args.every, args.max)
        return
    optional = [v for b in ("pardiso", "umfpack") if sparse.installed(b)
                for v in (b, f"{b}-numeric")]
    backends = args.backends or [f"superlu:{o}" for o in ORDERINGS] + optional
    cases = args.cases or sorted(p.name for p in MATRICES.iterdir() if p.is_dir())
    rows, checks = [], []
    for case in cases:
        timed, checked = time_case(case, backends, args.repeats, args.natural_limit)
        rows, checks = rows + timed, checks + checked
    summary = summarise(rows)
    rejected = [r for r in checks if r["outcome"] != "accepted"]
    print(f"\nicewall's own path: {len(checks) - len(rejected)} of {len(checks)} accepted, "
          f"worst relative residual {max(r['relative_residual'] for r in checks):.2e}")
    if rejected:
        print_table(rejected, "rejected by icewall")
    print_table(summary, "median per matrix (ms), ratio to the fastest (not *-numeric) on the "
                         "same matrix, worst backward error and relative residual")
    info = environment()
    write_csv(OUT / "backends.csv", [{**r, **info} for r in rows])
    write_csv(OUT / "backends_summary.csv", [{**r, **info} for r in summary])
    write_csv(OUT / "backends_product.csv", checks)
    print(f"\nwritten: {OUT / 'backends.csv'}, {OUT / 'backends_summary.csv'}, "
          f"{OUT / 'backends_product.csv'}")


if __name__ == "__main__":
    main()
