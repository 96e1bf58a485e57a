"""The load drop at a held stroke, integrated in time with the wall's own mass.

Where the static path under the held quantity has a limit point (`mode.Mode.located`:
displacement control fails beyond a located limit), a stroke-controlled test holds its stroke
while the wall's resistance falls, and the wall moves, with its own mass, to the state it comes
to rest in; the load cell records the vertical drop of the stroke curve. Inertia selects that
state. The motion is integrated by generalized-alpha (`solve.integrator`), each time step the
static Newton iteration of every step (`newton.newton_increment`) with the inertia and damping
as an extra force and in its matrix, converged to the deck's tolerances and committed: the
laws, the pairs and friction follow the motion. The held stroke (its row fixes the jack load,
the bordering of eq. 3.48) moves to the drop's target on a smooth ramp.

M is the HRZ-lumped mass (`fem.mass`) of the deck's densities (plus a loading head's), C the
mass-proportional Rayleigh damping 2 xi omega_1 M at the wall's first mode (omega_1 from the
Rayleigh quotient of the static response to the jack loads at the run's first step). The time
step follows a local error estimate (Zienkiewicz & Xie 1991: (beta - 1/6) dt^2 (a1 - a0) against
the drop's motion) and the iteration count, below a twentieth of the first period, and below
half the e-folding time of the fastest unstable mode where a static step from the motion finds
an unstable equilibrium (`stability.fastest_growth`: a longer implicit step holds the wall on
it); `analysis.time_step_scale` scales every one.

The drop ends where the motion no longer changes the equilibrium it settles about: every half
period (CHECK_PERIODS) a static Newton step from the moving state seeks the equilibrium at the
held stroke; where it is stable and agrees with the last one found (the load factor within
the deck's load tolerance, the displacements within its displacement tolerance of the drop's
motion) or takes out less than KINETIC_END of what the drop moved, the drop ends there. What
the vibration still held (its kinetic energy and the work of the forces the inertia held) is
what the damping would have taken, booked as the kinetic energy left. A state whose static
unbalance meets the tolerances as it stands, with the kinetic energy below KINETIC_END of what
the drop moved, ends it at once. Its work terms are summed over the time steps
(`DropEnergy`), so the energy balance of the run (external = stored + dissipated + damped +
kinetic + the integrator's numerical dissipation, from each time step's work identity:
solve/energy.py) stays closed through it.
"""

from __future__ import annotations

import logging
import math
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from icewall.errors import ConvergenceError
from icewall.solve.energy import DropEnergy, structural_unbalance
from icewall.solve.imperfection import Seed
from icewall.solve.integrator import Dynamics, GeneralizedAlpha, Motion, TimeStep, ramp
from icewall.solve.newton import newton_increment, static_load_norm
from icewall.solve.problem import Problem
from icewall.solve.stability import fastest_growth, stable_under_stroke
from icewall.solve.state import Increment, PathState, StepFailed

if TYPE_CHECKING:
    from icewall.solve.settings import SolverSettings

log = logging.getLogger(__name__)

STEPS_PER_PERIOD = 40
"""The first time step of a drop: this fraction of the first period."""
LARGEST_STEP = 1.0 / 20.0
"""The largest time step, as a fraction of the first period (times time_step_scale): the first
mode stays resolved, and so does a mode that grows at its rate. (An implicit step much longer
than a growing mode's e-folding time damps its growth: a drop whose steps grew without bound
stood still on the unstable equilibrium it was to leave, CF-4 at 10.93 mm.)"""
RESOLVED_GROWTH = 0.5
"""Where the equilibrium a static step from the motion reaches is unstable, the time step is at
most this over the growth rate of its fastest unstable mode (`stability.fastest_growth`):
an implicit step longer than the growth's e-folding time holds the wall on the unstable
state (CF-4 at 10.93 mm: a local mode growing at 99 omega_1 under steps of 1/20 of the
period, 40 periods at rest; under steps of 1/1240 it left in 0.7 of a period). The bound is
lifted once the moving state's tangent is stable again (tested every CHECK_EVERY steps)."""
CHECK_EVERY = 10
"""Time steps between two tests of that, while the bound holds (one sparse LU each)."""
TIME_TOLERANCE = 1e-2
"""Local error of a time step, (beta - 1/6) dt^2 |a1 - a0|, against the displacement the drop
has made so far (times time_step_scale^3: the steps scale with it)."""
TARGET_ITERATIONS = 6
"""Time steps converged in more Newton iterations than this shrink the next one."""
STEP_ITERATIONS = 12
"""A time step not converged in this many Newton iterations (or the deck's limit, if lower)
is retried with half the time step: a shorter step crosses fewer kinks of the laws, and a
failed try costs less than the static limit."""
KINETIC_END = 1e-2
"""A state whose static unbalance meets the tolerances as it stands ends the drop where the
kinetic energy is below this fraction of the energy the drop put into motion (kinetic +
damped so far): not where a vibration passes its mean with the energy in its velocity."""
CHECK_PERIODS = 0.5
"""First periods between two tries of the static step that may end the drop: the motion swings
from one side of its mean to the other between them."""
CHECK_ITERATIONS = 10
"""Newton iterations of that static step: it starts next to an equilibrium or not at all."""
MAX_TIME_STEPS = 5000
"""Time steps of one drop before it counts as failed."""
SMALLEST_STEP = 1e-6
"""A time step below this fraction of the first period that still fails ends the drop."""
RAMP_PERIODS = 1.0
"""The held quantity moves from where the static path left it to the drop's target over this
many first periods, on a smooth (1 - cos) ramp: the stroke of a test moves on while the wall
begins to fall. (A jump would impose an infinite acceleration on the held point.)"""


def drop_dynamics(problem: Problem, settings: SolverSettings, omega: float) -> Dynamics:
    """The drops' mass, damping and integrator (omega: the first mode's frequency, rad/s)."""
    scheme = settings.scheme  # solve.schemes.Dynamic
    return Dynamics(problem.mass, omega, scheme.damping_ratio,
                    GeneralizedAlpha(scheme.spectral_radius), scheme.time_step_scale)


def dynamic_drop(problem: Problem, settings: SolverSettings, state: PathState, control,
                 preload: float, dynamics: Dynamics) -> Increment:
    """Integrate the wall's motion under `control`'s held quantity from rest at `state` until
    it comes to rest; return the equilibrium it ends at, with the drop's time steps, largest
    kinetic energy and work terms (`Increment.path_energy`); forensics "tested_rest" where it
    is one the held determinant calls unstable and an imperfection showed stable. StepFailed
    where a time step fails at SMALLEST_STEP of the period or MAX_TIME_STEPS do not bring it
    to rest."""
    drop = _Drop(problem, settings, state, control, preload, dynamics)
    while drop.steps < MAX_TIME_STEPS:
        if not drop.advance():
            continue
        end = drop.at_rest()
        if end is not None:
            return end
    raise StepFailed(f"dynamic drop: not at rest after {MAX_TIME_STEPS} time steps "
                     f"(t = {drop.time:.4g} s, kinetic energy {drop.energy.kinetic:.3g} N mm)"
                     f"{drop.unstable_rest()}", "non-convergence")


class _Drop:
    """The state of one dynamic drop between its time steps."""

    def __init__(self, problem: Problem, settings: SolverSettings, state: PathState, control,
                 preload: float, dynamics: Dynamics) -> None:
        c = problem.constraints
        self.problem, self.start, self.preload = problem, state, preload
        self.settings = replace(settings, max_iterations=min(settings.max_iterations,
                                                             STEP_ITERATIONS))
        self.static_settings = settings
        self.F_pre = (np.zeros_like(state.u) if problem.preload is None
                      else preload * problem.preload)
        self.mass, self.damping = c.restrict(dynamics.mass), c.restrict(dynamics.damping)
        self.scheme, self.period, self.omega = dynamics.scheme, dynamics.period, dynamics.omega
        scale = dynamics.time_step_scale
        self.dt, self.scale = scale * self.period / STEPS_PER_PERIOD, scale
        self.free_largest = self.largest = scale * self.period * LARGEST_STEP
        self.tolerance = TIME_TOLERANCE * scale ** 3
        zero = np.zeros_like(state.u)
        self.motion = Motion(state.u, zero, zero)
        self.control, self.held_from = control, control.measure(state.u)
        self.ramp_time = RAMP_PERIODS * self.period
        # the drop's displacement scale before it has moved: the state scaled to the advance
        # of the held quantity (from rest, the error estimate is of the order of the motion),
        # and at least that advance (from zero, the motion and the error both grow with dt^2)
        advance = abs(control.target - self.held_from)
        self.reference = max(float(np.linalg.norm(state.u)) * advance / max(
            abs(self.held_from), abs(control.target), 1e-300), advance)
        if state.evaluation is None:  # resumed from a checkpoint: its stresses and strains
            state = replace(state, evaluation=problem.structure.evaluate(state.u, state.states))
            self.start = state
        self.current: Increment | PathState = state
        # the applied less the resisting forces without the gap forces, which a time step
        # carries at its end only (`advance`): at the start, an equilibrium, the gap forces
        # (its own unbalance, within the tolerance, is taken as zero: the same bits whether
        # the start's stresses are the converged iterate's or a checkpoint's)
        self.r0 = c.restrict(c.constraint_force())
        self.energy, self.iterations, self.steps, self.time = DropEnergy(), 0, 0, 0.0
        self.next_check = self.ramp_time
        self.settled: Increment | None = None  # the last check's equilibrium (rolled back)
        self.seed: Seed | None = None  # the imperfection under test

    def held(self, time: float):
        """The held quantity's control at `time` (the ramp from where the drop began)."""
        advance = self.control.target - self.held_from
        return replace(self.control, target=self.held_from + advance * ramp(time,
                                                                             self.ramp_time))

    def advance(self) -> bool:
        """Try one time step of the current dt: True and committed where it converged within
        the local error, else rolled back with a shorter dt."""
        c, s = self.problem.constraints, self.scheme
        history = s.alpha_f / (1.0 - s.alpha_f) * (self.damping * self.motion.v - self.r0)
        step = TimeStep(self.mass, self.damping, self.dt, s, self.motion, history)
        try:
            inc = newton_increment(self.problem, self.settings, self._state(),
                                   self.held(self.time + self.dt), self.preload, dampers=step)
        except (StepFailed, ConvergenceError) as exc:
            c.rollback()
            self._shorter(0.5, exc)
            return False
        end = step.motion(inc.u)
        moved = max(float(np.linalg.norm(inc.u - self.start.u)), self.reference)
        ratio = step.local_error(end.a) / max(self.tolerance * moved, 1e-300)
        if ratio > 1.0:
            c.rollback()
            if self.dt <= SMALLEST_STEP * self.period:
                raise StepFailed(f"dynamic drop: the local error of a time step of "
                                 f"{self.dt:.3g} s (at most {SMALLEST_STEP:g} of the first "
                                 f"period) is {ratio:.3g} times its tolerance at t = "
                                 f"{self.time:.4g} s: the displacements jump, and no shorter "
                                 f"step resolves a jump", "non-convergence")
            self.dt *= max(0.25, 0.9 * ratio ** (-1.0 / 3.0))
            return False
        c.commit_time_step(1.0 - s.alpha_f)  # its gap forces act at its end
        self.steps, self.time = self.steps + 1, self.time + self.dt
        self.iterations += inc.iterations
        r1 = structural_unbalance(self.problem, inc, self.F_pre)
        self.energy.add(self.problem, self.current, inc, step, end, self.F_pre, self.r0, r1)
        self.r0 = r1
        self.motion, self.current = end, inc
        growth = min(2.0, max(0.5, 0.9 * max(ratio, 1e-12) ** (-1.0 / 3.0)))
        if inc.iterations > TARGET_ITERATIONS:
            growth = min(growth, math.sqrt(TARGET_ITERATIONS / inc.iterations))
        self.dt = min(self.largest, self.dt * growth)
        if self.largest < self.free_largest and self.steps % CHECK_EVERY == 0 and self._stable(
                inc):
            self.largest = self.free_largest  # the unstable mode has gone
        return True

    def _shorter(self, factor: float, exc: Exception) -> None:
        self.dt *= factor
        if self.dt < SMALLEST_STEP * self.period:
            raise StepFailed(f"dynamic drop: a time step of {self.dt / factor:.3g} s (below "
                             f"{SMALLEST_STEP:g} of the first period) failed at t = "
                             f"{self.time:.4g} s ({exc})",
                             getattr(exc, "reason", "non-convergence")) from None

    def at_rest(self) -> Increment | None:
        """The drop's end where the wall has come to rest, past the ramp: the kinetic energy
        below KINETIC_END, the static unbalance of the state within the load tolerance and its
        last correction within the displacement tolerance; or, every CHECK_PERIODS, a static
        Newton step from it (the held quantity fixed, at most CHECK_ITERATIONS) to a stable
        equilibrium that the last one reached too or that removes less than KINETIC_END (an
        unstable one bounds the time steps: `_resolve_growth`). At rest on an equilibrium the
        determinant calls unstable, an imperfection tests it (`solve.imperfection`). None
        (rolled back) otherwise."""
        if self.time < self.ramp_time:
            return None
        if self.seed is not None:
            return self._seed_outcome()
        e = self.energy
        static = self._resting()
        if static is not None:
            if self._stable(self.current):
                return _ended(self.current, static, self.iterations, self.steps, self.time,
                              self.energy, self.start)
            self._seed_imperfection()
            return None
        if self.time < self.next_check:
            return None
        self.next_check = self.time + CHECK_PERIODS * self.period
        check = replace(self.static_settings, max_iterations=min(
            self.static_settings.max_iterations, CHECK_ITERATIONS))
        c = self.problem.constraints
        try:
            inc = newton_increment(self.problem, check, self._state(), self.held(self.time),
                                   self.preload)
        except (StepFailed, ConvergenceError):
            inc = None
        if inc is None:
            c.rollback()
            return None
        # the static step takes the vibration left out of the account: its kinetic energy and
        # the work of the forces the inertia held (the strain energy of the oscillation)
        removed = e.kinetic + e.net_work(self.problem, self.current, inc, self.F_pre)
        settled, self.settled = self.settled, inc
        if not self._stable(inc):
            self._resolve_growth(inc)  # at the check's pair states
            c.rollback()
            return None
        if not (abs(removed) <= KINETIC_END * (e.kinetic + e.damping)
                or self._agrees(settled, inc)):
            c.rollback()
            return None
        c.commit()
        self.energy.close(self.problem, self.current, inc, self.F_pre)
        static = static_load_norm(self.problem, inc, self.start.load_scale)
        return _ended(inc, static, self.iterations + inc.iterations, self.steps, self.time,
                      self.energy, self.start)

    def _seed_imperfection(self, seed: Seed | None = None) -> None:
        """Seed an imperfection at the current rest (`solve.imperfection`): along its unstable
        mode, or along `seed`'s in the other sense; the time steps resolve its growth."""
        e, u = self.energy, self.current.u
        work = 0.5 * abs(float((self.current.load_factor * self.problem.reference_load
                                + self.F_pre) @ u))
        if seed is None:
            seed = Seed.at_rest(self.problem, self.current.evaluation, self.control.weights,
                                self.omega, 1.0 / (SMALLEST_STEP * self.period), self.time,
                                work, e.kinetic)
        else:
            seed = seed.opposite(self.omega, self.time, work, e.kinetic)
        self.seed, v0 = seed, self.motion.v
        self.motion = Motion(self.motion.u, v0 + seed.velocity, self.motion.a)
        added = 0.5 * float(self.motion.v @ (self.mass * self.motion.v) - v0 @ (self.mass * v0))
        e.external, e.seeded = e.external + added, e.seeded + added
        if seed.rate > 0.0:
            self._bound_growth(seed.rate)
        log.debug("dynamic drop: at rest at t = %.4g s on a state the held determinant calls "
                  "unstable (growth %.3g omega_1): an imperfection of %.3g N mm seeded along "
                  "its mode (%+g)", self.time, seed.rate / self.omega, seed.energy, seed.sense)

    def _seed_outcome(self) -> Increment | None:
        """The seeded imperfection's verdict: grown (the drop goes on), died in both senses
        (the drop ends at the rest: the motion shows it stable) or not yet (None)."""
        seed = self.seed
        if self.energy.kinetic > seed.grown:
            log.debug("dynamic drop: the seeded motion grows at t = %.4g s: the rest was "
                      "unstable", self.time)
            self.seed = None
            return None
        static = self._resting() if self.time >= seed.until else None
        if static is None:
            return None
        if seed.sense > 0.0:
            self._seed_imperfection(seed)
            return None
        self.seed = None
        log.info("dynamic drop: at rest on an equilibrium the held determinant calls unstable, "
                 "which an imperfection along its unstable mode left in neither sense: a "
                 "stable rest (docs/solver.md, item 43)")
        end = _ended(self.current, static, self.iterations, self.steps, self.time,
                     self.energy, self.start)
        if not self._stable(end):  # (the motion may have left the branch it was called on)
            end = replace(end, forensics={**end.forensics, "tested_rest": [1]})
        return end

    def _resting(self) -> float | None:
        """The static load norm of the current state where it is at rest as it stands: the
        kinetic energy below KINETIC_END of what the drop put into motion, the static
        unbalance within the load tolerance, the last correction within the displacement
        tolerance. None otherwise."""
        e = self.energy
        if self.steps == 0 or e.kinetic > KINETIC_END * (e.kinetic + e.damping):
            return None
        static = static_load_norm(self.problem, self.current, self.start.load_scale)
        if (static <= self.settings.tolerance_load
                and self.current.displacement_norm <= self.settings.tolerance_displacement):
            return static
        return None

    def unstable_rest(self) -> str:
        """Why a drop did not end, where it was testing a rest the held determinant calls
        unstable (else '')."""
        if self.seed is None:
            return ""
        return ("; it came to rest on an equilibrium within the tolerances that the held "
                "determinant calls unstable, and the imperfection seeded there had neither "
                "grown nor died (docs/solver.md, items 42-43)")

    def _resolve_growth(self, unstable: Increment) -> None:
        """Bound the time step by RESOLVED_GROWTH over the fastest growth rate at `unstable`."""
        fastest = 1.0 / (SMALLEST_STEP * self.period)
        rate = fastest_growth(self.problem, unstable.evaluation, self.control.weights,
                              self.omega, fastest)
        if rate > 0.0:
            self._bound_growth(rate)

    def _bound_growth(self, rate: float) -> None:
        self.largest = min(self.free_largest, self.scale * RESOLVED_GROWTH / rate)
        self.dt = min(self.dt, self.largest)
        log.debug("dynamic drop: unstable equilibrium at t = %.4g s, growth %.3g omega_1: "
                  "time steps below %.3g s", self.time, rate / self.omega, self.largest)

    def _agrees(self, before: Increment | None, after: Increment) -> bool:
        """Whether two static equilibria reached from the motion are the same: the load
        factors within the load tolerance of the load, the displacements within the
        displacement tolerance of the drop's motion."""
        if before is None:
            return False
        s = self.settings
        load = abs(after.load_factor - before.load_factor) <= s.tolerance_load * max(
            abs(after.load_factor), 1e-300)
        motion = float(np.linalg.norm(after.u - self.start.u))
        return load and float(np.linalg.norm(after.u - before.u)) <= (
            s.tolerance_displacement * motion)

    def _stable(self, end: Increment | PathState) -> bool:
        """Whether the drop may end at `end`: an equilibrium stable with the stroke held (an
        unstable one is where the motion passes through, or lingers before it leaves; where
        the drop holds another quantity, any equilibrium)."""
        weights = getattr(self.control, "weights", None)
        return weights is None or stable_under_stroke(self.problem, end.evaluation, weights,
                                                      self.omega)

    def _state(self) -> PathState:
        return _as_state(self.current, self.start)


def _as_state(current: Increment | PathState, start: PathState) -> PathState:
    """The committed state a time step starts from."""
    if isinstance(current, PathState):
        return current
    return PathState(current.u, current.load_factor, current.evaluation.states,
                     current.evaluation, current.preload_factor, start.load_scale)


def _ended(inc: Increment, static: float, iterations: int, steps: int, time: float,
           energy: DropEnergy, start: PathState) -> Increment:
    log.info("dynamic drop: %d time steps (%.4g s), %d iterations, load factor %.6g -> %.6g, "
             "largest kinetic energy %.4g N mm, numerical dissipation %.4g N mm", steps, time,
             iterations, start.load_factor, inc.load_factor, energy.largest_kinetic,
             energy.numerical)
    return replace(inc, iterations=iterations, load_norm=static, path_energy=energy,
                   forensics={**inc.forensics, "time_steps": [steps],
                              "drop_duration_us": [int(round(time * 1e6))]})
