"""The fixed augmented pattern (icewall.interface.pattern) against the augmented matrix of
eq. 3.35 written out densely, entry by entry, for many pair states on one pattern."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from icewall.interface import FIXED, FREE, SLIP, GapState, augmented_matrix
from icewall.interface.augmented import active_rows, upper_rows
from icewall.interface.pattern import AugmentedPattern

N_EQ, N_PAIRS, MU = 14, 4, 0.5


def _problem(seed: int):
    rng = np.random.default_rng(seed)
    band = sp.random(N_EQ, N_EQ, density=0.3, random_state=seed)
    K = sp.csr_matrix(band + band.T + 10.0 * sp.eye(N_EQ))
    K.sum_duplicates()
    C = sp.csr_matrix(rng.choice([0.0, 0.6, -0.8, 1.0], size=(2 * N_PAIRS, N_EQ),
                                 p=[0.8, 0.08, 0.06, 0.06]))
    fixed = np.array([0, 5])
    return rng, K, C, fixed


def _states(rng, count: int):
    for _ in range(count):
        state = rng.choice([FIXED, SLIP, FREE], size=N_PAIRS).astype(np.int8)
        s = GapState.initial(N_PAIRS)
        yield GapState(state, -rng.random(N_PAIRS), rng.normal(size=N_PAIRS), s.gap_N,
                       s.gap_T, s.stick_T, s.permanent)


def _dense(K, C, fixed, state, implicit_slip, k=0.0, pad=None):
    """[[K_r, C_u^T], [C_a, D]] entry by entry (the docstring of augmented_matrix)."""
    Kd = K.toarray() + k * (C.T @ C).toarray()
    Kd[fixed, :], Kd[:, fixed] = 0.0, 0.0
    Kd[fixed, fixed] = 1.0
    Cd = C.toarray()
    Cd[:, fixed] = 0.0
    m = N_EQ + 2 * N_PAIRS
    A = np.zeros((m, m))
    A[:N_EQ, :N_EQ] = Kd
    active, upper = active_rows(state), upper_rows(state, implicit_slip)
    for r in range(2 * N_PAIRS):
        if active[r]:
            A[N_EQ + r, :N_EQ] = Cd[r]
        else:
            A[N_EQ + r, N_EQ + r] = 1.0
        if upper[r]:
            A[:N_EQ, N_EQ + r] = Cd[r]
    if pad is not None:
        A[N_EQ:, N_EQ:] += np.diag(pad)
    if implicit_slip:
        for i in np.flatnonzero(state.state == SLIP):
            A[N_EQ + 2 * i + 1, N_EQ + 2 * i] = np.sign(state.lam_T[i]) * MU
    return A


@pytest.mark.parametrize("implicit_slip", [False, True])
def test_one_pattern_gives_the_augmented_matrix_of_every_pair_state(implicit_slip):
    rng, K, C, fixed = _problem(3)
    pattern = AugmentedPattern(K, C, fixed, C.T @ C)
    for state in _states(rng, 12):
        K_now = K.copy()
        K_now.data = K.data * rng.uniform(0.5, 2.0, K.nnz)  # new values, same pattern
        pad = rng.choice([0.0, 1.0], size=2 * N_PAIRS) * active_rows(state)
        A = pattern.matrix(K_now, active_rows(state), upper_rows(state, implicit_slip), state,
                           MU, implicit_slip, stabilisation_factor=0.3, diagonal_pad=pad)
        np.testing.assert_array_equal(A.toarray(), _dense(K_now, C, fixed, state,
                                                          implicit_slip, 0.3, pad))
        assert A.has_canonical_format and np.all(A.data != 0.0)  # no stored zeros
        reference = augmented_matrix(K_now, C, state, fixed, MU, implicit_slip)
        np.testing.assert_array_equal(reference.toarray(),
                                      _dense(K_now, C, fixed, state, implicit_slip))


def test_pattern_fits_only_its_own_stiffness_pattern():
    _, K, C, fixed = _problem(4)
    pattern = AugmentedPattern(K, C, fixed)
    same = K.copy()
    same.data *= 3.0
    assert pattern.fits(same)
    i, j = np.argwhere(K.toarray() == 0.0)[0]
    other = sp.csr_matrix(K + sp.csr_matrix(([1.0], ([i], [j])), shape=K.shape))
    assert not pattern.fits(other) and not pattern.fits(K.tocsc())
