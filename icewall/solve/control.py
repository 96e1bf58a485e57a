"""Path following: load control of the preload (Newton-Raphson with the secant stiffness) and
displacement control (thesis 3.5, eqs. 3.44-3.50, Fig. 3.18 with errata 1.3), each a generator
of converged increments so that the writer keeps every converged step on disk.

Each iteration factorises one matrix and solves it for two right-hand sides: the reference
load R* (3.46) and the unbalance dQ plus the interface rows (3.45); the load-factor increment
follows from eq. 3.48 with the remaining control increment (errata §3: it reduces to 3.49 on
the first iteration and 3.50 afterwards, and absorbs a non-zero first residual).
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Iterator
from dataclasses import replace
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from icewall.errors import ConvergenceError
from icewall.model.structure import Evaluation
from icewall.solve.problem import Problem
from icewall.solve.state import (
    Increment,
    PathState,
    SecantCursor,
    StepFailed,
    external_force_norm,
    next_state,
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


class _Attempt(NamedTuple):
    """_advance's next try: its step size, iteration scheme (index into _schemes), the steps
    over a stall made so far (the scheme's max_jumps) and whether this try is one."""

    size: float
    retry: int = 0
    jumps: int = 0
    jumping: bool = False


def _after_failure(exc: StepFailed | ConvergenceError, settings: SolverSettings, kind: str,
                   goal: float, current: float, step_size: float, smallest: float,
                   attempt: _Attempt) -> _Attempt:
    """The try after a failed increment to `goal`: on the smallest step each fallback scheme,
    then a step over the stall (control only), else half the step; ConvergenceError if none."""
    reason = getattr(exc, "reason", "non-convergence")
    size, retry, jumps, jumping = attempt
    if (size <= smallest and reason == "non-convergence"
            and retry < len(_schemes(settings)) - 1):
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
        return _Attempt(size, 0, jumps + 1, True)
    if jumping:
        raise ConvergenceError(f"{exc} at {kind} {goal:.4g}, also when stepping over "
                               f"the stall ({jumps} jumps)", reason=reason) from None
    if size <= smallest:
        raise ConvergenceError(f"{exc} at {kind} {goal:.4g} after "
                               f"{settings.max_step_cuts} step cuts",
                               reason=reason) from None
    return attempt._replace(size=0.5 * size)


def _advance(problem: Problem, settings: SolverSettings, state: PathState, target, preload,
             step_size: float, kind: str, resume: SecantCursor | None = None
             ) -> Iterator[tuple[Increment, PathState]]:
    """Reach `target` (deflection or preload fraction) from `state`, halving failed steps."""
    c = problem.constraints
    smallest = step_size / 2 ** settings.max_step_cuts * (1 + 1e-9)
    current = (-float(state.u[problem.control_equation]) if kind == "control"
               else state.preload_factor)
    attempt = _Attempt(step_size)
    peak_load = state.load_factor
    if resume is not None:  # the checkpoint holds the jumps: a resumed run makes no more
        current, peak_load = resume.position, resume.peak
        attempt = _Attempt(resume.size, jumps=resume.jumps)
    while current < target - 1e-12 * max(1.0, abs(target)):
        goal = min(current + attempt.size, target)
        tic = time.perf_counter()
        scheme, damp_cycles = _schemes(settings)[attempt.retry]
        try:
            if kind == "control":
                inc = _iterate(problem, scheme, state, goal, preload, damp_cycles)
            else:
                inc = _iterate(problem, scheme, state, None, goal, damp_cycles)
        except (StepFailed, ConvergenceError) as exc:
            c.rollback()
            attempt = _after_failure(exc, settings, kind, goal, current, step_size, smallest,
                                     attempt)
            continue
        snap = kind == "control" and _abrupt_drop(state, inc, peak_load)
        if snap and not ((attempt.size <= smallest or attempt.jumping)
                         and settings.on_snap_back == "continue"):
            c.rollback()
            if attempt.size <= smallest:
                raise ConvergenceError(
                    f"snap-back at the control point: the load drops from {state.load_factor:.4g}"
                    f" to {inc.load_factor:.4g} within {goal - current:.3g} mm and the drop does "
                    f"not shrink with the step ({settings.max_step_cuts} cuts); displacement "
                    "control cannot follow this branch", reason="snap-back") from None
            attempt = attempt._replace(size=0.5 * attempt.size)
            continue
        c.commit()
        inc.jumped = attempt.jumping
        inc.snap_back = bool(snap)  # accepted load drop (on_snap_back: continue)
        if snap:
            log.info("snap-back at %.4g mm accepted: load %.4g -> %.4g", goal,
                     state.load_factor, inc.load_factor)
        peak_load = max(peak_load, inc.load_factor)
        inc.cuts = round(math.log2(step_size / attempt.size))
        inc.wall_time = time.perf_counter() - tic
        current = goal
        # grow back after a successful cut step; the deck's scheme again, no jump under way
        attempt = _Attempt(min(step_size, 2.0 * attempt.size), jumps=attempt.jumps)
        state = next_state(problem, state, inc,
                           SecantCursor(kind, current, attempt.size, peak_load, attempt.jumps))
        yield inc, state


FALLBACKS = 4
"""Iteration schemes tried at most, in turn, on a smallest step that did not converge."""

LONG_ITERATIONS = 3
"""The last fallback iterates this many times the deck's iteration limit (a snap-through)."""


def _schemes(settings: SolverSettings) -> list[tuple[SolverSettings, bool]]:
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


def _abrupt_drop(state: PathState, inc: Increment, peak_load: float) -> bool:
    return (peak_load > 0.0 and inc.load_factor < state.load_factor
            and state.load_factor - inc.load_factor > SNAP_BACK_DROP * peak_load)


def follow_path(problem: Problem, settings: SolverSettings, initial: PathState,
                resume: bool = False) -> Iterator[tuple[Increment, PathState]]:
    """Preload by load control (if any), then displacement control to the target; `resume`
    goes on from where `initial.cursor` says (an interrupted run's last converged step)."""
    current = initial
    cursor = initial.cursor if resume else None
    stage = "" if cursor is None else cursor.stage
    if problem.preload is not None and stage != "control":
        for inc, current in _advance(problem, settings, initial, 1.0, None,
                                     1.0 / settings.preload_increments, "preload", cursor):
            yield inc, current
        cursor = None
    preload = 1.0 if problem.preload is not None else 0.0
    yield from _advance(problem, settings, current, settings.target, preload,
                        settings.increment, "control", cursor)
