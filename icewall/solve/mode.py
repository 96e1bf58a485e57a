"""The Newton scheme's control stage as a state machine (`Mode`): the control of the next step
and its size, and what follows a failed or a converged step - a cut, the bisection of a limit
point's bracket, the switch to the snap-back control or to a drop. Its fields are where the
stage goes on: the path state holds a copy of it whole, and the checkpoint writes and reads it
field by field (solve/checkpoint.py)."""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, ClassVar

from icewall.errors import ConvergenceError
from icewall.solve.controls import DisplacementControl, StrokeControl
from icewall.solve.drop import FIRST_INVERSE_STEP
from icewall.solve.problem import Problem
from icewall.solve.state import Increment
from icewall.solve.steps import StepSizeController

if TYPE_CHECKING:
    from icewall.solve.newton_stages import _Path
    from icewall.solve.settings import SolverSettings

log = logging.getLogger(__name__)

FIRST_OPENING = 0.05
"""First opening step after a switch, as a fraction of the cracking strain of the set."""
SMALLEST_OPENING = 1e-8
"""Opening steps below this fraction of the cracking strain of the set stop the run."""
STILL = 1e-9
"""A converged step that changes the deflection by less than this fraction of the increment
and the load factor by less than this fraction of itself has not moved the path."""
LOCATED_WIDTH = 1e-12
"""A limit point's bracket narrower than this fraction of the increment is located whatever
the slope (round-off of the deflection itself)."""


@dataclass
class Mode:
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

    kind: ClassVar[str] = "mode"  # its name in the checkpoint (solve/checkpoint.py)
    stage: ClassVar[str] = "control"
    name: str
    size: float
    release: float
    damping: float = FIRST_INVERSE_STEP
    ceiling: float = math.nan  # the smallest deflection that failed in the bracket (locating)
    slope: float = math.nan  # the secant dP/dd of the last converged displacement step
    peak: float = 0.0  # the largest |load factor| so far: the scale of a separated structure
    omega: float = math.nan  # the wall's first-mode frequency (rad/s): the drops' damping
    kinked: bool = False  # after a located bracket whose end converged (Newton's failure)
    unstable: bool = False  # the last failure was an unstable state, not a Newton failure
    held: int = 1  # the held determinant's sign at the last stable state (-1: a tested rest)
    stagnant: int = 0  # converged steps in a row that did not move the path
    # stop after the step just taken (on_snap_back: stop, separated): not where a run goes on
    halt: bool = field(default=False, metadata={"transient": True})

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
        if self.name == "drop" and (settings.scheme.drop_held == "stroke"
                                    or settings.scheme.inertia):
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
        elif reason != "singular system" and settings.scheme.trace_snap_backs:
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
                      steps: StepSizeController, settings: SolverSettings) -> bool:
        """Size the next step, and leave a snap-back control once load and deflection rise
        together again; whether the step is a snap-back (a drop, or a traced step whose
        deflection turned back)."""
        self.peak = max(self.peak, abs(inc.load_factor))
        snap_back = False
        if self.name == "drop":
            snap_back, self.name = True, "displacement"
            self.slope = d_load / d_deflection if d_deflection > 0.0 else math.nan
        elif self.name == "opening":
            snap_back = d_deflection < 0.0
            growth = math.sqrt(settings.scheme.target_iterations / max(inc.iterations, 1))
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
        return snap_back

    def _switch(self, name: str, where: str) -> None:
        self.name = name
        log.info("%s: %s", where, {"opening": "switching to opening control",
                                   "drop": "a drop at a fixed deflection"}[name])
