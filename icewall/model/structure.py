"""Internal forces and (secant) stiffness of the whole mesh for given nodal displacements.

Material states are immutable: `evaluate` returns trial states; the solver keeps the
committed ones and commits trial states only on a converged increment. Elastic groups cost
their B^T D B once; only nonlinear groups are recomputed per iteration.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import scipy.sparse as sp

from icewall.fem.assembly import Assembler
from icewall.fem.kinematics import (
    ElementKinematics,
    internal_force_blocks,
    stiffness_blocks,
    strain,
)
from icewall.model.materials import MaterialGroup


@dataclass(frozen=True)
class Evaluation:
    """Everything one pass over the Gauss points gives."""

    strain: np.ndarray  # (n_el, nq, 4)
    stress: np.ndarray  # (n_el, nq, 4)
    moduli: np.ndarray  # (n_el, nq, 4, 4)
    internal_force: np.ndarray  # (n_eq,)
    states: tuple[Any, ...]  # trial state per group
    tangent: bool = False  # moduli are every law's consistent tangent d sigma / d eps
    # the committed states it was evaluated from (None for a pass with frozen points): where
    # Structure.with_tangent differentiates the laws
    committed: tuple[Any, ...] | None = None


class Structure:
    """The assembled solid: kinematics, assembler and material groups."""

    def __init__(self, kinematics: ElementKinematics, assembler: Assembler,
                 groups: tuple[MaterialGroup, ...]) -> None:
        self.kinematics, self.assembler, self.groups = kinematics, assembler, groups
        self.n_elements, self.n_gauss = kinematics.dV.shape
        self._group_kinematics = tuple(
            replace(kinematics, B=kinematics.B[g.cells], dV=kinematics.dV[g.cells],
                    x=kinematics.x[g.cells], dofs=kinematics.dofs[g.cells],
                    detJ=kinematics.detJ[g.cells]) for g in groups)
        nd = kinematics.B.shape[-1]
        self._blocks = np.zeros((self.n_elements, nd, nd))
        for group, kin in zip(groups, self._group_kinematics, strict=True):
            if group.law.constant_moduli is not None:
                self._blocks[group.cells] = stiffness_blocks(kin, group.law.constant_moduli)

    def initial_states(self) -> tuple[Any, ...]:
        return tuple(g.law.initial_state(g.cells.size * self.n_gauss) for g in self.groups)

    @property
    def nonlinear(self) -> bool:
        return any(g.law.constant_moduli is None for g in self.groups)

    def evaluate(self, u: np.ndarray, states: tuple[Any, ...],
                 frozen: tuple[np.ndarray | None, ...] | None = None,
                 returned_secant: bool = False, tangent: bool = False) -> Evaluation:
        """Strains, stresses, moduli and internal forces at equation vector `u`.

        `frozen`, per group, marks points that may only unload/reload in this pass (the
        solver's chatter damping; a freezable law's option, as is `returned_secant`).
        `tangent`: every law's moduli are its consistent tangent d sigma / d eps (concrete's
        rotating-crack tangent instead of its iteration matrix), so `stiffness` assembles the
        tangent stiffness d f_int / d u."""
        eps = strain(self.kinematics, u)
        stress = np.empty_like(eps)
        moduli = np.empty(eps.shape + (4,))
        trial = []
        frozen = frozen or (None,) * len(self.groups)
        for group, state, mask in zip(self.groups, states, frozen, strict=True):
            n = group.cells.size * self.n_gauss
            sig, D, new = group.law.update(eps[group.cells].reshape(n, 4), state, mask,
                                           returned_secant, tangent)
            stress[group.cells] = sig.reshape(-1, self.n_gauss, 4)
            moduli[group.cells] = np.broadcast_to(D, (n, 4, 4)).reshape(-1, self.n_gauss, 4, 4)
            trial.append(new)
        f_int = self.assembler.vector(internal_force_blocks(self.kinematics, stress))
        return Evaluation(eps, stress, moduli, f_int, tuple(trial), tangent,
                          None if any(m is not None for m in frozen) else states)

    def with_tangent(self, evaluation: Evaluation) -> Evaluation:
        """`evaluation` with every law's consistent tangent as moduli: the same as
        `evaluate(..., tangent=True)` at its displacements, from the stresses, trial states
        and committed states it holds (`tangent_of` of every law with secant moduli; the
        others' moduli already are their tangents), without updating the laws again."""
        if evaluation.tangent:
            return evaluation
        if evaluation.committed is None:
            raise ValueError("an evaluation with frozen points has no consistent tangent")
        moduli = evaluation.moduli.copy()
        for group, state, trial in zip(self.groups, evaluation.committed, evaluation.states,
                                       strict=True):
            if not group.law.secant_moduli:
                continue
            n, cells = group.cells.size * self.n_gauss, group.cells
            D = group.law.tangent_of(evaluation.strain[cells].reshape(n, 4),
                                     evaluation.stress[cells].reshape(n, 4), trial, state)
            moduli[cells] = np.broadcast_to(D, (n, 4, 4)).reshape(-1, self.n_gauss, 4, 4)
        return replace(evaluation, moduli=moduli, tangent=True)

    def stiffness(self, evaluation: Evaluation) -> sp.csr_matrix:
        """Global stiffness from the moduli of `evaluation` (secant or tangent, per law)."""
        blocks = self._blocks
        for group, kin in zip(self.groups, self._group_kinematics, strict=True):
            if group.law.constant_moduli is None:
                blocks[group.cells] = stiffness_blocks(kin, evaluation.moduli[group.cells])
        return self.assembler.matrix(blocks)
