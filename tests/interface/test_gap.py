"""Gap-element unit tests: Table 3.2 decision matrix, Table 3.1/3.3 (with errata §1.2),
constraint matrix of eq. 3.39, new-step reset, fixed points and bookkeeping."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from icewall.interface import (
    FIXED,
    FREE,
    SLIP,
    GapState,
    augmented_matrix,
    augmented_rhs,
    choose_fixed_points,
    constraint_matrix,
    count_states,
    friction_work_increment,
    new_step,
    relative_displacement,
    update_states,
)
from icewall.interface.augmented import prescribed_increments

MU = 0.5


def _state(states, lam_N=0.0, lam_T=0.0, gap_N=0.0, gap_T=0.0, permanent=None):
    n = len(states)
    s = GapState.initial(n, permanent)
    f = [np.broadcast_to(np.asarray(v, float), (n,)).copy() for v in (lam_N, lam_T, gap_N,
                                                                        gap_T)]
    return GapState(np.asarray(states, np.int8), *f, s.stick_T, s.permanent)


def _update(states, lam_N, lam_T, gap_N=0.0, gap_T=0.0, permanent=None):
    s = _state(states, permanent=permanent)
    n = len(states)
    arr = [np.broadcast_to(np.asarray(v, float), (n,)) for v in (lam_N, lam_T, gap_N, gap_T)]
    return update_states(s, *arr, MU, force_scale=100.0)


# --- Table 3.2, every cell (corrected: absolute values, lam_N < 0 contact) -----------------

@pytest.mark.parametrize("old, lam_N, lam_T, gap_N, expected", [
    (FIXED, -10.0, 4.9, 0.0, FIXED),     # |lam_T| < mu |lam_N|: stick
    (FIXED, -10.0, -4.9, 0.0, FIXED),
    (FIXED, -10.0, 0.0, 0.0, FIXED),     # printed lam_T < mu lam_N (0 < -5) is false -> "slip"
    (FIXED, -10.0, 5.0, 0.0, SLIP),      # |lam_T| >= mu |lam_N| (boundary belongs to slip)
    (FIXED, -10.0, -7.0, 0.0, SLIP),     # printed lam_T > mu lam_N (-7 > -5) false -> "stick"
    (FIXED, 3.0, 0.0, 0.0, FREE),        # tension
    (FIXED, 3.0, 50.0, 0.0, FREE),       # tension wins over the friction check
    (FIXED, 0.0, 0.0, 0.0, FIXED),       # unloaded pair stays bonded
    (SLIP, -10.0, 5.0, 0.0, SLIP),
    (SLIP, -10.0, 0.1, 0.0, SLIP),       # no slip -> fixed within a step
    (SLIP, 1.0, 5.0, 0.0, FREE),
    (FREE, 0.0, 0.0, -0.01, FIXED),      # penetration closes the gap
    (FREE, 0.0, 0.0, 0.01, FREE),        # open stays free
    (FREE, 0.0, 0.0, 0.0, FREE),         # touching without overlap stays free
])
def test_decision_matrix_every_cell(old, lam_N, lam_T, gap_N, expected):
    new, flips = _update([old], lam_N, lam_T, gap_N)
    assert new.state[0] == expected
    assert flips == int(expected != old)


def test_printed_table_3_2_would_fail_these_cases():
    lam_N, lam_T = np.array([-10.0, -10.0]), np.array([0.0, -7.0])
    printed_slip = lam_T > MU * lam_N  # as printed: zero shear slips, large negative sticks
    new, _ = _update([FIXED, FIXED], lam_N, lam_T)
    assert printed_slip.tolist() == [True, False]
    assert new.state.tolist() == [FIXED, SLIP]


def test_round_off_tension_and_gap_do_not_chatter():
    new, flips = _update([FIXED, FIXED, FREE], [1e-12, 0.0, 0.0], [0.0, 1e-12, 0.0],
                         [0.0, 0.0, -1e-13])
    assert flips == 0 and new.state.tolist() == [FIXED, FIXED, FREE]


def test_free_to_fixed_holds_the_current_tangential_offset():
    new, _ = _update([FREE, FREE], 0.0, 0.0, [-0.2, 0.1], [0.7, 0.3])
    assert new.state.tolist() == [FIXED, FREE]
    assert new.stick_T[0] == 0.7 and new.transitions["free->fixed"] == 1


def test_permanent_pairs_never_leave_fixed():
    perm = np.array([True, True, False])
    new, flips = _update([FIXED] * 3, [5.0, -1.0, 5.0], [0.0, 9.0, 0.0], permanent=perm)
    assert new.state.tolist() == [FIXED, FIXED, FREE] and flips == 1
    stepped = new_step(_state([SLIP, FIXED, SLIP], permanent=perm))
    assert stepped.state.tolist() == [FIXED, FIXED, FIXED]


# --- Table 3.3 / eq. 3.41 (errata): friction return keeps the direction of lam_T ------------

@pytest.mark.parametrize("lam_T", [8.0, -8.0])
def test_slip_return_to_coulomb_limit_both_signs(lam_T):
    s = _state([SLIP], lam_N=-10.0, lam_T=lam_T)
    d_lam = prescribed_increments(s, MU)
    assert d_lam[0] == 0.0  # the normal row is a constraint, not prescribed
    assert s.lam_T[0] + d_lam[1] == pytest.approx(np.sign(lam_T) * MU * 10.0, rel=1e-15)
    printed_eq_3_41 = lam_T - MU * -10.0  # "T = lam_T - mu lam_N" adds the excess
    printed_table_3_3 = MU * -10.0 - lam_T  # right only for lam_T < 0
    assert lam_T + printed_eq_3_41 != pytest.approx(np.sign(lam_T) * MU * 10.0)
    if lam_T > 0:
        assert lam_T + printed_table_3_3 == pytest.approx(-5.0)  # friction reversed
        assert d_lam[1] != pytest.approx(printed_table_3_3)


def test_free_pairs_return_multipliers_to_zero():
    s = _state([FREE], lam_N=4.0, lam_T=-3.0)
    np.testing.assert_array_equal(prescribed_increments(s, MU), [-4.0, 3.0])  # eq. 3.43


@pytest.mark.parametrize("kind", [SLIP, FREE])
def test_rhs_equals_table_3_1_load_column(kind):
    """Top rows = -C_T^T T (slip) and -C_N^T N - C_T^T T (free) when r_u = C^T lam."""
    phi = 0.6
    c, s = np.cos(phi), np.sin(phi)
    C = constraint_matrix(np.array([[0, 1]]), np.array([[c, s]]), np.arange(4).reshape(2, 2), 4)
    st = _state([kind], lam_N=-10.0 if kind == SLIP else 2.0, lam_T=7.0)
    rhs = augmented_rhs(C.T @ st.lam, np.zeros(4), C, st, MU)
    T = (MU * 10.0 - 7.0) if kind == SLIP else -7.0
    N = 0.0 if kind == SLIP else -2.0
    table = np.array([c * N - s * T, s * N + c * T, -c * N + s * T, -s * N - c * T])
    np.testing.assert_allclose(rhs[:4], table, atol=1e-13)
    assert rhs[5] == pytest.approx(T)


# --- eq. 3.39 and Table 3.1 stiffness (errata: +S) ----------------------------------------

def test_constraint_matrix_measures_normal_and_tangential_gap():
    rng = np.random.default_rng(1)
    n_nodes, n_pairs = 12, 6
    pairs = rng.permutation(n_nodes)[: 2 * n_pairs].reshape(n_pairs, 2)
    angle = rng.uniform(0, 2 * np.pi, n_pairs)
    normals = np.column_stack([np.cos(angle), np.sin(angle)])
    C = constraint_matrix(pairs, normals, np.arange(2 * n_nodes).reshape(-1, 2), 2 * n_nodes)
    u = rng.normal(size=2 * n_nodes)
    d = u.reshape(-1, 2)[pairs[:, 1]] - u.reshape(-1, 2)[pairs[:, 0]]
    tangents = np.column_stack([-normals[:, 1], normals[:, 0]])
    gap_N, gap_T = relative_displacement(C, u)
    np.testing.assert_allclose(gap_N, np.sum(normals * d, 1), atol=1e-14)
    np.testing.assert_allclose(gap_T, np.sum(tangents * d, 1), atol=1e-14)


def test_fixed_stiffness_is_symmetric_with_plus_S():
    phi = 0.4
    c, s = np.cos(phi), np.sin(phi)
    C = constraint_matrix(np.array([[0, 1]]), np.array([[c, s]]), np.arange(4).reshape(2, 2), 4)
    A = augmented_matrix(sp.csr_matrix((4, 4)), C, GapState.initial(1)).toarray()
    np.testing.assert_allclose(A, A.T, atol=0)
    corrected = np.array([[-c, s], [-s, -c], [c, -s], [s, c]])  # Table 3.1 with U1/lam_T = +S
    printed = corrected.copy()
    printed[0, 1] = -s
    np.testing.assert_allclose(A[:4, 4:], corrected, atol=1e-15)
    assert not np.allclose(printed, C.toarray().T)


# --- new step, bookkeeping, fixed points ---------------------------------------------------

def test_new_step_resets_slip_to_fixed_at_current_offset_switchable():
    s = _state([SLIP, FREE, FIXED], lam_N=-1.0, gap_T=[0.3, 0.2, 0.1])
    reset = new_step(s)
    assert reset.state.tolist() == [FIXED, FREE, FIXED]
    assert reset.stick_T[0] == 0.3 and reset.transitions["slip->fixed (new step)"] == 1
    kept = new_step(s, reset_slip=False)
    assert kept.state.tolist() == [SLIP, FREE, FIXED]


def test_count_states_and_friction_work():
    old = _state([FIXED, SLIP, FREE], lam_T=[2.0, 4.0, 0.0], gap_T=[0.0, 1.0, 5.0])
    new = _state([FIXED, SLIP, FREE], lam_T=[2.0, -6.0, 0.0], gap_T=[0.0, 0.5, 9.0])
    assert count_states(new) == {"fixed": 1, "slip": 1, "free": 1}
    assert friction_work_increment(old, new) == pytest.approx(0.5 * (4.0 + 6.0) * 0.5)


def test_fixed_points_on_top_face_nearest_mid_length(driver):
    m = driver.model(concrete_on_top=False, nx=10)
    chosen = choose_fixed_points(m.mesh)
    x = m.mesh.points[m.pairs[chosen, 1], 0]
    assert chosen.sum() == 2 and sorted(x.tolist()) == [40.0, 50.0]
    assert choose_fixed_points(m.mesh, per_core=1).sum() == 1


def test_fixed_points_of_a_wall_deck():
    from icewall.deck.load import load_deck
    from icewall.mesh.build import build_mesh

    deck = load_deck(Path(__file__).resolve().parents[2] / "decks" / "cf4.yaml", ()).deck
    mesh = build_mesh(deck)
    chosen = choose_fixed_points(mesh)
    cores = [r for r in mesh.regions if r.kind == "concrete"]
    assert chosen.sum() == 2 * len(cores)
    np.testing.assert_allclose(mesh.interface_normals[chosen], [[0.0, -1.0]] * chosen.sum())
    top = mesh.points[mesh.interface_pairs[chosen, 1], 1]
    assert np.allclose(top, top.max())  # all under the top plate
    assert 0.0 in mesh.points[mesh.interface_pairs[chosen, 1], 0]  # core cut by symmetry


def test_slip_against_its_friction_force_is_reversed_switchable():
    """Not in the thesis: a slip opposing lam_T (negative dissipation) flips its direction."""
    s = replace(_state([SLIP, SLIP], lam_N=-10.0, lam_T=-5.0, gap_T=[0.01, -0.01]),
                step_T=np.zeros(2))
    args = (s.lam_N, s.lam_T, s.gap_N, s.gap_T, MU)
    new, flips = update_states(s, *args, reverse_slip=True)
    assert new.lam_T.tolist() == [5.0, -5.0] and flips == 1
    assert new.transitions["slip reversed"] == 1 and new.state.tolist() == [SLIP, SLIP]
    kept, flips = update_states(s, *args, reverse_slip=False)
    assert kept.lam_T.tolist() == [-5.0, -5.0] and flips == 0
    # the default ("stick"): the pair whose slip opposes its friction force sticks where it is
    stuck, flips = update_states(s, *args)
    assert stuck.state.tolist() == [FIXED, SLIP] and flips == 1
    assert stuck.stick_T[0] == pytest.approx(0.01)
    assert stuck.transitions["slip->fixed (reversal)"] == 1


def _cf4_mesh():
    from icewall.deck.load import load_deck
    from icewall.mesh.build import build_mesh

    return build_mesh(load_deck(Path(__file__).resolve().parents[2] / "decks" / "cf4.yaml",
                                ()).deck)


def test_fixed_points_at_the_diaphragm_plate_corners():
    mesh = _cf4_mesh()
    chosen = choose_fixed_points(mesh, placement="corners")
    xy = mesh.points[mesh.interface_pairs[chosen, 1]]
    # CF-4 half model: diaphragms at 450 and 750 (t_d 6.4), end plate at 1083: both faces of
    # each diaphragm meet both plates, the end plate's inner face too
    xs = sorted({round(float(x), 1) for x in xy[:, 0]})
    assert xs == [446.8, 453.2, 746.8, 753.2, 1076.6]
    assert sorted({round(float(y), 1) for y in xy[:, 1]}) == [12.6, 237.4]
    assert chosen.sum() == 10


def test_fixed_points_on_the_bottom_face_next_to_the_support():
    mesh = _cf4_mesh()
    chosen = choose_fixed_points(mesh, per_core=2, placement="bottom_support")
    xy = mesh.points[mesh.interface_pairs[chosen, 1]]
    assert chosen.sum() == 4
    np.testing.assert_allclose(mesh.interface_normals[chosen], [[0.0, 1.0]] * 4)
    assert np.allclose(xy[:, 1], 12.6)  # on the bottom plate
    inward, outward = np.sort(xy[xy[:, 0] < 750.0, 0]), np.sort(xy[xy[:, 0] > 750.0, 0])
    assert len(inward) == len(outward) == 2
    assert inward[-1] > 690.0 and outward[0] < 810.0  # the pairs nearest the support


def test_fixed_points_at_one_station_across_each_core():
    """"station": per core the top-face and the bottom-face pair nearest its mid-length, at
    the same x: two pins across the depth (TF-5's half model, four cores, one cut by the
    symmetry line)."""
    from icewall.deck.load import load_deck
    from icewall.mesh.build import build_mesh

    mesh = build_mesh(load_deck(Path(__file__).resolve().parents[2] / "decks" / "tf5.yaml",
                                ()).deck)
    chosen = choose_fixed_points(mesh, per_core=1, placement="station")
    cores = [r for r in mesh.regions if r.kind == "concrete"]
    assert chosen.sum() == 2 * len(cores) == 8
    xy = mesh.points[mesh.interface_pairs[chosen, 1]]
    normals = mesh.interface_normals[chosen]
    top, bottom = normals[:, 1] < 0, normals[:, 1] > 0
    assert top.sum() == bottom.sum() == len(cores)
    np.testing.assert_allclose(np.sort(xy[top, 0]), np.sort(xy[bottom, 0]))
    # mid-lengths of the cores 0-100 (cut by the symmetry line), 100-450, 450-625, 625-770
    # (from the diaphragm faces, 3.2 mm each side): the pairs nearest them on a 25 mm mesh
    np.testing.assert_allclose(np.sort(xy[top, 0]), [0.0, 275.0, 537.5, 690.0], atol=13.0)
    assert np.allclose(xy[top, 1], xy[:, 1].max()) and np.allclose(xy[bottom, 1],
                                                                     xy[:, 1].min())
    # one station's top pairs are the "top" placement's
    assert np.array_equal(chosen & (mesh.interface_normals[:, 1] < 0),
                          choose_fixed_points(mesh, per_core=1))


def test_fixed_point_mask_of_a_deck_combines_placements():
    from types import SimpleNamespace

    from icewall.interface.fixed_points import fixed_point_mask

    mesh = _cf4_mesh()
    none = SimpleNamespace(fixed_points_per_core=0, fixed_point_placement=("top",))
    assert fixed_point_mask(mesh, none) is None
    both = SimpleNamespace(fixed_points_per_core=2, fixed_point_placement=("top", "corners"))
    mask = fixed_point_mask(mesh, both)
    assert mask.sum() == (choose_fixed_points(mesh).sum()
                          + choose_fixed_points(mesh, placement="corners").sum())
    with pytest.raises(ValueError, match="placement"):
        choose_fixed_points(mesh, placement="sides")
