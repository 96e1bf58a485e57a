"""Displacement control against closed forms: a linear problem, a softening bar, snap-back."""

from __future__ import annotations

import numpy as np
import pytest
from softening_bar import bar_problem, settings

from icewall.errors import ConvergenceError
from icewall.solve import control
from icewall.solve.path import follow_path
from icewall.solve.recovery import FALLBACKS, LONG_ITERATIONS, fallbacks


def analytic_softening_load(deflection, length, h, E, f_weak, failure_strain, area=10.0):
    """P(delta) of a bar with one softening element of length h (linear softening)."""
    peak_strain = f_weak / E
    delta_peak = length * peak_strain
    if deflection <= delta_peak:
        return E * deflection / length * area
    # delta = (L - h) sigma / E + h (eps0 + (f - sigma)/f (eps_f - eps0))
    slope = (length - h) / E - h * (failure_strain - peak_strain) / f_weak
    sigma = (deflection - h * failure_strain) / slope
    return sigma * area


def test_softening_bar_follows_its_descending_branch():
    length, n_el, E, f, weak, eps_f = 100.0, 10, 30000.0, 3.0, 0.9, 0.002
    problem, initial = bar_problem(length, n_el, E, f, weak, eps_f)
    loads, deflections, iterations = [], [], []
    # peak at 0.009 mm, the weak element is fully softened at h eps_f = 0.02 mm
    for inc, _ in follow_path(problem, settings(0.019, 0.001), initial):
        loads.append(inc.load_factor)
        deflections.append(inc.control_displacement)
        iterations.append(inc.iterations)
    deflections, loads = np.array(deflections), np.array(loads)
    assert deflections[-1] == pytest.approx(0.019)
    expected = [analytic_softening_load(d, length, length / n_el, E, weak * f, eps_f)
                for d in deflections]
    assert np.allclose(loads, expected, rtol=1e-5, atol=1e-6 * max(expected))
    peak = int(np.argmax(loads))
    assert 0 < peak < len(loads) - 1  # peak traced, then the descending branch
    assert np.all(np.diff(loads[peak:]) < 0)


def test_linear_bar_converges_in_one_iteration():
    problem, initial = bar_problem(100.0, 5, strength=1e9)  # never softens
    for inc, _ in follow_path(problem, settings(0.05, 0.01), initial):
        assert inc.iterations == 1
        assert inc.load_factor == pytest.approx(30000.0 * inc.control_displacement / 100 * 10)


def test_snap_back_is_reported_not_mis_solved():
    # (L - h)/E > h (eps_f - eps0)/f: the softening branch turns back in the end displacement
    problem, initial = bar_problem(1000.0, 10, failure_strain=0.0003)
    converged = []
    with pytest.raises(ConvergenceError) as info:
        for inc, _ in follow_path(problem, settings(0.5, 0.02, iterations=200, cuts=3),
                                  initial):
            converged.append(inc)
    assert info.value.reason == "snap-back"
    assert converged  # the steps before the snap-back were delivered
    # every delivered step is a genuine equilibrium of the ascending branch
    for inc in converged:
        assert inc.load_factor == pytest.approx(30000.0 * inc.control_displacement / 1000 * 10,
                                                rel=1e-6)


def test_snap_back_accepted_as_snap_through_lands_on_the_softened_branch():
    # on_snap_back: continue (the deck default): the drop is accepted only at the smallest
    # step, flagged, and the run goes on from a genuine equilibrium after the jump: the weak
    # element is fully softened (stress 0 beyond eps_f), so the bar carries no load.
    problem, initial = bar_problem(1000.0, 10, failure_strain=0.0003)
    steps = list(follow_path(problem, settings(0.5, 0.02, iterations=200, cuts=3,
                                               on_snap_back="continue"), initial))
    incs = [inc for inc, _ in steps]
    assert incs[-1].control_displacement == pytest.approx(0.5)
    jumps = [k for k, inc in enumerate(incs) if inc.snap_back]
    assert len(jumps) == 1
    before, after = incs[: jumps[0]], incs[jumps[0]:]
    for inc in before:  # the ascending branch, exact
        assert inc.load_factor == pytest.approx(30000.0 * inc.control_displacement / 1000 * 10,
                                                rel=1e-6)
    peak = max(inc.load_factor for inc in before)
    assert all(abs(inc.load_factor) < 1e-6 * peak for inc in after)


def test_fallback_schemes_on_the_smallest_step():
    """A smallest step that does not converge is retried with the undamped halving
    relaxation, then with Aitken's, then with the returned secant in the iteration matrix,
    last undamped with LONG_ITERATIONS times the iteration limit; tolerances and everything
    else stay the deck's."""
    base = settings(1.0, 0.1)
    schemes, n = fallbacks(base), base.max_iterations
    assert len(schemes) == FALLBACKS + 1
    assert [(s.scheme.acceleration, damp, s.scheme.iteration_secant, s.max_iterations)
            for s, damp in schemes] == [
        ("halving", True, "committed", n), ("halving", False, "committed", n),
        ("aitken", True, "committed", n), ("halving", True, "returned", n),
        ("halving", False, "committed", LONG_ITERATIONS * n)]
    for scheme, _ in schemes:
        assert (scheme.tolerance_load, scheme.tolerance_displacement) == (
            base.tolerance_load, base.tolerance_displacement)
    # a fallback that would repeat the failed iteration exactly is not tried
    assert [(s.scheme.acceleration, damp)
            for s, damp in fallbacks(settings(1.0, 0.1, acceleration="none"))
            ] == [("none", True), ("aitken", True), ("none", True), ("none", False)]
    only_long = fallbacks(settings(1.0, 0.1, acceleration="aitken", iteration_secant="returned"))
    assert [s.max_iterations for s, _ in only_long] == [n, LONG_ITERATIONS * n]


def _stall_between(monkeypatch, low: float, high: float) -> list[float]:
    """Make every increment whose target lies in (low, high) fail to converge."""
    real, attempted = control._iterate, []

    def stalling(problem, scheme, state, goal, *args):
        attempted.append(goal)
        if goal is not None and low < goal < high:
            raise control.StepFailed("stalled (test)", "non-convergence")
        return real(problem, scheme, state, goal, *args)

    monkeypatch.setattr(control, "_iterate", stalling)
    return attempted


def test_a_stall_is_stepped_over_and_recorded(monkeypatch):
    """A control step that fails at every size and scheme is retried as one step of two
    increments from the last converged state; the landing step is flagged, the rest of the
    path is the same equilibrium as without the stall (softening bar, closed form)."""
    length, n_el, E, f, weak, eps_f = 100.0, 10, 30000.0, 3.0, 0.9, 0.002
    problem, initial = bar_problem(length, n_el, E, f, weak, eps_f)
    attempted = _stall_between(monkeypatch, 0.0060, 0.0071)  # fails on the way to 0.007
    run = settings(0.012, 0.001, cuts=2, max_jumps=1)
    incs = [inc for inc, _ in follow_path(problem, run, initial)]
    deflections = [round(inc.control_displacement, 9) for inc in incs]
    assert 0.007 not in deflections and 0.008 in deflections
    assert [d for d, inc in zip(deflections, incs, strict=True) if inc.jumped] == [0.008]
    assert deflections[-1] == pytest.approx(0.012)
    for inc in incs:
        assert inc.load_factor == pytest.approx(analytic_softening_load(
            inc.control_displacement, length, length / n_el, E, weak * f, eps_f), rel=1e-5)
    assert sum(0.006 < g < 0.0071 for g in attempted) == 2 + 1 + FALLBACKS  # 3 sizes + schemes


def test_a_stall_stops_the_run_when_no_jumps_are_allowed(monkeypatch):
    problem, initial = bar_problem(100.0, 10)
    _stall_between(monkeypatch, 0.0060, 0.0071)
    converged = []
    with pytest.raises(ConvergenceError) as info:
        for inc, _ in follow_path(problem, settings(0.012, 0.001, cuts=2), initial):
            converged.append(inc.control_displacement)
    assert info.value.reason == "non-convergence" and "step cuts" in str(info.value)
    assert converged[-1] == pytest.approx(0.006)
