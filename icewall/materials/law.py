"""What the solver and the result writer ask of a constitutive law, over all Gauss points of a
material group at once.

A law holds its parameters and is called as `update(strain (n, 4), state) -> (stress (n, 4),
moduli (n, 4, 4), trial_state)`; states are immutable, so the committed state stays as it was.
The defaults are those of a law without internal state worth reporting: it cannot be frozen,
has no chatter flags, no counts, no state fields, and its whole strain is elastic.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any, ClassVar

import numpy as np

Update = tuple[np.ndarray, np.ndarray, Any]  # stress (n, 4), moduli (n, 4, 4), trial state


class MaterialLaw(ABC):
    """A constitutive law with its parameters (subclasses are frozen dataclasses)."""

    # update(frozen=) is honoured: frozen points may only unload or reload (chatter damping)
    freezable: ClassVar[bool] = False
    # update's moduli are an iteration matrix, not d sigma / d eps; update(tangent=True) and
    # tangent_of give that tangent (the other laws' moduli already are their tangents)
    secant_moduli: ClassVar[bool] = False

    params: Any

    @property
    def constant_moduli(self) -> np.ndarray | None:
        """(4, 4) moduli of every point in every state (an elastic law), else None."""
        return None

    def initial_state(self, n: int) -> Any:
        """The virgin state of n points (None for a law without state)."""
        return None

    @abstractmethod
    def update(self, strain: np.ndarray, state: Any, frozen: np.ndarray | None = None,
               returned_secant: bool = False, tangent: bool = False) -> Update:
        """Stress, moduli and trial state at `strain` from the committed `state`. `frozen`
        (n,) bool and `returned_secant` are options of a freezable law; `tangent` asks for
        the consistent tangent as moduli (a law with secant moduli)."""

    def tangent_of(self, strain: np.ndarray, stress: np.ndarray, trial: Any,
                   state: Any) -> np.ndarray:
        """The consistent tangent (n, 4, 4) of the update from `state` that gave `stress` and
        `trial` at `strain` (here: that update made again, with the tangent)."""
        return self.update(strain, state, tangent=True)[1]

    def flags(self, state: Any) -> np.ndarray | None:
        """(n, k) bool flags whose switching within an increment the solver counts as chatter
        (None: nothing to count)."""
        return None

    def counts(self, state: Any) -> dict[str, int]:
        """Points in each named condition, for the step record."""
        return {}

    def elastic_strain(self, strain: np.ndarray, state: Any) -> np.ndarray:
        """The strain (n, 4) whose secant energy 1/2 sigma : eps is recoverable."""
        return strain

    def state_fields(self, state: Any) -> dict[str, np.ndarray]:
        """Named per-point state fields (n, k) of the result file."""
        return {}

    def cracking(self, state: Any) -> tuple[np.ndarray, np.ndarray] | None:
        """The cracking strain (n,) of each point and whether it has cracked (n,) bool; None
        for a law that does not crack."""
        return None

    def crushed(self, state: Any) -> np.ndarray | None:
        """(n,) bool: points in compressive softening; None for a law that does not crush."""
        return None

    def yielded(self, state: Any) -> np.ndarray | None:
        """(n,) bool: points that have yielded; None for a law that does not yield."""
        return None
