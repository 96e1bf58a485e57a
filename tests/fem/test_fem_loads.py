"""Consistent edge loads: resultants and moments against hand integration."""

from __future__ import annotations

import numpy as np
import pytest

from icewall.fem.loads import edge_pressure_loads, edge_traction_loads, point_loads
from icewall.mesh.structured import rectangle_mesh


@pytest.mark.parametrize("cell_type", ["quad4", "quad8"])
def test_uniform_traction_resultant_and_quad8_nodal_split(cell_type):
    mesh = rectangle_mesh(0.0, 60.0, 0.0, 30.0, 3, 2, cell_type)
    f = edge_traction_loads(mesh.points, mesh.edge_sets["top"], [2.0, -1.5], "plane_strain", 4.0)
    # resultant = traction x length x thickness
    assert f[0::2].sum() == pytest.approx(2.0 * 60.0 * 4.0, rel=1e-14)
    assert f[1::2].sum() == pytest.approx(-1.5 * 60.0 * 4.0, rel=1e-14)
    if cell_type == "quad8":  # consistent split of a uniform load on one line3: 1/6, 2/3, 1/6
        start, end, mid = mesh.edge_sets["top"][0]
        q = -1.5 * 20.0 * 4.0
        assert f[2 * mid + 1] == pytest.approx(2 / 3 * q, rel=1e-14)
        assert f[2 * start + 1] == pytest.approx(q / 6, rel=1e-14)  # mesh corner (x = 60)
        assert f[2 * end + 1] == pytest.approx(q / 3, rel=1e-14)  # shared by two edges


def test_linearly_varying_traction_by_nodal_values_and_callable():
    """Triangular load q(x) = x / 60 on y = 30: resultant 30 t, moment about x = 0: 1200 t."""
    mesh = rectangle_mesh(0.0, 60.0, 0.0, 30.0, 3, 2, "quad8")
    edges = mesh.edge_sets["top"]
    nodal = np.stack([np.zeros(mesh.points[edges].shape[:2]), mesh.points[edges][..., 0] / 60],
                     axis=-1)
    f1 = edge_traction_loads(mesh.points, edges, nodal, "plane_stress", 2.0)
    f2 = edge_traction_loads(mesh.points, edges,
                             lambda x: np.column_stack([0 * x[:, 0], x[:, 0] / 60]),
                             "plane_stress", 2.0)
    np.testing.assert_allclose(f1, f2, rtol=1e-14, atol=1e-14)
    assert f1[1::2].sum() == pytest.approx(30.0 * 2.0, rel=1e-14)
    assert f1[1::2] @ mesh.points[:, 0] == pytest.approx(1200.0 * 2.0, rel=1e-14)


def test_axisymmetric_ring_load():
    """Axial traction on the annulus 1 <= r <= 3: total force q pi (3^2 - 1^2)."""
    mesh = rectangle_mesh(1.0, 3.0, 0.0, 1.0, 4, 1, "quad8")
    f = edge_traction_loads(mesh.points, mesh.edge_sets["top"], [0.0, -2.0], "axisymmetric")
    assert f[1::2].sum() == pytest.approx(-2.0 * np.pi * 8.0, rel=1e-14)
    f = edge_traction_loads(mesh.points, mesh.edge_sets["top"], np.tile([0.0, -2.0], (4, 1)),
                            "axisymmetric")
    assert f[1::2].sum() == pytest.approx(-2.0 * np.pi * 8.0, rel=1e-14)


def test_pressure_acts_inwards_on_counter_clockwise_edges():
    mesh = rectangle_mesh(0.0, 2.0, 0.0, 1.0, 2, 2, "quad8")
    for side, direction in [("bottom", (0, 1)), ("right", (-1, 0)), ("top", (0, -1)),
                            ("left", (1, 0))]:
        f = edge_pressure_loads(mesh.points, mesh.edge_sets[side], 3.0, "plane_stress", 5.0)
        length = 2.0 if side in ("bottom", "top") else 1.0
        np.testing.assert_allclose([f[0::2].sum(), f[1::2].sum()],
                                   3.0 * length * 5.0 * np.array(direction), atol=1e-12)


def test_point_loads():
    f = point_loads(4, [1, 3], [[1.0, 2.0], [3.0, 4.0]])
    np.testing.assert_array_equal(f, [0, 0, 1, 2, 0, 0, 3, 4])
