"""Path following with the converged (Newton) scheme: one loop that proposes a step, iterates
it to convergence, and yields it or cuts it. No fallback schemes and no frozen points: a step
that does not converge is cut, and the run stops with a reason when the smallest fails.

The preload goes by load control. The control stage goes by displacement control while it
converges (with dynamic drops, to states stable with the stroke held: `stability`). Where it
cannot at the smallest step (a snap-back: a crack or a crushing zone releases more energy than
the rest of the wall can take up at a fixed deflection, or the tangent is singular), the load
drops, as in a stroke-controlled test: through the wall's motion (`dynamic.dynamic_drop`) or
committed viscous sub-steps (`drop.drop_step`) to a static equilibrium, accepted on the same
tolerances and flagged `snap_back` (`analysis.on_snap_back: stop` stops there instead). With
`analysis.trace_snap_backs` the snap-back is first traced under the opening of the points at
or near cracking (`controls.OpeningControl`; the energy released for other laws) until load and
deflection rise together again. The step size follows the iteration count (`steps`).
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Iterator
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from icewall.errors import ConvergenceError
from icewall.solve.controls import (
    DissipationControl,
    LoadControl,
    OpeningControl,
    largest_principal,
)
from icewall.solve.drop import drop_step
from icewall.solve.dynamic import drop_dynamics, dynamic_drop
from icewall.solve.integrator import first_mode_frequency
from icewall.solve.mode import STILL, Mode
from icewall.solve.newton import newton_increment
from icewall.solve.problem import Problem
from icewall.solve.stability import require_stable
from icewall.solve.state import (
    Increment,
    PathState,
    PreloadCursor,
    StepFailed,
    next_state,
)
from icewall.solve.steps import StepSizeController

if TYPE_CHECKING:
    from icewall.solve.settings import SolverSettings

log = logging.getLogger(__name__)

NEAR_CRACKING = 0.8
"""Points whose largest principal strain exceeds this fraction of their cracking strain (or
that have cracked) form the opening control's set."""

STAGNANT_STEPS = 5
"""Consecutive steps that do not move the path after which the run stops (stagnation)."""


class _Path:
    """What the control stage carries from step to step."""

    def __init__(self, problem: Problem, state: PathState, preload: float) -> None:
        c = problem.constraints
        self.R = c.restrict(problem.reference_load)
        self.F_pre = (np.zeros_like(self.R) if problem.preload is None
                      else c.restrict(preload * problem.preload))
        self.problem, self.state = problem, state

    def work(self) -> float:
        """1/2 f.u of the current state (N mm): the scale of the released energies."""
        f = self.state.load_factor * self.R + self.F_pre
        return 0.5 * abs(float(f @ self.state.u))

    def snap_back_control(self, fraction: float):
        """The control through a snap-back: the opening of the concrete points at or near
        cracking (`opening_control`); without a law that cracks (e.g. the test bars),
        the energy released, as `fraction` of the external work so far."""
        if any(g.law.cracking(s) is not None
               for g, s in zip(self.problem.structure.groups, self.state.states, strict=True)):
            return self.opening_control(fraction)
        return DissipationControl(self.state.u, self.state.load_factor, self.R, self.F_pre,
                                  fraction * self.work())

    def opening_control(self, fraction: float) -> OpeningControl:
        """The opening control of the concrete points at or near cracking in the current
        state, asking for `fraction` of their (volume-weighted) cracking strain."""
        s = self.problem.structure
        kin, nq = s.kinematics, s.n_gauss
        elements, points, scales = [], [], []
        for group, state in zip(s.groups, self.state.states, strict=True):
            cracking = group.law.cracking(state)
            if cracking is None:
                continue
            eps_t, cracked = cracking
            largest = largest_principal(state.strain)[0]
            chosen = np.flatnonzero((largest >= NEAR_CRACKING * eps_t) | cracked)
            if chosen.size == 0:  # none near cracking: the ten nearest
                chosen = np.argsort(largest / eps_t)[-10:]
            elements.append(group.cells[chosen // nq])
            points.append(chosen % nq)
            scales.append(eps_t[chosen])
        e, q = np.concatenate(elements), np.concatenate(points)
        weights = kin.dV[e, q]
        control = OpeningControl(kin.B[e, q], kin.dofs[e], weights, 0.0, 0.0)
        reference = largest_principal(control.strains(self.state.u))[0]
        return replace(control, reference=reference,
                       increment=fraction * float(weights @ np.concatenate(scales)))


def _advance_preload(problem: Problem, settings: SolverSettings, state: PathState,
                     resume: PreloadCursor | None) -> Iterator[tuple[Increment, PathState]]:
    c = problem.constraints
    steps = StepSizeController.of(settings, 1.0 / settings.preload_increments)
    current, size = ((resume.position, resume.size) if resume is not None
                     else (state.preload_factor, steps.largest))
    while current < 1.0 - 1e-12:
        goal = min(current + size, 1.0)
        tic = time.perf_counter()
        try:
            inc = newton_increment(problem, settings, state, LoadControl(), goal, "preload")
        except (StepFailed, ConvergenceError) as exc:
            c.rollback()
            size = steps.after_failure(size, f"preload {goal:.4g}",
                                       getattr(exc, "reason", "non-convergence"), str(exc))
            continue
        c.commit()
        inc.wall_time = time.perf_counter() - tic
        current, size = goal, steps.after_success(size, inc.iterations)
        state = next_state(problem, state, inc, PreloadCursor(current, size))
        yield inc, state


def _advance_control(problem: Problem, settings: SolverSettings, state: PathState,
                     preload: float, resume: Mode | None) -> Iterator[tuple[Increment, PathState]]:
    """Displacement control to the target, the snap-back control through snap-backs, a drop
    at a fixed deflection where neither converges."""
    c = problem.constraints
    steps = StepSizeController.of(settings, settings.increment)
    mode = Mode("displacement", steps.largest, 0.0) if resume is None else replace(resume)
    path = _Path(problem, state, preload)
    last_increment = state.last_increment
    while -float(state.u[problem.control_equation]) < settings.target - 1e-12 * max(
            1.0, settings.target):
        current = -float(state.u[problem.control_equation])
        control, where = mode.control(problem, path, current, steps, settings)
        tic = time.perf_counter()
        try:
            if mode.name == "drop" and problem.mass is not None:
                inc = dynamic_drop(problem, settings, state, control, preload,
                                   drop_dynamics(problem, settings, mode.omega))
                mode.held = -1 if inc.forensics.get("tested_rest") else 1
            elif mode.name == "drop":
                inc, mode.damping = drop_step(problem, settings, state, control, preload,
                                              mode.damping, last_increment)
            else:
                inc = newton_increment(problem, settings, state, control, preload,
                                       last_increment=last_increment)
                if mode.name == "displacement" and problem.mass is not None:
                    mode.held = require_stable(problem, inc, path.R, mode.omega, mode.held)
            if mode.name == "opening" and inc.control_displacement > settings.target * (
                    1 + 1e-12):
                raise StepFailed("the opening step passed the target deflection", "overshoot")
        except (StepFailed, ConvergenceError) as exc:
            c.rollback()
            log.info("%s: %s", where, exc)
            mode.after_failure(exc, where, steps, settings, current, state.load_factor)
            continue
        c.commit()
        inc.wall_time = time.perf_counter() - tic
        d_deflection = inc.control_displacement - current
        d_load = inc.load_factor - state.load_factor
        # a step within a limit point's bracket is as small as the bracket: not stagnation
        still = math.isnan(mode.ceiling) and abs(d_deflection) <= STILL * max(
            settings.increment, 1e-30) and abs(d_load) <= STILL * max(abs(state.load_factor),
                                                                     1e-30)
        mode.stagnant = mode.stagnant + 1 if still else 0
        mode.after_success(inc, d_deflection, d_load, steps, settings)
        last_increment = inc.u - state.u
        if math.isnan(mode.omega) and problem.mass is not None:  # the run's first step
            mode.omega = first_mode_frequency(last_increment, d_load, path.R, problem.mass)
        if mode.stagnant >= STAGNANT_STEPS and mode.name == "opening":
            mode._switch("drop", where)  # the traced snap-back stalls: the test drops
            mode.stagnant = 0
        state = next_state(problem, state, inc, replace(mode), last_increment)
        path.state = state
        yield inc, state
        if mode.halt:
            raise ConvergenceError(f"the traced snap-back separated the structure at {where}: "
                                   "no load is carried, and only drops at fixed deflections go "
                                   "on (analysis.on_snap_back: stop; 'continue' takes them)",
                                   reason="snap-back")
        if mode.stagnant >= STAGNANT_STEPS:  # after the step is on disk, as every converged one
            raise ConvergenceError(f"the path no longer moves at {where}: {mode.stagnant} "
                                   "converged steps in a row changed neither the deflection "
                                   "nor the load", reason="stagnation")


def follow_path(problem: Problem, settings: SolverSettings, initial: PathState,
                resume: bool = False) -> Iterator[tuple[Increment, PathState]]:
    """Preload by load control (if any), then the control stage to the target deflection;
    `resume` goes on from where `initial.cursor` says."""
    current = initial
    cursor = initial.cursor if resume else None
    if problem.preload is not None and (cursor is None or cursor.stage != "control"):
        for inc, current in _advance_preload(problem, settings, initial, cursor):
            yield inc, current
        cursor = None
    preload = 1.0 if problem.preload is not None else 0.0
    yield from _advance_control(problem, settings, current, preload, cursor)
