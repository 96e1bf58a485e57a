"""Direct solution of a linear system with prescribed (fixed) equations."""

from __future__ import annotations

import warnings

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from icewall.errors import ConvergenceError

# A pivot smaller than this fraction of its column's diagonal entry marks a (numerically)
# singular matrix. Unrestrained rigid modes gave 1e-16..3e-13 on quad4/quad8 meshes up to
# 60 x 60 elements, a legitimate L/h = 1000 cantilever 1.5e-10. Limit: a free rotation of a
# beam as slender as L/h = 1000 is not detected (its pivot is above the tolerance).
PIVOT_TOLERANCE = 1e-12
# Stiffness matrices are (nearly) structurally symmetric: symmetric ordering, diagonal pivots
# preferred (threshold partial pivoting still guards nonsymmetric tangents). ~3x faster than
# the default COLAMD ordering on a 10 000-element quad8 mesh.
SPLU_OPTIONS = {"permc_spec": "MMD_AT_PLUS_A", "diag_pivot_thresh": 1e-3,
                "options": {"SymmetricMode": True}}


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
    block cannot be factorised or gives a non-finite solution.
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
        with warnings.catch_warnings():
            warnings.simplefilter("error", spla.MatrixRankWarning)
            try:
                lu = spla.splu(K_ff, **SPLU_OPTIONS)
            except (RuntimeError, spla.MatrixRankWarning) as exc:
                raise _singular(str(exc)) from exc
        column = np.argsort(lu.perm_c)  # column j of L U is column perm_c^-1[j] of K_ff
        pivots = np.abs(lu.U.diagonal())
        small = pivots <= PIVOT_TOLERANCE * np.abs(K_ff.diagonal()[column])
        if np.any(small):
            raise _singular(f"{small.sum()} (near-)zero pivot(s)", free[column[small]])
        u[free] = lu.solve(rhs)
        if not np.all(np.isfinite(u)):
            raise _singular("non-finite solution")
    if return_reactions:
        return u, (K @ u - f)[fixed]
    return u
