"""Format knowledge in one place: gmsh and meshio names and node orders of icewall cells.

icewall uses gmsh's node order for quadrilaterals and lines, so the permutations are the
identity; they are kept here so that any other format is added in one table.
"""

from __future__ import annotations

import numpy as np

# icewall cell type -> (gmsh element type id, meshio cell name, permutation gmsh -> icewall)
CELL_TABLE: dict[str, tuple[int, str, tuple[int, ...]]] = {
    "quad4": (3, "quad", (0, 1, 2, 3)),
    "quad8": (16, "quad8", (0, 1, 2, 3, 4, 5, 6, 7)),
}
# icewall edge arity -> (gmsh line type id, meshio name)
EDGE_TABLE: dict[int, tuple[int, str]] = {2: (1, "line"), 3: (8, "line3")}
# Local edges of a quadrilateral as (start, end[, mid]) in icewall order, counter-clockwise.
QUAD_EDGES: dict[str, np.ndarray] = {
    "quad4": np.array([[0, 1], [1, 2], [2, 3], [3, 0]]),
    "quad8": np.array([[0, 1, 4], [1, 2, 5], [2, 3, 6], [3, 0, 7]]),
}


def gmsh_type(cell_type: str) -> int:
    return CELL_TABLE[cell_type][0]


def meshio_name(cell_type: str) -> str:
    return CELL_TABLE[cell_type][1]


def from_gmsh(cell_type: str, connectivity: np.ndarray) -> np.ndarray:
    """Reorder gmsh connectivity (n, k) into icewall order."""
    return connectivity[:, list(CELL_TABLE[cell_type][2])]


def to_meshio(cell_type: str, cells: np.ndarray) -> np.ndarray:
    """icewall connectivity -> meshio/VTK order (identical for quad, quad8)."""
    inverse = np.argsort(CELL_TABLE[cell_type][2])
    return cells[:, inverse]


def orient_counter_clockwise(points: np.ndarray, cells: np.ndarray, cell_type: str) -> np.ndarray:
    """Return cells with every element counter-clockwise (positive signed corner area)."""
    corners = points[cells[:, :4]]
    x, y = corners[..., 0], corners[..., 1]
    area = 0.5 * np.sum(x * np.roll(y, -1, axis=1) - np.roll(x, -1, axis=1) * y, axis=1)
    flip = area < 0
    if not flip.any():
        return cells
    order = [0, 3, 2, 1] if cell_type == "quad4" else [0, 3, 2, 1, 7, 6, 5, 4]
    out = cells.copy()
    out[flip] = cells[flip][:, order]
    return out
