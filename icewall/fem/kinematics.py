"""Isoparametric element kinematics: B matrices, volume weights and element kernels.

All arrays are vectorised over elements x Gauss points, shapes (n_el, nq, ...).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from icewall.fem.dofs import DofMap
from icewall.fem.quadrature import Quadrature
from icewall.fem.shape import shape_derivatives, shape_functions
from icewall.formulations import check_formulation


@dataclass(frozen=True)
class ElementKinematics:
    """Strain-displacement data of a set of elements of one cell type."""

    B: np.ndarray  # (n_el, nq, 4, 2 nn) strain [xx, yy, zz, xy] from element dofs
    dV: np.ndarray  # (n_el, nq) detJ * w * (thickness | 2 pi r)
    x: np.ndarray  # (n_el, nq, 2) Gauss-point coordinates
    dofs: np.ndarray  # (n_el, 2 nn) global dof (or equation) ids, node-major
    N: np.ndarray  # (nq, nn) shape functions at the Gauss points
    detJ: np.ndarray  # (n_el, nq)

    @property
    def n_elements(self) -> int:
        return int(self.B.shape[0])


def element_kinematics(points: np.ndarray, cells: np.ndarray, cell_type: str,
                       quadrature: Quadrature, formulation: str, thickness: float = 1.0,
                       dof_map: DofMap | None = None) -> ElementKinematics:
    """B matrices, volume weights and dof ids of `cells` at the points of `quadrature`."""
    check_formulation(formulation)
    cells = np.asarray(cells, dtype=int)
    N = shape_functions(cell_type, quadrature.points)  # (q, a)
    dN = shape_derivatives(cell_type, quadrature.points)  # (q, a, l)
    if cells.shape[1] != N.shape[1]:
        raise ValueError(f"{cell_type} cells need {N.shape[1]} nodes, got {cells.shape[1]}")
    X = np.asarray(points, dtype=float)[cells]  # (e, a, k)
    J = np.einsum("eak,qal->eqkl", X, dN)  # dx_k / dxi_l
    detJ = J[..., 0, 0] * J[..., 1, 1] - J[..., 0, 1] * J[..., 1, 0]
    bad = np.unique(np.nonzero(detJ <= 0.0)[0])
    if bad.size:
        raise ValueError(f"non-positive Jacobian determinant in {bad.size} element(s) "
                         f"(inverted or badly distorted; check node order): {bad[:20].tolist()}")
    inv_J = np.empty_like(J)
    inv_J[..., 0, 0], inv_J[..., 1, 1] = J[..., 1, 1], J[..., 0, 0]
    inv_J[..., 0, 1], inv_J[..., 1, 0] = -J[..., 0, 1], -J[..., 1, 0]
    inv_J /= detJ[..., None, None]
    dNdx = np.einsum("qal,eqlk->eqak", dN, inv_J)  # (e, q, a, k)
    x = np.einsum("qa,eak->eqk", N, X)

    n_el, nq, nn = dNdx.shape[:3]
    B = np.zeros((n_el, nq, 4, 2 * nn))
    B[:, :, 0, 0::2] = dNdx[..., 0]
    B[:, :, 1, 1::2] = dNdx[..., 1]
    B[:, :, 3, 0::2] = dNdx[..., 1]
    B[:, :, 3, 1::2] = dNdx[..., 0]
    dV = detJ * quadrature.weights
    if formulation == "axisymmetric":
        r = x[..., 0]
        if np.any(r <= 0.0):
            raise ValueError("axisymmetric model: Gauss points at r <= 0 (mesh must lie at x >= 0)")
        B[:, :, 2, 0::2] = N / r[..., None]  # hoop strain u_r / r
        dV = dV * 2.0 * np.pi * r
    else:
        dV = dV * thickness
    if dof_map is None:
        dofs = (2 * cells[:, :, None] + np.arange(2)).reshape(n_el, -1)
    else:
        dofs = dof_map.element_dofs(cells)
    return ElementKinematics(B=B, dV=dV, x=x, dofs=dofs, N=N, detJ=detJ)


def stiffness_blocks(kin: ElementKinematics, moduli: np.ndarray) -> np.ndarray:
    """Element stiffness matrices sum_q B^T D B dV, shaped (n_el, nd, nd).

    One batched matmul per element over the stacked (q, i) rows: (B^T)(D B dV), with
    (q, i) as the contracted axis (BLAS, no einsum path search per call)."""
    n_el, nq, n_strain, nd = kin.B.shape
    D = np.broadcast_to(moduli, (n_el, nq, n_strain, n_strain))
    DB = np.matmul(D, kin.B) * kin.dV[..., None, None]  # (e, q, 4, nd)
    B_rows = kin.B.reshape(n_el, nq * n_strain, nd)
    return np.matmul(B_rows.transpose(0, 2, 1), DB.reshape(n_el, nq * n_strain, nd))


def internal_force_blocks(kin: ElementKinematics, stress: np.ndarray) -> np.ndarray:
    """Element internal force vectors sum_q B^T sigma dV, shaped (n_el, nd)."""
    n_el, nq, n_strain, nd = kin.B.shape
    weighted = (stress * kin.dV[..., None]).reshape(n_el, nq * n_strain, 1)
    return np.matmul(kin.B.reshape(n_el, nq * n_strain, nd).transpose(0, 2, 1),
                     weighted)[..., 0]


def strain(kin: ElementKinematics, u_global: np.ndarray) -> np.ndarray:
    """Gauss-point strains (n_el, nq, 4) of the displacement vector indexed by kin.dofs."""
    n_el, nq, n_strain, nd = kin.B.shape
    u_element = np.asarray(u_global)[kin.dofs]  # (e, nd)
    return np.matmul(kin.B.reshape(n_el, nq * n_strain, nd),
                     u_element[..., None]).reshape(n_el, nq, n_strain)


def gauss_point_spacing(points: np.ndarray, cells: np.ndarray, n_gauss: int) -> np.ndarray:
    """Characteristic length h_c = sqrt(h1 h2) per element (thesis eq. 4.3).

    h1, h2 are the Gauss-point spacings in the two element directions: the mean length of each
    pair of opposite edges divided by `n_gauss`. Quad8 edges are measured along the polyline
    through their mid-side node.
    """
    cells = np.asarray(cells, dtype=int)
    X = np.asarray(points, dtype=float)[cells]
    corners = X[:, :4]
    ends = np.roll(corners, -1, axis=1)  # edge i runs corner i -> corner i+1
    if cells.shape[1] == 8:
        mid = X[:, 4:8]
        length = (np.linalg.norm(mid - corners, axis=-1) + np.linalg.norm(ends - mid, axis=-1))
    else:
        length = np.linalg.norm(ends - corners, axis=-1)  # (e, 4)
    h1 = 0.5 * (length[:, 0] + length[:, 2]) / n_gauss
    h2 = 0.5 * (length[:, 1] + length[:, 3]) / n_gauss
    return np.sqrt(h1 * h2)
