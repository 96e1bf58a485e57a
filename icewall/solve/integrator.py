"""Time integration of the wall's motion: generalized-alpha (Chung & Hulbert 1993) in the
force-averaged form, as the dynamic drops use it (solve/dynamic.py).

The equation of motion at t_{n+1-alpha},

    (1-am) M a1 + am M a0 + (1-af) [C v1 + f_int(u1) + G lam1 - P1 R - F]
                          +   af  [C v0 + f_int(u0) + G lam0 - P0 R - F] = 0,

with Newmark's u1 = u0 + dt v0 + dt^2 ((1/2 - beta) a0 + beta a1) and v1 = v0 + dt ((1 - gamma)
a0 + gamma a1). Divided by (1 - af), the static Newton iteration solves it with `TimeStep.force`
as an extra force and `TimeStep.shift` added to its matrix. Units: N, mm, s, t.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from icewall.errors import ConvergenceError


def ramp(time: float, duration: float) -> float:
    """0 -> 1 over `duration`, with zero rate at both ends."""
    if time >= duration:
        return 1.0
    return 0.5 * (1.0 - math.cos(math.pi * time / duration))


@dataclass(frozen=True)
class GeneralizedAlpha:
    """Chung & Hulbert's parameters for a spectral radius rho_inf at infinite frequency:
    second-order accurate, unconditionally stable, the high modes damped to rho_inf per step."""

    rho_inf: float

    @property
    def alpha_m(self) -> float:
        return (2.0 * self.rho_inf - 1.0) / (self.rho_inf + 1.0)

    @property
    def alpha_f(self) -> float:
        return self.rho_inf / (self.rho_inf + 1.0)

    @property
    def gamma(self) -> float:
        return 0.5 - self.alpha_m + self.alpha_f

    @property
    def beta(self) -> float:
        return 0.25 * (1.0 - self.alpha_m + self.alpha_f) ** 2


@dataclass(frozen=True)
class Motion:
    """Displacements, velocities and accelerations (equation space) at one time."""

    u: np.ndarray
    v: np.ndarray
    a: np.ndarray


@dataclass(frozen=True)
class TimeStep:
    """The inertia and damping terms of one time step of length dt from `start`: the force the
    Newton residual carries (`force`) and the shift of its matrix (`shift`), as the drop's
    dampers did before them. `history` is af / (1 - af) (C v0 - r0), r0 the static unbalance
    at the start (P0 R + F - f_int(u0) - G lam0)."""

    mass: np.ndarray
    damping: np.ndarray
    dt: float
    scheme: GeneralizedAlpha
    start: Motion
    history: np.ndarray

    def acceleration(self, u: np.ndarray) -> np.ndarray:
        s, m, dt = self.scheme, self.start, self.dt
        return (u - m.u - dt * m.v - dt * dt * (0.5 - s.beta) * m.a) / (s.beta * dt * dt)

    def motion(self, u: np.ndarray) -> Motion:
        a = self.acceleration(u)
        s, m = self.scheme, self.start
        return Motion(u, m.v + self.dt * ((1.0 - s.gamma) * m.a + s.gamma * a), a)

    def force(self, u: np.ndarray) -> np.ndarray:
        """[(1-am) M a1 + am M a0] / (1-af) + C v1 + history."""
        s, m = self.scheme, self.motion(u)
        inertia = self.mass * ((1.0 - s.alpha_m) * m.a + s.alpha_m * self.start.a)
        return inertia / (1.0 - s.alpha_f) + self.damping * m.v + self.history

    def shift(self) -> sp.dia_matrix:
        s, dt = self.scheme, self.dt
        return sp.diags(self.mass * (1.0 - s.alpha_m) / ((1.0 - s.alpha_f) * s.beta * dt * dt)
                        + self.damping * s.gamma / (s.beta * dt))

    def local_error(self, a1: np.ndarray) -> float:
        """|(beta - 1/6) dt^2 (a1 - a0)| (Zienkiewicz & Xie 1991)."""
        return abs(self.scheme.beta - 1.0 / 6.0) * self.dt ** 2 * float(
            np.linalg.norm(a1 - self.start.a))


@dataclass(frozen=True)
class Dynamics:
    """What a run's drops integrate with: the lumped mass (equation space), the first mode's
    circular frequency (rad/s), the damping ratio there, the integrator and the step scale."""

    mass: np.ndarray
    omega: float
    damping_ratio: float
    scheme: GeneralizedAlpha
    time_step_scale: float = 1.0

    @property
    def damping(self) -> np.ndarray:
        """Diagonal of C = 2 xi omega_1 M (mass-proportional Rayleigh damping)."""
        return 2.0 * self.damping_ratio * self.omega * self.mass

    @property
    def period(self) -> float:
        return 2.0 * math.pi / self.omega


def first_mode_frequency(u: np.ndarray, load_factor: float, reference: np.ndarray,
                         mass: np.ndarray) -> float:
    """omega_1 (rad/s) by the Rayleigh quotient of a static response u to P R: with K u = P R,
    omega^2 = u.K u / u.M u = P R.u / u.M u (an upper bound, within a few per cent for the
    deflected shape of a beam under its loads)."""
    stiffness = load_factor * float(reference @ u)
    inertia = float(u @ (mass * u))
    if not (stiffness > 0.0 and inertia > 0.0):
        raise ConvergenceError("no first-mode frequency: the first step's response does no "
                               "positive work or the wall has no mass (materials.*.density)",
                               reason="no mass")
    return math.sqrt(stiffness / inertia)
