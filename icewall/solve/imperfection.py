"""The imperfection that tests a rest the held determinant calls unstable (solve/dynamic.py).

Where a drop's motion comes to rest on an equilibrium whose held tangent has a negative
determinant (`stability.held_sign`), the test of the wall would still leave it if it is
unstable: a real wall has imperfections. The determinant is that of one branch of the laws
(each point on the branch of its last increment, each pair in its last state); a motion that
unloads a point or sticks a pair takes another, so the tangent alone does not say whether the
motion leaves (CF-4 at 17.15 mm, docs/solver.md items 42-43: at rest with a kinetic energy of
7e-22 N mm for 5 000 time steps on a state the determinant calls unstable). The motion says:
a velocity along the unstable mode (`stability.unstable_mode`) whose kinetic energy is
SEED_ENERGY of the work the loads hold there (1/2 |(P R + F) . u|), in one sense and then in
the other; the rest is stable where it dies in both. (Scaled to the drop's own motion, the
seed vanishes where nothing has moved: the snap-back bar at rest on its descending branch,
balanced to round-off, sat there for 5 000 time steps.) Its kinetic energy is booked as
external work (the imperfection's).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from icewall.solve.problem import Problem
from icewall.solve.stability import fastest_growth, unstable_mode

SEED_ENERGY = 1e-6
"""The imperfection's kinetic energy, as a fraction of the work the loads hold at the rest
(for a linear response: an amplitude of 1e-3 of the deflection)."""
SEED_GROWN = 4.0
"""A seeded motion whose kinetic energy passes this multiple of the seed's (with what moved
when it was seeded) has left the rest: the drop goes on."""
SEED_FOLDINGS = 3.0
"""A seeded motion that has not grown in this many e-foldings of the slowest growth the mode
may have (half the bracketed rate) has died; it runs at least SEED_PERIODS first periods."""
SEED_PERIODS = 1.0


@dataclass(frozen=True)
class Seed:
    """An imperfection under test: the mode (M-normalised, all equations), its growth rate
    (1/s, 0 where the determinant saw none), the sense, the seeded kinetic energy, the
    kinetic energy it counts as grown beyond (N mm) and the time its test ends (s)."""

    mode: np.ndarray
    rate: float
    sense: float
    energy: float
    grown: float
    until: float

    @classmethod
    def at_rest(cls, problem: Problem, evaluation, weights: np.ndarray, omega: float,
                fastest: float, time: float, work: float, kinetic: float) -> Seed:
        """The first seed at the rest of `evaluation` (the stroke `weights . u` held; omega:
        omega_1, fastest: the largest growth rate resolved, 1/s), at `time`; `work`: the
        work the loads hold, `kinetic`: the kinetic energy there (N mm)."""
        rate = fastest_growth(problem, evaluation, weights, omega, fastest)
        mode = unstable_mode(problem, evaluation, weights, rate)
        return cls._of(mode, rate, 1.0, omega, time, work, kinetic)

    def opposite(self, omega: float, time: float, work: float, kinetic: float) -> Seed:
        """The seed in the other sense, once this one has died."""
        return self._of(self.mode, self.rate, -self.sense, omega, time, work, kinetic)

    @classmethod
    def _of(cls, mode, rate, sense, omega, time, work, kinetic) -> Seed:
        energy = SEED_ENERGY * work
        folding = 2.0 / rate if rate > 0.0 else 0.0
        until = time + max(SEED_PERIODS * 2.0 * math.pi / omega, SEED_FOLDINGS * folding)
        return cls(mode, rate, sense, energy, SEED_GROWN * (energy + kinetic), until)

    @property
    def velocity(self) -> np.ndarray:
        """The seeded velocity: 1/2 v.M v = energy."""
        return self.sense * math.sqrt(2.0 * self.energy) * self.mode
