"""Energy bookkeeping per step: external work = stored elastic energy + concrete cracking and
crushing dissipation + steel plastic work + interface friction work + the dynamic drops'
viscous damping, the kinetic energy left where they ended and their integrator's numerical
dissipation (+ imbalance).

A static step books trapezoidal rules: the loads' work 1/2 (P0 + P1) R . du, each group's stress
work 1/2 (s0 + s1) : (e1 - e0) dV, the friction of the slipping pairs. A dynamic drop's time step
(`DropEnergy.add`) books the same physical terms, and besides them what the integrator takes,
from the step's own work identity. Its residual (solve/integrator.py), converged to e (the
Newton unbalance, restricted to the free equations), is

    (1-af) e = (1-af) s1 + af s0 - G lam - (1-am) M a1 - am M a0 - (1-af) C v1 - af C v0,

s = P R + F - f_int(u) the unbalance without the gap forces (applied minus resisting forces),
G lam the gap forces, which the step carries at its end only (`structural_unbalance`; lam
the multipliers scaled to the end at the commit, `commit_time_step`; a pair opening in the
step is not pushed apart by its old compression, nor a slip that reverses by its old
friction). Dotted with the step's du = u1 - u0:

    W_inertia + W_damping + W_static + G lam . du = -(1-af) e . du  (~ 0, the Newton tolerance),
    W_inertia = [(1-am) M a1 + am M a0] . du,
    W_damping = [(1-af) C v1 + af C v0] . du,
    W_static  = -[(1-af) s1 + af s0] . du,

each with the scheme's weights. The physical account weighs every force 1/2, 1/2 instead:
external work E = (1/2 (P0 + P1) R + F) . du, stress work I = 1/2 (f_int0 + f_int1) . du (the
groups' trapezoidal stress work, the same sum: eps = B u), damping D = 1/2 C (v0 + v1) . du,
and the kinetic energy T = 1/2 v M v. With q = C v - s (the damping less the unbalance)
the numerical dissipation of the step is

    N = (W_inertia - (T1 - T0)) + (1/2 - af) (q1 - q0) . du,

the inertia's algorithmic dissipation (the scheme's inertia work less the change of kinetic
energy) plus the difference between the af-weighted and the trapezoidal work of the other
forces. Then, exactly,

    E = I + Fr + D + (T1 - T0) + N + [(1-af) e . du + (G lam . du - Fr)],

the bracket being the imbalance the step leaves: the equilibrium tolerance times du and the
gap forces' work against the friction booked (Fr = |lam_T| |dDelta_T| over the pairs slipping
at the step's end; the two differ where pairs close in the step, an impact's loss, or a slip
turns within it). The stress work stays the trapezoidal
estimate of the integral of sigma : d eps (the concrete's dissipation is that less its
stored secant energy); N is the integrator's, not the wall's.
With af = am = 1/2 (rho_inf = 1: the trapezoidal rule, gamma = 1/2, beta = 1/4) du = dt (v0 +
v1) / 2 and v1 - v0 = dt (a0 + a1) / 2, so W_inertia = T1 - T0 and N = 0 to round-off; below
it the high modes lose energy on purpose (tests/solve/test_drop_energy.py).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from icewall.solve.integrator import Motion, TimeStep
    from icewall.solve.problem import Problem
    from icewall.solve.state import Increment, PathState


@dataclass
class EnergyAccount:
    """Cumulative energies in N mm; `record()` gives the per-step history columns."""

    external_work: float = 0.0
    internal_work: dict[str, float] = field(default_factory=dict)  # per material group
    friction_work: float = 0.0
    elastic_energy: dict[str, float] = field(default_factory=dict)
    damping_work: float = 0.0  # viscous damping of the dynamic drops
    kinetic_lost: float = 0.0  # what the vibration held where a drop ended (solve.dynamic)
    numerical_dissipation: float = 0.0  # the drops' integrator's (DropEnergy.numerical)
    dynamic: bool = False  # the run can take dynamic drops: record their columns

    def add_drop(self, drop) -> None:
        """The work terms of a dynamic drop (DropEnergy), summed over its time
        steps."""
        self.external_work += drop.external
        for group, work in drop.internal.items():
            self.internal_work[group] = self.internal_work.get(group, 0.0) + work
        self.friction_work += drop.friction
        self.damping_work += drop.damping
        self.kinetic_lost += drop.kinetic
        self.numerical_dissipation += drop.numerical

    def add_external(self, load_old: np.ndarray, load_new: np.ndarray, du: np.ndarray) -> None:
        """Trapezoidal work of the applied loads over a converged increment."""
        self.external_work += float(0.5 * (load_old + load_new) @ du)

    def add_internal(self, group: str, stress_old: np.ndarray, stress_new: np.ndarray,
                     strain_old: np.ndarray, strain_new: np.ndarray, dV: np.ndarray) -> None:
        """Trapezoidal stress work over the increment of a group's points (n_el, nq, 4)."""
        density = np.einsum("eqi,eqi->eq", 0.5 * (stress_old + stress_new),
                            strain_new - strain_old)
        self.internal_work[group] = self.internal_work.get(group, 0.0) + float(
            np.sum(density * dV))

    def set_elastic(self, group: str, energy: float) -> None:
        self.elastic_energy[group] = float(energy)

    def record(self) -> dict[str, float]:
        stored = sum(self.elastic_energy.values())
        work = sum(self.internal_work.values())
        concrete = self.internal_work.get("concrete", 0.0) - self.elastic_energy.get(
            "concrete", 0.0)
        steel = self.internal_work.get("steel", 0.0) - self.elastic_energy.get("steel", 0.0)
        imbalance = (self.external_work - work - self.friction_work - self.damping_work
                     - self.kinetic_lost - self.numerical_dissipation)
        out = {"external_work": self.external_work, "elastic_energy": stored,
               "concrete_dissipation": concrete, "plastic_work": steel,
               "friction_work": self.friction_work, "energy_imbalance": imbalance}
        if self.dynamic:
            out.update(damping_work=self.damping_work, kinetic_energy_lost=self.kinetic_lost,
                       numerical_dissipation=self.numerical_dissipation)
        return out


def secant_elastic_energy(stress: np.ndarray, strain: np.ndarray, dV: np.ndarray) -> float:
    """1/2 sigma : eps, the energy recovered by secant unloading to the origin (concrete,
    Fig. 3.13; elastic groups)."""
    return float(0.5 * np.sum(np.einsum("eqi,eqi->eq", stress, strain) * dV))


@dataclass
class DropEnergy:
    """Work terms of one drop summed over its time steps (N mm): the physical ones, the
    integrator's numerical dissipation (`numerical`, the module's N) and, as a check that is no
    part of the account, the work of the Newton unbalance the time steps converged to
    (`unbalance`, the module's (1-af) e . du, with the gap forces' work G lam . du where there
    are pairs)."""

    external: float = 0.0
    internal: dict[str, float] = field(default_factory=dict)
    friction: float = 0.0
    damping: float = 0.0
    kinetic: float = 0.0  # at the end
    largest_kinetic: float = 0.0
    seeded: float = 0.0  # the kinetic energy of the imperfections seeded (counted external)
    numerical: float = 0.0  # the integrator's algorithmic dissipation
    unbalance: float = 0.0  # the converged residual's work (imbalance, not in the account)

    def add(self, problem: Problem, before: Increment | PathState, after: Increment,
            step: TimeStep, motion: Motion, F_pre: np.ndarray, unbalance_before: np.ndarray,
            unbalance_after: np.ndarray) -> None:
        """A committed time step: the trapezoidal work of the loads, the stresses and the
        damping, the friction work and the kinetic energy at its end; and from the step's
        work identity (module docstring) the integrator's numerical dissipation.
        `unbalance_before`, `unbalance_after`: the unbalances without the gap forces s0 (the
        one the step's history carried) and s1 (at its converged state), equation space; the
        friction work the constraints booked at its end forces (`commit_time_step`)."""
        self._static_terms(problem, before, after, F_pre)
        du = after.u - before.u
        start, s = step.start, step.scheme
        v_mean = 0.5 * (start.v + motion.v)
        self.damping += float(problem.constraints.restrict(step.damping * v_mean) @ du)
        kinetic_before = 0.5 * float(start.v @ (step.mass * start.v))
        self.kinetic = 0.5 * float(motion.v @ (step.mass * motion.v))
        self.largest_kinetic = max(self.largest_kinetic, self.kinetic)
        inertia = float(step.mass * ((1.0 - s.alpha_m) * motion.a + s.alpha_m * start.a) @ du)
        q0 = step.damping * start.v - unbalance_before
        q1 = step.damping * motion.v - unbalance_after
        self.numerical += (inertia - (self.kinetic - kinetic_before)
                           + (0.5 - s.alpha_f) * float((q1 - q0) @ du))
        scheme_weighted = (1.0 - s.alpha_f) * q1 + s.alpha_f * q0  # damping less the static
        self.unbalance -= inertia + float(scheme_weighted @ du)

    def close(self, problem: Problem, before: Increment, after: Increment,
              F_pre: np.ndarray) -> None:
        """The static step that ends the drop: its work terms; `kinetic` becomes what it took
        out of the account (the kinetic energy left and the work of the forces the inertia
        held)."""
        self.kinetic += self.net_work(problem, before, after, F_pre)
        self._static_terms(problem, before, after, F_pre)

    def net_work(self, problem: Problem, before: Increment, after: Increment,
                 F_pre: np.ndarray) -> float:
        """Trapezoidal work of the loads less that of the stresses from `before` to `after`."""
        probe = DropEnergy()
        probe._static_terms(problem, before, after, F_pre, friction=False)
        return probe.external - sum(probe.internal.values())

    def _static_terms(self, problem: Problem, before: Increment | PathState, after: Increment,
                      F_pre: np.ndarray, friction: bool = True) -> None:
        R, du = problem.reference_load, after.u - before.u
        self.external += float((0.5 * (before.load_factor + after.load_factor) * R + F_pre)
                               @ du)
        dV = problem.structure.kinematics.dV
        s0, s1 = before.evaluation.stress, after.evaluation.stress
        e0, e1 = before.evaluation.strain, after.evaluation.strain
        for group in problem.structure.groups:
            cells = group.cells
            density = np.einsum("eqi,eqi->eq", 0.5 * (s0[cells] + s1[cells]), e1[cells] -
                                e0[cells])
            self.internal[group.name] = self.internal.get(group.name, 0.0) + float(
                np.sum(density * dV[cells]))
        if friction:
            self.friction += float(problem.constraints.friction_work_increment())


def structural_unbalance(problem: Problem, state: Increment | PathState,
                         F_pre: np.ndarray) -> np.ndarray:
    """s = P R + F - f_int of a committed state (equation space, fixed rows zero): the static
    unbalance without the gap forces. A time step carries the forces of its start weighted
    af and those of its end 1 - af, but its gap forces at its end only (the equation's G lam1
    is their whole force over 1 - af): a pair that opens in the step is not pushed apart by
    its old compression, nor a pair whose slip reverses by its old friction (TF-1's and
    CF-4's drops made up to 9 % of the external work that way, docs/solver.md item 47).
    Backward Euler for the constraint forces, as the Moreau-Jean scheme and the nonsmooth
    generalized-alpha take them (Acary 2016)."""
    applied = state.load_factor * problem.reference_load + F_pre
    return problem.constraints.restrict(applied - state.evaluation.internal_force)
