"""Pseudo-transient continuation of one displacement-controlled step: the step a
stroke-controlled test takes where the load drops at a fixed deflection.

Where neither displacement control nor the opening control converges (after the peak, where
the concrete under the load crushes, the tangent is singular or indefinite at the step's
start and Newton diverges at any step size), the step to the next deflection is iterated with
the matrix K_t + D / dt (Kelley & Keyes 1998; Coffey, Kelley & Keyes 2003): D the diagonal of
the step's first matrix (the predictor's tangent), floored, so that 1/dt > 0 keeps the matrix
regular and the iterates go down the energy like a damped dynamic relaxation towards a stable
equilibrium at the fixed deflection; 1/dt halves after every iteration that lowers the
unbalance and grows 4x after one that raises it, so the last iterations are Newton's. Only
the matrix carries the pseudo-time: the residual is the law's, and the step is accepted on
the same tolerances as every other, so a converged drop is an equilibrium of the model.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

FIRST_INVERSE_STEP = 0.1
"""1/dt of the first iteration (the shift is 1/dt times the diagonal of the tangent)."""
LARGEST_INVERSE_STEP = 10.0
"""1/dt never exceeds this: beyond, the iterates barely move and the pivots of the
constraint rows drown next to the shifted diagonal."""
DIAGONAL_FLOOR = 1e-3
"""D is floored at this fraction of its median: the points whose tangent has lost its
stiffness (crushed and cracked) get a shift too."""
ITERATIONS = 1500
"""Iterations of one drop step before it counts as failed (CF-13's first drop, w 6.9586 ->
6.9555 MPa at 10.5 mm, takes 726: the iterates creep down a shallow softening mode)."""


@dataclass
class PseudoTransient:
    """The pseudo-time of one drop step: D (taken from the first matrix it shifts, unless
    given) and the current 1/dt."""

    diagonal: np.ndarray | None = None
    inverse_step: float = FIRST_INVERSE_STEP
    max_iterations: int = ITERATIONS

    @classmethod
    def from_tangent(cls, tangent_diagonal: np.ndarray) -> PseudoTransient:
        return cls(floored_diagonal(tangent_diagonal))

    def shift(self, tangent: sp.spmatrix | None = None) -> sp.dia_matrix:
        """D / dt, to be added to the tangent; D is the first tangent's floored diagonal."""
        if self.diagonal is None:
            self.diagonal = floored_diagonal(tangent.diagonal())
        return sp.diags(self.inverse_step * self.diagonal)

    def after_iteration(self, before: float, after: float) -> None:
        """Halve 1/dt after an iteration that lowered the unbalance, else grow it 4x."""
        factor = 0.5 if after < before else 4.0
        self.inverse_step = min(self.inverse_step * factor, LARGEST_INVERSE_STEP)

    def after_singular(self) -> bool:
        """Grow 1/dt after a singular matrix; False when it is already at its largest."""
        if self.inverse_step >= LARGEST_INVERSE_STEP:
            return False
        self.inverse_step = min(max(4.0 * self.inverse_step, FIRST_INVERSE_STEP),
                                LARGEST_INVERSE_STEP)
        return True


def floored_diagonal(tangent_diagonal: np.ndarray) -> np.ndarray:
    """|diag K_t| floored at DIAGONAL_FLOOR of the median of its non-zero entries."""
    d = np.abs(np.asarray(tangent_diagonal, dtype=float))
    return np.maximum(d, DIAGONAL_FLOOR * float(np.median(d[d > 0.0])))
