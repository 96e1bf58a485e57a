"""The stability of an equilibrium with the stroke held (solve/stability.py) against closed
forms: the sign of a determinant from the sparse LU against a dense one, and the softening
bar, whose held tangent (springs in series, both ends held) has det = prod k_i sum 1/k_i: with
the weak element on its softening branch (k_w < 0) the bar is unstable where the softening is
steeper than the rest of the bar is stiff, |k_w| > k / (n - 1), the snap-back of
test_newton.py, and stable where it is gentler."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import scipy.sparse as sp
from test_newton import newton_bar, newton_settings

from icewall.errors import ConvergenceError
from icewall.solve.controls import StrokeControl
from icewall.solve.path import follow_path
from icewall.solve.stability import (
    _parity,
    determinant_sign,
    fastest_growth,
    held_tangent,
    stable_under_stroke,
)


@pytest.mark.parametrize("n", [1, 7, 60, 300])
def test_determinant_sign_equals_the_dense_one(n):
    rng = np.random.default_rng(n)
    for _ in range(10):
        A = rng.standard_normal((n, n)) * (rng.random((n, n)) < 0.1) + np.diag(
            rng.standard_normal(n) * 3.0)
        assert determinant_sign(sp.csr_matrix(A)) == np.linalg.slogdet(A)[0]
        p = rng.permutation(n)
        assert _parity(p) == round(np.linalg.det(np.eye(n)[p]))
    assert determinant_sign(sp.csr_matrix((n + 1, n + 1))) == 0  # singular


def _stability_along(problem, steps):
    weights = StrokeControl.of_load(problem.constraints.restrict(problem.reference_load)).weights
    return [stable_under_stroke(problem, inc.evaluation, weights) for inc in steps]


def test_a_gently_softening_bar_stays_stable_past_its_peak():
    # 10 elements of 10 mm, eps_f 0.002: |k_w| = f / (eps_f - eps0) h < k / 9, the load falls
    # under the held end without a snap-back, and every state is stable
    problem, initial = newton_bar(100.0, 10, failure_strain=0.002)
    steps = [inc for inc, _ in follow_path(problem, newton_settings(0.019, 0.001), initial)]
    P = np.array([inc.load_factor for inc in steps])
    assert 0 < int(np.argmax(P)) < len(P) - 3  # well past the peak
    assert all(_stability_along(problem, steps))


def test_a_bar_that_snaps_back_is_unstable_on_its_descending_branch():
    # the snap-back bar: every state before the peak is stable, every state the dissipation
    # control traces down the snap-back (the weak element loading on its softening branch,
    # the others unloading, down to the separated bar) is unstable with the end held
    problem, initial = newton_bar(1000.0, 10, failure_strain=0.0003)
    steps = []
    with pytest.raises(ConvergenceError):  # the bar separates
        for inc, _ in follow_path(problem, newton_settings(0.5, 0.02, cuts=3), initial):
            steps.append(inc)
    P = np.array([inc.load_factor for inc in steps])
    at_peak = np.flatnonzero(P >= P.max() * (1 - 1e-9))  # the located limit point's states
    stable = _stability_along(problem, steps)
    assert at_peak[0] > 2 and all(stable[:at_peak[0]])
    descending = stable[at_peak[-1] + 1:]
    assert len(descending) > 3 and not any(descending)


def _descending_massive_bar():
    """The snap-back bar with its mass at a state of its descending branch (traced
    statically), its first-mode frequency and the stroke's weights."""
    from test_dynamic_drop import massive_bar

    from icewall.solve.integrator import first_mode_frequency

    problem, initial = massive_bar(residual=False)
    steps = []
    with pytest.raises(ConvergenceError):
        for inc, _ in follow_path(replace(problem, mass=None),  # traced statically
                                  newton_settings(0.5, 0.02, cuts=3), initial):
            steps.append(inc)
    R = problem.constraints.restrict(problem.reference_load)
    omega = first_mode_frequency(steps[0].u, steps[0].load_factor, R, problem.mass)
    weights = StrokeControl.of_load(R).weights
    P = np.array([inc.load_factor for inc in steps])
    descending = steps[int(np.flatnonzero(P >= P.max() * (1 - 1e-9))[-1]) + 2]
    assert descending.load_factor < 0.9 * P.max()
    return problem, descending.evaluation, omega, weights


def test_modes_that_grow_slower_than_the_margin_do_not_count():
    # the snap-back bar with its mass, on its descending branch: unstable without the margin
    # and at its own first-mode frequency (the snap-back is fast), stable only once the
    # margin's (0.01 omega)^2 M outweighs the softening (an absurd omega: the units and the
    # direction of the shift)
    problem, ev, omega, weights = _descending_massive_bar()
    assert not stable_under_stroke(problem, ev, weights)
    assert not stable_under_stroke(problem, ev, weights, omega)
    assert stable_under_stroke(problem, ev, weights, 1e6 * omega)


def test_the_fastest_growth_rate_bounds_the_dense_one_within_a_factor_two():
    # on the descending branch of the snap-back bar one mode of M u'' + K u = 0 grows: its
    # rate sqrt(-lambda), lambda the negative eigenvalue of the dense pencil (K, M), lies in
    # the scan's last cell [rate / 2, rate]; a stable state has none, and a bound below the
    # rate answers the bound (no time step above its inverse resolves the growth)
    import scipy.linalg

    problem, ev, omega, weights = _descending_massive_bar()
    A, mass = held_tangent(problem, ev, weights)
    eigenvalues = scipy.linalg.eigh(A.toarray(), np.diag(mass), eigvals_only=True)
    assert np.count_nonzero(eigenvalues < 0.0) == 1
    exact = float(np.sqrt(-eigenvalues.min()))
    rate = fastest_growth(problem, ev, weights, omega, 1e6 * omega)
    assert 0.5 * rate <= exact <= rate
    assert fastest_growth(problem, ev, weights, omega, 0.5 * exact) == 0.5 * exact
    from test_dynamic_drop import massive_bar

    elastic = follow_path(problem, newton_settings(0.001, 0.001), massive_bar(False)[1])
    assert fastest_growth(problem, next(elastic)[0].evaluation, weights, omega,
                          1e6 * omega) == 0.0


def _two_sliding_blocks(link: float, slips: tuple[float, float]):
    """Two blocks on a frictional floor, each held by a ground spring k_g = 1 and joined by a
    link of stiffness `link` (negative: a softening strut), both slipping (SLIP, lam_T of the
    signs `slips`: the sense each slides in), with unit masses; a fifth, separate equation
    stands for the stroke. Equations x1, y1, x2, y2, s; pair i: normal row y_i, tangential
    row x_i. Returns (problem, weights)."""
    from types import SimpleNamespace

    from icewall.interface.gap import SLIP, GapState

    K = np.zeros((5, 5))
    K[np.ix_([0, 2], [0, 2])] = np.eye(2) + link * np.array([[1.0, -1.0], [-1.0, 1.0]])
    K[1, 1] = K[3, 3] = K[4, 4] = 1.0
    C = sp.csr_matrix((np.ones(4), ([0, 1, 2, 3], [1, 0, 3, 2])), shape=(4, 5))
    state = GapState.initial(2)
    state = replace(state, state=np.full(2, SLIP, dtype=np.int8),
                    lam_N=np.array([-10.0, -10.0]), lam_T=np.array(slips))
    structure = SimpleNamespace(stiffness=lambda evaluation: sp.csr_matrix(K),
                                with_tangent=lambda evaluation: evaluation)
    constraints = SimpleNamespace(C=C, state=state, fixed=np.array([], dtype=int))
    problem = SimpleNamespace(structure=structure, constraints=constraints, mass=np.ones(5))
    return problem, np.array([0.0, 0.0, 0.0, 0.0, 1.0])


@pytest.mark.parametrize("link", [-0.2, -0.45, -0.55, -0.8, -0.95, -1.05, -1.5])
def test_a_mode_that_reverses_a_slip_in_either_sense_is_arrested(link):
    # the held tangent's x block [[1 + k, -k], [-k, 1 + k]] has the eigenvalues 1 (blocks
    # together) and 1 + 2k (apart), so with both pairs free to slip the blocks are unstable
    # past k = -1/2. Sliding the same way, the mode apart reverses one block's slip in either
    # sense, and a reversed slip sticks: the other block alone on 1 + k, stable up to
    # k = -1. Sliding apart, the mode continues both slips in one sense: unstable past -1/2.
    from icewall.solve.stability import held_sign, stability_sign

    omega = 1e-3  # the growth margin (1e-5)^2 M is negligible against the stiffnesses
    same, _ = _two_sliding_blocks(link, (1.0, 1.0))
    apart, weights = _two_sliding_blocks(link, (1.0, -1.0))
    assert (held_sign(same, None, weights, omega) > 0) == (1.0 + 2.0 * link > 0.0)
    assert (stability_sign(same, None, weights, omega) > 0) == (1.0 + link > 0.0)
    assert (stability_sign(apart, None, weights, omega) > 0) == (1.0 + 2.0 * link > 0.0)
