"""Direct solution of a linear system with prescribed (fixed) equations."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from icewall.errors import ConvergenceError
from icewall.sparse import SingularMatrixError, factorize

# A pivot smaller than this fraction of its column's diagonal entry marks a (numerically)
# singular matrix. Unrestrained rigid modes gave 1e-16..3e-13 on quad4/quad8 meshes up to
# 60 x 60 elements, a legitimate L/h = 1000 cantilever 1.5e-10. Limit: a free rotation of a
# beam as slender as L/h = 1000 is not detected (its pivot is above the tolerance).
PIVOT_TOLERANCE = 1e-12


def _singular(message: str, equations: np.ndarray | None = None) -> ConvergenceError:
    hint = ""
    if equations is not None and equations.size:
        hint = f" (near free equation(s) {equations[:10].tolist()}, node = eq // 2 without ties)"
    return ConvergenceError(f"stiffness matrix is singular{hint}: {message}; rigid-body mode "
                            "not restrained? check supports", reason="singular system")


def solve_linear(K: sp.spmatrix, f: np.ndarray, fixed: np.ndarray | None = None,
                 values: np.ndarray | float = 0.0, return_reactions: bool = False
                 ) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """Solve K u = f with u[fixed] = values by partitioning into free and fixed equations.

    Returns u (n_eq,), and with `return_reactions` also the reactions (k,) = (K u - f)[fixed]
    in the order of `fixed`. Raises ConvergenceError(reason="singular system") when the free
    block cannot be factorised or gives a non-finite solution. Always SuperLU: its pivots
    detect an unrestrained rigid-body mode, and a linear analysis factorises only once.
    """
    K = sp.csr_matrix(K)
    f = np.asarray(f, dtype=float)
    n = K.shape[0]
    fixed = np.zeros(0, dtype=int) if fixed is None else np.atleast_1d(np.asarray(fixed, int))
    values = np.broadcast_to(np.asarray(values, dtype=float), fixed.shape)
    u = np.zeros(n)
    u[fixed] = values
    if fixed.size and not np.allclose(u[fixed], values):
        raise ValueError("an equation is fixed twice with different values")
    is_free = np.ones(n, dtype=bool)
    is_free[fixed] = False
    free = np.flatnonzero(is_free)
    if free.size:
        K_ff = K[free][:, free].tocsc()
        rhs = f[free] - K[free] @ u
        try:
            lu = factorize(K_ff, "superlu", pivot_scale=np.abs(K_ff.diagonal()),
                           pivot_rtol=PIVOT_TOLERANCE)
        except SingularMatrixError as exc:
            raise _singular(str(exc), free[exc.columns]) from exc
        u[free] = lu.solve(rhs)
        if not np.all(np.isfinite(u)):
            raise _singular("non-finite solution")
    if return_reactions:
        return u, (K @ u - f)[fixed]
    return u
