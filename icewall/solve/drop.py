"""The load drop at a fixed deflection, taken as a stroke-controlled test takes it: a sequence
of committed viscous sub-steps that ends at a static equilibrium.

Where displacement control fails at its smallest step (past a peak, where the concrete under a
load station crushes and the tangent is indefinite or singular), the step to the next
deflection is solved as a dynamic relaxation with dampers on every equation and no mass (a
gradient flow, backward Euler in a pseudo-time): each sub-step solves

    P R + F_pre - F_int(u) - D (u - u_n) / dt - C^T lam = 0,    deflection = target

by the Newton iteration of every step (`newton.newton_increment`, matrix K_t + D / dt), and is
committed, so the concrete, the steel and the pairs follow the motion as they do in the test.
(Iterating the whole drop as one increment from the state before it, with the damper only in
the matrix - pseudo-transient continuation, docs/solver.md item 13 - evaluated the
path-dependent laws over one large increment and stalled.) D is the diagonal of the tangent at
the drop's start, floored; 1/dt falls while the sub-steps converge in few iterations (the flow
speeds up) and rises after a failed one; a sub-step that fails with the stiffest dampers is
retried with weaker ones (frozen dampers do not carry a point across a jump of its law). The
sub-steps are the drop's path, not results: each converges to SUBSTEP_TOLERANCE times the
deck's tolerances. A sub-step whose jack load runs away (a mechanism away from the control
point) ends the drop as failed. The drop ends where the static unbalance (the damper
force taken out) and the last sub-step's motion are within the tolerances of eqs. 4.4 and 4.5,
or where a static Newton step from a sub-step converges: either way an equilibrium of the model
at that deflection, on the same norms as every step. The sub-steps themselves are not written.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp

from icewall.errors import ConvergenceError
from icewall.solve.newton import newton_increment, static_load_norm
from icewall.solve.problem import Problem
from icewall.solve.state import Increment, PathState, StepFailed

if TYPE_CHECKING:
    from icewall.solve.settings import SolverSettings

log = logging.getLogger(__name__)

DIAGONAL_FLOOR = 1e-3
"""D is floored at this fraction of its median: the points whose tangent has lost its
stiffness (crushed and cracked) get a damper too."""
FIRST_INVERSE_STEP = 1.0
"""1/dt of a drop's first sub-step (dampers as stiff as the tangent's diagonal)."""
LARGEST_INVERSE_STEP = 1e4
"""A sub-step that fails with dampers this stiff ends the drop (failed)."""
FAST, SLOW = 4, 10
"""Sub-steps converged within FAST iterations halve 1/dt (not below SMALLEST_INVERSE_STEP);
beyond SLOW they double it."""
CHECK_AT = 10.0
"""A static Newton step is tried once the damper force is within this multiple of the load
tolerance (then at most every CHECK_EVERY sub-steps), with at most CHECK_ITERATIONS: it
starts next to an equilibrium, and where it cycles the sub-steps go on."""
CHECK_EVERY = 5
CHECK_ITERATIONS = 10
SUBSTEP_ITERATIONS = 20
"""A sub-step not converged in this many iterations (or the deck's limit, if lower) is
retried with other dampers."""
SUBSTEP_TOLERANCE = 10.0
"""The sub-steps are the drop's path, not results: each converges to this multiple of the
deck's tolerances at most (tighter near the end of a drop: substep_settings); the state the
drop ends at meets the deck's own."""
SUBSTEP_FRACTION = 0.5
"""A sub-step converges to at most this fraction of the static unbalance it starts from."""
SMALLEST_INVERSE_STEP = 1e-4
"""The weakest dampers: quick sub-steps halve 1/dt down to this (the dampers are then negligible
against the tangent), and once a sub-step has failed at LARGEST_INVERSE_STEP (frozen dampers do
not get a point across a jump of its law: docs/solver.md items 7 and 10) it is retried with
dampers 4x weaker each time, from FIRST_INVERSE_STEP / 4 down to this."""
SUBSTEPS = 20000
"""Sub-steps of one drop before it counts as failed."""
PROGRESS_WINDOW = 500
"""A drop whose last PROGRESS_WINDOW sub-steps neither lowered the static unbalance below
PROGRESS_UNBALANCE of its best before them nor moved the load factor by PROGRESS_LOAD of itself
has stalled: it fails. (A large drop, CF-4's jack load from 612 to 127 kN at 9.75 mm, took 3 535
sub-steps and progressed all along.)"""
PROGRESS_UNBALANCE, PROGRESS_LOAD = 0.9, 1e-3
RUNAWAY = 100.0
"""A sub-step whose jack loads exceed this multiple of the largest external force system so
far (eq. 4.5's reference), or of the dampers' force when the whole wall moves by the drop's
deflection step, has run away - the loads push a mechanism away from the control point
against the dampers: the drop fails."""


def floored_diagonal(tangent_diagonal: np.ndarray) -> np.ndarray:
    """|diag K_t| floored at DIAGONAL_FLOOR of the median of its non-zero entries."""
    d = np.abs(np.asarray(tangent_diagonal, dtype=float))
    return np.maximum(d, DIAGONAL_FLOOR * float(np.median(d[d > 0.0])))


@dataclass(frozen=True)
class Dampers:
    """Dampers D on every equation over a sub-step of length dt that starts at `origin`."""

    diagonal: np.ndarray
    inverse_step: float
    origin: np.ndarray

    def force(self, u: np.ndarray) -> np.ndarray:
        """D (u - origin) / dt, the damper force the residual carries."""
        return self.inverse_step * self.diagonal * (u - self.origin)

    def shift(self) -> sp.dia_matrix:
        """D / dt, added to the tangent."""
        return sp.diags(self.inverse_step * self.diagonal)


def drop_step(problem: Problem, settings: SolverSettings, state: PathState, control,
              preload: float, inverse_step: float = FIRST_INVERSE_STEP,
              last_increment: np.ndarray | None = None) -> tuple[Increment, float]:
    """Take the step to `control`'s deflection through committed viscous sub-steps; return the
    equilibrium it ends at (its iterations: all sub-steps') and the 1/dt to start the next
    drop with. StepFailed when a sub-step fails at every 1/dt, the load runs away or no
    equilibrium is reached in SUBSTEPS or a window of them makes no progress.

    The first sub-step moves the control deflection against the dampers. Where the jack loads
    move the control point little through K_t + D / dt (TF-1: jacks away from midspan, the
    dampers a stiff foundation under every node), the load it takes runs away; it is then
    retried with the dampers at rest on the last converged increment's motion scaled to the
    step (`last_increment`), so that they resist only the departure from it."""
    c = problem.constraints
    diagonal = _damper_diagonal(problem, state)
    sub, iterations, next_check = state, 0, 0
    reference = float(np.linalg.norm(c.restrict(problem.reference_load)))
    step = abs(control.target - control.measure(state.u))
    origin = state.u.copy()
    moving = _moving_origin(control, state, step, last_increment)  # after a runaway
    loose, check = _drop_settings(settings)
    weakening = False  # retrying a failed sub-step with weaker dampers
    progress = _Progress(state.load_factor)
    static = float("inf")
    for k in range(SUBSTEPS):
        if k and k % PROGRESS_WINDOW == 0 and not progress.made(sub.load_factor):
            raise StepFailed(f"drop at a fixed deflection: no progress in the {PROGRESS_WINDOW} "
                             f"sub-steps to {k} (static load norm {progress.best:.3g})",
                             "non-convergence")
        dampers = Dampers(diagonal, inverse_step, origin)
        try:
            inc = newton_increment(problem, substep_settings(loose, settings, static), sub,
                                   control, preload, dampers=dampers)
            _refuse_runaway(inc, dampers, state.load_scale, step, reference)
        except (StepFailed, ConvergenceError) as exc:
            c.rollback()
            if (exc.reason == "runaway" and k == 0 and moving is not None
                    and not np.array_equal(origin, moving)):
                origin = moving
                log.debug("drop sub-step 0 ran away: the dampers follow the last increment")
                continue
            inverse_step, weakening = _after_failed_substep(exc, k, inverse_step, weakening)
            continue
        c.commit()
        weakening = False
        iterations += inc.iterations
        origin = inc.u.copy()
        sub = PathState(inc.u, inc.load_factor, inc.evaluation.states, inc.evaluation,
                        inc.preload_factor, state.load_scale)
        static = static_load_norm(problem, inc, state.load_scale)
        progress.window = min(progress.window, static)
        moved = float(np.linalg.norm(inc.u - dampers.origin)) / max(
            float(np.linalg.norm(inc.u)), 1e-30)
        log.debug("drop sub-step %d: 1/dt %.3g, %d iterations, load factor %.6g, static load "
                  "norm %.3e, moved %.3e", k, inverse_step, inc.iterations, inc.load_factor,
                  static, moved)
        if static <= settings.tolerance_load and moved <= settings.tolerance_displacement:
            return _ended(replace(inc, load_norm=static), iterations, k, state), inverse_step
        if static <= CHECK_AT * settings.tolerance_load and k >= next_check:
            next_check = k + CHECK_EVERY
            final = _static_step(problem, check, sub, control, preload, k)
            if final is not None:
                return _ended(final, iterations + final.iterations, k, state), inverse_step
        inverse_step = _adapted_inverse_step(inverse_step, inc.iterations)
    raise StepFailed(f"drop at a fixed deflection: no equilibrium after {SUBSTEPS} sub-steps",
                     "non-convergence")


def _drop_settings(settings: SolverSettings) -> tuple[SolverSettings, SolverSettings]:
    """The sub-steps' settings before substep_settings (SUBSTEP_TOLERANCE times the deck's
    tolerances, at most SUBSTEP_ITERATIONS) and the static Newton step's (CHECK_ITERATIONS)."""
    loose = replace(settings, tolerance_load=SUBSTEP_TOLERANCE * settings.tolerance_load,
                    tolerance_displacement=SUBSTEP_TOLERANCE * settings.tolerance_displacement,
                    max_iterations=min(settings.max_iterations, SUBSTEP_ITERATIONS))
    check = replace(settings, max_iterations=min(settings.max_iterations, CHECK_ITERATIONS))
    return loose, check


def _damper_diagonal(problem: Problem, state: PathState) -> np.ndarray:
    """D: the floored diagonal of the tangent at the drop's start (floored_diagonal)."""
    evaluation = (problem.structure.evaluate(state.u, state.states, tangent=True)
                  if state.evaluation is None else problem.structure.with_tangent(
                      state.evaluation))
    return floored_diagonal(problem.structure.stiffness(evaluation).diagonal())


def _refuse_runaway(inc: Increment, dampers: Dampers, load_scale: float, step: float,
                    reference: float) -> None:
    """StepFailed ("runaway") where the sub-step's jack loads (its load factor times
    `reference`, the norm of the reference load) exceed RUNAWAY times the larger of
    `load_scale` and the dampers' force when the whole wall moves by the deflection `step`."""
    bound = max(load_scale, dampers.inverse_step * float(dampers.diagonal.sum()) * step)
    if abs(inc.load_factor) * reference > RUNAWAY * bound:
        raise StepFailed(f"the load runs away ({inc.load_factor:.4g})", "runaway")


def _after_failed_substep(exc: StepFailed | ConvergenceError, k: int, inverse_step: float,
                          weakening: bool) -> tuple[float, bool]:
    """(1/dt, weakening) to retry failed sub-step `k` with: stiffer dampers up to
    LARGEST_INVERSE_STEP, then 4x weaker ones from FIRST_INVERSE_STEP / 4; StepFailed for a
    runaway or where the weakest dampers (SMALLEST_INVERSE_STEP) failed too."""
    if inverse_step >= LARGEST_INVERSE_STEP and not weakening:
        weakening, inverse_step = True, 4.0 * FIRST_INVERSE_STEP
    if exc.reason == "runaway":
        raise StepFailed(f"drop at a fixed deflection: sub-step {k}: {exc}",
                         exc.reason) from None
    if weakening and inverse_step <= SMALLEST_INVERSE_STEP:
        raise StepFailed(f"drop at a fixed deflection: sub-step {k} failed with 1/dt "
                         f"from {FIRST_INVERSE_STEP:.3g} to {LARGEST_INVERSE_STEP:.3g} "
                         f"and down to {inverse_step:.3g} ({exc})", exc.reason) from None
    inverse_step = (0.25 * inverse_step if weakening
                    else min(4.0 * inverse_step, LARGEST_INVERSE_STEP))
    log.debug("drop sub-step %d failed (%s): 1/dt %.3g", k, exc, inverse_step)
    return inverse_step, weakening


def _static_step(problem: Problem, check: SolverSettings, sub: PathState, control,
                 preload: float, k: int) -> Increment | None:
    """The static Newton step from sub-step `k` (at most CHECK_ITERATIONS), or None (rolled
    back) where it does not converge."""
    try:
        return newton_increment(problem, check, sub, control, preload)
    except (StepFailed, ConvergenceError) as exc:
        problem.constraints.rollback()
        log.debug("drop: static step at sub-step %d failed (%s)", k, exc)
        return None


def _adapted_inverse_step(inverse_step: float, iterations: int) -> float:
    """1/dt after a sub-step converged in `iterations`: halved after a quick one (FAST, not
    below SMALLEST_INVERSE_STEP), doubled after a slow one (SLOW, up to LARGEST_INVERSE_STEP)."""
    if iterations <= FAST:
        return max(0.5 * inverse_step, SMALLEST_INVERSE_STEP)
    if iterations > SLOW:
        return min(2.0 * inverse_step, LARGEST_INVERSE_STEP)
    return inverse_step


def substep_settings(loose: SolverSettings, settings: SolverSettings, static: float
                     ) -> SolverSettings:
    """A sub-step's settings: `loose` (SUBSTEP_TOLERANCE times the deck's), but its load
    tolerance at most SUBSTEP_FRACTION of the static unbalance `static` it starts from and at
    least the deck's. Near the end of a drop the unbalance is already below the loose
    tolerance; a sub-step held to that was accepted after one iteration that hardly moved it,
    and the drop crept without progress (TF-2 at 8.37 mm, TF-4 at 9.01 mm: docs/solver.md
    item 23)."""
    target = min(loose.tolerance_load, max(settings.tolerance_load, SUBSTEP_FRACTION * static))
    return replace(loose, tolerance_load=target)


class _Progress:
    """The static unbalance and load factor of a drop over its windows of sub-steps."""

    def __init__(self, load_factor: float) -> None:
        self.best, self.window, self.load_factor = float("inf"), float("inf"), load_factor

    def made(self, load_factor: float) -> bool:
        """Whether the window just ended made progress; starts the next one."""
        made = (self.window < PROGRESS_UNBALANCE * self.best
                or abs(load_factor - self.load_factor) > PROGRESS_LOAD * abs(self.load_factor))
        self.best, self.window = min(self.best, self.window), float("inf")
        self.load_factor = load_factor
        return made


def _moving_origin(control, state: PathState, step: float,
                   last_increment: np.ndarray | None) -> np.ndarray | None:
    """The state moved along the last increment by `step` of the held deflection (None
    without one that moved it)."""
    if last_increment is None:
        return None
    moved = control.measure(last_increment)
    if not moved > 0.0:
        return None
    return state.u + (step / moved) * last_increment


def _ended(inc: Increment, iterations: int, substep: int, start: PathState) -> Increment:
    log.info("drop at a fixed deflection: %d sub-steps, %d iterations, load factor %.6g -> "
             "%.6g", substep + 1, iterations, start.load_factor, inc.load_factor)
    return replace(inc, iterations=iterations,
                   forensics={**inc.forensics, "drop_substeps": [substep + 1]})
