"""The one sparse direct solver behind every linear system of icewall.

Backends: SciPy's SuperLU (always there), UMFPACK (scikit-umfpack) and MKL PARDISO (pypardiso),
the latter two optional (extra `fast`). `ICEWALL_SPARSE_SOLVER` = superlu | umfpack | pardiso |
auto chooses one; the default is superlu with the MMD_AT_PLUS_A ordering
(`ICEWALL_SUPERLU_ORDERING` changes it). auto chooses by the size of the matrix (choose_for,
measured on Newton iteration matrices: docs/solver_backends.md): from AUTO_LARGE_ROWS rows up
PARDISO, else UMFPACK; otherwise SuperLU with COLAMD (below AUTO_ORDERING_ROWS) or MMD_ATA.
Asked without a size, auto is the first installed of umfpack, pardiso, superlu. A requested
optional backend that is not installed falls back to SuperLU with a warning, never an error.

Why the default is the old SuperLU call: it reproduces earlier results bit for bit, and the
post-peak path of a cracked wall is chaotic in round-off (SuperLU with COLAMD instead moved the
final CF-4 load by -2.4 % and its iterations by +34 %, UMFPACK by +4.5 % and -26 %; the peak
agreed to 1e-13). The faster ones are much faster on the augmented gap-element matrix (one
10 600-unknown CF-4 matrix: MMD_AT_PLUS_A 810 ms, COLAMD 167 ms, UMFPACK 65 ms; see
benchmarks/). UMFPACK reuses its symbolic analysis while the pattern stays the same.
"""

from __future__ import annotations

import importlib
import os
import warnings
from abc import ABC, abstractmethod
from functools import cache, cached_property
from typing import NamedTuple

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

ENVIRONMENT_VARIABLE = "ICEWALL_SPARSE_SOLVER"
ORDERING_VARIABLE = "ICEWALL_SUPERLU_ORDERING"  # SuperLU's permc_spec, e.g. COLAMD
BACKENDS = ("superlu", "umfpack", "pardiso")
_MODULES = {"umfpack": "scikits.umfpack", "pardiso": "pypardiso"}
# Stiffness and augmented matrices are (nearly) structurally symmetric: symmetric ordering,
# diagonal pivots preferred; threshold partial pivoting still guards unsymmetric tangents and
# picks off-diagonal pivots for the zero diagonal of a multiplier block. ~3x faster than the
# default COLAMD ordering on a 10 000-element quad8 mesh.
SUPERLU_OPTIONS = {"permc_spec": "MMD_AT_PLUS_A", "diag_pivot_thresh": 1e-3,
                   "options": {"SymmetricMode": True}}
# ICEWALL_SPARSE_SOLVER=auto (choose_for), from benchmarks/bench_backends.py on Newton matrices
# (docs/solver_backends.md). SuperLU: COLAMD below AUTO_ORDERING_ROWS rows (5-15 % ahead of
# MMD_ATA at 2 000), MMD_ATA from there up (~22 % less time than COLAMD at 10 000 and 40 000);
# MMD_AT_PLUS_A, the default, is up to 16x slower than either. PARDISO (one MKL thread) ties
# SuperLU MMD_ATA at 10 000 rows and takes 0.55x of its time at 40 000.
AUTO_LARGE_ROWS = 10_000
AUTO_ORDERING_ROWS = 5_000
# Backends without pivot access: relative residual |A x - b| / (|A| |x| + |b|) above which a
# solution is rejected as that of a singular matrix.
RESIDUAL_RTOL = 1e-8


def superlu_options() -> dict:
    """SUPERLU_OPTIONS with the column ordering of $ICEWALL_SUPERLU_ORDERING if set."""
    ordering = os.environ.get(ORDERING_VARIABLE, "").strip().upper()
    return {**SUPERLU_OPTIONS, "permc_spec": ordering} if ordering else SUPERLU_OPTIONS


class SingularMatrixError(ArithmeticError):
    """The matrix is (numerically) singular; `columns` are the columns of its small pivots."""

    def __init__(self, message: str, columns: np.ndarray | None = None) -> None:
        super().__init__(message)
        self.columns = np.zeros(0, dtype=int) if columns is None else np.asarray(columns)


@cache
def installed(backend: str) -> bool:
    """Whether `backend` imports here (tried once, only when asked for)."""
    if backend == "superlu":
        return True
    try:
        module = importlib.import_module(_MODULES[backend])
        if backend == "umfpack":  # a build against other headers imports without its solvers
            module.UmfpackContext("di")
    except Exception:  # a broken optional install counts as absent
        return False
    return True


def available_backends() -> tuple[str, ...]:
    """The backends that import on this machine, SuperLU first."""
    return tuple(b for b in BACKENDS if installed(b))


class Choice(NamedTuple):
    """A backend and, for SuperLU, its column ordering (None: superlu_options())."""

    backend: str
    ordering: str | None = None


def choose_for(n_rows: int) -> Choice:
    """The fastest installed backend for an iteration matrix of `n_rows` rows (measured on
    Newton matrices, docs/solver_backends.md): from AUTO_LARGE_ROWS rows up pardiso, else
    umfpack; otherwise SuperLU, ordered by COLAMD below AUTO_ORDERING_ROWS rows and MMD_ATA
    from there up ($ICEWALL_SUPERLU_ORDERING, if set, wins)."""
    if n_rows >= AUTO_LARGE_ROWS:
        for backend in ("pardiso", "umfpack"):
            if installed(backend):
                return Choice(backend)
    if os.environ.get(ORDERING_VARIABLE, "").strip():
        return Choice("superlu")
    return Choice("superlu", "COLAMD" if n_rows < AUTO_ORDERING_ROWS else "MMD_ATA")


def _requested(requested: str | None) -> str:
    """The backend asked for: `requested`, else $ICEWALL_SPARSE_SOLVER, else superlu."""
    return (requested or os.environ.get(ENVIRONMENT_VARIABLE) or "superlu").strip().lower()


def choose_backend(requested: str | None = None, n_rows: int | None = None) -> str:
    """`requested`, else $ICEWALL_SPARSE_SOLVER, else superlu; auto = choose_for(n_rows), or
    without a size the first installed of umfpack, pardiso, superlu. An absent optional
    backend falls back to superlu."""
    name = _requested(requested)
    if name == "auto":
        if n_rows is not None:
            return choose_for(n_rows).backend
        return next(b for b in ("umfpack", "pardiso", "superlu") if installed(b))
    if name not in BACKENDS:
        raise ValueError(f"unknown sparse solver {name!r}; expected auto or one of {BACKENDS}")
    if not installed(name):
        warnings.warn(f"sparse solver {name!r} is not installed (pip install icewall[fast]); "
                      "using superlu", RuntimeWarning, stacklevel=2)
        return "superlu"
    return name


class SparseLU(ABC):
    """LU factors of one square sparse matrix; `solve` takes (n,) or (n, k) right-hand sides."""

    backend = "superlu"

    def __init__(self, A: sp.csc_matrix) -> None:
        self.A = A

    @cached_property
    def norm_A(self) -> float:
        """max |A_ij|, the |A| of the residual check (computed once, when first needed)."""
        return float(np.abs(self.A.data).max(initial=0.0))

    @abstractmethod
    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """x with A x = rhs (unchecked)."""

    def backward_error(self, b: np.ndarray, x: np.ndarray) -> float:
        """max over columns of |A x - b| / (|A| |x| + |b|) (max norms; NaN if x is not
        finite)."""
        if not np.all(np.isfinite(x)):
            return float("nan")
        residual = np.abs(b - self.A @ x).max(axis=0)
        scale = self.norm_A * np.abs(x).max(axis=0) + np.abs(b).max(axis=0)
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where(scale > 0.0, residual / np.where(scale > 0.0, scale, 1.0),
                             np.where(residual > 0.0, np.inf, 0.0))
        return float(np.max(ratio))

    def accurate(self, b: np.ndarray, x: np.ndarray) -> bool:
        """x is finite and leaves residuals below RESIDUAL_RTOL (|A| |x| + |b|) in every
        column (the check of the backends without pivot access)."""
        return self.backward_error(b, x) <= RESIDUAL_RTOL


class SuperLUFactor(SparseLU):
    """scipy.sparse.linalg.splu with superlu_options(); pivots are checked against a scale."""

    def __init__(self, A: sp.csc_matrix, pivot_scale: np.ndarray | None,
                 pivot_rtol: float, ordering: str | None = None) -> None:
        super().__init__(A)
        options = superlu_options() if ordering is None else {**SUPERLU_OPTIONS,
                                                              "permc_spec": ordering}
        with warnings.catch_warnings():
            warnings.simplefilter("error", spla.MatrixRankWarning)
            try:
                self.lu = spla.splu(A, **options)
            except (RuntimeError, spla.MatrixRankWarning) as exc:
                raise SingularMatrixError(str(exc)) from exc
        if pivot_scale is not None:
            column = np.argsort(self.lu.perm_c)  # column j of L U is column perm_c^-1[j] of A
            small = np.abs(self.lu.U.diagonal()) <= pivot_rtol * pivot_scale[column]
            if np.any(small):
                raise SingularMatrixError(f"{small.sum()} (near-)zero pivot(s)", column[small])

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        return self.lu.solve(np.asarray(rhs, dtype=float))


class UmfpackFactor(SparseLU):
    """scikit-umfpack; one context whose symbolic analysis is reused while the pattern stays
    the same. An older factor whose numeric factors were replaced refactorises on solve."""

    backend = "umfpack"
    _last: tuple[np.ndarray, np.ndarray, object] | None = None  # indptr, indices, context
    _owner: UmfpackFactor | None = None  # whose numeric factors the context holds

    def __init__(self, A: sp.csc_matrix) -> None:
        from scikits import umfpack

        A = sp.csc_matrix((A.data, A.indices.astype(np.int32), A.indptr.astype(np.int32)),
                          shape=A.shape)
        super().__init__(A)
        self._umfpack = umfpack
        last = UmfpackFactor._last
        if last is None or not (np.array_equal(last[0], A.indptr)
                                and np.array_equal(last[1], A.indices)):
            context = umfpack.UmfpackContext("di")
            context.control[umfpack.UMFPACK_IRSTEP] = 0  # callers refine (AugmentedFactor)
            last = (A.indptr.copy(), A.indices.copy(), context)
        self._context = last[2]
        UmfpackFactor._last = None
        self._numeric()
        UmfpackFactor._last = last

    def _numeric(self) -> None:
        umfpack = self._umfpack
        UmfpackFactor._owner = None
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", umfpack.UmfpackWarning)
            try:
                self._context.numeric(self.A)
            except RuntimeError as exc:
                raise SingularMatrixError(f"umfpack: {exc}") from exc
        if any("singular" in str(w.message).lower() for w in caught):
            raise SingularMatrixError("umfpack: singular matrix")
        UmfpackFactor._owner = self

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        if UmfpackFactor._owner is not self:
            self._numeric()
        b = np.asarray(rhs, dtype=float)
        columns = b.reshape(b.shape[0], -1)
        with warnings.catch_warnings():  # its condition estimate: the callers check residuals
            warnings.simplefilter("ignore", self._umfpack.UmfpackWarning)
            x = [self._context.solve(self._umfpack.UMFPACK_A, self.A, np.ascontiguousarray(c),
                                     autoTranspose=True) for c in columns.T]
        return np.column_stack(x).reshape(b.shape)


class PardisoFactor(SparseLU):
    """MKL PARDISO through pypardiso, real unsymmetric (mtype 11, weighted matching). One
    solver handle serves every factorisation; pypardiso refactorises if a newer matrix was
    factorised in between. Perturbed pivots count as singular."""

    backend = "pardiso"
    _solver = None

    def __init__(self, A: sp.csc_matrix) -> None:
        import pypardiso

        super().__init__(A)
        if PardisoFactor._solver is None:
            PardisoFactor._solver = pypardiso.PyPardisoSolver(mtype=11)
        self._csr = A.tocsr()
        try:
            PardisoFactor._solver.factorize(self._csr)
        except pypardiso.pardiso_wrapper.PyPardisoError as exc:
            raise SingularMatrixError(f"pardiso: {exc}") from exc
        perturbed = int(PardisoFactor._solver.get_iparm(14))  # pivots replaced by eps |A|
        if perturbed:
            raise SingularMatrixError(f"pardiso: {perturbed} perturbed (near-zero) pivot(s)")

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        b = np.asarray(rhs, dtype=float)
        return np.asarray(PardisoFactor._solver.solve(self._csr, b)).reshape(b.shape)


def factorize(A: sp.spmatrix, backend: str | None = None,
              pivot_scale: np.ndarray | None = None, pivot_rtol: float = 1e-12) -> SparseLU:
    """LU factors of A with the chosen backend (see choose_backend; auto: choose_for with the
    size of A, and SuperLU then with its ordering).

    SuperLU also rejects pivots |U_jj| <= pivot_rtol * pivot_scale[j] (column j of A) when a
    scale is given; the others have no pivot access: check their solutions (accurate).
    Raises SingularMatrixError.
    """
    A = sp.csc_matrix(A)
    name = _requested(backend)
    choice = choose_for(A.shape[0]) if name == "auto" else Choice(choose_backend(name))
    if choice.backend == "umfpack":
        return UmfpackFactor(A)
    if choice.backend == "pardiso":
        return PardisoFactor(A)
    return SuperLUFactor(A, pivot_scale, pivot_rtol, choice.ordering)
