"""Supports (and, through a subclass, gap elements) as the linear algebra of one iteration.

A constraint set owns the multipliers of its constraints and turns the stiffness K into the
matrix that is factorised once per iteration and solved for two right-hand sides (reference
load and unbalance, eqs. 3.45-3.46). Fixed equations become identity rows with zero RHS.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from icewall.errors import ConvergenceError


class Factorization:
    """Sparse LU of one iteration matrix; `solve` takes (n,) or (n, k) right-hand sides."""

    def __init__(self, A: sp.spmatrix, hint: str = "") -> None:
        try:
            self._lu = spla.splu(sp.csc_matrix(A), permc_spec="MMD_AT_PLUS_A",
                                 options={"SymmetricMode": True},
                                 diag_pivot_thresh=1e-3)
        except RuntimeError as exc:
            raise ConvergenceError(f"singular system ({exc}){hint}",
                                   reason="singular system") from None

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        x = self._lu.solve(np.asarray(rhs, dtype=float))
        if not np.all(np.isfinite(x)):
            raise ConvergenceError("the linear solve gave non-finite values (singular or "
                                   "badly conditioned system)", reason="singular system")
        return x


class SupportConstraints:
    """Homogeneous supports only: u[fixed] = 0. No multipliers."""

    n_multipliers = 0

    def __init__(self, n_equations: int, fixed: np.ndarray) -> None:
        self.n_equations = n_equations
        self.fixed = np.asarray(fixed, dtype=int)
        free = np.ones(n_equations)
        free[self.fixed] = 0.0
        self._free = sp.diags(free)
        self._fixed_identity = sp.diags(1.0 - free)

    # --- state over a step -------------------------------------------------------------
    def begin_step(self) -> None:
        """Start a new increment from the committed state."""

    def commit(self) -> None:
        """Accept the current iterate as converged."""

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
        A = self._free @ K @ self._free + self._fixed_identity
        return Factorization(A, " - a rigid-body mode is not restrained: check supports")

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
