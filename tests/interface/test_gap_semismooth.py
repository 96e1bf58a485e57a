"""The semismooth pair states (interface.gap.semismooth_states, Alart & Curnier 1991): every
case of the normal and Coulomb complementarity decided from the augmented multipliers, a
converged state decided as itself, and the decision independent of the augmentation where
forces and gaps agree."""

from __future__ import annotations

import numpy as np
import pytest

from icewall.interface import FIXED, FREE, SLIP, GapState
from icewall.interface.gap import semismooth_states

MU, R = 0.5, 1000.0


def _decide(old, lam_N, lam_T, gap_N, gap_T, stick_T=0.0, permanent=False, r=R):
    s = GapState.initial(1, np.array([permanent]))
    s = GapState(np.array([old], np.int8), np.array([lam_N], float), np.array([lam_T], float),
                 np.array([gap_N], float), np.array([gap_T], float),
                 np.array([stick_T], float), s.permanent, np.array([stick_T], float))
    new, _ = semismooth_states(s, s.lam_N, s.lam_T, s.gap_N, s.gap_T, MU, r)
    return new


@pytest.mark.parametrize("old, lam_N, lam_T, gap_N, gap_T, expected", [
    (FIXED, -10.0, 4.0, 0.0, 0.0, FIXED),    # compressed, inside the cone: stick
    (FIXED, -10.0, 6.0, 0.0, 0.0, SLIP),     # outside the cone: slip
    (FIXED, -10.0, -6.0, 0.0, 0.0, SLIP),
    (FIXED, 3.0, 0.0, 0.0, 0.0, FREE),       # tension opens
    (FREE, 0.0, 0.0, 0.01, 0.3, FREE),       # open stays open
    (FREE, 0.0, 0.0, -0.01, 0.3, FIXED),     # penetration closes, held where it closed
    (SLIP, -10.0, 5.0, 0.0, 0.002, SLIP),    # sliding with its force: keeps sliding
    (SLIP, -10.0, 5.0, 0.0, -0.002, FIXED),  # slid back within the cone: sticks
    (SLIP, -10.0, 5.0, 0.0, -0.02, SLIP),    # slid back beyond it: slides the other way
    (SLIP, 1.0, 0.5, 0.0, 0.01, FREE),       # pulled apart while sliding
])
def test_every_case_of_the_complementarity(old, lam_N, lam_T, gap_N, gap_T, expected):
    new = _decide(old, lam_N, lam_T, gap_N, gap_T)
    assert new.state[0] == expected
    if expected == SLIP:  # on the Coulomb cone, in the direction of the trial force
        trial = lam_T + R * gap_T
        normal = abs(lam_N + R * gap_N)
        assert new.lam_T[0] == pytest.approx(np.sign(trial) * MU * normal)
    if old == FREE and expected == FIXED:
        assert new.stick_T[0] == gap_T


def test_permanent_pairs_stay_fixed_in_tension():
    assert _decide(FIXED, 50.0, 80.0, 0.1, 0.1, permanent=True).state[0] == FIXED


def test_a_converged_state_is_decided_as_itself_for_any_augmentation():
    """At a solution of the complementarity conditions the decision does not move it."""
    cases = [(FIXED, -10.0, 3.0, 0.0, 0.0), (SLIP, -10.0, -5.0, 0.0, -0.4),
             (FREE, 0.0, 0.0, 0.2, 1.0)]
    for r in (1.0, 1e3, 1e6):
        for old, lam_N, lam_T, gap_N, gap_T in cases:
            new = _decide(old, lam_N, lam_T, gap_N, gap_T, r=r)
            assert new.state[0] == old
            assert new.lam_T[0] == pytest.approx(lam_T)


def test_cycling_pairs_are_settled_and_the_others_keep_table_3_2():
    """Pair 0 cycles held <-> open (held: tension; open: penetration): pulled open again it
    stays closed and slides at the Coulomb limit of its augmented normal force, in the
    direction of its trial friction force. Pair 1 makes the same move without cycling and
    opens, as Table 3.2 says. Pair 2 cycles while sliding and is in tension: it opens."""
    from icewall.interface import update_states
    from icewall.interface.gap import settle_cycling_pairs

    old = GapState(np.array([FIXED, FIXED, SLIP], np.int8), np.array([200.0, 200.0, 150.0]),
                   np.array([380.0, 380.0, 60.0]), np.zeros(3), np.array([0.0, 0.0, 0.01]),
                   np.zeros(3), np.zeros(3, bool), np.zeros(3))
    gap_N, gap_T = np.full(3, -0.05), np.array([-1.0, -1.0, 0.01])
    new, _ = update_states(old, old.lam_N, old.lam_T, gap_N, gap_T, MU)
    assert list(new.state) == [FREE, FREE, FREE]
    settled = settle_cycling_pairs(old, new, np.array([True, False, True]), gap_N, gap_T, MU, R)
    assert list(settled.state) == [SLIP, FREE, FREE]
    normal = abs(200.0 + R * -0.05)
    trial = 380.0 + R * (-1.0 - 0.0)
    assert settled.lam_T[0] == pytest.approx(np.sign(trial) * MU * normal)
    assert settled.lam_T[1] == new.lam_T[1]
