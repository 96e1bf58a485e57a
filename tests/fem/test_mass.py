"""HRZ lumped masses of the 8-node quad against the consistent mass matrix in closed form."""

from __future__ import annotations

import numpy as np
import pytest

from icewall.fem.kinematics import element_kinematics
from icewall.fem.mass import hrz_nodal_masses, lumped_mass_vector
from icewall.fem.quadrature import gauss_rule

RECTANGLE = np.array([[0, 0], [2, 0], [2, 1], [0, 1], [1, 0], [2, 0.5], [1, 1], [0, 0.5]],
                     dtype=float)


def _kinematics(points, order=3, thickness=3.0):
    cells = np.arange(8)[None]
    return element_kinematics(points, cells, "quad8", gauss_rule(order), "plane_stress",
                              thickness)


def test_hrz_masses_of_a_rectangle_are_the_scaled_consistent_diagonal():
    # Zienkiewicz & Taylor: the consistent Q8 mass of a rectangle of mass m has diagonal
    # m/30 at the corners and 8m/45 at the mid-side nodes; HRZ scales them to sum to m:
    # corners 3/76 m, mid-sides 4/19 m (the 3x3 rule integrates N_a^2 exactly)
    kin = _kinematics(RECTANGLE)
    rho = 2.4e-9
    m = hrz_nodal_masses(kin, np.array([rho]))[0]
    total = rho * 2.0 * 1.0 * 3.0
    assert m[:4] == pytest.approx(np.full(4, 3 / 76 * total), rel=1e-12)
    assert m[4:] == pytest.approx(np.full(4, 4 / 19 * total), rel=1e-12)


def test_row_sum_lumping_would_give_negative_corners_hrz_does_not():
    kin = _kinematics(RECTANGLE)
    # consistent mass M_ab = sum_q N_a N_b dV (rho = 1): its row sums at the corners are -1/12
    M = np.einsum("qa,qb,q->ab", kin.N, kin.N, kin.dV[0])
    row_sums = M.sum(axis=1)
    assert np.all(row_sums[:4] < 0.0) and row_sums[:4] == pytest.approx(-6.0 / 12.0)
    assert np.all(hrz_nodal_masses(kin, np.array([1.0])) > 0.0)


def test_distorted_element_keeps_its_mass_and_positive_entries():
    distorted = RECTANGLE.copy()
    distorted[2] = [2.6, 1.4]
    distorted[5] = [2.3, 0.7]
    distorted[6] = [1.3, 1.2]
    for order in (2, 3, 4):
        kin = _kinematics(distorted, order)
        m = hrz_nodal_masses(kin, np.array([7.85e-9]))
        assert np.all(m > 0.0)
        assert m.sum() == pytest.approx(7.85e-9 * kin.dV.sum(), rel=1e-12)


def test_assembled_vector_carries_each_node_mass_on_both_dofs():
    kin = _kinematics(RECTANGLE)
    nodal = hrz_nodal_masses(kin, np.array([1.0]))[0]
    vector = lumped_mass_vector(kin, np.array([1.0]), 16)
    assert vector[0::2] == pytest.approx(nodal) and vector[1::2] == pytest.approx(nodal)
    assert vector.sum() == pytest.approx(2.0 * kin.dV.sum())
