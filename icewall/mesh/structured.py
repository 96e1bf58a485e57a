"""Numpy-only structured quad4/quad8 mesher of a rectangle (tests and small studies)."""

from __future__ import annotations

import numpy as np

from icewall.mesh.mesh import Mesh, Region


def rectangle_mesh(x0: float, x1: float, y0: float, y1: float, nx: int, ny: int,
                   cell_type: str = "quad8", region_name: str = "body", kind: str = "elastic",
                   distort: float = 0.0, seed: int = 0) -> Mesh:
    """Structured nx x ny mesh of [x0, x1] x [y0, y1] with node/edge sets on the four sides.

    Node sets and edge sets "left", "right", "bottom", "top"; edges run counter-clockwise
    around the rectangle (body on the left). `distort` > 0 moves the interior corner nodes
    randomly by up to `distort` times the element size in each direction (reproducibly from
    `seed`); quad8 mid-side nodes stay at the midpoints of the then straight edges.
    """
    if cell_type not in ("quad4", "quad8"):
        raise ValueError(f"cell_type must be 'quad4' or 'quad8', got {cell_type!r}")
    if nx < 1 or ny < 1 or not (x1 > x0 and y1 > y0):
        raise ValueError("need nx, ny >= 1 and x1 > x0, y1 > y0")
    if not 0.0 <= distort < 0.5:
        raise ValueError("distort must lie in [0, 0.5)")
    quadratic = cell_type == "quad8"
    s = 2 if quadratic else 1  # grid steps per element
    gx, gy = s * nx + 1, s * ny + 1
    i, j = np.meshgrid(np.arange(gx), np.arange(gy), indexing="ij")  # grid (i along x)
    keep = ~((i % 2 == 1) & (j % 2 == 1)) if quadratic else np.ones_like(i, dtype=bool)
    node_id = np.full((gx, gy), -1)
    node_id[keep] = np.arange(keep.sum())
    xs = np.linspace(x0, x1, gx)[i[keep]]
    ys = np.linspace(y0, y1, gy)[j[keep]]
    points = np.column_stack([xs, ys])

    ci, cj = np.meshgrid(np.arange(nx) * s, np.arange(ny) * s, indexing="ij")
    ci, cj = ci.ravel(), cj.ravel()  # lower-left grid corner of each cell, cells x-major
    corner_offsets = [(0, 0), (s, 0), (s, s), (0, s)]
    offsets = corner_offsets + ([(1, 0), (2, 1), (1, 2), (0, 1)] if quadratic else [])
    cells = np.column_stack([node_id[ci + a, cj + b] for a, b in offsets])

    if distort > 0.0:
        hx, hy = (x1 - x0) / nx, (y1 - y0) / ny
        corner = (i % s == 0) & (j % s == 0)
        inner = corner & (i > 0) & (i < gx - 1) & (j > 0) & (j < gy - 1)
        ids = node_id[inner]
        shift = np.random.default_rng(seed).uniform(-distort, distort, (ids.size, 2))
        points[ids] += shift * [hx, hy]
        if quadratic:
            ends = np.array([[0, 1], [1, 2], [2, 3], [3, 0]])
            points[cells[:, 4:]] = points[cells[:, ends]].mean(axis=2)

    sides = {
        "bottom": node_id[::1, 0], "right": node_id[-1, ::1],
        "top": node_id[::-1, -1], "left": node_id[0, ::-1],
    }  # each traversed counter-clockwise around the rectangle
    node_sets = {name: np.sort(ids) for name, ids in sides.items()}
    edge_sets = {}
    for name, ids in sides.items():
        start, end = ids[:-1:s], ids[s::s]
        edge_sets[name] = np.column_stack([start, end, ids[1::s]] if quadratic else [start, end])
    return Mesh(points=points, cells=cells, cell_type=cell_type,
                cell_region=np.ones(cells.shape[0], dtype=int),
                regions=(Region(name=region_name, kind=kind, tag=1),),
                node_sets=node_sets, edge_sets=edge_sets)
