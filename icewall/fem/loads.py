"""Consistent nodal forces of edge tractions, edge pressures and point loads."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from icewall.fem.quadrature import line_rule
from icewall.fem.shape import shape_derivatives, shape_functions
from icewall.formulations import check_formulation

Traction = np.ndarray | Callable[[np.ndarray], np.ndarray]


def _edge_quadrature(points: np.ndarray, edges: np.ndarray, n_gauss: int):
    """Shape functions N (q, a), Gauss-point coordinates (e, q, 2), tangents dx/ds (e, q, 2)."""
    edges = np.asarray(edges, dtype=int)
    line = {2: "line2", 3: "line3"}.get(edges.shape[1])
    if line is None:
        raise ValueError(f"edges must have 2 or 3 nodes, got shape {edges.shape}")
    rule = line_rule(n_gauss)
    N = shape_functions(line, rule.points)
    dN = shape_derivatives(line, rule.points)[..., 0]
    X = np.asarray(points, dtype=float)[edges]  # (e, a, k)
    return N, np.einsum("qa,eak->eqk", N, X), np.einsum("qa,eak->eqk", dN, X), rule.weights


def _scatter(n_nodes: int, edges: np.ndarray, nodal: np.ndarray) -> np.ndarray:
    """(e, a, 2) edge-node forces -> (2 n_nodes,) global vector."""
    dofs = 2 * np.asarray(edges, dtype=int)[:, :, None] + np.arange(2)
    return np.bincount(dofs.ravel(), weights=nodal.ravel(), minlength=2 * n_nodes)


def _measure(x: np.ndarray, formulation: str, thickness: float) -> np.ndarray:
    check_formulation(formulation)
    return 2.0 * np.pi * x[..., 0] if formulation == "axisymmetric" else np.full(x.shape[:-1],
                                                                                 thickness)


def edge_traction_loads(points: np.ndarray, edges: np.ndarray, traction: Traction,
                        formulation: str, thickness: float = 1.0, n_gauss: int = 3) -> np.ndarray:
    """Consistent nodal forces (2 n_nodes,) of a surface traction (MPa, global x/y) on edges.

    `traction` is (2,) uniform, (n_edges, 2) constant per edge, (n_edges, nn_edge, 2) nodal
    values interpolated along each edge, or a callable mapping coordinates (m, 2) -> (m, 2).
    Planar models integrate over `thickness`, axisymmetric ones over the full ring 2 pi r.
    """
    edges = np.asarray(edges, dtype=int)
    N, x, tangent, w = _edge_quadrature(points, edges, n_gauss)
    if callable(traction):
        t = np.asarray(traction(x.reshape(-1, 2)), dtype=float).reshape(x.shape)
    else:
        t = np.asarray(traction, dtype=float)
        if t.ndim == 3:
            t = np.einsum("qa,eak->eqk", N, t)
        elif t.ndim == 2:
            t = np.broadcast_to(t[:, None, :], x.shape)
        else:
            t = np.broadcast_to(t, x.shape)
    ds = np.linalg.norm(tangent, axis=-1) * w * _measure(x, formulation, thickness)
    nodal = np.einsum("qa,eqk,eq->eak", N, t, ds)
    return _scatter(np.shape(points)[0], edges, nodal)


def edge_pressure_loads(points: np.ndarray, edges: np.ndarray, pressure: float | np.ndarray,
                        formulation: str, thickness: float = 1.0, n_gauss: int = 3) -> np.ndarray:
    """Consistent nodal forces (2 n_nodes,) of a pressure (MPa, positive pushing on the body).

    Edges must run counter-clockwise around the loaded body (body on the left), so that the
    outward normal is (t_y, -t_x) / |t|. `pressure` is a scalar or (n_edges,) per edge.
    """
    edges = np.asarray(edges, dtype=int)
    N, x, tangent, w = _edge_quadrature(points, edges, n_gauss)
    p = np.broadcast_to(np.asarray(pressure, dtype=float).reshape(-1, 1), x.shape[:-1])
    # traction -p n times |t|: the Jacobian |t| cancels the normalisation of n
    t_ds = -np.stack([tangent[..., 1], -tangent[..., 0]], axis=-1) * p[..., None]
    t_ds *= (w * _measure(x, formulation, thickness))[..., None]
    nodal = np.einsum("qa,eqk->eak", N, t_ds)
    return _scatter(np.shape(points)[0], edges, nodal)


def point_loads(n_nodes: int, nodes: np.ndarray, forces: np.ndarray) -> np.ndarray:
    """Nodal force vector (2 n_nodes,) of forces (2,) or (k, 2) in N at `nodes`.

    For axisymmetric models a point force is the total ring force (already times 2 pi r).
    """
    nodes = np.atleast_1d(np.asarray(nodes, dtype=int))
    f = np.broadcast_to(np.asarray(forces, dtype=float), (nodes.size, 2))
    dofs = 2 * nodes[:, None] + np.arange(2)
    return np.bincount(dofs.ravel(), weights=f.ravel(), minlength=2 * n_nodes)
