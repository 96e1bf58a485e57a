"""Newton-Raphson iteration of one increment with the consistent tangent and a line search.

One iteration: add the consistent tangent to the evaluation of the current iterate (stress,
internal force; the line search's trials are evaluated without it), factorise the augmented
tangent (supports and gap elements, whose pair states are updated after every solve: an
active-set Newton on the contact and stick-slip conditions), solve for the reference load and
the unbalance (bordering, eq. 3.48: the control displacement reaches its target exactly after
every full step), and take the step scaled by a backtracking line search on the equilibrium
norm. Converged means: displacement norm (eq. 4.4) and load norm (eq. 4.5) within the
tolerances, the control's constraint met (a step of length eta leaves 1 - eta of it: an
equilibrium short of the target is not the increment asked for), and no pair changed state in
the last iteration; the constitutive law is never frozen or relaxed, so a converged increment
is an equilibrium of the law as it is.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from icewall.errors import ConvergenceError
from icewall.solve.controls import LoadControl
from icewall.solve.integrator import TimeStep
from icewall.solve.problem import Problem
from icewall.solve.state import Increment, PathState, StepFailed, external_force_norm

if TYPE_CHECKING:
    from icewall.solve.drop import Dampers
    from icewall.solve.settings import SolverSettings

log = logging.getLogger(__name__)

LINE_SEARCH_CUTS = 5
"""Halvings of the step length tried when a full Newton step raises the unbalance."""
STALL_ITERATIONS = 8
"""An increment whose worse norm (each over its tolerance) has not fallen below STALL_GAIN of
its best for this many iterations has stalled: it fails at once, as at the iteration limit. A
Newton iteration cycling among the branches of kinked laws (a softening point loading or
unloading, an axis swap, a pair opening and closing) does not converge by going on; the path
following cuts or bisects the step (docs/solver.md, item 38)."""
STALL_GAIN = 0.9
CONTROL_ROUNDOFF = 1e-12
"""A control's constraint is met within this fraction of its target besides the displacement
tolerance of the increment's change (the round-off of a held target)."""
LINE_SEARCH_RISE = 4.0
"""While the pair states still change, a step is backtracked only when its unbalance exceeds
this multiple of the current one (the active set walks the load; a decrease is not required);
once they have settled, whenever it does not decrease (Armijo with a zero slope factor)."""


def _norm(x: np.ndarray) -> float:
    return float(np.sqrt(x @ x))


@dataclass
class Iterate:
    """A point of the Newton iteration: displacements, load factor and what they give."""

    u: np.ndarray
    load_factor: float
    evaluation: object
    structural: np.ndarray  # F_ext - F_int on the free equations, without gap forces
    unbalance: np.ndarray  # structural - C^T lam
    scale: float  # the eq. 4.5 reference: external loads and reactions

    @property
    def load_norm(self) -> float:
        """Eq. 4.5."""
        return _norm(self.unbalance) / self.scale


def _evaluate(problem: Problem, start: PathState, u: np.ndarray, P: float,
              F_pre: np.ndarray, R: np.ndarray, lam_force: np.ndarray | None = None,
              dampers: Dampers | None = None) -> Iterate:
    s, c = problem.structure, problem.constraints
    ev = s.evaluate(u, start.states)  # its tangent when a matrix is built from it
    if not np.all(np.isfinite(ev.internal_force)):
        raise StepFailed("non-finite internal forces", "NaN")
    external = P * R + c.restrict(F_pre)
    structural = c.restrict(external - ev.internal_force)
    if dampers is not None:  # a sub-step of a drop (icewall.solve.drop)
        structural = structural - c.restrict(dampers.force(u))
    gap_force = c.restrict(c.constraint_force()) if lam_force is None else lam_force
    unbalance = structural - gap_force
    scale = max(external_force_norm(c, external, ev.internal_force), start.load_scale, 1e-30)
    return Iterate(u, P, ev, structural, unbalance, scale)


def _trial_gap_force(problem: Problem, multiplier_increment: np.ndarray, eta: float):
    """C^T (lam + eta dlam) on the free equations: the gap forces of a trial step length."""
    c = problem.constraints
    C = getattr(c, "C", None)
    if C is None or multiplier_increment.size == 0:
        return c.restrict(np.zeros(c.n_equations))
    return c.restrict(C.T @ (c.state.lam + eta * multiplier_increment))


PREDICTOR_PROBE = 1e-6
"""The first iteration's tangent is taken this fraction of the last increment ahead."""
PROBE_FLOOR = 1e-9
"""... but never less than this fraction of the displacements ahead: a shorter probe is lost
in the round-off of the strains, and at a point on a kink of its law (a located limit point:
docs/solver.md, item 35) the tangent would be that of whichever side the last bits fall on."""


def _probe(u: np.ndarray, last_increment: np.ndarray) -> np.ndarray:
    """Where the first iteration's tangent is taken: ahead of u along the last increment."""
    size = _norm(last_increment)
    scale = max(PREDICTOR_PROBE, PROBE_FLOOR * _norm(u) / size)
    return u + scale * last_increment


def newton_increment(problem: Problem, settings: SolverSettings, start: PathState,
                     control, preload_factor: float, kind: str = "control",
                     last_increment: np.ndarray | None = None,
                     dampers: Dampers | None = None) -> Increment:
    """Iterate one increment to convergence by Newton-Raphson under `control`
    (icewall.solve.controls: load, displacement or dissipation control; the preload at
    `preload_factor`). Raises StepFailed when it does not converge in
    `settings.max_iterations`. `last_increment`: the displacements of the last converged
    increment; the predictor's tangent is taken a PREDICTOR_PROBE of it ahead of the committed
    state, so that a point that was loading on its envelope predicts with its loading branch
    (at the committed state itself every point unloads: its secant). `dampers`: a sub-step
    of a drop at a fixed deflection (icewall.solve.drop.Dampers: their force in the residual,
    D / dt in the matrix)."""
    c = problem.constraints
    R = c.restrict(problem.reference_load)
    F_pre = (np.zeros_like(start.u) if problem.preload is None
             else preload_factor * problem.preload)
    c.begin_step(time_step=isinstance(dampers, TimeStep))
    forensics: dict[str, list[int]] = {"gap_flips": [], "line_search": [],
                                       "gauss_flag_changes": []}
    current = _evaluate(problem, start, start.u.copy(), start.load_factor, F_pre, R,
                        dampers=dampers)
    flags = problem.point_flags(current.evaluation.states)
    disp_norm, flips = math.inf, 0
    previous_moduli = None
    forensics["chords"] = []
    limit = settings.max_iterations
    stall = _Stall(settings)
    # the constraint met: within the displacement tolerance of the increment's change
    unmet = (settings.tolerance_displacement * abs(control.residual(start.u, start.load_factor))
             + CONTROL_ROUNDOFF * abs(getattr(control, "target", 0.0)))
    for iteration in range(1, limit + 2):  # the last correction's iterate is tested too
        log.debug("newton %d: displacement norm %.3e, load norm %.3e, load factor %.6g, "
                  "gap flips %d, Gauss-point flag changes %s, step length %s", iteration,
                  disp_norm, current.load_norm, current.load_factor, flips,
                  (forensics["gauss_flag_changes"] or ["-"])[-1],
                  (forensics["line_search"] or ["-"])[-1])
        # after the first correction only the load norm can be judged: met 100 times tighter
        # (a linear problem then converges in one iteration), as in the secant scheme
        displacement_ok = disp_norm <= settings.tolerance_displacement or (
            iteration == 2 and current.load_norm <= 0.01 * settings.tolerance_load)
        if (iteration > 1 and displacement_ok and current.load_norm <= settings.tolerance_load
                and abs(control.residual(current.u, current.load_factor)) <= unmet
                and _constraints_hold(problem, settings, current,
                                      _gap_scale(start, current, dampers))):
            return Increment(kind, -float(current.u[problem.control_equation]),
                             current.load_factor, preload_factor, iteration - 1, disp_norm,
                             current.load_norm, current.evaluation, current.u, forensics)
        if iteration > 1 and stall.stalled(iteration, disp_norm, current.load_norm):
            raise StepFailed(f"stalled: no convergence in {iteration - 1} Newton iterations "
                             f"(the norms have not fallen below {STALL_GAIN:g} of their best "
                             f"for {STALL_ITERATIONS}; displacement norm {disp_norm:.3g}, load "
                             f"norm {current.load_norm:.3g})", "non-convergence")
        if iteration > limit:
            break
        tangent = problem.structure.with_tangent(current.evaluation)
        matrix_at = tangent
        if iteration == 1 and last_increment is not None and _norm(last_increment) > 0.0:
            matrix_at = problem.structure.evaluate(
                _probe(current.u, last_increment), start.states, tangent=True)
        elif previous_moduli is not None:
            matrix_at = _chords_at_kinks(tangent, current.evaluation.moduli, previous_moduli,
                                         forensics)
        previous_moduli = tangent.moduli
        du, dP, dm = _newton_direction(problem, current, control, matrix_at, dampers)
        eta, trial = _line_search(problem, start, current, du, dP, dm, F_pre, R,
                                  LINE_SEARCH_RISE if flips else 1.0, dampers)
        forensics["line_search"].append(round(math.log2(1.0 / eta)))
        flips = c.apply(eta * dm, trial.u)
        forensics["gap_flips"].append(int(flips))
        new_flags = problem.point_flags(trial.evaluation.states)
        forensics["gauss_flag_changes"].append(_count_changes(flags, new_flags))
        if log.isEnabledFor(logging.DEBUG) and forensics["gauss_flag_changes"][-1]:
            log.debug("  flag changes per column of each group (the laws' flags): "
                      "%s", _changes_per_column(flags, new_flags))
        flags = new_flags
        # the gap forces after the pair states were updated
        trial.unbalance = trial.structural - c.restrict(c.constraint_force())
        disp_norm = eta * _norm(du) / max(_norm(trial.u), 1e-30)  # eq. 4.4
        current = trial
    raise StepFailed(f"no convergence in {limit} Newton iterations "
                     f"(displacement norm {disp_norm:.3g}, load norm {current.load_norm:.3g})",
                     "non-convergence")


class _Stall:
    """The best of the worse of the two norms (each over its tolerance) so far, and when."""

    def __init__(self, settings: SolverSettings) -> None:
        self.tolerances = (settings.tolerance_displacement, settings.tolerance_load)
        self.best, self.at = math.inf, 0

    def stalled(self, iteration: int, disp_norm: float, load_norm: float) -> bool:
        """Record an iterate's norms; True once STALL_ITERATIONS went by without a gain."""
        merit = max(disp_norm / self.tolerances[0], load_norm / self.tolerances[1])
        if merit < STALL_GAIN * self.best:
            self.best, self.at = merit, iteration
        return iteration - self.at >= STALL_ITERATIONS


def _constraints_hold(problem: Problem, settings: SolverSettings, current: Iterate,
                      gap_scale: float) -> bool:
    """The pair states' targets and forces hold to the tolerances (gaps against the
    displacement tolerance times `gap_scale`, forces against the load norm of eq. 4.5): the
    pairs that changed carried no force and had no gap, and no row was left short of its
    target by a shortened step (a line search's eta < 1 leaves 1 - eta of every row's
    correction: CF-14's time step at 6.7 mm was taken with a pair that had closed in its first
    iteration still 0.113 mm deep, docs/solver.md item 49)."""
    gap, force = problem.constraints.constraint_residuals(current.u)
    return (gap <= settings.tolerance_displacement * gap_scale
            and force <= settings.tolerance_load * current.scale)


def _gap_scale(start: PathState, current: Iterate, dampers: Dampers | None) -> float:
    """What a pair's gap is measured against: the displacements (eq. 4.4) in a static step, the
    step's own motion in a time step. A pair that closed in a time step's last iteration and
    was committed penetrating is pulled shut by the next step whatever its length, a jump of
    its nodes at a velocity gap / dt that no shorter step reduces (TF-1 at 14.98 mm: 0.011 mm,
    within 1e-4 of the displacements; the error test shrank the step to 1e-6 of the period and
    the step taken there put 5e9 N mm into motion). Within the step's motion, it is a
    penetration the integrator resolves."""
    if isinstance(dampers, TimeStep):
        return _norm(current.u - start.u)
    return _norm(current.u)


KINK_JUMP = 0.1
"""A Gauss point whose tangent moduli jumped by more than this fraction in an iteration has
crossed a kink of its law (loading/unloading, a peak): its secant stands in the matrix."""


def _chords_at_kinks(tangent: object, secant: np.ndarray, previous_moduli: np.ndarray,
                     forensics: dict) -> object:
    """The evaluation whose moduli build the matrix: the consistent tangent (`tangent`, an
    evaluation), except at the points whose tangent jumped from `previous_moduli` in the last
    iteration (a kink crossed), where the law's secant (its iteration moduli, `secant`) is
    taken: Newton on a kinked function cycles across the kink, the secant (a chord through
    the origin of the point's branch) does not. The residual is the law's as it is; only the
    matrix changes."""
    moduli = tangent.moduli
    jump = np.linalg.norm(moduli - previous_moduli, axis=(-2, -1))
    size = np.maximum(np.linalg.norm(previous_moduli, axis=(-2, -1)), 1e-30)
    kinked = jump > KINK_JUMP * size
    forensics["chords"].append(int(np.count_nonzero(kinked)))
    if not kinked.any():
        return tangent
    return replace(tangent, moduli=np.where(kinked[..., None, None], secant, moduli))


def _count_changes(before, after) -> int:
    """Gauss points whose crack/crush/softening/axis flags differ between two iterates."""
    return int(sum(np.count_nonzero(np.any(a != b, axis=1))
                   for a, b in zip(before, after, strict=True) if a is not None))


def _changes_per_column(before, after) -> list[list[int]]:
    """Per group, how many points changed each flag column (-vv forensics)."""
    return [np.count_nonzero(a != b, axis=0).tolist()
            for a, b in zip(before, after, strict=True) if a is not None]


def _newton_direction(problem: Problem, current: Iterate, control, matrix_at,
                      dampers: Dampers | None = None) -> tuple[np.ndarray, float, np.ndarray]:
    """(du, dP, dlam) of a full Newton step: one factorisation of the augmented tangent (plus
    a drop sub-step's D / dt), two solves (reference load and unbalance), the load factor from
    the control's row."""
    c = problem.constraints
    factor = _factorize(problem, current, matrix_at, dampers)
    rhs_unbalance = c.unbalance_rhs(current.structural, current.u)
    if isinstance(control, LoadControl):
        du, dm = c.split(factor.solve(rhs_unbalance))
        return du, 0.0, dm
    solution = factor.solve(np.column_stack([c.reference_rhs(problem.reference_load),
                                             rhs_unbalance]))
    (q1, q2), (m1, m2) = c.split(solution)[0].T, c.split(solution)[1].T
    dP = control.correction(current.u, current.load_factor, q1, q2)
    if not math.isfinite(dP):
        raise StepFailed("the control no longer fixes the load factor (singular bordering)",
                         "snap-back")
    du, dm = dP * q1 + q2, dP * m1 + m2
    if not np.all(np.isfinite(du)):
        raise StepFailed("non-finite displacement correction", "NaN")
    return du, dP, dm


def _factorize(problem: Problem, current: Iterate, matrix_at, dampers: Dampers | None):
    """The factorisation of the iteration matrix built from `matrix_at`. Where the consistent
    tangent is singular (a Gauss point sitting on a kink of its law, whose tangent there is
    the branch's it rounds to: the snap-back bar's weak element at its peak strain), the law's
    secant moduli at the same iterate (a chord through the origin of each point's branch)
    stand in the matrix instead; the residual stays the law's as it is (docs/solver.md, item
    35). A system singular under both is singular."""
    s, c = problem.structure, problem.constraints
    shift = None if dampers is None else dampers.shift()
    K = s.stiffness(matrix_at)
    try:
        return c.factorize(K if shift is None else K + shift)
    except ConvergenceError as exc:
        if exc.reason != "singular system" or not getattr(matrix_at, "tangent", False):
            raise
        log.debug("singular consistent tangent (%s): the secant moduli stand in", exc)
    K = s.stiffness(current.evaluation)
    return c.factorize(K if shift is None else K + shift)


def _line_search(problem: Problem, start: PathState, current: Iterate, du: np.ndarray,
                 dP: float, dm: np.ndarray, F_pre: np.ndarray, R: np.ndarray,
                 rise: float, dampers: Dampers | None = None) -> tuple[float, Iterate]:
    """Step length eta and the iterate it gives: the full step unless its unbalance (with the
    gap multipliers moved by eta dlam at their current states) exceeds `rise` times the
    current one; then halve, keeping the best step length tried. Both unbalances are taken
    against the load the full step aims at, P + dP: the bordered step solves equilibrium and
    the control's constraint together, and the constraint's part of the unbalance is the
    load it still asks for, (1 - eta) dP R (at a converged start the current unbalance
    alone is round-off, against which any step looks worse)."""
    eta, best, full = 1.0, None, None  # full: the trial of the full step
    reference = _norm(current.unbalance + dP * R)
    for _ in range(LINE_SEARCH_CUTS + 1):
        trial = _evaluate(problem, start, current.u + eta * du, current.load_factor + eta * dP,
                          F_pre, R, _trial_gap_force(problem, dm, eta), dampers)
        merit = _norm(trial.unbalance + (1.0 - eta) * dP * R)
        full = full or trial
        if best is None or merit < best[0]:
            best = (merit, eta, trial)
        if merit <= rise * reference or reference == 0.0:
            return eta, trial
        eta *= 0.5
    # no step length lowers the unbalance: along this direction the residual is not smooth
    # (a kink within the step); the full step leaves the kink's neighbourhood, where the
    # chords (_chords_at_kinks) take over, while a tiny one stalls in front of it
    # (unless the direction has gone wild: a load-factor change larger than the load factor,
    # as a control row that is nearly singular at its first iterate gives)
    if abs(dP) <= abs(current.load_factor):
        return 1.0, full
    return best[1], best[2]


def static_load_norm(problem: Problem, inc: Increment, load_scale: float) -> float:
    """Eq. 4.5 of a converged increment without any damper force: the unbalance of the
    external loads, the internal forces and the gap forces, over the external force system
    (never less than `load_scale`)."""
    c = problem.constraints
    applied = c.restrict(inc.load_factor * problem.reference_load + (
        0.0 if problem.preload is None else inc.preload_factor * problem.preload))
    unbalance = c.restrict(applied - inc.evaluation.internal_force - c.constraint_force())
    scale = max(external_force_norm(c, applied, inc.evaluation.internal_force), load_scale,
                1e-30)
    return _norm(unbalance) / scale
