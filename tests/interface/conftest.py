"""Shared helpers of the interface tests: a steel-concrete block model, a load-control driver."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
import scipy.sparse as sp

from icewall.fem.assembly import Assembler
from icewall.fem.kinematics import element_kinematics, stiffness_blocks
from icewall.fem.loads import edge_traction_loads
from icewall.fem.quadrature import gauss_rule
from icewall.interface import (
    augmented_matrix,
    augmented_rhs,
    constraint_matrix,
    factorize,
    relative_displacement,
    split_solution,
    update_states,
)
from icewall.materials.elastic import elastic_moduli
from icewall.mesh.mesh import CONCRETE, STEEL, Mesh, Region
from icewall.mesh.structured import rectangle_mesh

THICKNESS = 10.0


def steel_concrete_model(concrete_on_top: bool = True, nx: int = 10, springs_x: float = 0.0,
                         springs_y: float = 0.0):
    """A concrete block on a steel plate (or a concrete core under a steel top plate), quad4.

    concrete_on_top: steel [0,100]x[0,10] with its bottom fixed, concrete [0,100]x[10,30],
    interface normal (0, 1). Otherwise concrete [0,100]x[0,20] under steel [0,100]x[20,30]
    with its top fixed, normal (0, -1). Pairs (steel node, concrete node) along the interface;
    optional springs to ground (N/mm per direction) at the two far corners of the concrete.
    """
    y_s, y_c = ((0.0, 10.0), (10.0, 30.0)) if concrete_on_top else ((20.0, 30.0), (0.0, 20.0))
    steel = rectangle_mesh(0.0, 100.0, *y_s, nx, 1, "quad4", "plate", STEEL)
    concrete = rectangle_mesh(0.0, 100.0, *y_c, nx, 2, "quad4", "core", CONCRETE)
    off = steel.n_nodes
    points = np.vstack([steel.points, concrete.points])
    cells = np.vstack([steel.cells, concrete.cells + off])
    E = np.r_[np.full(steel.n_cells, 200_000.0), np.full(concrete.n_cells, 30_000.0)]
    nu = np.r_[np.full(steel.n_cells, 0.3), np.full(concrete.n_cells, 0.2)]
    kin = element_kinematics(points, cells, "quad4", gauss_rule(2), "plane_stress", THICKNESS)
    D = elastic_moduli(E, nu, "plane_stress")[:, None]
    n_eq = 2 * len(points)
    K = Assembler(kin.dofs, n_eq).matrix(stiffness_blocks(kin, D))
    s_side, c_side, far = ("top", "bottom", "top") if concrete_on_top else ("bottom", "top",
                                                                            "bottom")
    far_nodes = concrete.node_sets[far] + off
    corners = far_nodes[[np.argmin(points[far_nodes, 0]), np.argmax(points[far_nodes, 0])]]
    spring = np.zeros(n_eq)
    spring[2 * corners] = springs_x
    spring[2 * corners + 1] = springs_y
    K = (K + sp.diags(spring)).tocsr()
    s_nodes, c_nodes = steel.node_sets[s_side], concrete.node_sets[c_side] + off
    pairs = np.column_stack([s_nodes[np.argsort(points[s_nodes, 0])],
                             c_nodes[np.argsort(points[c_nodes, 0])]])
    normals = np.tile([0.0, 1.0 if concrete_on_top else -1.0], (len(pairs), 1))
    C = constraint_matrix(pairs, normals, np.arange(n_eq).reshape(-1, 2), n_eq)
    support = steel.node_sets["bottom" if concrete_on_top else "top"]
    fixed = np.concatenate([2 * support, 2 * support + 1])
    mesh = Mesh(points=points, cells=cells, cell_type="quad4",
                cell_region=np.r_[np.full(steel.n_cells, 1), np.full(concrete.n_cells, 2)],
                regions=(Region("plate", STEEL, 1), Region("core", CONCRETE, 2)),
                interface_pairs=pairs, interface_normals=normals,
                interface_corner=np.zeros(len(pairs), dtype=bool))
    loaded = concrete.edge_sets[far] + off

    def load(tx: float, ty: float) -> np.ndarray:
        """Nodal forces of a uniform traction on the concrete's far face, totals (tx, ty) N."""
        return edge_traction_loads(points, loaded, [tx / (100.0 * THICKNESS),
                                                    ty / (100.0 * THICKNESS)],
                                   "plane_stress", THICKNESS)

    return SimpleNamespace(K=K, C=C, fixed=fixed, pairs=pairs, n_eq=n_eq, load=load,
                           spring=spring, corners=corners, mesh=mesh)


def solve_load_level(K, F, C, gaps, mu, fixed, u, max_iter: int = 60, tol: float = 1e-9):
    """Load control: iterate displacements, multipliers and states to convergence at load F.

    Returns (u, gaps, iterations, total state changes).
    """
    n_eq = K.shape[0]
    scale = np.abs(F).max() + 1.0
    flips, changes = 1, 0
    for it in range(max_iter):
        rhs = augmented_rhs(F - K @ u, u, C, gaps, mu, fixed)
        if flips == 0 and np.abs(rhs).max() <= tol * scale:
            return u, gaps, it, changes
        du, d_N, d_T = split_solution(factorize(augmented_matrix(K, C, gaps, fixed)).solve(rhs),
                                      n_eq)
        u = u + du
        gaps, flips = update_states(gaps, gaps.lam_N + d_N, gaps.lam_T + d_T,
                                    *relative_displacement(C, u), mu)
        changes += flips
    raise AssertionError(f"no convergence in {max_iter} iterations")


@pytest.fixture
def driver():
    return SimpleNamespace(model=steel_concrete_model, solve_load_level=solve_load_level)
