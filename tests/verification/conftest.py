"""Shared helper of the verification tests: a complete linear-elastic FE solve."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from icewall.fem.assembly import Assembler
from icewall.fem.dofs import DofMap
from icewall.fem.kinematics import element_kinematics, stiffness_blocks, strain
from icewall.fem.quadrature import gauss_rule
from icewall.materials.elastic import update_elastic
from icewall.solve.linear import solve_linear


def _solve(points, cells, cell_type, formulation, E, nu, fixed_nodes=(), fixed_dirs=(),
           fixed_values=(), f_nodal=None, n_gauss=None, thickness=1.0, ties=None):
    """Assemble and solve; supports are (node, direction, value) triples given as 3 arrays."""
    n_gauss = n_gauss or (3 if cell_type == "quad8" else 2)
    dof_map = DofMap(len(points), ties)
    kin = element_kinematics(points, cells, cell_type, gauss_rule(n_gauss), formulation,
                             thickness, dof_map)
    _, D = update_elastic(np.zeros(kin.dV.shape + (4,)), E, nu, formulation)
    K = Assembler(kin.dofs, dof_map.n_equations).matrix(stiffness_blocks(kin, D))
    f_nodal = np.zeros(2 * len(points)) if f_nodal is None else f_nodal
    fixed = dof_map.node_equations[np.asarray(fixed_nodes, int), np.asarray(fixed_dirs, int)]
    u, reactions = solve_linear(K, dof_map.restrict(f_nodal), fixed,
                                np.asarray(fixed_values, float), return_reactions=True)
    eps = strain(kin, u)
    sig, _ = update_elastic(eps, E, nu, formulation)
    return SimpleNamespace(u=dof_map.expand(u), kin=kin, strain=eps, stress=sig, K=K,
                           reactions=reactions)


@pytest.fixture
def solve_elastic():
    """solve_elastic(points, cells, cell_type, formulation, E, nu, fixed_nodes, fixed_dirs,
    fixed_values, f_nodal, n_gauss, thickness, ties) -> namespace(u (n,2), kin, strain, stress)."""
    return _solve
