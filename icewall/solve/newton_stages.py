"""The Newton scheme's stages (solve.path.Stage): the preload by load control, then the control
to the target deflection; a step that does not converge is cut, and the run stops with a
reason when the smallest fails. No fallback iterations and no frozen points.

The control stage goes by displacement control while it converges (with dynamic drops, to
states stable with the stroke held: `stability`). Where it cannot at the smallest step (a
snap-back: a crack or a crushing zone releases more energy than the rest of the wall can take
up at a fixed deflection, or the tangent is singular), the limit point is located and the load
drops, as in a stroke-controlled test: through the wall's motion (`dynamic.dynamic_drop`) or
committed viscous sub-steps (`drop.drop_step`) to a static equilibrium, accepted on the same
tolerances and flagged `snap_back` (`analysis.on_snap_back: stop` stops there instead). With
`analysis.trace_snap_backs` the snap-back is first traced under the opening of the points at
or near cracking (`controls.OpeningControl`; the energy released for other laws) until load and
deflection rise together again. Which control comes next, and what follows a failed or a
converged step, is the state machine `mode.Mode`; the step size follows the iteration count
(`steps`).
"""

from __future__ import annotations

import logging
import math
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
from icewall.solve.state import Increment, PathState, PreloadCursor, StepFailed
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



class NewtonPreload:
    """The preload by load control, its step size from the iteration count."""

    direction = None  # (the control stage starts without a predictor direction)

    def __init__(self, problem: Problem, settings: SolverSettings, state: PathState,
                 cursor: PreloadCursor | None = None) -> None:
        self.problem, self.settings = problem, settings
        self.steps = StepSizeController.of(settings, 1.0 / settings.preload_increments)
        self.current, self.size = ((cursor.position, cursor.size) if cursor is not None
                                   else (state.preload_factor, self.steps.largest))
        self.goal = self.current

    def done(self, state: PathState) -> bool:
        return not self.current < 1.0 - 1e-12

    def step(self, state: PathState) -> Increment:
        self.goal = min(self.current + self.size, 1.0)
        return newton_increment(self.problem, self.settings, state, LoadControl(), self.goal,
                                "preload")

    def failed(self, exc: StepFailed | ConvergenceError, state: PathState) -> None:
        self.size = self.steps.after_failure(self.size, f"preload {self.goal:.4g}",
                                             getattr(exc, "reason", "non-convergence"),
                                             str(exc))

    def converged(self, state: PathState, inc: Increment) -> Increment:
        self.current, self.size = self.goal, self.steps.after_success(self.size, inc.iterations)
        return inc

    def cursor(self) -> PreloadCursor:
        return PreloadCursor(self.current, self.size)

    def stop(self) -> None:
        """Nothing ends the stage after a converged step."""


class NewtonControl:
    """Displacement control to the target, the snap-back control through snap-backs, a drop
    at a fixed deflection (or stroke) where neither converges: viscous, or the wall's motion
    under the Dynamic scheme (`inertia`), whose static steps must be stable with the stroke
    held."""

    def __init__(self, problem: Problem, settings: SolverSettings, state: PathState,
                 cursor: Mode | None = None) -> None:
        self.problem, self.settings = problem, settings
        self.dynamic = settings.scheme.inertia
        if self.dynamic and problem.mass is None:
            raise ValueError("the dynamic drops need the wall's mass (Problem.mass: "
                             "build_problem with the Dynamic scheme)")
        self.steps = StepSizeController.of(settings, settings.increment)
        self.mode = (Mode("displacement", self.steps.largest, 0.0) if cursor is None
                     else replace(cursor))
        self.preload = 1.0 if problem.preload is not None else 0.0
        self.path = _Path(problem, state, self.preload)
        self.direction = state.last_increment  # the Newton predictor's
        self.current, self.where = 0.0, ""

    def done(self, state: PathState) -> bool:
        target = self.settings.target
        return not -float(state.u[self.problem.control_equation]) < target - 1e-12 * max(
            1.0, target)

    def step(self, state: PathState) -> Increment:
        """The step under the mode's control: a drop, or a Newton increment (stable with the
        stroke held under the Dynamic scheme); StepFailed for an opening step past the
        target."""
        problem, settings, mode = self.problem, self.settings, self.mode
        self.current = -float(state.u[problem.control_equation])
        self.path.state = state
        control, self.where = mode.control(problem, self.path, self.current, self.steps,
                                           settings)
        if mode.name == "drop" and self.dynamic:
            inc = dynamic_drop(problem, settings, state, control, self.preload,
                               drop_dynamics(problem, settings, mode.omega))
            mode.held = -1 if inc.forensics.get("tested_rest") else 1
        elif mode.name == "drop":
            inc, mode.damping = drop_step(problem, settings, state, control, self.preload,
                                          mode.damping, self.direction)
        else:
            inc = newton_increment(problem, settings, state, control, self.preload,
                                   last_increment=self.direction)
            if mode.name == "displacement" and self.dynamic:
                mode.held = require_stable(problem, inc, self.path.R, mode.omega, mode.held)
        if mode.name == "opening" and inc.control_displacement > settings.target * (
                1 + 1e-12):
            raise StepFailed("the opening step passed the target deflection", "overshoot")
        return inc

    def failed(self, exc: StepFailed | ConvergenceError, state: PathState) -> None:
        log.info("%s: %s", self.where, exc)
        self.mode.after_failure(exc, self.where, self.steps, self.settings, self.current,
                                state.load_factor)

    def converged(self, state: PathState, inc: Increment) -> Increment:
        """The increment flagged where it is a snap-back; the mode of the next step (a traced
        snap-back that stalls ends in a drop, as a test's does), the predictor's direction and,
        after the run's first step under the Dynamic scheme, the first mode's frequency."""
        mode, settings = self.mode, self.settings
        d_deflection = inc.control_displacement - self.current
        d_load = inc.load_factor - state.load_factor
        # a step within a limit point's bracket is as small as the bracket: not stagnation
        still = math.isnan(mode.ceiling) and abs(d_deflection) <= STILL * max(
            settings.increment, 1e-30) and abs(d_load) <= STILL * max(abs(state.load_factor),
                                                                     1e-30)
        mode.stagnant = mode.stagnant + 1 if still else 0
        snap_back = mode.after_success(inc, d_deflection, d_load, self.steps, settings)
        self.direction = inc.u - state.u
        if math.isnan(mode.omega) and self.dynamic:  # the run's first step
            mode.omega = first_mode_frequency(self.direction, d_load, self.path.R,
                                              self.problem.mass)
        if mode.stagnant >= STAGNANT_STEPS and mode.name == "opening":
            mode._switch("drop", self.where)  # the traced snap-back stalls: the test drops
            mode.stagnant = 0
        return replace(inc, snap_back=snap_back)

    def cursor(self) -> Mode:
        return replace(self.mode)

    def stop(self) -> None:
        """After the step is on disk, as every converged one: ConvergenceError where a traced
        snap-back separated the structure (on_snap_back: stop) or the path stagnates."""
        if self.mode.halt:
            raise ConvergenceError(f"the traced snap-back separated the structure at "
                                   f"{self.where}: no load is carried, and only drops at fixed "
                                   "deflections go on (analysis.on_snap_back: stop; 'continue' "
                                   "takes them)", reason="snap-back")
        if self.mode.stagnant >= STAGNANT_STEPS:
            raise ConvergenceError(f"the path no longer moves at {self.where}: "
                                   f"{self.mode.stagnant} converged steps in a row changed "
                                   "neither the deflection nor the load", reason="stagnation")
