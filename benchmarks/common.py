"""Shared pieces of the solver benchmarks: per-phase timing of the global iterations (by
wrapping the solver's methods, so the product code carries no timers), bare factor+solve
timing of the iteration matrices seen in the same run, tables and CSV output."""

from __future__ import annotations

import csv
import os
import platform
import resource
import statistics
import time
from collections import defaultdict
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import scipy.sparse.linalg as spla

import icewall.interface.augmented as augmented
import icewall.solve.constraints as constraints
import icewall.solve.gap_constraints as gap_constraints
from icewall.model.structure import Structure

try:
    from icewall import sparse
except ImportError:  # a checkout before the sparse backends (a "before" measurement)
    sparse = None

OUT = Path(__file__).resolve().parent / "out"
SUPERLU_OPTIONS = {"permc_spec": "MMD_AT_PLUS_A", "diag_pivot_thresh": 1e-3,
                   "options": {"SymmetricMode": True}}  # icewall's SuperLU call
PHASES = ("constitutive", "assembly", "matrix", "lu", "solves", "interface")


class StopBenchmark(Exception):
    """Raised by PhaseTimer after `stop_after` factorisations."""


def bare_factor_solve(A, backend: str, repeats: int = 2) -> float:
    """Best wall time (s) of one LU factorisation of A plus one solve for two right-hand sides
    (the reference and unbalance solves of displacement control), nothing else. `backend`:
    superlu (icewall's SuperLU call), superlu:ORDERING (another permc_spec), umfpack, pardiso.
    """
    A = A.tocsc()
    B = np.random.default_rng(0).random((A.shape[0], 2))
    name, _, ordering = backend.partition(":")
    options = {**SUPERLU_OPTIONS, "permc_spec": ordering or SUPERLU_OPTIONS["permc_spec"]}
    times = []
    for _ in range(repeats):
        tic = time.perf_counter()
        if name == "superlu":
            spla.splu(A, **options).solve(B)
        else:
            sparse.factorize(A, name).solve(B)
        times.append(time.perf_counter() - tic)
    return min(times)


class PhaseTimer:
    """Times the phases of every global iteration of a nonlinear run.

    constitutive: Structure.evaluate (strains, material laws, internal forces) and
    Structure.with_tangent (the consistent tangent of an evaluation);
    assembly: Structure.stiffness; matrix: building the iteration matrix (constraints'
    factorize minus the LU); lu: the sparse factorisation with its pivot check;
    solves: the two solves of displacement control (with refinement and checks);
    interface: the gap-state update. Every `sample_every`-th iteration matrix is also
    factorised and solved bare (bare_factor_solve) by each backend in `backends`, outside
    the timed phases.
    """

    def __init__(self, sample_every: int = 0, backends: tuple[str, ...] = ("superlu",),
                 stop_after: int | None = None) -> None:
        self.times: dict[str, list[float]] = defaultdict(list)
        self.iteration_of: dict[str, list[int]] = defaultdict(list)
        self.factorisations = 0
        self.sample_every, self.backends, self.stop_after = sample_every, backends, stop_after
        self.bare: dict[str, list[float]] = defaultdict(list)
        self.sampled_iterations: list[int] = []
        self.sampling_seconds = 0.0  # spent on the bare timings (not part of any phase)
        self.matrix_size: tuple[int, int] = (0, 0)

    def _add(self, phase: str, seconds: float) -> None:
        self.times[phase].append(seconds)
        self.iteration_of[phase].append(self.factorisations)

    def _timed(self, phase: str, function):
        timer = self

        def wrapper(*args, **kwargs):
            tic = time.perf_counter()
            try:
                return function(*args, **kwargs)
            finally:
                timer._add(phase, time.perf_counter() - tic)
        return wrapper

    def _factorize(self, function):
        timer = self

        def wrapper(this, K):
            if timer.stop_after is not None and timer.factorisations >= timer.stop_after:
                raise StopBenchmark
            lu_before = sum(timer.times["lu"])
            tic = time.perf_counter()
            factor = function(this, K)
            total = time.perf_counter() - tic
            timer._add("matrix", total - (sum(timer.times["lu"]) - lu_before))
            timer.factorisations += 1
            A = factor.A if hasattr(factor, "A") else factor._lu.A
            timer.matrix_size = (A.shape[0], A.nnz)
            if timer.sample_every and (timer.factorisations - 1) % timer.sample_every == 0:
                start = time.perf_counter()
                timer.sampled_iterations.append(timer.factorisations)
                for backend in timer.backends:
                    timer.bare[backend].append(bare_factor_solve(A, backend))
                timer.sampling_seconds += time.perf_counter() - start
            return factor
        return wrapper

    @contextmanager
    def installed(self):
        """Wrap the solver's methods for the duration of the block."""
        targets = [
            (Structure, "evaluate", self._timed("constitutive", Structure.evaluate)),
            (Structure, "stiffness", self._timed("assembly", Structure.stiffness)),
            *([(Structure, "with_tangent",
                self._timed("constitutive", Structure.with_tangent))]
              if hasattr(Structure, "with_tangent") else []),
            (gap_constraints, "factorize", self._timed("lu", gap_constraints.factorize)),
            (constraints.Factorization, "__init__",
             self._timed("lu", constraints.Factorization.__init__)),
            (augmented.AugmentedFactor, "solve",
             self._timed("solves", augmented.AugmentedFactor.solve)),
            (constraints.Factorization, "solve",
             self._timed("solves", constraints.Factorization.solve)),
            (gap_constraints.GapConstraints, "apply",
             self._timed("interface", gap_constraints.GapConstraints.apply)),
            (gap_constraints.GapConstraints, "factorize",
             self._factorize(gap_constraints.GapConstraints.factorize)),
            (constraints.SupportConstraints, "factorize",
             self._factorize(constraints.SupportConstraints.factorize)),
        ]
        saved = [(owner, name, owner.__dict__[name]) for owner, name, _ in targets]
        for owner, name, wrapped in targets:
            setattr(owner, name, wrapped)
        try:
            yield self
        finally:
            for owner, name, original in saved:
                setattr(owner, name, original)

    def per_iteration(self, phase: str) -> float:
        """Mean seconds of `phase` per factorisation (global iteration)."""
        return sum(self.times[phase]) / max(self.factorisations, 1)

    def per_iteration_phases(self) -> dict[str, np.ndarray]:
        """Seconds of each phase in each global iteration (its evaluation, assembly, matrix,
        LU, solves and interface update; a step's last, converged evaluation counts with the
        next iteration)."""
        out = {}
        for phase, values in self.times.items():
            index = np.asarray(self.iteration_of[phase])
            if phase in ("constitutive", "assembly", "matrix", "lu"):
                index = index + 1  # recorded before the factorisation counter moves on
            totals = np.zeros(self.factorisations + 2)
            np.add.at(totals, index, values)
            out[phase] = totals[1:self.factorisations + 1]
        return out

    def iteration_totals(self) -> np.ndarray:
        """Seconds of all phases of each global iteration."""
        return sum(self.per_iteration_phases().values(), np.zeros(self.factorisations))


def peak_memory_mb() -> float:
    """Peak resident memory of this process (MB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def environment() -> dict[str, str]:
    """What the numbers depend on: machine, load, threads, versions, sparse backends."""
    import scipy

    keys = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS",
            "ICEWALL_SPARSE_SOLVER")
    info = {"machine": f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores",
            "load_average_1min": f"{os.getloadavg()[0]:.2f}",
            "python": platform.python_version(), "numpy": np.__version__,
            "scipy": scipy.__version__,
            "backends_installed": " ".join(sparse.available_backends()) if sparse else "-"}
    info.update({k: os.environ[k] for k in keys if k in os.environ})
    return info


def median(values) -> float:
    values = list(values)
    return float(statistics.median(values)) if values else float("nan")


def write_csv(path: Path, rows: list[dict]) -> None:
    """Rows (dicts with the same keys) as CSV; creates the folder."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)


def print_table(rows: list[dict], title: str = "") -> None:
    """A plain aligned table of dict rows (floats with 4 significant digits)."""
    def cell(value) -> str:
        if isinstance(value, float):
            return f"{value:.4g}"
        return str(value)
    if title:
        print(f"\n{title}")
    keys = list(rows[0])
    text = [[cell(r[k]) for k in keys] for r in rows]
    widths = [max(len(k), *(len(t[i]) for t in text)) for i, k in enumerate(keys)]
    print("  ".join(k.rjust(w) for k, w in zip(keys, widths, strict=True)))
    for t in text:
        print("  ".join(v.rjust(w) for v, w in zip(t, widths, strict=True)))
