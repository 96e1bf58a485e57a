"""The structured rectangle mesher: counts, sets, orientation and distortion."""

from __future__ import annotations

import numpy as np
import pytest

from icewall.fem.kinematics import element_kinematics
from icewall.fem.quadrature import gauss_rule
from icewall.mesh.structured import rectangle_mesh


@pytest.mark.parametrize(("cell_type", "n_nodes"), [("quad4", 4 * 3), ("quad8", 7 * 5 - 6)])
def test_counts_and_sets(cell_type, n_nodes):
    mesh = rectangle_mesh(-1.0, 2.0, 0.5, 1.5, 3, 2, cell_type, region_name="plate",
                          kind="steel")
    assert mesh.n_nodes == n_nodes and mesh.n_cells == 6 and mesh.cell_type == cell_type
    assert mesh.region("plate").kind == "steel" and mesh.cells_of_kind("steel").all()
    x, y = mesh.points.T
    for name, mask in [("left", x == -1.0), ("right", x == 2.0), ("bottom", y == 0.5),
                       ("top", y == 1.5)]:
        np.testing.assert_array_equal(mesh.node_sets[name], np.flatnonzero(mask))
        edges = mesh.edge_sets[name]
        assert edges.shape == ((3 if name in ("bottom", "top") else 2),
                               mesh.nodes_per_cell // 4 + 1)
        assert np.all(np.isin(edges, mesh.node_sets[name]))
    assert np.unique(mesh.cells).size == mesh.n_nodes  # every node is used


@pytest.mark.parametrize("cell_type", ["quad4", "quad8"])
def test_edges_run_counter_clockwise_and_cells_are_valid(cell_type):
    mesh = rectangle_mesh(0.0, 4.0, 0.0, 2.0, 4, 2, cell_type, distort=0.3, seed=3)
    centre = mesh.points.mean(axis=0)
    for edges in mesh.edge_sets.values():
        a, b = mesh.points[edges[:, 0]] - centre, mesh.points[edges[:, 1]] - centre
        assert np.all(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0] > 0)  # CCW about the centre
        if cell_type == "quad8":  # mid-side node halfway along the straight boundary edge
            np.testing.assert_allclose(mesh.points[edges[:, 2]],
                                       0.5 * (mesh.points[edges[:, 0]] + mesh.points[edges[:, 1]]))
    kin = element_kinematics(mesh.points, mesh.cells, cell_type, gauss_rule(3), "plane_strain")
    assert kin.dV.sum() == pytest.approx(8.0, rel=1e-13)  # area preserved by the distortion


def test_distortion_moves_interior_nodes_only_and_is_reproducible():
    plain = rectangle_mesh(0.0, 4.0, 0.0, 2.0, 4, 2, "quad8")
    moved = rectangle_mesh(0.0, 4.0, 0.0, 2.0, 4, 2, "quad8", distort=0.3, seed=3)
    boundary = np.unique(np.concatenate(list(plain.node_sets.values())))
    np.testing.assert_array_equal(moved.points[boundary], plain.points[boundary])
    assert np.abs(moved.points - plain.points).max() > 0.05
    again = rectangle_mesh(0.0, 4.0, 0.0, 2.0, 4, 2, "quad8", distort=0.3, seed=3)
    np.testing.assert_array_equal(again.points, moved.points)


def test_invalid_arguments():
    with pytest.raises(ValueError):
        rectangle_mesh(0.0, 1.0, 0.0, 1.0, 1, 1, "tri3")
    with pytest.raises(ValueError):
        rectangle_mesh(1.0, 0.0, 0.0, 1.0, 1, 1)
    with pytest.raises(ValueError):
        rectangle_mesh(0.0, 1.0, 0.0, 1.0, 1, 1, distort=0.6)
