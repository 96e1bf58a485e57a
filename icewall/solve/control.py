"""The thesis' secant scheme: load control of the preload (Newton-Raphson with the secant
stiffness) and displacement control (thesis 3.5, eqs. 3.44-3.50, Fig. 3.18 with errata 1.3),
one increment iterated by `_iterate` and the stages of the path by `SecantStage` (the loop:
solve/path.py; what follows a failed step: solve/recovery.py).

Each iteration factorises one matrix and solves it for two right-hand sides: the reference
load R* (3.46) and the unbalance dQ plus the interface rows (3.45); the load-factor increment
follows from eq. 3.48 with the remaining control increment (errata §3: it reduces to 3.49 on
the first iteration and 3.50 afterwards, and absorbs a non-zero first residual).
"""

from __future__ import annotations

import logging
import math
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np

from icewall.errors import ConvergenceError
from icewall.model.structure import Evaluation
from icewall.solve.problem import Problem
from icewall.solve.recovery import Attempt, SnapBack, after_failure, fallbacks
from icewall.solve.state import (
    Increment,
    PathState,
    SecantCursor,
    StepFailed,
    external_force_norm,
)

if TYPE_CHECKING:
    from icewall.solve.settings import SolverSettings

# a load fall above this fraction of the largest load in one increment is suspect (a distant
# equilibrium past a snap-back): halved, and at the smallest step a stop ("snap-back")
SNAP_BACK_DROP = 0.25
MIN_RELAXATION = 0.125
MAX_RELAXATION = 1.0
CYCLE_RISES = 3  # rises of the load norm in an increment before the growth limit halves
log = logging.getLogger(__name__)


def _norm(x: np.ndarray) -> float:
    return float(np.sqrt(x @ x))


def _chatter(problem: Problem, settings: SolverSettings, states, flags_before, changes,
             forensics: dict[str, list[int]]) -> tuple[tuple | None, tuple]:
    """Count Gauss points whose crack/crush/yield flags changed in this iteration; points that
    changed `max_flag_changes` times in the increment may only unload/reload for the rest of
    it (they go on loading in the next increment). Returns the per-group frozen masks (None
    if no point is frozen) and this iteration's flags."""
    flags = problem.point_flags(states)
    total, frozen, any_frozen = 0, [], False
    for k, (new, old) in enumerate(zip(flags, flags_before, strict=True)):
        if new is None:
            frozen.append(None)
            continue
        changed = np.any(new != old, axis=1)
        total += int(np.count_nonzero(changed))
        changes[k] += changed
        mask = changes[k] >= settings.scheme.max_flag_changes
        freezable = problem.structure.groups[k].law.freezable
        frozen.append(mask if freezable and mask.any() else None)
        any_frozen |= frozen[-1] is not None
    forensics["gauss_flag_changes"].append(total)
    forensics.setdefault("gauss_frozen", []).append(
        int(sum(np.count_nonzero(f) for f in frozen if f is not None)))
    return (tuple(frozen) if any_frozen else None), flags


def _relaxation(kind: str, iteration: int, relaxation: float, correction: np.ndarray,
                previous: np.ndarray | None, load_norm: float, previous_load_norm: float,
                growth_limit: float = 1.0) -> float:
    """Relaxation of this iteration's correction (the secant iteration is a fixed-point
    iteration): Aitken's dynamic relaxation from two successive corrections, or halving when
    the load norm grew and growing by half (up to `growth_limit`, which may over-relax the
    slow drift of a softening structure) while it falls. Both damp the limit cycles of Gauss
    points that switch between loading and unloading every iteration; iteration 1 (the
    predictor) is never relaxed."""
    if kind == "none" or iteration < 3 or previous is None:
        return 1.0
    if kind == "aitken":
        difference = correction - previous
        denominator = float(difference @ difference)
        if denominator <= 0.0:
            return relaxation
        omega = -relaxation * float(previous @ difference) / denominator
        return float(np.clip(omega, MIN_RELAXATION, MAX_RELAXATION))
    if load_norm > previous_load_norm:
        return max(MIN_RELAXATION, 0.5 * relaxation)
    return min(growth_limit, 1.5 * relaxation)


def _growth_limit(max_relaxation: float, rises: int) -> float:
    """The largest relaxation the halving scheme may grow back to after the load norm rose
    `rises` times in this increment: halved every CYCLE_RISES rises, so that a limit cycle of
    the secant iteration (grow to 1, overshoot, halve, grow again: CF-14 near its peak repeats
    load norms 0.125, 0.070, 0.066 for 200 iterations) is damped out."""
    return max(MIN_RELAXATION, max_relaxation * 0.5 ** (rises // CYCLE_RISES))


def _residual(c: Any, load_scale: float, ev: Evaluation, external: np.ndarray
              ) -> tuple[np.ndarray, float]:
    """F_ext - F_int on the equations of `c` (no gap forces) and the eq. 4.5 load norm of the
    unbalance (with them)."""
    structural = c.restrict(external - ev.internal_force)
    unbalance = structural - c.restrict(c.constraint_force())
    # eq. 4.5. The reference R is the external force system: applied loads and support
    # reactions (the load reaches the supports through the structure), and never less than
    # the largest reached, so the norm stays meaningful far down the descending branch.
    scale = max(external_force_norm(c, external, ev.internal_force), load_scale, 1e-30)
    return structural, _norm(unbalance) / scale


def _converged(settings: SolverSettings, iteration: int, disp_norm: float, load_norm: float,
               flips: int) -> bool:
    """Eqs. 4.4 and 4.5 met, no gap flipped. The predictor is not a correction: after it only
    the load norm is judged, 100 times tighter (a linear problem converges in one iteration)."""
    displacement_ok = disp_norm <= settings.tolerance_displacement or (
        iteration == 2 and load_norm <= 0.01 * settings.tolerance_load)
    return (iteration > 1 and displacement_ok and load_norm <= settings.tolerance_load
            and flips == 0)


def _correction(problem: Problem, factor: Any, structural: np.ndarray, u: np.ndarray,
                target_deflection: float | None) -> tuple[np.ndarray, np.ndarray, float]:
    """(du, dm, dP), the corrections of u, the multipliers and P: solved for the unbalance (3.45)
    and, under displacement control, for R* (3.46) too, combined by eq. 3.48."""
    c = problem.constraints
    rhs_unbalance = c.unbalance_rhs(structural, u)
    if target_deflection is None:
        du, dm = c.split(factor.solve(rhs_unbalance))
        return du, dm, 0.0
    solution = factor.solve(np.column_stack([c.reference_rhs(problem.reference_load),
                                             rhs_unbalance]))
    (q1, q2), (m1, m2) = (part.T for part in c.split(solution))
    control_1 = -q1[problem.control_equation]
    if not abs(control_1) > 0.0 or not math.isfinite(control_1):
        raise StepFailed("the reference load no longer moves the control point", "snap-back")
    remaining = target_deflection + u[problem.control_equation]  # = target - deflection
    dP = (remaining + q2[problem.control_equation]) / control_1  # eq. 3.48
    return dP * q1 + q2, dP * m1 + m2, dP


def _iterate(problem: Problem, settings: SolverSettings, start: PathState,
             target_deflection: float | None, preload_factor: float,
             damp_cycles: bool = True) -> Increment:
    """Iterate one increment to convergence. target_deflection None means load control;
    damp_cycles False lets the relaxation grow back to its full limit after every rise."""
    s, c = problem.structure, problem.constraints
    u, P = start.u.copy(), start.load_factor
    R = c.restrict(problem.reference_load)
    F_pre = np.zeros_like(u) if problem.preload is None else preload_factor * problem.preload
    c.begin_step()
    forensics: dict[str, list[int]] = {"gauss_flag_changes": [], "gap_flips": []}
    flags_before = problem.point_flags(start.states)
    changes = [None if f is None else np.zeros(len(f), dtype=int) for f in flags_before]
    frozen: tuple | None = None
    disp_norm = load_norm = math.inf
    flips = 0
    factor = None
    relaxation, previous_load_norm, previous_correction = 1.0, math.inf, None
    rises = 0  # times the load norm rose in this increment
    for iteration in range(1, settings.max_iterations + 1):
        ev = s.evaluate(u, start.states, frozen, settings.scheme.iteration_secant == "returned")
        if not np.all(np.isfinite(ev.internal_force)):
            raise StepFailed("non-finite internal forces", "NaN")
        frozen, flags_before = _chatter(problem, settings, ev.states, flags_before, changes,
                                        forensics)
        external = P * R + c.restrict(F_pre)
        structural, load_norm = _residual(c, start.load_scale, ev, external)
        log.debug("iteration %d: displacement norm %.3e, load norm %.3e, load factor %.6g, "
                  "gap flips %d, Gauss-point flag changes %d", iteration, disp_norm, load_norm,
                  P, flips, forensics["gauss_flag_changes"][-1])
        if _converged(settings, iteration, disp_norm, load_norm, flips):
            return Increment("control" if target_deflection is not None else "preload",
                             -float(u[problem.control_equation]), P, preload_factor,
                             iteration - 1, disp_norm, load_norm, ev, u, forensics)
        if factor is None or settings.scheme.stiffness_update == "every_iteration" or flips:
            factor = c.factorize(s.stiffness(ev))
        du, dm, dP = _correction(problem, factor, structural, u, target_deflection)
        if not (np.all(np.isfinite(du)) and math.isfinite(dP)):
            raise StepFailed("non-finite displacement correction", "NaN")
        rises += iteration >= 3 and load_norm > previous_load_norm
        relaxation = _relaxation(settings.scheme.acceleration, iteration, relaxation, du,
                                 previous_correction, load_norm, previous_load_norm,
                                 _growth_limit(settings.scheme.max_relaxation,
                                               rises if damp_cycles else 0))
        previous_correction, previous_load_norm = du, load_norm
        # (multipliers are not relaxed: prescribed ones, e.g. zero on open pairs, stay exact)
        du, dP = relaxation * du, relaxation * dP
        u = u + du
        P = P + dP
        flips = c.apply(dm, u)
        forensics["gap_flips"].append(int(flips))
        disp_norm = _norm(du) / max(_norm(u), 1e-30)  # eq. 4.4
    raise StepFailed(f"no convergence in {settings.max_iterations} iterations (displacement "
                     f"norm {disp_norm:.3g}, load norm {load_norm:.3g})", "non-convergence")


class SecantStage:
    """A stage of the secant scheme (solve.path.Stage): the preload by load control to its
    whole, or displacement control to the target, in steps of the deck's size; a failed step
    and a load drop displacement control cannot follow are cut (recovery.after_failure), and
    at the smallest step such a drop is accepted as a snap-through at the held deflection
    (on_snap_back: continue) or ends the run."""

    direction = None  # the secant iteration keeps no predictor direction

    def __init__(self, name: str, problem: Problem, settings: SolverSettings,
                 state: PathState, cursor: SecantCursor | None = None) -> None:
        control = name == "control"
        self.name, self.problem, self.settings = name, problem, settings
        self.target = settings.target if control else 1.0
        self.preload = 1.0 if problem.preload is not None else 0.0
        self.step_size = settings.increment if control else 1.0 / settings.preload_increments
        self.smallest = self.step_size / 2 ** settings.max_step_cuts * (1 + 1e-9)
        self.current = (-float(state.u[problem.control_equation]) if control
                        else state.preload_factor)
        self.attempt, self.peak = Attempt(self.step_size), state.load_factor
        if cursor is not None:  # the checkpoint holds the jumps: a resumed run makes no more
            self.current, self.peak = cursor.position, cursor.peak
            self.attempt = Attempt(cursor.size, jumps=cursor.jumps)
        self.goal, self.snap = self.current, False

    def done(self, state: PathState) -> bool:
        return not self.current < self.target - 1e-12 * max(1.0, abs(self.target))

    def step(self, state: PathState) -> Increment:
        """The increment to the next goal under the try's iteration; SnapBack where its load
        drops more than the path can follow and the step is not yet the smallest."""
        settings, attempt = self.settings, self.attempt
        self.goal = min(self.current + attempt.size, self.target)
        scheme, damp_cycles = fallbacks(settings)[attempt.retry]
        if self.name == "control":
            inc = _iterate(self.problem, scheme, state, self.goal, self.preload, damp_cycles)
        else:
            inc = _iterate(self.problem, scheme, state, None, self.goal, damp_cycles)
        self.snap = self.name == "control" and _abrupt_drop(state, inc, self.peak)
        if self.snap and not ((attempt.size <= self.smallest or attempt.jumping)
                              and settings.on_snap_back == "continue"):
            raise SnapBack(
                f"snap-back at the control point: the load drops from {state.load_factor:.4g}"
                f" to {inc.load_factor:.4g} within {self.goal - self.current:.3g} mm and the "
                f"drop does not shrink with the step ({settings.max_step_cuts} cuts); "
                "displacement control cannot follow this branch")
        return inc

    def failed(self, exc: StepFailed | ConvergenceError, state: PathState) -> None:
        self.attempt = after_failure(exc, self.settings, self.name, self.goal, self.current,
                                     self.step_size, self.smallest, self.attempt)

    def converged(self, state: PathState, inc: Increment) -> Increment:
        """The increment with its flags (jumped, snap_back, cuts); the next try grows back
        after a cut step, with the deck's iteration and no jump under way."""
        if self.snap:  # accepted load drop (on_snap_back: continue)
            log.info("snap-back at %.4g mm accepted: load %.4g -> %.4g", self.goal,
                     state.load_factor, inc.load_factor)
        attempt = self.attempt
        self.peak = max(self.peak, inc.load_factor)
        self.current = self.goal
        self.attempt = Attempt(min(self.step_size, 2.0 * attempt.size), jumps=attempt.jumps)
        return replace(inc, jumped=attempt.jumping, snap_back=bool(self.snap),
                       cuts=round(math.log2(self.step_size / attempt.size)))

    def cursor(self) -> SecantCursor:
        return SecantCursor(self.name, self.current, self.attempt.size, self.peak,
                            self.attempt.jumps)

    def stop(self) -> None:
        """Nothing ends the stage after a converged step."""


def _abrupt_drop(state: PathState, inc: Increment, peak_load: float) -> bool:
    return (peak_load > 0.0 and inc.load_factor < state.load_factor
            and state.load_factor - inc.load_factor > SNAP_BACK_DROP * peak_load)
