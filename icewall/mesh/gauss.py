"""Gauss-point positions and area weights of a mesh's cells (the point order of
icewall.fem.quadrature.gauss_rule, as the solver stores Gauss fields)."""

from __future__ import annotations

import numpy as np

from icewall.fem.quadrature import gauss_rule
from icewall.fem.shape import shape_derivatives, shape_functions
from icewall.mesh.mesh import Mesh


def gauss_points_xy(mesh: Mesh, gauss_order: int) -> np.ndarray:
    """Coordinates (n_el, nq, 2) of the Gauss points of every cell (point order of
    icewall.fem.quadrature.gauss_rule, as the solver stores Gauss fields)."""
    N = shape_functions(mesh.cell_type, gauss_rule(gauss_order).points)  # (nq, nn)
    return np.einsum("qn,enx->eqx", N, mesh.points[mesh.cells])


def gauss_volumes(mesh: Mesh, gauss_order: int) -> np.ndarray:
    """Area weights (n_el, nq) of the Gauss points: quadrature weight x |det J| (mm^2)."""
    rule = gauss_rule(gauss_order)
    dN = shape_derivatives(mesh.cell_type, rule.points)  # (nq, nn, 2)
    J = np.einsum("qna,enx->eqax", dN, mesh.points[mesh.cells])
    return rule.weights * np.abs(np.linalg.det(J))
