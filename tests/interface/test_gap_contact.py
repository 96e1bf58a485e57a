"""Contact verification with closed-form answers: stick, Coulomb slip, separation, re-contact,
displacement control with two right-hand sides, and floating cores (§4.3.2 fixed points)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from icewall.errors import ConvergenceError
from icewall.interface import (
    FIXED,
    FREE,
    SLIP,
    GapState,
    augmented_matrix,
    augmented_rhs,
    choose_fixed_points,
    constraint_matrix,
    count_states,
    factorize,
    friction_work_increment,
    new_step,
    reference_rhs,
    relative_displacement,
    split_solution,
    update_states,
)
from icewall.interface.augmented import (
    PIVOT_RTOL,
    EquilibratedLU,
    column_max_abs,
    pivot_scales,
)
from icewall.sparse import superlu_options

MU, N = 0.5, 1000.0


# --- one inclined pair: steel node fixed, concrete node on springs k -----------------------

def test_single_inclined_pair_closed_form(driver):
    phi, k = np.deg2rad(30.0), 100.0
    n, t = np.array([np.cos(phi), np.sin(phi)]), np.array([-np.sin(phi), np.cos(phi)])
    C = constraint_matrix(np.array([[0, 1]]), n[None], np.arange(4).reshape(2, 2), 4)
    K = sp.diags([0.0, 0.0, k, k]).tocsr()
    fixed = np.array([0, 1])
    gaps, u = GapState.initial(1), np.zeros(4)

    def level(f_n, f_t):
        nonlocal gaps, u
        gaps = new_step(gaps)
        F = np.r_[0.0, 0.0, f_n * n + f_t * t]
        u, gaps, _, _ = driver.solve_load_level(K, F, C, gaps, MU, fixed, u)
        return gaps

    g = level(-10.0, 4.9)  # stick: lam = (F.n, F.t), no relative motion
    assert g.state[0] == FIXED and np.allclose(u, 0.0, atol=1e-14)
    assert (g.lam_N[0], g.lam_T[0]) == pytest.approx((-10.0, 4.9), rel=1e-12)
    for sign in (1.0, -1.0):  # slip both ways: lam_T = sign mu |lam_N|, s = (f_t - lam_T) / k
        g = level(-10.0, 6.0 * sign)
        assert g.state[0] == SLIP
        assert g.lam_T[0] == pytest.approx(sign * MU * 10.0, rel=1e-12)
        assert g.gap_T[0] == pytest.approx(sign * 1.0 / k, rel=1e-12)
        assert abs(g.gap_N[0]) < 1e-14
    g = level(5.0, 2.0)  # tension: free, zero forces, u2 = F / k
    assert g.state[0] == FREE and g.lam_N[0] == 0.0 and g.lam_T[0] == 0.0
    assert g.gap_N[0] == pytest.approx(5.0 / k, rel=1e-12)
    g = level(-10.0, 1.0)  # re-contact: closed, compressed, held at the Delta_T of closure
    assert g.state[0] == FIXED and abs(g.gap_N[0]) < 1e-12
    assert g.lam_N[0] == pytest.approx(-10.0, rel=1e-12)
    np.testing.assert_allclose(k * u[2:] + g.lam_N[0] * n + g.lam_T[0] * t,
                               -10.0 * n + t, atol=1e-11)


# --- block pressed on a plate, then pushed sideways (load control) -------------------------

def test_block_sticks_below_mu_n_and_slips_at_mu_n(driver):
    m = driver.model(springs_x=50.0)
    gaps, u = GapState.initial(len(m.pairs)), np.zeros(m.n_eq)
    u, gaps, _, _ = driver.solve_load_level(m.K, m.load(0.0, -N), m.C, gaps, MU, m.fixed, u)
    assert count_states(gaps)["fixed"] == len(m.pairs)
    assert gaps.lam_N.sum() == pytest.approx(-N, rel=1e-12) and np.all(gaps.lam_N < 0)
    for ratio in (0.2, 0.7):  # stick: no relative tangential displacement anywhere
        gaps = new_step(gaps)
        u, gaps, _, _ = driver.solve_load_level(m.K, m.load(ratio * MU * N, -N), m.C, gaps, MU,
                                                m.fixed, u)
        assert count_states(gaps)["fixed"] == len(m.pairs)
        assert np.abs(gaps.gap_T).max() < 1e-12 and np.abs(gaps.gap_N).max() < 1e-12
    before = gaps
    T = 1.5 * MU * N
    gaps = new_step(gaps)
    u, gaps, its, _ = driver.solve_load_level(m.K, m.load(T, -N), m.C, gaps, MU, m.fixed, u)
    assert count_states(gaps)["slip"] == len(m.pairs)
    # t = (-S, C) = (-1, 0): the block moves along -t, lam_T < 0 resists it
    assert -gaps.lam_T.sum() == pytest.approx(MU * N, rel=1e-8)
    np.testing.assert_allclose(np.abs(gaps.lam_T), MU * np.abs(gaps.lam_N), rtol=1e-8)
    spring_force = np.sum(m.spring * u)
    assert spring_force == pytest.approx(T - MU * N, rel=1e-8)
    assert np.all(gaps.gap_T < 0) and np.abs(gaps.gap_N).max() < 1e-12
    assert before.lam_T.sum() == pytest.approx(-0.7 * MU * N, rel=1e-3)
    # one more step at full slip: dissipation = mu N x slip (trapezoid exact: force constant)
    start = gaps
    gaps = new_step(gaps)
    u, gaps, _, _ = driver.solve_load_level(m.K, m.load(2.0 * MU * N, -N), m.C, gaps, MU,
                                            m.fixed, u)
    slip = -(gaps.gap_T - start.gap_T)
    assert np.all(slip > 0) and np.ptp(slip) < 1e-2 * slip.mean()
    assert friction_work_increment(start, gaps) == pytest.approx(MU * N * slip.mean(),
                                                                 rel=1e-2)


def test_block_separates_in_tension_and_recontacts(driver):
    m = driver.model(springs_x=50.0, springs_y=50.0)
    gaps, u = GapState.initial(len(m.pairs)), np.zeros(m.n_eq)
    u, gaps, _, _ = driver.solve_load_level(m.K, m.load(0.0, -N), m.C, gaps, MU, m.fixed, u)
    gaps = new_step(gaps)
    u, gaps, _, _ = driver.solve_load_level(m.K, m.load(0.0, 0.1 * N), m.C, gaps, MU, m.fixed, u)
    assert count_states(gaps)["free"] == len(m.pairs)
    assert np.all(gaps.lam_N == 0.0) and np.all(gaps.lam_T == 0.0)
    assert np.all(gaps.gap_N > 0)
    assert np.sum(m.spring[1::2] * u[1::2]) == pytest.approx(0.1 * N, rel=1e-9)
    gaps = new_step(gaps)
    u, gaps, _, changes = driver.solve_load_level(m.K, m.load(0.0, -N), m.C, gaps, MU,
                                                  m.fixed, u)
    # every pair closes again (free -> fixed on penetration), none penetrates; the lateral
    # mismatch frozen at closure is then held at the Coulomb limit (path dependence, §3.3.4)
    assert changes >= len(m.pairs) and count_states(gaps)["free"] == 0
    assert gaps.gap_N.min() > -1e-9 and np.abs(gaps.gap_N).max() < 1e-12
    assert np.all(gaps.lam_N < 0)
    assert np.all(np.abs(gaps.lam_T) <= MU * np.abs(gaps.lam_N) * (1 + 1e-8))
    spring_y = np.sum(m.spring[1::2] * u[1::2])  # vertical equilibrium of the block
    assert -gaps.lam_N.sum() - spring_y == pytest.approx(N, rel=1e-9)


# --- displacement control: two right-hand sides on one factorisation -----------------------

def test_displacement_control_push_reaches_coulomb_plateau(driver):
    m = driver.model(springs_x=50.0)
    gaps, u = GapState.initial(len(m.pairs)), np.zeros(m.n_eq)
    dead = m.load(0.0, -N)  # held constant: not scaled by the load factor
    u, gaps, _, _ = driver.solve_load_level(m.K, dead, m.C, gaps, MU, m.fixed, u)
    R_ref = m.load(-1.0, 0.0)  # push along -x, i.e. along +t
    control = 2 * m.corners[0]  # x dof of a loaded corner
    load_factor, start = 0.0, gaps
    for target in np.linspace(-0.002, -0.02, 4):
        gaps = new_step(gaps)
        remaining, flips = target - u[control], 1
        for _ in range(80):
            r_u = dead + load_factor * R_ref - m.K @ u
            rhs_II = augmented_rhs(r_u, u, m.C, gaps, MU, m.fixed)
            if abs(remaining) < 1e-15 and np.abs(rhs_II).max() < 1e-9 * N and flips == 0:
                break
            lu = factorize(augmented_matrix(m.K, m.C, gaps, m.fixed))
            x = lu.solve(np.column_stack([reference_rhs(R_ref, len(m.pairs), m.fixed),
                                          rhs_II]))
            d_load = (remaining - x[control, 1]) / x[control, 0]  # eq. 3.48
            du, d_N, d_T = split_solution(x[:, 1] + d_load * x[:, 0], m.n_eq)
            u, load_factor, remaining = u + du, load_factor + d_load, 0.0
            gaps, flips = update_states(gaps, gaps.lam_N + d_N, gaps.lam_T + d_T,
                                        *relative_displacement(m.C, u), MU, reverse_slip=True)
        else:
            raise AssertionError("displacement control did not converge")
        assert u[control] == pytest.approx(target, rel=1e-12)
    assert count_states(gaps)["slip"] == len(m.pairs)
    assert gaps.lam_T.sum() == pytest.approx(MU * N, rel=1e-8)
    # reference load along -x: the jack force equals mu N plus the springs' pull
    assert load_factor + np.sum(m.spring * u) == pytest.approx(MU * N, rel=1e-8)
    assert friction_work_increment(start, gaps) > 0


def test_gap_loads_are_not_scaled_by_the_load_factor(driver):
    """A penetrated pair just re-fixed closes exactly whatever the load factor (errata §3)."""
    m = driver.model(springs_x=50.0, springs_y=50.0)
    n = len(m.pairs)
    u = np.zeros(m.n_eq)
    u[2 * m.pairs[:, 1] + 1] = -0.01  # concrete 0.01 mm into the steel
    gaps = GapState.initial(n)
    gaps = GapState(np.full(n, FREE, np.int8), gaps.lam_N, gaps.lam_T, gaps.gap_N,
                    gaps.gap_T, gaps.stick_T, gaps.permanent)
    gaps, flips = update_states(gaps, gaps.lam_N, gaps.lam_T, *relative_displacement(m.C, u), MU)
    assert flips == n and count_states(gaps)["fixed"] == n
    lu = factorize(augmented_matrix(m.K, m.C, gaps, m.fixed))
    ref = reference_rhs(m.load(0.0, -N), n, m.fixed)
    assert np.all(ref[m.n_eq:] == 0.0)
    x_I = lu.solve(ref)
    x_II = lu.solve(augmented_rhs(-m.K @ u, u, m.C, gaps, MU, m.fixed))
    for d_load in (0.3, 2.0):
        du = split_solution(x_II + d_load * x_I, m.n_eq)[0]
        gap_N, _ = relative_displacement(m.C, u + du)
        assert np.abs(gap_N).max() < 1e-12


# --- floating cores and fixed points (§4.3.2) ----------------------------------------------

def _all_free(n, permanent=None):
    s = GapState.initial(n, permanent)
    state = np.where(s.permanent, FIXED, FREE).astype(np.int8)
    return GapState(state, s.lam_N, s.lam_T, s.gap_N, s.gap_T, s.stick_T, s.permanent)


def test_floating_core_is_singular_with_a_helpful_message(driver):
    m = driver.model(concrete_on_top=False)
    A = augmented_matrix(m.K, m.C, _all_free(len(m.pairs)), m.fixed)
    with pytest.raises(ConvergenceError, match="add fixed points") as err:
        factorize(A).solve(np.ones(A.shape[0]))
    assert err.value.reason == "singular system"
    one = choose_fixed_points(m.mesh, per_core=1)  # stops translation, not rotation
    with pytest.raises(ConvergenceError, match="singular"):
        factorize(augmented_matrix(m.K, m.C, _all_free(len(m.pairs), one), m.fixed)).solve(
            np.ones(A.shape[0]))


@pytest.mark.parametrize("mass_term", [0.0, 1e13, 1e14])
def test_a_mass_term_makes_no_pair_system_singular(driver, mass_term):
    """A dynamic drop's mass term M / (beta dt^2) (CF-4: 1e12-1e14 N/mm at dt = 6e-9 s) makes
    the pair rows' pivots -C K^-1 C^T about |C|^2 / diag, far below the largest entry of their
    columns (the pivot test's scale), and row exchanges carry such pivots into displacement
    columns: the test fails on a healthy matrix. Its equilibrated form passes and solves to
    round-off; without a mass term the factorisation is the plain one, and the floating core
    stays singular."""
    m = driver.model(concrete_on_top=False)
    K = m.K + mass_term * sp.eye(m.K.shape[0])
    gaps = GapState.initial(len(m.pairs))  # every pair FIXED
    A = sp.csc_matrix(augmented_matrix(K, m.C, gaps, m.fixed))
    b = np.random.default_rng(0).standard_normal(A.shape[0])
    factor = factorize(A)
    assert isinstance(factor.lu, EquilibratedLU) == bool(mass_term)
    x = factor.solve(b)
    assert factor.lu.backward_error(b, x) < 1e-15
    dense = np.linalg.solve(A.toarray(), b)
    for block in (slice(0, m.n_eq), slice(m.n_eq, None)):  # displacements, multipliers
        assert np.abs(x[block] - dense[block]).max() <= 1e-6 * np.abs(dense[block]).max()
    schur = pivot_scales(A)[m.n_eq:]  # sum_i C_ji^2 / K_ii per multiplier row
    C = sp.csr_matrix(m.C)
    diagonal = np.where(np.isin(np.arange(m.n_eq), m.fixed), np.inf, K.diagonal())
    expected = np.asarray(C.multiply(C) @ (1.0 / diagonal)).ravel()
    np.testing.assert_allclose(schur, expected, rtol=1e-12)
    if mass_term:
        lu = spla.splu(A, **superlu_options())  # the plain test fails: healthy pivots flagged
        column = np.argsort(lu.perm_c)
        assert np.any(np.abs(lu.U.diagonal()) <= PIVOT_RTOL * column_max_abs(A)[column])
    else:
        with pytest.raises(ConvergenceError, match="add fixed points"):
            factorize(augmented_matrix(K, m.C, _all_free(len(m.pairs)), m.fixed)).solve(b)


def test_core_with_fixed_points_is_solvable(driver):
    m = driver.model(concrete_on_top=False)
    gaps, u = _all_free(len(m.pairs), choose_fixed_points(m.mesh)), np.zeros(m.n_eq)
    F = m.load(0.0, -0.1 * N)  # pulls the core off the plate: it hangs from its fixed points
    u, gaps, _, _ = driver.solve_load_level(m.K, F, m.C, gaps, MU, m.fixed, u)
    assert np.all(gaps.state[gaps.permanent] == FIXED)
    assert gaps.lam_N.sum() == pytest.approx(0.1 * N, rel=1e-10)  # net tension, n = (0, -1)
    assert np.all(gaps.lam_N[gaps.permanent] > 0)  # the fixed points carry tension
    assert np.all(gaps.lam_N[~gaps.permanent] <= 0)  # others free, or pressed as it tilts
    assert gaps.gap_N.min() > -1e-9 and count_states(gaps)["free"] >= len(m.pairs) - 3


def test_refinement_only_where_the_first_solve_is_inaccurate(monkeypatch):
    """AugmentedFactor.solve refines once when the first solve's backward error exceeds
    REFINE_RTOL, and not otherwise; a factor of a slightly wrong matrix (an inaccurate first
    solve) is refined to an accurate solution."""
    import icewall.interface.augmented as aug

    rng = np.random.default_rng(0)
    A = sp.csc_matrix(sp.random(40, 40, density=0.2, random_state=1) + 10 * sp.eye(40))
    b = rng.standard_normal((40, 2))
    calls = []
    factor = factorize(A)
    real = factor.lu.solve
    monkeypatch.setattr(factor.lu, "solve", lambda rhs: calls.append(1) or real(rhs))
    x = factor.solve(b)
    assert len(calls) == 1 and factor.lu.backward_error(b, x) <= aug.REFINE_RTOL
    # the factors of A + 1e-9 |A| stand for an inaccurate LU of A: its first solve is off
    near = factorize(sp.csc_matrix(A + 1e-9 * abs(A))).lu.solve
    wrong = factorize(A)
    calls.clear()
    monkeypatch.setattr(wrong.lu, "solve", lambda rhs: calls.append(1) or near(rhs))
    first = near(b)
    assert wrong.lu.backward_error(b, first) > aug.REFINE_RTOL
    refined = wrong.solve(b)
    assert len(calls) == 2
    assert wrong.lu.backward_error(b, refined) < 1e-3 * wrong.lu.backward_error(b, first)
