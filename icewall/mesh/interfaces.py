"""Split the conforming mesh along every steel-concrete interface into coincident node pairs."""

from __future__ import annotations

import numpy as np

from icewall.mesh.convert import QUAD_EDGES


def boundary_edges(cells: np.ndarray, cell_type: str, mask: np.ndarray) -> tuple[np.ndarray,
                                                                                  np.ndarray]:
    """Edges of the cells in `mask` that no other masked cell shares.

    Returns (edges (k, 2|3) as (start, end[, mid]) counter-clockwise around their cell, and the
    index of the owning cell (k,)).
    """
    local = QUAD_EDGES[cell_type]
    owner = np.repeat(np.flatnonzero(mask), len(local))
    edges = cells[mask][:, local].reshape(-1, local.shape[1])
    key = np.sort(edges[:, :2], axis=1)
    _, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    single = counts[inverse.ravel()] == 1
    return edges[single], owner[single]


def split_interfaces(points: np.ndarray, cells: np.ndarray, cell_type: str,
                     concrete: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                    np.ndarray, np.ndarray]:
    """Give concrete cells their own copies of the nodes they share with other cells.

    concrete: (n_el,) bool. Returns (points, cells, pairs (n,2) = (other node, concrete node),
    normals (n,2) pointing from the steel into the concrete, corner (n,) bool).
    """
    concrete_nodes = np.unique(cells[concrete])
    other_nodes = np.unique(cells[~concrete])
    shared = np.intersect1d(concrete_nodes, other_nodes)
    n = len(points)
    new_id = np.full(n, -1)
    new_id[shared] = n + np.arange(len(shared))
    cells = cells.copy()
    sub = cells[concrete]
    hit = new_id[sub] >= 0
    sub[hit] = new_id[sub[hit]]
    cells[concrete] = sub
    points = np.vstack([points, points[shared]])
    pairs = np.column_stack([shared, new_id[shared]])

    # Inward normals of the concrete boundary edges that lie on the interface.
    edges, owner = boundary_edges(cells, cell_type, concrete)
    on_interface = np.all(edges >= n, axis=1)
    edges, owner = edges[on_interface], owner[on_interface]
    tangent = points[edges[:, 1]] - points[edges[:, 0]]
    inward = np.column_stack([-tangent[:, 1], tangent[:, 0]])  # left of a CCW edge
    inward /= np.linalg.norm(inward, axis=1, keepdims=True)
    sums = np.zeros((len(points), 2))
    counts = np.zeros(len(points), dtype=int)
    for column in range(edges.shape[1]):  # 2 or 3 nodes per edge, not a per-element loop
        np.add.at(sums, edges[:, column], inward)
        np.add.at(counts, edges[:, column], 1)
    normals = sums[pairs[:, 1]]
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    normals = np.divide(normals, length, out=np.zeros_like(normals), where=length > 0)
    # A node on two non-parallel interface faces is a core corner: its unit normals do not add
    # up to their count.
    corner = length[:, 0] < counts[pairs[:, 1]] - 1e-9
    return points, cells, pairs, normals, corner
