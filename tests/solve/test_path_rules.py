"""The path following's decisions after a failed step (solve/mode.py `Mode`), one at a time:
where the smallest step goes on to a located bracket, and where it is taken in time at once
(the kink rule and the stability rule of docs/solver.md item 38)."""

from __future__ import annotations

import math

import pytest
from test_newton import newton_settings

from icewall.solve.mode import Mode
from icewall.solve.state import Increment, StepFailed
from icewall.solve.steps import StepSizeController

STEPS = StepSizeController(largest=1.0, smallest=1.0 / 64)
SETTINGS = newton_settings(40.0, 1.0, tolerance=1e-4, trace=False)


def _failed(reason: str) -> StepFailed:
    return StepFailed("test", reason)


def _converged(at: float, load: float, iterations: int = 1) -> Increment:
    return Increment("control", at, load, 0.0, iterations, 0.0, 0.0, None, None, {})


@pytest.mark.parametrize("omega", [math.nan, 250.0])
def test_a_smallest_step_that_fails_first_brackets_the_limit_point(omega):
    mode = Mode("displacement", STEPS.smallest, 0.0, slope=1e5, omega=omega)
    mode.after_failure(_failed("non-convergence"), "here", STEPS, SETTINGS, 7.0, 7e5)
    assert mode.name == "displacement" and mode.size == pytest.approx(STEPS.smallest / 2)
    assert mode.ceiling == pytest.approx(7.0 + STEPS.smallest)


def test_after_a_bracket_whose_end_converged_the_next_failure_is_taken_in_time():
    mode = Mode("displacement", STEPS.smallest, 0.0, slope=1e5, omega=250.0)
    mode.after_failure(_failed("non-convergence"), "here", STEPS, SETTINGS, 7.0, 7e5)
    end = mode.ceiling
    mode.after_success(_converged(end, 7e5), end - 7.0, 0.0, STEPS, SETTINGS)  # its end
    assert mode.kinked and math.isnan(mode.ceiling) and mode.size == STEPS.smallest
    mode.after_failure(_failed("non-convergence"), "there", STEPS, SETTINGS, end, 7e5)
    assert mode.name == "drop" and not mode.kinked
    # without masses (viscous drops) the bracket is located as before
    static = Mode("displacement", STEPS.smallest, 0.0, slope=1e5, kinked=True)
    static.after_failure(_failed("non-convergence"), "there", STEPS, SETTINGS, end, 7e5)
    assert static.name == "displacement" and not math.isnan(static.ceiling)


def test_a_smooth_step_clears_the_kink_and_an_unstable_bracket_ends_in_a_drop():
    # an unstable smallest step is bracketed like a failed one (the peak stays a property of
    # the path, issue 35), but once located the drop is taken from there: its end is never
    # tried again (from nearer starts Newton lands on other equilibria, and retrying crawls)
    mode = Mode("displacement", 4 * STEPS.smallest, 0.0, slope=1e5, omega=250.0, kinked=True)
    mode.after_success(_converged(7.1, 7.1e5, 5), 4 * STEPS.smallest, 1e3, STEPS, SETTINGS)
    assert not mode.kinked
    mode.after_failure(_failed("unstable"), "here", STEPS, SETTINGS, 7.1, 7.1e5)
    assert mode.name == "displacement" and mode.size < 4 * STEPS.smallest  # cut first
    mode.size = STEPS.smallest
    mode.after_failure(_failed("unstable"), "here", STEPS, SETTINGS, 7.1, 7.1e5)
    assert mode.name == "displacement" and mode.unstable and not math.isnan(mode.ceiling)
    current, steps_taken = 7.1, 0
    while mode.name == "displacement":  # bisect towards it: every half converges, stable
        at = current + mode.size
        assert at < mode.ceiling
        mode.after_success(_converged(at, 7.1e5 + 1e5 * (at - 7.1)), at - current, 0.0,
                           STEPS, SETTINGS)
        current, steps_taken = at, steps_taken + 1
    assert mode.name == "drop" and math.isnan(mode.ceiling) and 3 <= steps_taken <= 10
