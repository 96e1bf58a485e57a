"""What the secant scheme does after a failed step: half the step; on the smallest step each
fallback iteration in turn (`fallbacks`), then a step over the stall from the last converged
state (`analysis.max_jumps` per run, `jump_increments` increments long, flagged `jumped`); a
load drop displacement control cannot follow (`SnapBack`) is cut until it is accepted at the
smallest step (control.SecantStage) or ends the run. ConvergenceError where nothing is left."""

from __future__ import annotations

import logging
from dataclasses import replace
from typing import TYPE_CHECKING, NamedTuple

from icewall.errors import ConvergenceError
from icewall.solve.state import StepFailed

if TYPE_CHECKING:
    from icewall.solve.settings import SolverSettings

log = logging.getLogger(__name__)

FALLBACKS = 4
"""Iteration schemes tried at most, in turn, on a smallest step that did not converge."""

LONG_ITERATIONS = 3
"""The last fallback iterates this many times the deck's iteration limit (a snap-through)."""


class SnapBack(StepFailed):
    """A converged step whose load dropped more than displacement control can follow before
    the smallest step (or with on_snap_back: stop): rolled back like a failure."""

    def __init__(self, message: str) -> None:
        super().__init__(message, "snap-back")


class Attempt(NamedTuple):
    """A stage's next try: its step size, iteration (index into `fallbacks`), the steps over
    a stall made so far (the scheme's max_jumps) and whether this try is one."""

    size: float
    retry: int = 0
    jumps: int = 0
    jumping: bool = False


def after_failure(exc: StepFailed | ConvergenceError, settings: SolverSettings, kind: str,
                  goal: float, current: float, step_size: float, smallest: float,
                  attempt: Attempt) -> Attempt:
    """The try after a failed increment to `goal`: a snap-back halved, at the smallest step
    the end; on the smallest step each fallback scheme, then a step over the stall (control
    only), else half the step; ConvergenceError if none is left."""
    reason = getattr(exc, "reason", "non-convergence")
    size, retry, jumps, jumping = attempt
    if isinstance(exc, SnapBack):
        if size <= smallest:
            raise ConvergenceError(str(exc), reason=reason) from None
        return attempt._replace(size=0.5 * size)
    if (size <= smallest and reason == "non-convergence"
            and retry < len(fallbacks(settings)) - 1):
        # the damped relaxation can crawl where another scheme gets through: retry
        # the smallest step with each fallback (same equilibrium, same tolerances)
        log.info("%s %.4g: retrying the smallest step with fallback %d", kind, goal, retry + 1)
        return attempt._replace(retry=retry + 1)
    if size <= smallest and kind == "control" and jumps < settings.scheme.max_jumps:
        # step over the stall from the last converged state, as a stroke-controlled
        # test goes on past a local instability (recorded in the history)
        size = settings.scheme.jump_increments * step_size
        log.info("control %.4g: stepping over the stall to %.4g (jump %d)", goal,
                 current + size, jumps + 1)
        return Attempt(size, 0, jumps + 1, True)
    if jumping:
        raise ConvergenceError(f"{exc} at {kind} {goal:.4g}, also when stepping over "
                               f"the stall ({jumps} jumps)", reason=reason) from None
    if size <= smallest:
        raise ConvergenceError(f"{exc} at {kind} {goal:.4g} after "
                               f"{settings.max_step_cuts} step cuts",
                               reason=reason) from None
    return attempt._replace(size=0.5 * size)


def fallbacks(settings: SolverSettings) -> list[tuple[SolverSettings, bool]]:
    """(settings, cycle damping) of the deck's own scheme and of each fallback that differs
    from it: the halving relaxation without the cycle damping (only the halving scheme reads
    it), then Aitken's relaxation (unless that is the setting), then the deck's relaxation with
    the returned secant in the iteration matrix (concrete.matrix_secant): the concrete E_i no
    stiffer than the stress the update returned, which frozen points held at their envelope
    are (CF-8 at 9.6-11.5 mm crawled at a load norm of 0.08-0.12 with 80 such points under
    every other scheme). Last of all, the deck's relaxation without cycle damping and with
    LONG_ITERATIONS times the iteration limit: at a snap-through on the smallest step the
    secant iteration walks the load down a long way (VTT1, one realization, at 8.94 mm:
    2.38 -> 1.14 MN in 203 iterations; the run stopped at the deck's 200). Each fallback comes
    after those that were there before it, so a run that never needs it is unchanged."""
    secant = settings.scheme
    schemes = [(settings, True)]
    if secant.acceleration == "halving":
        schemes.append((settings, False))
    if secant.acceleration != "aitken":
        schemes.append((replace(settings, scheme=replace(secant, acceleration="aitken")), True))
    if secant.iteration_secant != "returned":
        schemes.append((replace(settings, scheme=replace(secant, iteration_secant="returned")),
                        True))
    schemes.append((replace(settings, max_iterations=LONG_ITERATIONS * settings.max_iterations),
                    False))
    return schemes
