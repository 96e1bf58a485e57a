"""Shape functions of quad4, quad8 (serendipity) and line2/line3 reference elements.

Quads live on [-1, 1]^2 with the icewall node order (corners CCW from (-1, -1), then the
mid-side nodes of edges 0-1, 1-2, 2-3, 3-0); lines on [-1, 1] in the order (start, end, mid).
"""

from __future__ import annotations

import numpy as np

_CORNERS = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
_MIDSIDES = np.array([[0.0, -1.0], [1.0, 0.0], [0.0, 1.0], [-1.0, 0.0]])
_REFERENCE_NODES = {
    "quad4": _CORNERS,
    "quad8": np.vstack([_CORNERS, _MIDSIDES]),
    "line2": np.array([[-1.0], [1.0]]),
    "line3": np.array([[-1.0], [1.0], [0.0]]),
}
NODES_PER_CELL = {name: nodes.shape[0] for name, nodes in _REFERENCE_NODES.items()}


def reference_nodes(cell_type: str) -> np.ndarray:
    """Reference coordinates (nn, dim) of the nodes of `cell_type`."""
    try:
        return _REFERENCE_NODES[cell_type].copy()
    except KeyError:
        raise ValueError(f"unknown cell type {cell_type!r}") from None


def _as_points(cell_type: str, xi: np.ndarray) -> np.ndarray:
    dim = reference_nodes(cell_type).shape[1]
    xi = np.asarray(xi, dtype=float)
    return xi.reshape(-1, dim)


def shape_functions(cell_type: str, xi: np.ndarray) -> np.ndarray:
    """Shape-function values N (nq, nn) at reference points xi (nq, dim)."""
    p = _as_points(cell_type, xi)
    if cell_type in ("line2", "line3"):
        s = p[:, 0]
        if cell_type == "line2":
            return np.column_stack([0.5 * (1 - s), 0.5 * (1 + s)])
        return np.column_stack([0.5 * s * (s - 1), 0.5 * s * (s + 1), 1 - s * s])
    r, s = p[:, 0:1], p[:, 1:2]
    rc, sc = _CORNERS[:, 0], _CORNERS[:, 1]  # (4,)
    if cell_type == "quad4":
        return 0.25 * (1 + r * rc) * (1 + s * sc)
    corner = 0.25 * (1 + r * rc) * (1 + s * sc) * (r * rc + s * sc - 1)
    r, s = r[:, 0], s[:, 0]
    mid = np.column_stack([
        0.5 * (1 - r * r) * (1 - s),
        0.5 * (1 + r) * (1 - s * s),
        0.5 * (1 - r * r) * (1 + s),
        0.5 * (1 - r) * (1 - s * s),
    ])
    return np.hstack([corner, mid])


def shape_derivatives(cell_type: str, xi: np.ndarray) -> np.ndarray:
    """Reference derivatives dN/dxi (nq, nn, dim) at reference points xi (nq, dim)."""
    p = _as_points(cell_type, xi)
    if cell_type in ("line2", "line3"):
        s = p[:, 0]
        if cell_type == "line2":
            d = np.column_stack([np.full_like(s, -0.5), np.full_like(s, 0.5)])
        else:
            d = np.column_stack([s - 0.5, s + 0.5, -2 * s])
        return d[:, :, None]
    r, s = p[:, 0:1], p[:, 1:2]
    rc, sc = _CORNERS[:, 0], _CORNERS[:, 1]
    if cell_type == "quad4":
        dr = 0.25 * rc * (1 + s * sc)
        ds = 0.25 * sc * (1 + r * rc)
        return np.stack([dr, ds], axis=-1)
    # corner N = 1/4 (1 + r rc)(1 + s sc)(r rc + s sc - 1)
    dr = 0.25 * rc * (1 + s * sc) * (2 * r * rc + s * sc)
    ds = 0.25 * sc * (1 + r * rc) * (r * rc + 2 * s * sc)
    r, s = r[:, 0], s[:, 0]
    mid_dr = np.column_stack([-r * (1 - s), 0.5 * (1 - s * s), -r * (1 + s), -0.5 * (1 - s * s)])
    mid_ds = np.column_stack([-0.5 * (1 - r * r), -s * (1 + r), 0.5 * (1 - r * r), -s * (1 - r)])
    return np.stack([np.hstack([dr, mid_dr]), np.hstack([ds, mid_ds])], axis=-1)
