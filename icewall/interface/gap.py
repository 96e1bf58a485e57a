"""Node-to-node steel-concrete gap elements (thesis §3.3, Katona 1984), vectorised over pairs.

Sign conventions (thesis eq. 3.39 and Fig. 3.14, errata §1.2):
  pair p = (node 1 = steel, node 2 = concrete); n = (C, S) unit normal from the steel into the
  concrete, t = (-S, C). Relative displacement d = u2 - u1, normal gap Delta_N = n.d (> 0
  opening), tangential Delta_T = t.d. Constraint rows on (u1, v1, u2, v2), eq. 3.39:
      C_N = [-C, -S, C, S] (row 2p),  C_T = [S, -C, -S, C] (row 2p + 1).
  Augmented equations (3.35): K du + C^T dlam = dQ, C du = da. The gap force on the nodes is
  -C^T lam (C^T lam belongs with the internal forces), so lam_N < 0 is contact (compression)
  and lam_N > 0 is tension, which frees the pair. lam_T > 0 resists a positive slip Delta_T.

States: FIXED (both rows constrained, total targets Delta_N = 0, Delta_T = stick_T), SLIP
(normal row constrained, lam_T prescribed at the Coulomb limit), FREE (lam_N = lam_T = 0).
Multipliers and gaps are accumulated (total) values; `icewall.interface.augmented` builds the
iteration matrix and right-hand sides from a GapState. A SLIP pair keeps sign(lam_T) (errata
3.41) unless its slip in the step opposes lam_T (update_states(reverse_slip=True), not thesis).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
import scipy.sparse as sp

FIXED, SLIP, FREE = 0, 1, 2
STATE_NAMES = ("fixed", "slip", "free")

# Tolerances of the state checks (Table 3.2). Forces are compared with the pair-force scale
# max_p max(|lam_N|, |lam_T|) (or `force_scale`), gaps with max(GAP_ATOL, GAP_RTOL max|Delta_N|):
#  - a FIXED/SLIP pair frees only if lam_N > FORCE_RTOL * scale (round-off tension of an unloaded
#    pair must not free it and chatter);
#  - FIXED -> SLIP needs |lam_T| >= mu |lam_N| - FORCE_RTOL * scale and |lam_T| > FORCE_RTOL *
#    scale (the errata's ">=" boundary, round-off safe, and no "slip" of an unloaded pair);
#  - FREE -> FIXED needs Delta_N < -gap_tol (real penetration, not round-off of a closed gap).
FORCE_RTOL = 1e-9
GAP_RTOL = 1e-9
GAP_ATOL = 1e-9  # mm; displacements of interest are >= 1e-4 mm, round-off ~ 1e-15 mm

TRANSITIONS = ("fixed->slip", "fixed->free", "slip->free", "free->fixed", "slip reversed")


@dataclass(frozen=True)
class GapState:
    """Interface state of all pairs: states, accumulated multipliers and separations."""

    state: np.ndarray  # (n,) int8 FIXED | SLIP | FREE
    lam_N: np.ndarray  # (n,) accumulated normal multiplier (N), < 0 compression
    lam_T: np.ndarray  # (n,) accumulated tangential multiplier (N)
    gap_N: np.ndarray  # (n,) accumulated normal separation Delta_N (mm), > 0 open
    gap_T: np.ndarray  # (n,) accumulated tangential separation Delta_T (mm)
    stick_T: np.ndarray  # (n,) Delta_T at which a FIXED pair is held (total target of its C_T row)
    permanent: np.ndarray  # (n,) bool, "fixed points" (§4.3.2): always FIXED
    # (n,) Delta_T where the current slip began: the start of the load step (new_step), or the
    # iterate at which the pair last started to slip
    step_T: np.ndarray | None = None
    transitions: dict[str, int] = field(default_factory=dict)  # of the last update/new_step
    # (n,) Delta_N at which a FIXED/SLIP pair is held (the total target of its C_N row): None,
    # zero (contact), except in a time step, which holds the pairs closed at its start at the
    # gap they had (`hold_start_gaps`)
    hold_N: np.ndarray | None = None

    @classmethod
    def initial(cls, n_pairs: int, permanent: np.ndarray | None = None,
                separated: bool = False) -> GapState:
        """All pairs FIXED (perfect bond of the coincident nodes), zero forces and gaps; with
        `separated`, all but the permanent ones FREE: the concrete separated from the steel, as
        an in-plane tension applied first makes it (thesis 4.2.2), each pair closing where it
        would penetrate (Table 3.2's FREE -> FIXED). From the bonded state the first iterate
        of such a tension drags the cores with the plates, and the pair states that follow
        from it cycle (TF-5 with its cores pinned at one station: docs/solver.md item 50)."""
        zeros = np.zeros(n_pairs)
        perm = np.zeros(n_pairs, bool) if permanent is None else np.asarray(permanent, bool)
        if perm.shape != (n_pairs,):
            raise ValueError(f"permanent must be ({n_pairs},) bool, got shape {perm.shape}")
        state = np.where(perm | (not separated), FIXED, FREE).astype(np.int8)
        return cls(state=state, lam_N=zeros, lam_T=zeros.copy(),
                   gap_N=zeros.copy(), gap_T=zeros.copy(), stick_T=zeros.copy(), permanent=perm,
                   step_T=zeros.copy())

    @property
    def n_pairs(self) -> int:
        return int(self.state.size)

    @property
    def lam(self) -> np.ndarray:
        """Multipliers (2n,) in constraint-row order [N_0, T_0, N_1, T_1, ...]."""
        return np.column_stack([self.lam_N, self.lam_T]).ravel()

    @property
    def n_flips(self) -> int:
        return int(sum(self.transitions.values()))


def constraint_matrix(pairs: np.ndarray, normals: np.ndarray, node_equations: np.ndarray,
                      n_eq: int) -> sp.csr_matrix:
    """C (2 n_pairs, n_eq) of eq. 3.39: row 2p = C_N, row 2p+1 = C_T of pair p. Build once."""
    pairs = np.asarray(pairs, dtype=int).reshape(-1, 2)
    c, s = np.asarray(normals, dtype=float).reshape(-1, 2).T
    n = pairs.shape[0]
    eqs = np.asarray(node_equations)[pairs].reshape(n, 4)  # (u1, v1, u2, v2)
    # eq. 3.39 (errata §1.2: correct as printed; Table 3.1's U1/lam_T entry is +S, = C_T[0])
    values = np.stack([np.stack([-c, -s, c, s], 1), np.stack([s, -c, -s, c], 1)], 1)  # (n,2,4)
    rows = np.broadcast_to(2 * np.arange(n)[:, None, None] + np.arange(2)[None, :, None],
                           (n, 2, 4))
    cols = np.broadcast_to(eqs[:, None, :], (n, 2, 4))
    return sp.csr_matrix((values.ravel(), (rows.ravel(), cols.ravel())), shape=(2 * n, n_eq))


def relative_displacement(C: sp.spmatrix, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(Delta_N, Delta_T) (n_pairs,) of the equation displacement vector u: C u by rows."""
    d = C @ np.asarray(u, dtype=float)
    return d[0::2].copy(), d[1::2].copy()


def slip_force(lam_N: np.ndarray, lam_T: np.ndarray, mu: float) -> np.ndarray:
    """Coulomb limit with the direction of lam_T kept: sign(lam_T) mu |lam_N| (errata 3.41)."""
    return np.sign(lam_T) * mu * np.abs(lam_N)


def update_states(state: GapState, lam_N: np.ndarray, lam_T: np.ndarray, gap_N: np.ndarray,
                  gap_T: np.ndarray, mu: float, force_scale: float | None = None,
                  reverse_slip: bool | str = "stick") -> tuple[GapState, int]:
    """Table 3.2 (corrected, errata §1.2) applied to the updated multipliers and gaps.

    FIXED -> FREE if lam_N > 0; FIXED -> SLIP if lam_N <= 0 and |lam_T| >= mu |lam_N| (the
    printed "lam_T > mu lam_N" lost its absolute values); SLIP -> FREE if lam_N > 0 (no SLIP ->
    FIXED within a step, §3.3.4); FREE -> FIXED if Delta_N < 0, holding stick_T = Delta_T.
    Permanent pairs stay FIXED. Returns (new state with the new lam/gaps, number of changes).

    reverse_slip (not in the thesis): a SLIP pair whose slip in this step, Delta_T - step_T,
    opposes its lam_T (negative dissipation, e.g. a sign picked up from a transient
    iterate, which 3.41 would otherwise lock in for the whole step) gets lam_T negated, so the
    next prescribed return uses the friction direction that opposes the slip.
    reverse_slip="stick" (not in the thesis either) returns such a pair to FIXED at its current
    Delta_T instead: its slip has stopped or turned, so it sticks until its shear again
    reaches the Coulomb limit. False keeps the thesis rule (no SLIP -> FIXED within a step).
    """
    lam_N, lam_T = np.asarray(lam_N, float), np.asarray(lam_T, float)
    gap_N, gap_T = np.asarray(gap_N, float), np.asarray(gap_T, float)
    if force_scale is None:
        force_scale = float(max(np.abs(lam_N).max(initial=0.0), np.abs(lam_T).max(initial=0.0)))
    f_tol = FORCE_RTOL * force_scale
    step_T = state.gap_T if state.step_T is None else state.step_T
    g_tol = max(GAP_ATOL, GAP_RTOL * float(np.abs(gap_N).max(initial=0.0)))
    old = state.state
    tension = lam_N > f_tol
    at_limit = (np.abs(lam_T) >= mu * np.abs(lam_N) - f_tol) & (np.abs(lam_T) > f_tol)
    movable = ~state.permanent
    changes = {
        "fixed->free": (old == FIXED) & tension & movable,
        "fixed->slip": (old == FIXED) & ~tension & at_limit & movable,
        "slip->free": (old == SLIP) & tension & movable,
        "free->fixed": (old == FREE) & (gap_N < -g_tol),
        "slip reversed": (old == SLIP) & ~tension & (lam_T * (gap_T - step_T) < 0)
        & (np.abs(gap_T - step_T) > g_tol) & bool(reverse_slip),
    }
    sticks = changes["slip reversed"] if reverse_slip == "stick" else np.zeros_like(old, bool)
    if reverse_slip == "stick":
        changes["slip->fixed (reversal)"] = changes.pop("slip reversed")
    else:
        lam_T = np.where(changes["slip reversed"], -lam_T, lam_T)
    new = old.copy()
    new[changes["fixed->free"] | changes["slip->free"]] = FREE
    new[changes["fixed->slip"]] = SLIP
    new[changes["free->fixed"] | sticks | state.permanent] = FIXED
    # Table 3.3: db = 0, the pair is held where it is
    stick_T = np.where(changes["free->fixed"] | sticks, gap_T, state.stick_T)
    if reverse_slip == "stick":  # judge the slip direction from where the pair began to slip
        step_T = np.where(changes["fixed->slip"], gap_T, step_T)
    counts = {k: int(np.count_nonzero(v)) for k, v in changes.items()}
    new_state = replace(state, state=new, lam_N=lam_N.copy(), lam_T=lam_T.copy(),
                        gap_N=gap_N.copy(), gap_T=gap_T.copy(), stick_T=stick_T,
                        step_T=step_T, transitions=counts)
    return new_state, sum(counts.values())


def _augmented(lam_N: np.ndarray, lam_T: np.ndarray, gap_N: np.ndarray, gap_T: np.ndarray,
               stick_T: np.ndarray, augmentation: float) -> tuple[np.ndarray, np.ndarray]:
    """Augmented normal force lam_N + r Delta_N and trial friction force
    lam_T + r (Delta_T - stick_T) of each pair (Alart & Curnier 1991)."""
    return lam_N + augmentation * gap_N, lam_T + augmentation * (gap_T - stick_T)


def semismooth_states(state: GapState, lam_N: np.ndarray, lam_T: np.ndarray,
                      gap_N: np.ndarray, gap_T: np.ndarray, mu: float,
                      augmentation: float) -> tuple[GapState, int]:
    """The pair states of a semismooth Newton iteration (Alart & Curnier 1991): decided anew at
    every iterate from the augmented multipliers, not by transitions from the last state.

    Normal: closed iff lam_N + r Delta_N < 0 (the complementarity Delta_N >= 0, lam_N <= 0,
    lam_N Delta_N = 0 as the root of min(-lam_N, r Delta_N)). Tangential (a closed pair):
    the trial force t = lam_T + r (Delta_T - stick_T), stick_T the pair's position at the
    start of the step (or where it closed in it: backward-Euler friction); FIXED iff
    |t| <= mu |lam_N + r Delta_N|, else SLIP with lam_T = sign(t) mu |lam_N + r Delta_N|
    (the projection onto the Coulomb cone; the slip then follows the force, lam_T dDelta_T
    >= 0). Any r > 0 gives the same solutions; r of the order of the interface stiffness
    makes the decision weigh forces and gaps alike. Permanent pairs stay FIXED.
    """
    lam_N, lam_T = np.asarray(lam_N, float), np.asarray(lam_T, float)
    gap_N, gap_T = np.asarray(gap_N, float), np.asarray(gap_T, float)
    old = state.state
    closed = (lam_N + augmentation * gap_N < 0.0) | state.permanent
    stick_T = np.where(closed & (old == FREE), gap_T, state.stick_T)
    normal, trial = _augmented(lam_N, lam_T, gap_N, gap_T, stick_T, augmentation)
    limit = mu * np.abs(normal)
    slips = closed & ~state.permanent & (np.abs(trial) > limit)
    new = np.where(closed, np.where(slips, SLIP, FIXED), FREE).astype(np.int8)
    lam_T = np.where(slips, np.sign(trial) * limit, lam_T)
    counts = {f"{STATE_NAMES[a]}->{STATE_NAMES[b]}": int(np.count_nonzero((old == a) & (new == b)))
              for a in (FIXED, SLIP, FREE) for b in (FIXED, SLIP, FREE) if a != b}
    counts["slip reversed"] = int(np.count_nonzero(slips & (old == SLIP)
                                                   & (lam_T * state.lam_T < 0)))
    new_state = replace(state, state=new, lam_N=lam_N.copy(), lam_T=lam_T, gap_N=gap_N.copy(),
                        gap_T=gap_T.copy(), stick_T=stick_T, transitions=counts)
    return new_state, sum(counts.values())


def settle_cycling_pairs(old: GapState, new: GapState, cycling: np.ndarray,
                         gap_N: np.ndarray, gap_T: np.ndarray, mu: float,
                         augmentation: float) -> GapState:
    """`new` (Table 3.2's transitions from `old`) with the `cycling` pairs decided as a
    semismooth Newton would (`semismooth_states`). Table 3.2 walks a pair from held to open
    and back when each state contradicts itself (held: in tension; open: penetrating), as
    happens next to a concrete point at a kink of its law; the augmented multipliers weigh
    force and gap together, and a held pair that is pulled open again stays closed and
    slides, at the Coulomb limit in the direction of its trial friction force (if it is then
    in tension while sliding, it opens)."""
    decided, _ = semismooth_states(old, new.lam_N, new.lam_T, gap_N, gap_T, mu, augmentation)
    reopened = cycling & (decided.state == FREE) & (old.state == FIXED)
    normal, trial = _augmented(decided.lam_N, decided.lam_T, gap_N, gap_T, decided.stick_T,
                               augmentation)
    state = np.where(reopened, SLIP, decided.state)
    lam_T = np.where(reopened, np.sign(trial) * mu * np.abs(normal), decided.lam_T)
    return replace(new, state=np.where(cycling, state, new.state).astype(np.int8),
                   lam_T=np.where(cycling, lam_T, new.lam_T),
                   stick_T=np.where(cycling, decided.stick_T, new.stick_T))


def new_step(state: GapState, reset_slip: bool = True) -> GapState:
    """Start of a load step: slipped pairs reset to FIXED at their current Delta_T (§3.3.4).

    The reset makes the response path dependent; it is counted in transitions["slip->fixed
    (new step)"] so the solver can report it. reset_slip=False keeps the slip states.
    """
    reset = (state.state == SLIP) & reset_slip
    new = np.where(reset | state.permanent, FIXED, state.state).astype(np.int8)
    stick_T = np.where(reset, state.gap_T, state.stick_T)
    return replace(state, state=new, stick_T=stick_T, step_T=state.gap_T.copy(), hold_N=None,
                   transitions={"slip->fixed (new step)": int(np.count_nonzero(reset))})


def end_forces(state: GapState, end_share: float) -> GapState:
    """A time step's pair state with its multipliers at the step's end forces: solved with the
    af-weighted equation of motion, they are those forces over end_share = 1 - af
    (solve.energy.structural_unbalance)."""
    return replace(state, lam_N=end_share * state.lam_N, lam_T=end_share * state.lam_T)


def end_friction_work(state_old: GapState, state_new: GapState) -> float:
    """Friction work (N mm) of a time step at its end forces, sum |lam_T| |dDelta_T| over the
    pairs SLIP in `state_new` (the work a slip rule makes non-negative; the trapezoidal
    `friction_work_increment` would carry the start's force of a slip that reverses)."""
    slipping = state_new.state == SLIP
    return float(np.sum(np.abs(state_new.lam_T[slipping])
                        * np.abs(state_new.gap_T[slipping] - state_old.gap_T[slipping])))


def hold_start_gaps(state: GapState) -> GapState:
    """The state of a time step's start with each pair held there at the normal gap it has
    (zero for the open ones): the residual gap a static step leaves a closed pair (eq. 4.4's
    tolerance, up to 1e-4 of the displacements) is no target the motion must reach. Pulled
    shut within a time step it moves the pair's nodes by that gap whatever the step's length,
    a jump no shorter step resolves (CF-14 at 6.7 mm, CF-7 at 18.1 mm: docs/solver.md item 49).
    Moreau's contact conditions on the velocities leave it so."""
    closed = state.state != FREE
    return replace(state, hold_N=np.where(closed, state.gap_N, 0.0))


def count_states(state: GapState) -> dict[str, int]:
    """Number of pairs in each state: {"fixed": .., "slip": .., "free": ..}."""
    counts = np.bincount(state.state, minlength=3)
    return {name: int(counts[k]) for k, name in enumerate(STATE_NAMES)}


def friction_work_increment(state_old: GapState, state_new: GapState) -> float:
    """Energy (N mm) dissipated by slip between two converged states (e.g. one load step).

    Trapezoidal estimate sum 0.5 (|lam_T_old| + |lam_T_new|) |Delta_T_new - Delta_T_old| over
    the pairs that are SLIP in `state_new` (stuck pairs do not move, free pairs carry no force).
    """
    slipping = state_new.state == SLIP
    mean_force = 0.5 * (np.abs(state_old.lam_T) + np.abs(state_new.lam_T))
    return float(np.sum((mean_force * np.abs(state_new.gap_T - state_old.gap_T))[slipping]))
