"""Path-following controls: the extra equation that fixes the load factor of an increment.

Each control is one linear constraint phi(u, P) = g.u + h P - c = 0 on the displacements u and
the load factor P (the jack load). With the bordering of eq. 3.48 a Newton step is
du = dP q1 + q2 (q1: the response to the reference load, q2: to the unbalance), and the
linearised constraint gives dP = -(phi + g.q2) / (g.q1 + h). Load control has no constraint
(dP = 0).

- `DisplacementControl` (thesis 3.5): the control deflection -u[c] reaches its target.
- `StrokeControl`: the load-weighted mean deflection under the loads, R.u / sum |R|, reaches
  its target (the stroke of a loading head driving the loads through a distribution beam).
- `DissipationControl` (Gutierrez 2004; Verhoosel, Remmers & Gutierrez 2009, eq. 19): the
  energy released in the increment, G = 1/2 (f0.du - dP R.u0) with f0 = P0 R + F_pre the
  external force at its start, equals tau > 0. It follows the equilibrium path through the
  snap-backs of localised softening, where the control deflection turns back and displacement
  control has no solution; G is the dissipation of a secant-unloading (damage-like) material,
  and a monotone path parameter of the walls' cracking and crushing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class LoadControl:
    """The load factor is held (the preload's increments are applied by load control)."""

    def residual(self, u: np.ndarray, P: float) -> float:
        return 0.0  # no constraint to reach

    def correction(self, u: np.ndarray, P: float, q1: np.ndarray, q2: np.ndarray) -> float:
        return 0.0


@dataclass(frozen=True)
class DisplacementControl:
    """deflection = -u[equation] = target (eq. 3.48, errata §3)."""

    equation: int
    target: float

    def measure(self, u: np.ndarray) -> float:
        """The controlled deflection of displacements u (linear in u)."""
        return -float(u[self.equation])

    def residual(self, u: np.ndarray, P: float) -> float:
        return -float(u[self.equation]) - self.target

    def correction(self, u: np.ndarray, P: float, q1: np.ndarray, q2: np.ndarray) -> float:
        return _correction(self.residual(u, P), -q1[self.equation], -q2[self.equation], 0.0)


@dataclass(frozen=True)
class StrokeControl:
    """stroke = w.u = target, w = R / sum |R| (R the reference load on the free equations): the
    mean deflection under the loads weighted by them, whose product with P sum |R| is the
    external work of the jack load."""

    weights: np.ndarray
    target: float

    @classmethod
    def of_load(cls, reference: np.ndarray, target: float = 0.0) -> StrokeControl:
        return cls(reference / float(np.abs(reference).sum()), target)

    def measure(self, u: np.ndarray) -> float:
        """The stroke of displacements u (linear in u)."""
        return float(self.weights @ u)

    def residual(self, u: np.ndarray, P: float) -> float:
        return self.measure(u) - self.target

    def correction(self, u: np.ndarray, P: float, q1: np.ndarray, q2: np.ndarray) -> float:
        return _correction(self.residual(u, P), float(self.weights @ q1),
                           float(self.weights @ q2), 0.0)


@dataclass(frozen=True)
class DissipationControl:
    """Energy released in the increment from (u0, P0) equals `released` (N mm)."""

    u0: np.ndarray
    P0: float
    reference: np.ndarray  # R on the free equations
    preload: np.ndarray  # the constant in-plane force on the free equations (zero without)
    released: float

    def energy(self, u: np.ndarray, P: float) -> float:
        """G = 1/2 ((P0 R + F_pre).(u - u0) - (P - P0) R.u0)."""
        f0 = self.P0 * self.reference + self.preload
        return 0.5 * (float(f0 @ (u - self.u0)) - (P - self.P0) * float(self.reference @ self.u0))

    def residual(self, u: np.ndarray, P: float) -> float:
        return self.energy(u, P) - self.released

    def correction(self, u: np.ndarray, P: float, q1: np.ndarray, q2: np.ndarray) -> float:
        g = 0.5 * (self.P0 * self.reference + self.preload)
        h = -0.5 * float(self.reference @ self.u0)
        return _correction(self.residual(u, P), float(g @ q1), float(g @ q2), h)


SINGULAR_BORDER = 1e-12
"""A control row whose g.q1 + h is below this fraction of |g.q1| + |h| is singular."""


def _correction(phi: float, g_q1: float, g_q2: float, h: float) -> float:
    """dP of the linearised constraint phi + g.(dP q1 + q2) + h dP = 0."""
    denominator = g_q1 + h
    # a denominator lost in the round-off of its terms fixes no load factor (the energy
    # released along an elastic tangent, where g.q1 = -h)
    if not abs(denominator) > SINGULAR_BORDER * (abs(g_q1) + abs(h)) or not np.isfinite(
            denominator):
        return float("nan")
    return -(phi + g_q2) / denominator


@dataclass(frozen=True)
class OpeningControl:
    """Indirect displacement control (de Borst 1987): the sum over a set of Gauss points of
    their largest principal strain, weighted by their volumes, grows by `increment` in the
    increment. Through the snap-back of a localising crack the crack strains grow while the
    deflection turns back, so the opening is a monotone path parameter where the energy
    released is not (docs/solver.md). `B` (m, 4, nd), `dofs` (m, nd), `weights` (m,) of the
    chosen points; `start` the opening at the start of the increment."""

    B: np.ndarray
    dofs: np.ndarray
    weights: np.ndarray
    start: float
    increment: float
    reference: np.ndarray | None = None  # (m,) largest strains at the start: growth only

    def strains(self, u: np.ndarray) -> np.ndarray:
        """The chosen points' strains (m, 4)."""
        return np.einsum("mij,mj->mi", self.B, u[self.dofs])

    def _growing(self, largest: np.ndarray) -> np.ndarray:
        if self.reference is None:
            return np.ones(largest.shape, bool)
        return largest >= self.reference

    def opening(self, u: np.ndarray) -> float:
        largest = largest_principal(self.strains(u))[0]
        if self.reference is not None:
            largest = np.maximum(largest - self.reference, 0.0)
        return float(self.weights @ largest)

    def residual(self, u: np.ndarray, P: float) -> float:
        return self.opening(u) - self.start - self.increment

    def gradient(self, u: np.ndarray) -> np.ndarray:
        """d opening / d u (n_eq,)."""
        largest, d_eps = largest_principal(self.strains(u))
        weights = np.where(self._growing(largest), self.weights, 0.0)
        local = np.einsum("m,mi,mij->mj", weights, d_eps, self.B)
        return np.bincount(self.dofs.ravel(), local.ravel(), minlength=u.size)[:u.size]

    def correction(self, u: np.ndarray, P: float, q1: np.ndarray, q2: np.ndarray) -> float:
        g = self.gradient(u)
        return _correction(self.residual(u, P), float(g @ q1), float(g @ q2), 0.0)


def largest_principal(strain: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """In-plane largest principal strain (m,) of [xx, yy, zz, xy (engineering)] and its
    derivative (m, 4) with respect to the components."""
    xx, yy, xy = strain[:, 0], strain[:, 1], strain[:, 3]
    radius = np.sqrt((0.5 * (xx - yy)) ** 2 + (0.5 * xy) ** 2)
    safe = np.maximum(radius, 1e-300)
    d = np.zeros_like(strain)
    d[:, 0] = 0.5 + np.where(radius > 0, 0.25 * (xx - yy) / safe, 0.5)
    d[:, 1] = 0.5 - np.where(radius > 0, 0.25 * (xx - yy) / safe, 0.5)
    d[:, 3] = np.where(radius > 0, 0.25 * xy / safe, 0.0)
    return 0.5 * (xx + yy) + radius, d
