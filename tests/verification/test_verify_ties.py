"""Tied duplicate interface nodes (DofMap ties) must reproduce the merged (monolithic) mesh."""

from __future__ import annotations

import numpy as np
import pytest

from icewall.fem.loads import edge_traction_loads
from icewall.mesh.structured import rectangle_mesh

E, NU, T = 30_000.0, 0.2, 10.0


def _load_and_solve(solve_elastic, points, cells, cell_type, root, loaded_edges, ties=None):
    f = edge_traction_loads(points, loaded_edges, [0.3, -1.0], "plane_stress", T)
    return solve_elastic(points, cells, cell_type, "plane_stress", E, NU, np.repeat(root, 2),
                         np.tile([0, 1], root.size), np.zeros(2 * root.size), f,
                         thickness=T, ties=ties)


@pytest.mark.parametrize("cell_type", ["quad4", "quad8"])
def test_tied_two_block_mesh_equals_merged_mesh(solve_elastic, cell_type):
    """Blocks [0, 100] and [100, 250] x [0, 50] with duplicated nodes at x = 100."""
    merged = rectangle_mesh(0.0, 250.0, 0.0, 50.0, 5, 2, cell_type)
    ref = _load_and_solve(solve_elastic, merged.points, merged.cells, cell_type,
                          merged.node_sets["left"], merged.edge_sets["right"])

    a = rectangle_mesh(0.0, 100.0, 0.0, 50.0, 2, 2, cell_type)
    b = rectangle_mesh(100.0, 250.0, 0.0, 50.0, 3, 2, cell_type)
    off = a.n_nodes
    points = np.vstack([a.points, b.points])
    cells = np.vstack([a.cells, b.cells + off])
    master = a.node_sets["right"]
    slave = b.node_sets["left"] + off
    slave = slave[np.lexsort(points[slave].T[::-1])]  # pair coincident nodes by coordinates
    master = master[np.lexsort(points[master].T[::-1])]
    np.testing.assert_array_equal(points[master], points[slave])
    tied = _load_and_solve(solve_elastic, points, cells, cell_type, a.node_sets["left"],
                           b.edge_sets["right"] + off, ties=np.column_stack([master, slave]))

    # map every node of the two-block mesh to the merged-mesh node at the same place
    key = {tuple(np.round(p, 9)): i for i, p in enumerate(merged.points)}
    same = np.array([key[tuple(np.round(p, 9))] for p in points])
    scale = np.abs(ref.u).max()
    # reference: the merged mesh; identical equations up to ordering, so round-off only
    np.testing.assert_allclose(tied.u, ref.u[same], rtol=0, atol=1e-12 * scale)
    np.testing.assert_array_equal(tied.u[slave], tied.u[master])
