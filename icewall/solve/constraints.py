"""Supports (and, through a subclass, gap elements) as the linear algebra of one iteration.

A constraint set owns the multipliers of its constraints and turns the stiffness K into the
matrix that is factorised once per iteration and solved for two right-hand sides (reference
load and unbalance, eqs. 3.45-3.46). Fixed equations become identity rows with zero RHS.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from icewall.errors import ConvergenceError
from icewall.sparse import SingularMatrixError, factorize


class Factorization:
    """Sparse LU of one iteration matrix (icewall.sparse); `solve` takes (n,) or (n, k)
    right-hand sides."""

    def __init__(self, A: sp.spmatrix, hint: str = "", backend: str | None = None) -> None:
        try:
            self._lu = factorize(A, backend)
        except SingularMatrixError as exc:
            raise ConvergenceError(f"singular system ({exc}){hint}",
                                   reason="singular system") from None

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        b = np.asarray(rhs, dtype=float)
        x = self._lu.solve(b)
        # SuperLU reports exact singularity itself; the others need the residual check
        if not np.all(np.isfinite(x)) or not (self._lu.backend == "superlu"
                                              or self._lu.accurate(b, x)):
            raise ConvergenceError("the linear solve gave non-finite values (singular or "
                                   "badly conditioned system)", reason="singular system")
        return x


def restricted_matrix(K: sp.spmatrix, fixed: np.ndarray) -> sp.csc_matrix:
    """K with the rows and columns of `fixed` replaced by identity ones, canonical CSC without
    stored zeros (bit for bit diag(free) K diag(free) + diag(fixed))."""
    K = sp.csc_matrix(K, copy=True)
    K.sum_duplicates()
    is_fixed = np.zeros(K.shape[0], dtype=bool)
    is_fixed[fixed] = True
    cols = np.repeat(np.arange(K.shape[1]), np.diff(K.indptr))
    rows = K.indices
    K.data[is_fixed[rows] | is_fixed[cols]] = 0.0
    diagonal = np.flatnonzero((rows == cols) & is_fixed[cols])
    K.data[diagonal] = 1.0
    if diagonal.size < np.count_nonzero(is_fixed):  # a fixed equation outside K's pattern
        missing = is_fixed.copy()
        missing[cols[diagonal]] = False
        K = K + sp.diags(missing.astype(float), format="csc")
    K.eliminate_zeros()
    return K


class SupportConstraints:
    """Homogeneous supports only: u[fixed] = 0. No multipliers."""

    n_multipliers = 0
    sparse_backend: str | None = None  # icewall.sparse: None = $ICEWALL_SPARSE_SOLVER

    def __init__(self, n_equations: int, fixed: np.ndarray) -> None:
        self.n_equations = n_equations
        self.fixed = np.asarray(fixed, dtype=int)

    # --- state over a step -------------------------------------------------------------
    def begin_step(self, time_step: bool = False) -> None:
        """Start a new increment from the committed state."""

    def commit(self) -> None:
        """Accept the current iterate as converged."""

    def commit_time_step(self, end_share: float) -> None:
        """Accept a converged time step (end_share = 1 - af: `GapConstraints`')."""
        self.commit()

    def rollback(self) -> None:
        """Return to the committed state (a cut step)."""

    # --- one iteration -----------------------------------------------------------------
    def constraint_force(self) -> np.ndarray:
        """C^T lambda on the displacement equations (zero without multipliers)."""
        return np.zeros(self.n_equations)

    def restrict(self, vector: np.ndarray) -> np.ndarray:
        """Zero the fixed equations of a displacement-equation vector."""
        out = np.array(vector, dtype=float)
        out[self.fixed] = 0.0
        return out

    def factorize(self, K: sp.spmatrix) -> Factorization:
        """Factorisation of the iteration matrix for the current constraint states."""
        return Factorization(restricted_matrix(K, self.fixed),
                             " - a rigid-body mode is not restrained: check supports",
                             self.sparse_backend)

    def reference_rhs(self, reference: np.ndarray) -> np.ndarray:
        """RHS of eq. 3.46: R* on the free equations, zero in any multiplier rows (errata §3)."""
        return np.concatenate([self.restrict(reference), np.zeros(self.n_multipliers)])

    def unbalance_rhs(self, unbalance: np.ndarray, u: np.ndarray) -> np.ndarray:
        """RHS of eq. 3.45 from F_ext - F_int (without constraint forces) and the constraint
        rows of the current states."""
        return self.restrict(unbalance)

    def split(self, solution: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(displacement part, multiplier part) of a solution vector or its columns."""
        return solution[:self.n_equations], solution[self.n_equations:]

    def constraint_residuals(self, u: np.ndarray) -> tuple[float, float]:
        """(largest gap violation, largest multiplier off its prescribed value): none here."""
        return 0.0, 0.0

    def apply(self, multiplier_increment: np.ndarray, u: np.ndarray) -> int:
        """Add an iteration's multiplier increment; returns the number of state flips."""
        return 0

    # --- reporting -----------------------------------------------------------------------
    def counts(self) -> dict[str, int]:
        return {}

    def friction_work_increment(self) -> float:
        return 0.0

    def arrays(self) -> dict[str, np.ndarray]:
        return {}
