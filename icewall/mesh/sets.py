"""Named node and edge sets of a wall mesh: symmetry, supports, control point, load patches."""

from __future__ import annotations

import numpy as np

from icewall.deck.schema import Deck
from icewall.errors import MeshError
from icewall.mesh.convert import QUAD_EDGES
from icewall.mesh.layout import mirror_positions

_TOL = 1e-6


def nearest_node(points: np.ndarray, x: float, y: float, what: str) -> int:
    distance = np.hypot(points[:, 0] - x, points[:, 1] - y)
    node = int(np.argmin(distance))
    if distance[node] > _TOL:
        raise MeshError(f"no mesh node at the {what} ({x:g}, {y:g}) mm")
    return node


def outer_edges(cells: np.ndarray, cell_type: str) -> np.ndarray:
    """Edges (start, end[, mid]) on the outer boundary of the whole mesh."""
    local = QUAD_EDGES[cell_type]
    edges = cells[:, local].reshape(-1, local.shape[1])
    key = np.sort(edges[:, :2], axis=1)
    _, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    return edges[counts[inverse.ravel()] == 1]


def build_sets(deck: Deck, points: np.ndarray, cells: np.ndarray,
               cell_type: str) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Node sets (symmetry, supports, control) and edge sets (load patches, wall ends)."""
    geo, model = deck.geometry, deck.geometry.model
    half = geo.half_length
    x, y = points[:, 0], points[:, 1]
    node_sets: dict[str, np.ndarray] = {}
    if model == "half":
        node_sets["symmetry"] = np.flatnonzero(np.abs(x) < _TOL)
    for i, sup in enumerate(geo.supports, start=1):
        nodes = []
        for xs in mirror_positions([sup.x], model):
            column = np.abs(x - xs) < _TOL
            if not column.any():
                raise MeshError(f"no mesh node on the support line x = {xs:g} mm")
            level = 0.0 if sup.level == "wall" else y[column].min()
            nodes.append(nearest_node(points, xs, level, f"support {i}"))
        node_sets[f"support_{i}"] = np.array(nodes)
    node_sets["control"] = np.array([nearest_node(points, deck.loads.control.x, geo.depth,
                                                  "control point")])
    edges = outer_edges(cells, cell_type)
    ends = points[edges[:, :2]]  # (k, 2 ends, 2 coords)
    on_top = np.all(np.abs(ends[..., 1] - geo.depth) < _TOL, axis=1)
    mid_x = ends[..., 0].mean(axis=1)
    width = deck.loads.patches.width
    edge_sets: dict[str, np.ndarray] = {}
    for i, xc in enumerate(deck.loads.patches.positions, start=1):
        for side, xp in enumerate(mirror_positions([xc], model)):
            inside = on_top & (np.abs(mid_x - xp) < 0.5 * width)
            name = f"patch_{i}" + ("" if side == 0 else "_mirror")
            if not inside.any():
                raise MeshError(f"load patch at x = {xp:g} mm has no top-plate edge")
            edge_sets[name] = edges[inside]
    for name, xe in (("end_right", half), ("end_left", -half)):
        if name == "end_left" and model == "half":
            continue
        on_end = np.all(np.abs(ends[..., 0] - xe) < _TOL, axis=1)
        on_end &= np.all(ends[..., 1] >= -_TOL, axis=1)  # the wall, not a leg below it
        edge_sets[name] = edges[on_end]
    return node_sets, edge_sets
