"""Element kinematics: volumes, rigid-body modes, kernels and the Gauss-point spacing."""

from __future__ import annotations

import numpy as np
import pytest

from icewall.fem.kinematics import (
    element_kinematics,
    gauss_point_spacing,
    internal_force_blocks,
    stiffness_blocks,
    strain,
)
from icewall.fem.quadrature import gauss_rule
from icewall.materials.elastic import elastic_moduli
from icewall.mesh.structured import rectangle_mesh

E, NU = 30_000.0, 0.2


def _stiffness(points, cells, cell_type, n_gauss, formulation, thickness=1.0):
    kin = element_kinematics(points, cells, cell_type, gauss_rule(n_gauss), formulation,
                             thickness)
    return kin, stiffness_blocks(kin, elastic_moduli(E, NU, formulation))[0]


@pytest.mark.parametrize(("formulation", "n_rigid"),
                         [("plane_strain", 3), ("plane_stress", 3), ("axisymmetric", 1)])
def test_stiffness_symmetric_with_rigid_body_modes_only(single_element, formulation, n_rigid):
    """Free element: 2 translations + 1 rotation (planar); axial translation (axisymmetric)."""
    cell_type, points, cells, n_gauss = single_element
    _, K = _stiffness(points, cells, cell_type, n_gauss, formulation)
    np.testing.assert_allclose(K, K.T, rtol=0, atol=1e-12 * np.abs(K).max())
    eig = np.linalg.eigvalsh(K)
    zero = np.abs(eig) < 1e-10 * eig.max()
    assert zero.sum() == n_rigid
    assert np.all(eig[~zero] > 0)
    # the rigid modes themselves give zero force
    x, y = points.T
    modes = [np.column_stack([np.zeros_like(x), np.ones_like(x)])]
    if formulation != "axisymmetric":
        modes += [np.column_stack([np.ones_like(x), 0 * x]), np.column_stack([-y, x])]
    for mode in modes:
        assert np.abs(K @ mode.ravel()).max() < 1e-10 * np.abs(K).max()


def test_volume_weights_integrate_area_and_ring_volume():
    mesh = rectangle_mesh(1.0, 3.0, 0.0, 2.0, 3, 2, "quad8", distort=0.2)
    rule = gauss_rule(3)
    planar = element_kinematics(mesh.points, mesh.cells, "quad8", rule, "plane_stress", 5.0)
    assert planar.dV.sum() == pytest.approx(2.0 * 2.0 * 5.0, rel=1e-13)  # area x thickness
    axi = element_kinematics(mesh.points, mesh.cells, "quad8", rule, "axisymmetric")
    # ring volume pi (r1^2 - r0^2) h; 2 pi r detJ is a polynomial the 3x3 rule integrates
    assert axi.dV.sum() == pytest.approx(np.pi * (9.0 - 1.0) * 2.0, rel=1e-13)
    assert planar.B.shape == (mesh.n_cells, 9, 4, 16)
    assert planar.dofs.shape == (mesh.n_cells, 16)
    np.testing.assert_array_equal(planar.dofs[:, 0::2], 2 * mesh.cells)


def test_strain_of_linear_field_and_internal_force_equals_k_u(single_element):
    cell_type, points, cells, n_gauss = single_element
    kin, K = _stiffness(points, cells, cell_type, n_gauss, "axisymmetric")
    r, z = points.T
    u = np.column_stack([1e-3 * r, 2e-3 * z - 1e-3 * r]).ravel()  # u_z with shear term
    eps = strain(kin, u)
    expected = np.array([1e-3, 2e-3, 1e-3, -1e-3])  # [rr, zz, hoop = u_r / r, rz]
    np.testing.assert_allclose(eps, np.broadcast_to(expected, eps.shape), atol=1e-15)
    sig = eps @ elastic_moduli(E, NU, "axisymmetric").T
    np.testing.assert_allclose(internal_force_blocks(kin, sig)[0], K @ u, rtol=1e-12,
                               atol=1e-12 * np.abs(K @ u).max())


def test_inverted_element_is_reported_by_index():
    mesh = rectangle_mesh(0.0, 2.0, 0.0, 1.0, 2, 1, "quad4")
    cells = mesh.cells.copy()
    cells[1] = cells[1, ::-1]  # clockwise
    with pytest.raises(ValueError, match=r"Jacobian.*\[1\]"):
        element_kinematics(mesh.points, cells, "quad4", gauss_rule(2), "plane_strain")


def test_axisymmetric_mesh_must_lie_at_positive_radius():
    mesh = rectangle_mesh(-1.0, 1.0, 0.0, 1.0, 2, 1, "quad4")
    with pytest.raises(ValueError, match="r <= 0"):
        element_kinematics(mesh.points, mesh.cells, "quad4", gauss_rule(2), "axisymmetric")


def test_unknown_formulation_is_rejected(single_element):
    cell_type, points, cells, n_gauss = single_element
    with pytest.raises(ValueError, match="formulation"):
        element_kinematics(points, cells, cell_type, gauss_rule(n_gauss), "plane")


@pytest.mark.parametrize("cell_type", ["quad4", "quad8"])
def test_gauss_point_spacing_of_rectangles(cell_type):
    """Thesis eq. 4.3 for a 40 x 10 element: h_c = sqrt((40 / n) (10 / n))."""
    mesh = rectangle_mesh(0.0, 120.0, 0.0, 20.0, 3, 2, cell_type)
    for n in (2, 3):
        np.testing.assert_allclose(gauss_point_spacing(mesh.points, mesh.cells, n),
                                   np.sqrt(40.0 * 10.0) / n, rtol=1e-14)


def test_gauss_point_spacing_averages_opposite_edges():
    points = np.array([[0.0, 0.0], [4.0, 0.0], [3.0, 3.0], [0.0, 3.0]])  # trapezoid
    h = gauss_point_spacing(points, np.array([[0, 1, 2, 3]]), 2)
    h1, h2 = (4.0 + 3.0) / 2 / 2, (np.hypot(1.0, 3.0) + 3.0) / 2 / 2
    assert h[0] == pytest.approx(np.sqrt(h1 * h2), rel=1e-14)
