"""Supports plus the steel-concrete gap elements (thesis 3.3) as the solver's constraint set.

Owns the pair states: trial states within an increment, committed states between them; the
multipliers are unknowns of the augmented system (eq. 3.35) solved with a sparse LU.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import scipy.sparse as sp

from icewall.interface.augmented import (
    active_rows,
    augmented_rhs,
    factorize,
    interface_forces,
    reference_rhs,
    split_solution,
    upper_rows,
)
from icewall.interface.fixed_points import fixed_point_mask
from icewall.interface.gap import (
    FREE,
    GapState,
    constraint_matrix,
    count_states,
    end_forces,
    end_friction_work,
    friction_work_increment,
    hold_start_gaps,
    new_step,
    relative_displacement,
    settle_cycling_pairs,
    update_states,
)
from icewall.interface.pattern import AugmentedPattern, canonical_csr
from icewall.model.build import Model
from icewall.solve.constraints import SupportConstraints

CYCLE_TOGGLES = 6
"""Switches between held and open within one step after which a pair's state is decided
semismoothly (GapConstraints._settle_cycles)."""


class GapConstraints(SupportConstraints):
    """u[fixed] = 0 and one gap element per interface node pair."""

    def __init__(self, model: Model) -> None:
        super().__init__(model.dof_map.n_equations, model.fixed)
        mesh, interface = model.mesh, model.description.interface
        self.C = constraint_matrix(mesh.interface_pairs, mesh.interface_normals,
                                   model.dof_map.node_equations, self.n_equations)
        self.n_pairs = len(mesh.interface_pairs)
        self.n_multipliers = 2 * self.n_pairs
        self.mu = interface.friction
        self.reset_slip = interface.reset_slip_each_step
        self.reverse_slip = {"stick": "stick", "reverse": True, "none": False}[
            interface.slip_reversal]
        self.implicit_slip = interface.friction_update == "implicit"
        permanent = fixed_point_mask(mesh, interface)
        # Constraint rows acting only on supported equations (e.g. the tangential row of a pair
        # on the symmetry line, where both nodes have u_x = 0) are redundant: their multiplier
        # stays zero (an identity row while the row is active).
        free = np.ones(self.n_equations, dtype=bool)
        free[self.fixed] = False
        on_free = abs(self.C[:, np.flatnonzero(free)]).sum(axis=1)
        self.redundant = np.asarray(on_free).ravel() == 0.0
        self.committed = GapState.initial(self.n_pairs, permanent=permanent,
                                          separated=model.separating_preload)
        self.state = self.committed
        self._friction_work = 0.0
        self.max_changes = interface.max_state_changes
        self.stabilization = interface.stabilization
        self._CtC = (self.C.T @ self.C).tocsr()
        self.changes_in_step = np.zeros(self.n_pairs, dtype=int)
        self.frozen_pairs = 0
        # the Newton scheme: a pair that cycles between held and open is decided semismoothly
        self.settle_cycles = False
        self.augmentation: float | None = None
        self._pattern: AugmentedPattern | None = None  # built from the first stiffness
        self._checked_states = b""  # pair states of the last pivot-checked matrix

    def begin_step(self, time_step: bool = False) -> None:
        """The pair states of a new step; a time step holds its closed pairs at their gaps
        (interface.gap.hold_start_gaps)."""
        self.state = new_step(self.committed, reset_slip=self.reset_slip)
        if time_step:
            self.state = hold_start_gaps(self.state)
        self.changes_in_step = np.zeros(self.n_pairs, dtype=int)

    def commit(self) -> None:
        self._friction_work = friction_work_increment(self.committed, self.state)
        self.committed = self.state

    def rollback(self) -> None:
        self.state = self.committed

    def commit_time_step(self, end_share: float) -> None:
        """Accept a converged time step: it carries its gap forces at its end, so its solved
        multipliers are scaled to them (end_share = 1 - af) and its friction work is booked
        at them (interface.gap.end_forces, end_friction_work)."""
        before = self.committed
        self.committed = self.state = end_forces(self.state, end_share)
        self._friction_work = end_friction_work(before, self.committed)

    def constraint_force(self) -> np.ndarray:
        return interface_forces(self.C, self.state)

    def _redundant_active(self) -> np.ndarray:
        return self.redundant & active_rows(self.state)

    def factorize(self, K: sp.spmatrix):
        # weak springs on the relative displacement of every pair, in the iteration matrix
        # only (never in the residual): a core whose pairs are all open in some iterate
        # does not make the matrix singular, and the converged state is unchanged
        k = (self.stabilization * float(abs(K.diagonal()).max())
             if self.stabilization > 0.0 else 0.0)
        if self.settle_cycles and self.augmentation is None:
            self.augmentation = self._interface_stiffness(K)
        if self._pattern is None or not self._pattern.fits(K):
            K = canonical_csr(K)
            self._pattern = AugmentedPattern(K, self.C, self.fixed, self._CtC)
        A = self._pattern.matrix(K, active_rows(self.state),
                                 upper_rows(self.state, self.implicit_slip), self.state, self.mu,
                                 self.implicit_slip, stabilisation_factor=k,
                                 diagonal_pad=self._redundant_active().astype(float))
        # A floating core comes from the pair states: the pivots are checked whenever the
        # states differ from those of the last matrix that passed (the stiffness alone, with
        # its floored secants, does not make the matrix singular; SuperLU still reports an
        # exactly singular one and every solve checks its residual).
        states = self.state.state.tobytes()
        factor = factorize(A, self.sparse_backend,
                           check_pivots=states != self._checked_states)
        self._checked_states = states
        return factor

    def _interface_stiffness(self, K: sp.spmatrix) -> float:
        """The median diagonal stiffness (N/mm) of the equations the pairs connect: the
        augmentation r of the semismooth pair states."""
        touched = np.unique(self.C.tocoo().col)
        diagonal = np.abs(K.diagonal()[touched])
        return float(np.median(diagonal[diagonal > 0.0])) if np.any(diagonal > 0.0) else 1.0

    def reference_rhs(self, reference: np.ndarray) -> np.ndarray:
        return reference_rhs(reference, self.n_pairs, self.fixed)

    def unbalance_rhs(self, unbalance: np.ndarray, u: np.ndarray) -> np.ndarray:
        """`unbalance` = F_ext - F_int of the structure, without the gap forces."""
        rhs = augmented_rhs(unbalance, u, self.C, self.state, self.mu, self.fixed,
                            self.implicit_slip)
        rhs[self.n_equations:][self._redundant_active()] = 0.0
        return rhs

    def constraint_residuals(self, u: np.ndarray) -> tuple[float, float]:
        """(largest gap violation of an enforced row (mm), largest multiplier off its
        prescribed value (N)) at the current pair states: both vanish when every FIXED/SLIP
        target and every FREE/SLIP force holds, so a pair that changed state without moving
        the equilibrium (a pair with no force and no gap) does not block convergence."""
        bottom = augmented_rhs(np.zeros(self.n_equations), u, self.C, self.state, self.mu,
                               self.fixed, self.implicit_slip)[self.n_equations:]
        bottom[self._redundant_active()] = 0.0
        enforced = upper_rows(self.state, self.implicit_slip)
        gaps = np.abs(bottom[active_rows(self.state)])
        forces = np.abs(bottom[~enforced])
        return float(gaps.max(initial=0.0)), float(forces.max(initial=0.0))

    def apply(self, multiplier_increment: np.ndarray, u: np.ndarray) -> int:
        _, d_N, d_T = split_solution(np.concatenate([np.zeros(self.n_equations),
                                                     multiplier_increment]), self.n_equations)
        gap_N, gap_T = relative_displacement(self.C, u)
        old = self.state
        new, _ = update_states(old, old.lam_N + d_N, old.lam_T + d_T, gap_N, gap_T, self.mu,
                               reverse_slip=self.reverse_slip)
        if self.settle_cycles:  # Newton: no freezing
            self.state = self._settle_cycles(old, new, gap_N, gap_T)
            return int(np.count_nonzero(self.state.state != old.state))
        changed = (new.state != old.state) | (new.lam_T * old.lam_T < 0)
        # A pair that keeps changing state within one step (a limit cycle such as
        # fixed -> free -> fixed -> slip -> fixed) is frozen in its current state for the
        # rest of the step; the equilibrium norms then decide convergence, as in the thesis.
        frozen = changed & (self.changes_in_step >= self.max_changes)
        if frozen.any():
            new = replace(new, state=np.where(frozen, old.state, new.state),
                          stick_T=np.where(frozen, old.stick_T, new.stick_T),
                          lam_T=np.where(frozen, old.lam_T + d_T, new.lam_T))
            changed &= ~frozen
        self.changes_in_step += changed
        self.frozen_pairs = int(np.count_nonzero(self.changes_in_step >= self.max_changes))
        self.state = new
        return int(np.count_nonzero(changed))

    def _settle_cycles(self, old: GapState, new: GapState, gap_N: np.ndarray,
                       gap_T: np.ndarray) -> GapState:
        """Table 3.2's transitions, except for the pairs that have switched between held and
        open CYCLE_TOGGLES times in this step (interface.gap.settle_cycling_pairs)."""
        self.changes_in_step += (old.state != FREE) != (new.state != FREE)
        cycling = self.changes_in_step >= CYCLE_TOGGLES
        if not cycling.any():
            return new
        held = gap_N if old.hold_N is None else gap_N - old.hold_N  # against the row's target
        return settle_cycling_pairs(old, new, cycling, held, gap_T, self.mu,
                                    self.augmentation)

    def counts(self) -> dict[str, int]:
        counts = {f"gap_{name}": n for name, n in count_states(self.committed).items()}
        counts["gap_frozen"] = self.frozen_pairs
        return counts

    def friction_work_increment(self) -> float:
        return self._friction_work

    def arrays(self) -> dict[str, np.ndarray]:
        s = self.committed
        return {"interface/state": s.state, "interface/lam_N": s.lam_N,
                "interface/lam_T": s.lam_T, "interface/gap_N": s.gap_N,
                "interface/gap_T": s.gap_T}
