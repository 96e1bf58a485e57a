"""Augmented (saddle-point) equations of the gap elements for one iteration (eq. 3.35).

Unknowns x = [du (n_eq); dlam (2 n_pairs)] with dlam in constraint-row order [N_0, T_0, ...].
Tables 3.1/3.3 in TOTAL form, per pair state (see icewall.interface.gap for the signs):
  FIXED: C_N du = 0 - Delta_N,  C_T du = stick_T - Delta_T          (rows active)
  SLIP:  C_N du = 0 - Delta_N;  dlam_T = T = sign(lam_T) mu |lam_N| - lam_T  (prescribed)
  FREE:  dlam_N = N = -lam_N,   dlam_T = T = -lam_T                   (prescribed, eq. 3.43)
Prescribed multipliers are moved to the displacement right-hand side (-C_p^T dlam_p, exactly
Table 3.1's slip/free "load" columns) and their rows become identity rows, so
    A = [[K, C_a^T], [C_a, 0]]  (+)  I_prescribed
stays symmetric (indefinite). Supported equations become identity rows/columns with zero
increments. Displacement control (errata §3): reference solve [R*; 0] (R* is zero in the
multiplier rows) and unbalanced solve [r_u - C^T lam - C_p^T dlam_p; targets] (gap "loads" go
here, never scaled by the load factor), both on one factorisation.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from icewall.errors import ConvergenceError
from icewall.interface.gap import FIXED, FREE, SLIP, GapState, relative_displacement, slip_force
from icewall.interface.pattern import AugmentedPattern, canonical_csr, fixed_mask
from icewall.sparse import RESIDUAL_RTOL, SingularMatrixError, SparseLU
from icewall.sparse import factorize as sparse_factorize

# |U_jj| below this fraction of the largest entry of column j marks a singular system
# (a floating core gives ~1e-16), in the matrix or, where it fails, in the equilibrated one.
PIVOT_RTOL = 1e-12
# A solve whose backward error |A x - b| / (|A| |x| + |b|) exceeds this gets one step of
# iterative refinement: SuperLU's first solve of the CF-4 augmented matrices stays below 1e-18
# (2199 solves to 20 mm), so the step, which cost a third of the solve phase, is kept for the
# ill-conditioned systems it is for.
REFINE_RTOL = 1e-14

SINGULAR_HINT = ("a concrete core (or steel part) may have no active interface pair (all FREE) "
                 "and float: add fixed points (choose_fixed_points) or check the supports; or, "
                 "with the Newton scheme's tangent, the concrete around those unknowns has "
                 "lost its stiffness (crushed and cracked: docs/solver.md, item 9)")


def active_rows(state: GapState) -> np.ndarray:
    """(2n,) bool: constraint rows enforced as C_r du = target_r (the others are prescribed)."""
    active_N = state.state != FREE
    active_T = state.state == FIXED
    return np.column_stack([active_N, active_T]).ravel()


def prescribed_increments(state: GapState, mu: float) -> np.ndarray:
    """Prescribed dlam (2n,) of the inactive rows (Table 3.3, errata), zero on active rows.

    SLIP uses the CURRENT accumulated lam_N (the start of this iteration): the normal row is
    solved in the same system, so lam_T lags lam_N by one iteration and meets the Coulomb
    limit at convergence (when dlam_N -> 0). Printed 3.41 (lam_T - mu lam_N) would add the
    excess instead of removing it.
    """
    d_N = np.where(state.state == FREE, -state.lam_N, 0.0)  # eq. 3.43a
    d_T = np.zeros(state.n_pairs)
    slip, free = state.state == SLIP, state.state == FREE
    d_T[slip] = slip_force(state.lam_N[slip], state.lam_T[slip], mu) - state.lam_T[slip]
    d_T[free] = -state.lam_T[free]  # eq. 3.43b
    return np.column_stack([d_N, d_T]).ravel()


def constraint_targets(C: sp.spmatrix, u: np.ndarray, state: GapState) -> np.ndarray:
    """Right-hand sides (2n,) target - C u of the rows (normal target hold_N, zero where None;
    tangential stick_T)."""
    gap_N, gap_T = relative_displacement(C, u)
    normal = -gap_N if state.hold_N is None else state.hold_N - gap_N
    return np.column_stack([normal, state.stick_T - gap_T]).ravel()


def implicit_slip_rows(state: GapState) -> np.ndarray:
    """(2n,) bool: the tangential rows of SLIP pairs (unknown multipliers when implicit)."""
    return np.column_stack([np.zeros(state.n_pairs, bool), state.state == SLIP]).ravel()


def augmented_matrix(K: sp.spmatrix, C: sp.spmatrix, state: GapState,
                     fixed_equations: np.ndarray | None = None, mu: float = 0.0,
                     implicit_slip: bool = False) -> sp.csc_matrix:
    """A (n_eq + 2n square) for the current pair states; supports as identity rows.

    Symmetric with the thesis' lagged friction. With `implicit_slip` the tangential row of a
    SLIP pair is the Coulomb condition itself, dlam_T + s mu dlam_N = -(lam_T + s mu lam_N)
    with s = sign(lam_T) (so lam_T = s mu |lam_N| with lam_N < 0 holds at once instead of
    lagging one iteration behind lam_N); A is then unsymmetric.

    [[K_r, C_u^T], [C_a, D]] in canonical CSC without stored zeros (AugmentedPattern: the
    solver keeps the pattern for the whole run and only writes values into it).
    """
    K = canonical_csr(K)
    return AugmentedPattern(K, C, fixed_equations).matrix(
        K, active_rows(state), upper_rows(state, implicit_slip), state, mu, implicit_slip)


def upper_rows(state: GapState, implicit_slip: bool = False) -> np.ndarray:
    """(2n,) bool: the rows whose C^T stands beside K (active ones, and implicit-slip rows)."""
    active = active_rows(state)
    return active | implicit_slip_rows(state) if implicit_slip else active


def augmented_rhs(r_u: np.ndarray, u: np.ndarray, C: sp.spmatrix, state: GapState, mu: float,
                  fixed_equations: np.ndarray | None = None,
                  implicit_slip: bool = False) -> np.ndarray:
    """Unbalanced right-hand side (n_eq + 2n,) incl. the gap "loads" (the displacement-control
    II vector). r_u = F_ext - F_int of the structure WITHOUT the gap forces (C^T lam is
    subtracted here). Its norm, with r_u the full residual, measures convergence: it is zero
    when equilibrium, the FIXED/SLIP targets and the prescribed multipliers all hold.
    """
    C = sp.csr_matrix(C)
    active = active_rows(state)
    d_lam_p = prescribed_increments(state, mu)
    if implicit_slip:
        slip_T = implicit_slip_rows(state)
        d_lam_p[slip_T] = 0.0  # unknown, not prescribed
    top = np.asarray(r_u, dtype=float) - C.T @ (state.lam + d_lam_p)  # Table 3.1 "load" column
    top[fixed_mask(fixed_equations, C.shape[1])] = 0.0
    bottom = np.where(active, constraint_targets(C, u, state), d_lam_p)
    if implicit_slip:
        slip = state.state == SLIP
        coulomb = -(state.lam_T + np.sign(state.lam_T) * mu * state.lam_N)
        bottom[slip_T] = coulomb[slip]
    return np.concatenate([top, bottom])


def reference_rhs(R: np.ndarray, n_pairs: int, fixed_equations: np.ndarray | None = None
                  ) -> np.ndarray:
    """Reference-load right-hand side [R*; 0] (errata §3: R* is zero in the multiplier rows)."""
    top = np.array(R, dtype=float)
    top[fixed_mask(fixed_equations, top.size)] = 0.0
    return np.concatenate([top, np.zeros(2 * n_pairs)])


def split_solution(x: np.ndarray, n_eq: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(du (n_eq, ...), dlam_N (n, ...), dlam_T (n, ...)) of a solution (n_eq + 2n, ...)."""
    x = np.asarray(x)
    return x[:n_eq], x[n_eq::2], x[n_eq + 1::2]


def interface_forces(C: sp.spmatrix, state: GapState) -> np.ndarray:
    """C^T lam (n_eq,): gap forces on the nodes, on the internal-force side of the residual."""
    return sp.csr_matrix(C).T @ state.lam


class AugmentedFactor:
    """LU factors of an augmented matrix; `solve` takes one (m,) or several (m, k) RHS."""

    def __init__(self, A: sp.csc_matrix, lu: SparseLU) -> None:
        self.A, self.lu = A, lu

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        b = np.asarray(rhs, dtype=float)
        x = self.lu.solve(b)
        error = self.lu.backward_error(b, x)
        if not error <= REFINE_RTOL:  # (NaN refines too)
            x = x + self.lu.solve(b - self.A @ x)  # one step of iterative refinement
            error = self.lu.backward_error(b, x)
        if not error <= RESIDUAL_RTOL:  # the check of SparseLU.accurate, on |A x - b|
            raise ConvergenceError("augmented interface system is singular: inaccurate or "
                                   f"non-finite solution; {SINGULAR_HINT}",
                                   reason="singular system")
        return x


def column_max_abs(A: sp.csc_matrix) -> np.ndarray:
    """max_i |A_ij| per column j (zero for an empty column)."""
    counts = np.diff(A.indptr)
    if A.nnz == 0:
        return np.zeros(A.shape[1])
    starts = np.minimum(A.indptr[:-1], A.nnz - 1)
    return np.where(counts > 0, np.maximum.reduceat(np.abs(A.data), starts), 0.0)


def pivot_scales(A: sp.csc_matrix) -> np.ndarray:
    """The size (n,) of each equation's pivot, for a symmetric diagonal scaling: |A_jj|, and
    for a row without a diagonal (an active pair row) sum_i |A_ij A_ji| / |A_ii| over its
    neighbours, its Schur complement -C K^-1 C^T where K is diagonal (the largest entry of
    its column where no neighbour has a diagonal)."""
    magnitude = abs(A)
    diagonal = magnitude.diagonal()
    products = sp.csc_matrix(magnitude.multiply(magnitude.T))
    products.setdiag(0.0)
    products.eliminate_zeros()
    inverse = np.divide(1.0, diagonal, out=np.zeros_like(diagonal), where=diagonal > 0.0)
    columns = np.repeat(np.arange(A.shape[1]), np.diff(products.indptr))
    schur = np.bincount(columns, products.data * inverse[products.indices],
                        minlength=A.shape[1])
    return np.where(diagonal > 0.0, diagonal, np.where(schur > 0.0, schur, column_max_abs(A)))


class EquilibratedLU(SparseLU):
    """The factors of S A S with S = diag(pivot_scales(A))^-1/2, solving A x = b as
    x = S (S A S)^-1 S b; `A` stays the matrix whose residual the caller checks."""

    def __init__(self, A: sp.csc_matrix, backend: str | None) -> None:
        super().__init__(A)
        size = pivot_scales(A)
        self.scale = 1.0 / np.sqrt(np.where(size > 0.0, size, 1.0))
        scaling = sp.diags(self.scale)
        scaled = sp.csc_matrix(scaling @ A @ scaling)
        self.inner = sparse_factorize(scaled, backend, pivot_scale=column_max_abs(scaled),
                                      pivot_rtol=PIVOT_RTOL)
        self.backend = self.inner.backend

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        b = np.asarray(rhs, dtype=float)
        scale = self.scale if b.ndim == 1 else self.scale[:, None]
        return scale * self.inner.solve(scale * b)


def factorize(A: sp.spmatrix, backend: str | None = None, check_pivots: bool = True
              ) -> AugmentedFactor:
    """LU of the augmented matrix (icewall.sparse; SuperLU unless chosen otherwise);
    ConvergenceError(reason="singular system") when singular. `check_pivots`: compare SuperLU's
    pivots with the largest entries of their columns (extracting U costs about a tenth of the
    factorisation).

    A pivot that test calls small is tested again on the equilibrated matrix (EquilibratedLU),
    and that factorisation is used where it passes. The column's largest entry is no scale
    for a pair row's pivot, -C K^-1 C^T, about |C|^2 / K_ii, nor after the row exchanges that
    its zero diagonal forces: with a dynamic drop's mass term M / (beta dt^2) in K (CF-4: 1e12
    to 1e14 N/mm at dt = 6e-9 s) 50 healthy pivots fell below 1e-12 of it, and the run ended
    on a "singular" system. A matrix without such pivots factorises as before, to the bit."""
    A = sp.csc_matrix(A)
    A.sum_duplicates()
    try:
        try:
            lu = sparse_factorize(A, backend,
                                  pivot_scale=column_max_abs(A) if check_pivots else None,
                                  pivot_rtol=PIVOT_RTOL)
        except SingularMatrixError as exc:
            if not exc.columns.size:  # exactly singular (SuperLU), or another backend
                raise
            lu = EquilibratedLU(A, backend)
    except SingularMatrixError as exc:
        if exc.columns.size:
            where = np.sort(exc.columns)[:10].tolist()
            raise ConvergenceError(f"augmented interface system is singular ({exc.columns.size}"
                                   f" near-zero pivot(s) near unknown(s) {where}; displacement "
                                   f"equations come first, node = eq // 2 without ties); "
                                   f"{SINGULAR_HINT}", reason="singular system") from exc
        raise ConvergenceError(f"augmented interface system is singular ({exc}); "
                               f"{SINGULAR_HINT}", reason="singular system") from exc
    return AugmentedFactor(A, lu)
