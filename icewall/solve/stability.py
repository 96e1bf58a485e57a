"""Whether a converged equilibrium is stable with the loading system's stroke held.

A stroke-controlled test holds its stroke; the wall stays in an equilibrium only where that
equilibrium is stable, and elsewhere it moves, with its own mass, to one that is. A static
Newton iteration converges to unstable equilibria as readily as to stable ones (on CF-4 it
climbs past its first maximum along states whose held tangent has a negative eigenvalue:
docs/solver.md, item 38), so the path following asks this after every static step and takes
the drop where the answer is no (`mode.Mode`; issue 36's rule: a drop begins where "the held
tangent loses positive definiteness").

The test is the divergence criterion of M u'' + K_t u = 0 on the held subspace: K_t the
consistent tangent of the converged state (each point on the branch its last increment took),
restricted to the motions the supports, the held interface pairs (their active rows: closed
normals, stuck tangents; a slipping pair's tangent is free) and the held stroke allow. Its
determinant is positive in the elastic state; a negative one means an odd number of real
eigenvalues have crossed zero, i.e. a mode along which the wall accelerates away (Bazant &
Cedolin 1991, ch. 10; a pair crossing together or a flutter pair is not seen). The restriction
is a penalty, K_t + a B^T B with B the held rows and a = PENALTY times the largest diagonal of
K_t: for a large enough a, det has the sign of det(Z^T K_t Z) on the null space Z of B
(Finsler's lemma; on CF-4 the smallest eigenvalues agree to three digits between a = 1e4 and
1e7). The sign comes from one sparse LU: the signs of U's diagonal and the parities of the two
permutations.

A slipping pair's tangent is free in K_t: its stiffness while the slip goes on. Along a motion
that reverses the slip the pair sticks (Table 3.2 with the reversal rule of
`interface.gap.update_states`), so the wall's stiffness depends on the sense of the motion, and
a mode of the held tangent that reverses a slipping pair in either sense is no mode of the
wall (the linear comparison solid of Hill 1958 is the softest of its branches; Bazant &
Cedolin 1991, ch. 10). `stability_sign` therefore tests a negative determinant once more in
each sense of the fastest unstable mode, with the pairs that sense reverses held: the
equilibrium is unstable only where one sense stays unstable. (CF-4 from its first maximum to
8.6 mm: 33 of 41 such states, growing at 0.3-2.6 omega_1, are held in both senses, and 9 of
the 13 drops taken there raised the load; docs/solver.md item 52.) The sense of each
pair's slip and of the mode enter only as a product, so the verdict does not depend on either
sign convention. The concrete's unloading along the mode (also stiffer) is not looked at: the
test errs on the side of a drop.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.sparse.csgraph import connected_components

from icewall.interface.augmented import active_rows
from icewall.interface.gap import SLIP
from icewall.solve.controls import StrokeControl
from icewall.solve.problem import Problem
from icewall.solve.state import Increment, StepFailed

PENALTY = 1e4
"""The penalty on the held rows, as a multiple of the largest diagonal of the tangent."""
SLOWEST_GROWTH = 0.01
"""Modes that grow slower than this fraction of the first mode's circular frequency omega_1
do not count as an instability: det(K_t + (SLOWEST_GROWTH omega_1)^2 M) is tested, whose
eigenvalues omega^2 + (SLOWEST_GROWTH omega_1)^2 are negative only for a mode that grows as
exp(s t) with s above it (an e-folding time of 16 first periods). A mode growing slower
creeps while the stroke moves on (with the damping, slower still); a drop waiting for it to
leave a marginal state would not end."""
FASTEST_MODE = 1e4
"""The slips a mode reverses are read from the unstable mode that grows fastest, up to this
multiple of omega_1."""
REVERSAL_RESOLUTION = 1e-6
"""A mode moves a pair where the pair's tangential motion exceeds this fraction of the largest
relative motion of the mode's pairs (below it, the mode's digits, not its shape)."""
INVERSE_ITERATIONS = 30
"""Inverse iterations for an unstable mode (`unstable_mode`): the imperfection a drop seeds
needs the mode's direction, not its digits."""


def _parity(permutation: np.ndarray) -> int:
    """+1 for an even permutation, -1 for an odd one: (-1) ** (n - its number of cycles), the
    cycles being the connected components of the graph i -> permutation[i]."""
    n = permutation.size
    graph = sp.csr_matrix((np.ones(n), (np.arange(n), permutation)), shape=(n, n))
    cycles = connected_components(graph, directed=True, connection="weak")[0]
    return 1 if (n - cycles) % 2 == 0 else -1


def determinant_sign(A: sp.spmatrix) -> int:
    """The sign of det A (0 where the LU finds it exactly singular)."""
    try:
        lu = spla.splu(sp.csc_matrix(A), permc_spec="COLAMD")
    except RuntimeError:  # exactly singular
        return 0
    diagonal = lu.U.diagonal()
    if np.any(diagonal == 0.0):
        return 0
    negative = int(np.count_nonzero(diagonal < 0.0))
    return (-1) ** negative * _parity(lu.perm_r) * _parity(lu.perm_c)


def held_rows(problem: Problem, weights: np.ndarray, stuck: np.ndarray | None = None
              ) -> sp.csr_matrix:
    """B: the stroke's row (`weights`, normalised) over the held interface pairs' rows (and
    the tangential rows of the pairs `stuck`, (n_pairs,) bool)."""
    rows = [sp.csr_matrix(weights / max(float(np.linalg.norm(weights)), 1e-300))]
    C = getattr(problem.constraints, "C", None)
    if C is not None:
        held = active_rows(problem.constraints.state)
        if stuck is not None:
            held = held.copy()
            held[1::2] |= stuck
        rows.append(sp.csr_matrix(C)[held])
    return sp.vstack(rows, format="csr")


def free_equations(problem: Problem, n: int) -> np.ndarray:
    """The mask of the n equations the supports leave free (the held tangent's rows)."""
    free = np.ones(n, dtype=bool)
    free[problem.constraints.fixed] = False
    return free


def held_tangent(problem: Problem, evaluation, weights: np.ndarray,
                 stuck: np.ndarray | None = None) -> tuple[sp.csr_matrix, np.ndarray | None]:
    """K_t + a B^T B on the free equations (B: `held_rows`), and the lumped masses there
    (None without)."""
    s = problem.structure
    K = s.stiffness(s.with_tangent(evaluation)).tocsr()
    scale = float(np.abs(K.diagonal()).max())
    B = held_rows(problem, weights, stuck)
    A = (K + (PENALTY * scale) * (B.T @ B)).tocsr()
    free = free_equations(problem, A.shape[0])
    mass = None if problem.mass is None else problem.mass[free]
    return A[free][:, free], mass


def held_sign(problem: Problem, evaluation, weights: np.ndarray, omega: float = 0.0,
              stuck: np.ndarray | None = None) -> int:
    """The sign of det(K_t + a B^T B + (SLOWEST_GROWTH omega)^2 M) on the free equations at
    the equilibrium of `evaluation` (converged, at the constraints' current pair states, the
    pairs `stuck` held too), the stroke `weights . u` held (`omega`: the first mode's circular
    frequency, rad/s; 0 or without masses: det(K_t + a B^T B))."""
    A, mass = held_tangent(problem, evaluation, weights, stuck)
    if mass is not None and omega > 0.0:  # N/mm: (1/s^2) (t) = N/mm
        A = A + sp.diags((SLOWEST_GROWTH * omega) ** 2 * mass)
    return determinant_sign(A)


def stability_sign(problem: Problem, evaluation, weights: np.ndarray,
                   omega: float = 0.0) -> int:
    """`held_sign`, or +1 where it is not positive but each sense of the fastest unstable
    mode reverses a slipping pair and the held tangent with those pairs stuck is positive
    definite in both (`reversed_slips`): a mode the pairs' friction arrests either way."""
    sign = held_sign(problem, evaluation, weights, omega)
    if sign > 0:
        return sign
    senses = reversed_slips(problem, evaluation, weights, omega)
    if senses is None or not all(stuck.any() for stuck in senses):
        return sign
    if all(held_sign(problem, evaluation, weights, omega, stuck) > 0 for stuck in senses):
        return 1
    return sign


def reversed_slips(problem: Problem, evaluation, weights: np.ndarray, omega: float
                   ) -> tuple[np.ndarray, np.ndarray] | None:
    """The slipping pairs (n_pairs,) bool whose slip the fastest unstable mode of the held
    tangent (`fastest_growth`, `unstable_mode`) reverses, in the mode's sense and in the
    other: a slip reverses where the pair's tangential motion opposes its lam_T (the slip's
    sense, lam_T dDelta_T > 0 while it slips). None without slipping pairs, masses or omega."""
    state = getattr(problem.constraints, "state", None)
    if state is None or problem.mass is None or not omega > 0.0:
        return None
    slipping = state.state == SLIP
    if not slipping.any():
        return None
    rate = fastest_growth(problem, evaluation, weights, omega, FASTEST_MODE * omega)
    if rate == 0.0:
        return None
    mode = unstable_mode(problem, evaluation, weights, rate)
    motion = sp.csr_matrix(problem.constraints.C) @ mode
    tangential = motion[1::2]
    moved = np.abs(tangential) > REVERSAL_RESOLUTION * float(np.abs(motion).max())
    along = tangential * state.lam_T
    return slipping & moved & (along < 0.0), slipping & moved & (along > 0.0)


def stable_under_stroke(problem: Problem, evaluation, weights: np.ndarray,
                        omega: float = 0.0) -> bool:
    """Whether that equilibrium is stable with the stroke held: `stability_sign` positive."""
    return stability_sign(problem, evaluation, weights, omega) > 0


def fastest_growth(problem: Problem, evaluation, weights: np.ndarray, omega: float,
                   fastest: float) -> float:
    """The growth rate s (1/s) of the fastest unstable mode of M u'' + K_t u = 0 with the
    stroke held, to a factor 2 from above: the signs of det(K_t + a B^T B + sigma M) on
    sigma = (SLOWEST_GROWTH omega)^2 4^k, the largest sigma below which the sign changes (an
    odd number of eigenvalues -s^2 in between). 0 where the state is stable; `fastest` where
    the sign is still negative there (a growth no time step above 1 / fastest resolves)."""
    A, mass = held_tangent(problem, evaluation, weights)
    M = sp.diags(mass)
    rate, top = SLOWEST_GROWTH * omega, 0.0
    sign = determinant_sign(A + rate ** 2 * M)
    while rate < fastest:
        rate *= 2.0
        next_sign = determinant_sign(A + rate ** 2 * M)
        if next_sign != sign:
            top = rate
        sign = next_sign
    return fastest if sign <= 0 else top


def unstable_mode(problem: Problem, evaluation, weights: np.ndarray, rate: float,
                  iterations: int = INVERSE_ITERATIONS) -> np.ndarray:
    """The mode of M u'' + K_t u = 0 (the stroke held) that grows at about `rate` (1/s, from
    `fastest_growth`: the real eigenvalue -s^2 with s in [rate / 2, rate]; rate 0: the
    eigenvalue nearest zero), by inverse iteration on (K_t + a B^T B + (3 rate / 4)^2 M)^-1 M
    from a uniform start; M-normalised, on all equations (zero on the fixed ones)."""
    A, mass = held_tangent(problem, evaluation, weights)
    lu = spla.splu(sp.csc_matrix(A + sp.diags((0.75 * rate) ** 2 * mass)),
                   permc_spec="COLAMD")
    x = np.ones(A.shape[0])
    for _ in range(iterations):
        x = lu.solve(mass * x)
        x /= math.sqrt(float(x @ (mass * x)))
    mode = np.zeros(problem.mass.shape[0])
    mode[free_equations(problem, mode.size)] = x
    return mode


def require_stable(problem: Problem, inc: Increment, reference: np.ndarray,
                   omega: float, held: int = 1) -> int:
    """The sign of the converged step's `stability_sign` (`reference`: the jack loads, `omega`:
    omega_1 or NaN before it is known); StepFailed ("unstable") where the equilibrium has lost
    the stability of the last stable state, whose sign was `held`: negative where that was
    positive. The test would not stay there; the step is then cut like a failed one, and at
    the smallest step the drop is taken from the last stable state (issue 36, item 3;
    `mode.Mode.after_failure`). `held` is negative after a drop that came to rest on a state
    the determinant calls unstable and the motion showed stable (`solve.imperfection`): the
    determinant of one branch of the laws, which the motion does not take. Until it turns
    positive again, a negative determinant is that state's, and the test sees no instability
    (one that adds a negative eigenvalue turns it positive: a parity test sees no more)."""
    weights = StrokeControl.of_load(reference).weights
    sign = stability_sign(problem, inc.evaluation, weights, 0.0 if math.isnan(omega) else omega)
    if sign <= 0 and held > 0:
        raise StepFailed("the equilibrium reached is unstable with the stroke held (the held "
                         "tangent's determinant is not positive)", "unstable")
    return 1 if sign > 0 else -1
