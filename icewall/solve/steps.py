"""Automatic step size of the path following, from the iteration count and failures."""

from __future__ import annotations

import math
from dataclasses import dataclass

from icewall.errors import ConvergenceError


@dataclass(frozen=True)
class StepSizeController:
    """Grow a step that converged in few iterations, shrink one that needed many, halve a
    failed one; never above `largest` (the deck's increment) nor below `smallest`.

    The next size is size * (target / iterations) ** 0.5, clipped to [0.5, 2]: the classic
    rule of thumb (Crisfield 1991, eq. 9.40) that aims every step at `target` iterations.
    """

    largest: float
    smallest: float
    target_iterations: int = 6

    @classmethod
    def of(cls, settings, largest: float) -> StepSizeController:
        """The controller of a stage whose largest step is `largest`: `settings.max_step_cuts`
        halvings below it, aimed at the scheme's `target_iterations` (a SolverSettings whose
        scheme is the Newton scheme)."""
        return cls(largest=largest, smallest=largest / 2 ** settings.max_step_cuts,
                   target_iterations=settings.scheme.target_iterations)

    def after_success(self, size: float, iterations: int) -> float:
        ratio = math.sqrt(self.target_iterations / max(iterations, 1))
        return min(self.largest, max(self.smallest, size * min(2.0, max(0.5, ratio))))

    def after_failure(self, size: float, where: str, reason: str, message: str) -> float:
        """Half the size; ConvergenceError when the smallest step has failed."""
        if size <= self.smallest * (1 + 1e-9):
            raise ConvergenceError(f"{message} at {where} with the smallest step "
                                   f"{self.smallest:.3g}", reason=reason)
        return max(self.smallest, 0.5 * size)
