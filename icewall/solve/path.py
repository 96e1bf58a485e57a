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
from dataclasses import dataclass, replace

import numpy as np

from icewall.errors import ConvergenceError
from icewall.solve.control import (
    Increment,
    PathState,
    StepFailed,
    _external_force_norm,
)
from icewall.solve.controls import (
    DisplacementControl,
    DissipationControl,
    LoadControl,
    OpeningControl,
    StrokeControl,
    largest_principal,
)
from icewall.solve.drop import FIRST_INVERSE_STEP, drop_step
from icewall.solve.dynamic import drop_dynamics, dynamic_drop
from icewall.solve.integrator import first_mode_frequency
from icewall.solve.newton import newton_increment
from icewall.solve.problem import Problem
from icewall.solve.settings import SolverSettings
from icewall.solve.stability import require_stable
from icewall.solve.steps import StepSizeController

log = logging.getLogger(__name__)

FIRST_OPENING = 0.05
"""First opening step after a switch, as a fraction of the cracking strain of the set."""
SMALLEST_OPENING = 1e-8
"""Opening steps below this fraction of the cracking strain of the set stop the run."""
NEAR_CRACKING = 0.8
"""Points whose largest principal strain exceeds this fraction of their cracking strain (or
that have cracked) form the opening control's set."""

STILL = 1e-9
"""A converged step that changes the deflection by less than this fraction of the increment
and the load factor by less than this fraction of itself has not moved the path."""
STAGNANT_STEPS = 5
"""Consecutive steps that do not move the path after which the run stops (stagnation)."""
LOCATED_WIDTH = 1e-12
"""A limit point's bracket narrower than this fraction of the increment is located whatever
the slope (round-off of the deflection itself)."""


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
                     resume: tuple) -> Iterator[tuple[Increment, PathState]]:
    c = problem.constraints
    steps = StepSizeController.of(settings, 1.0 / settings.preload_increments)
    current, size = (resume[0], resume[1]) if resume else (state.preload_factor, steps.largest)
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
        state = _next_state(problem, state, inc, ("preload", current, size, 0.0, 0.0))
        yield inc, state


def _next_state(problem: Problem, state: PathState, inc: Increment, resume: tuple) -> PathState:
    c = problem.constraints
    applied = c.restrict(inc.load_factor * problem.reference_load + (
        0.0 if problem.preload is None else inc.preload_factor * problem.preload))
    scale = max(state.load_scale, _external_force_norm(c, applied,
                                                       inc.evaluation.internal_force))
    return PathState(inc.u, inc.load_factor, inc.evaluation.states, inc.evaluation,
                     inc.preload_factor, scale, resume)


@dataclass
class _Mode:
    """The control of the next step and its size: "displacement" (deflection step `size`),
    "opening" (the snap-back control, `release`) or "drop" (at a fixed deflection, its
    sub-steps starting from the 1/dt the last drop ended with, `damping`).

    Where displacement control fails at its smallest step, the limit point of the path is
    located before the snap-back control or the drop takes over: the bracket between the last
    converged deflection and the smallest one that failed (`ceiling`) is bisected until the
    load it can hide, `slope` (the secant dP/dd of the last converged step; an upper bound of
    the path's slope beyond it where the path is concave, as before a peak) times its width,
    is within a quarter of the load tolerance (eq. 4.5) of the load. The peak is then a
    property of the path, not of where the steps fell (docs/solver.md, item 35)."""

    name: str
    size: float
    release: float
    damping: float = FIRST_INVERSE_STEP
    ceiling: float = math.nan  # the smallest deflection that failed in the bracket (locating)
    slope: float = math.nan  # the secant dP/dd of the last converged displacement step
    peak: float = 0.0  # the largest |load factor| so far: the scale of a separated structure
    halt: bool = False  # stop after the step just taken (on_snap_back: stop, separated)
    omega: float = math.nan  # the wall's first-mode frequency (rad/s): the drops' damping
    kinked: bool = False  # after a located bracket whose end converged (Newton's failure)
    unstable: bool = False  # the last failure was an unstable state, not a Newton failure
    held: int = 1  # the held determinant's sign at the last stable state (-1: a tested rest)

    def located(self, current: float, load: float, settings: SolverSettings) -> bool:
        """Whether the bracket [current, ceiling] pins the limit point's load to the
        tolerance: the load was not rising (slope <= 0) or slope * width <= tol |P| / 4."""
        width = self.ceiling - current
        if not self.slope > 0.0 or not width > 0.0:
            return True
        floor = LOCATED_WIDTH * max(settings.increment, 1e-30)
        return (self.slope * width <= 0.25 * settings.tolerance_load * abs(load)
                or width <= floor)

    def control(self, problem: Problem, path: _Path, current: float,
                steps: StepSizeController, settings: SolverSettings) -> tuple[object, str]:
        """The control of the next step and where it stands (for messages)."""
        if self.name == "opening":
            return (path.snap_back_control(self.release),
                    f"control {current:.4g} (snap-back control, step {self.release:.3g})")
        step = self.size if self.name == "displacement" else steps.smallest
        if self.name == "drop" and (settings.drop_held == "stroke"
                                    or problem.mass is not None):
            # a dynamic drop holds the stroke, the jack loads' work-conjugate displacement:
            # a point elsewhere held through them is no constraint a loading system applies
            # (its force does not act along its gradient), and such a drop runs away
            # (docs/solver.md, item 36)
            stroke = StrokeControl.of_load(path.R)  # never past the run's target
            step = min(step, settings.target - current)
            stroke = replace(stroke, target=stroke.measure(path.state.u) + step)
            return stroke, (f"control {current:.4g}, stroke {stroke.target:.4g} (drop at a "
                            "fixed stroke)")
        goal = min(current + step, settings.target)
        where = f"control {goal:.4g}" + (" (drop at a fixed deflection)"
                                         if self.name == "drop" else "")
        return DisplacementControl(problem.control_equation, goal), where

    def after_failure(self, exc: Exception, where: str, steps: StepSizeController,
                      settings: SolverSettings, current: float = 0.0,
                      load: float = 0.0) -> None:
        """Cut the step, bisect the bracket of a limit point, or switch to the next control;
        ConvergenceError when none is left. `current`, `load`: the last converged state."""
        reason = getattr(exc, "reason", "non-convergence")
        if (self.name == "displacement" and self.size <= steps.smallest * (1 + 1e-9)
                and self.kinked and not math.isnan(self.omega)):
            # a failure right after a bracket whose end converged (a kink Newton cannot
            # settle): taken in time at once (bisecting again would crawl)
            self.kinked, self.ceiling = False, math.nan
            self._switch("drop", where)
            return
        self.unstable = reason == "unstable"  # its bracket ends in a drop, never a retry
        if self.name == "displacement" and self.size <= steps.smallest * (1 + 1e-9):
            self.ceiling = current + self.size  # the failed deflection bounds the bracket
            if not self.located(current, load, settings):
                self.size *= 0.5
                return
            self.size = steps.smallest  # the next control starts from the located point
        self.ceiling = math.nan
        stop = settings.on_snap_back == "stop"
        if self.name == "drop":
            raise ConvergenceError(f"{exc} at {where}: neither displacement control at its "
                                   "smallest step nor a drop at a fixed deflection converged",
                                   reason=reason) from None
        if self.name == "opening":
            self.release *= 0.5
            if self.release < SMALLEST_OPENING:
                if stop:
                    raise ConvergenceError(
                        f"{exc} at {where}, also under opening control at the smallest "
                        "opening step (analysis.on_snap_back: stop; 'continue' takes the "
                        "drop at a fixed deflection)", reason=reason) from None
                self._switch("drop", where)  # what a stroke-controlled test does
            return
        if self.size > steps.smallest * (1 + 1e-9):
            self.size = steps.after_failure(self.size, where, reason, str(exc))
        elif reason != "singular system" and settings.trace_snap_backs:
            # no equilibrium at the next deflection: a snap-back, followed by its control
            self.release = FIRST_OPENING
            self._switch("opening", where)
        elif stop:  # only the drop would go on
            raise ConvergenceError(f"{exc} at {where} with the smallest step "
                                   f"{steps.smallest:.3g} (analysis.on_snap_back: stop; "
                                   "'continue' takes the drop at a fixed deflection)",
                                   reason=reason) from None
        else:
            self._switch("drop", where)

    def after_success(self, inc: Increment, d_deflection: float, d_load: float,
                      steps: StepSizeController, settings: SolverSettings) -> None:
        """Size the next step, and leave a snap-back control once load and deflection rise
        together again."""
        self.peak = max(self.peak, abs(inc.load_factor))
        if self.name == "drop":
            inc.snap_back, self.name = True, "displacement"
            self.slope = d_load / d_deflection if d_deflection > 0.0 else math.nan
        elif self.name == "opening":
            inc.snap_back = d_deflection < 0.0
            growth = math.sqrt(settings.target_iterations / max(inc.iterations, 1))
            self.release *= min(2.0, max(0.5, growth))
            if abs(inc.load_factor) <= settings.tolerance_load * self.peak:
                # the snap-back has separated the structure (no load left within the
                # tolerance): nothing more to trace, and its tangent is singular; only drops
                # at fixed deflections go on (on_snap_back: stop stops after this step)
                self.halt = settings.on_snap_back == "stop"
                self._switch("drop", "the traced snap-back separated the structure")
            elif d_deflection > STILL * settings.increment and d_load > 0.0:
                # load and deflection rise together again (beyond round-off)
                self.name = "displacement"
                self.size = max(steps.smallest, min(steps.largest, d_deflection))
                self.slope = d_load / d_deflection
        elif math.isnan(self.ceiling):
            self.kinked = self.kinked and self.size <= 2.0 * steps.smallest  # smooth again?
            self.size = steps.after_success(self.size, inc.iterations)
            self.slope = d_load / d_deflection if d_deflection > 0.0 else math.nan
        elif inc.control_displacement >= self.ceiling - LOCATED_WIDTH * settings.increment:
            # its end converged after all: Newton's failure, not a limit point
            self.ceiling, self.size, self.kinked = math.nan, steps.smallest, True
        elif self.located(inc.control_displacement, inc.load_factor, settings):
            if self.unstable:  # located where the stable path ends: the drop from here
                self.ceiling = math.nan
                self._switch("drop", "the located end of the stable path")
            else:
                self.size = self.ceiling - inc.control_displacement  # its end once more
        else:  # locating a limit point: bisect the bracket, never retry its failed end (the
            # slope stays the secant of the step before it: the bound, and not the noise of
            # a load change within the tolerance over a tiny step)
            self.size = 0.5 * (self.ceiling - inc.control_displacement)

    def _switch(self, name: str, where: str) -> None:
        self.name = name
        log.info("%s: %s", where, {"opening": "switching to opening control",
                                   "drop": "a drop at a fixed deflection"}[name])


def _advance_control(problem: Problem, settings: SolverSettings, state: PathState,
                     preload: float, resume: tuple) -> Iterator[tuple[Increment, PathState]]:
    """Displacement control to the target, the snap-back control through snap-backs, a drop
    at a fixed deflection where neither converges."""
    c = problem.constraints
    steps = StepSizeController.of(settings, settings.increment)
    mode, stagnant = _Mode("displacement", steps.largest, 0.0), 0
    if resume:  # (size, release, opening?, stagnant steps, 1/dt, bracket end, slope, peak,
        # omega_1, kinked, unstable, held sign); an older checkpoint's missing tail: defaults
        r = tuple(resume) + (FIRST_INVERSE_STEP, math.nan, math.nan, 0.0, math.nan, 0.0, 0.0,
                             1.0)[len(resume) - 4:]
        mode = _Mode("opening" if r[2] else "displacement", r[0], r[1], r[4], *r[5:8],
                     omega=r[8], kinked=bool(r[9]), unstable=bool(r[10]), held=int(r[11]))
        stagnant = int(r[3])
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
        stagnant = stagnant + 1 if still else 0
        mode.after_success(inc, d_deflection, d_load, steps, settings)
        last_increment = inc.u - state.u
        if math.isnan(mode.omega) and problem.mass is not None:  # the run's first step
            mode.omega = first_mode_frequency(last_increment, d_load, path.R, problem.mass)
        state = _next_state(problem, state, inc, ("control", mode.size, mode.release,
                                                  float(mode.name == "opening"),
                                                  float(stagnant), mode.damping,
                                                  mode.ceiling, mode.slope, mode.peak,
                                                  mode.omega, float(mode.kinked),
                                                  float(mode.unstable), float(mode.held)))
        state.last_increment = last_increment
        path.state = state
        yield inc, state
        if mode.halt:
            raise ConvergenceError(f"the traced snap-back separated the structure at {where}: "
                                   "no load is carried, and only drops at fixed deflections go "
                                   "on (analysis.on_snap_back: stop; 'continue' takes them)",
                                   reason="snap-back")
        if stagnant >= STAGNANT_STEPS and mode.name == "opening":
            mode._switch("drop", where)  # the traced snap-back stalls: the test drops
            stagnant = 0
        if stagnant >= STAGNANT_STEPS:  # after the step is on disk, as every converged one
            raise ConvergenceError(f"the path no longer moves at {where}: {stagnant} converged "
                                   "steps in a row changed neither the deflection nor the "
                                   "load", reason="stagnation")


def follow_path(problem: Problem, settings: SolverSettings, initial: PathState,
                resume: bool = False) -> Iterator[tuple[Increment, PathState]]:
    """Preload by load control (if any), then the control stage to the target deflection;
    `resume` goes on from where `initial.resume` says."""
    current = initial
    stage, start = (initial.resume[0], initial.resume[1:]) if resume else ("", ())
    if problem.preload is not None and stage != "control":
        for inc, current in _advance_preload(problem, settings, initial, start):
            yield inc, current
        start = ()
    preload = 1.0 if problem.preload is not None else 0.0
    yield from _advance_control(problem, settings, current, preload, start)
