"""Patch tests: a linear displacement field imposed on the boundary of a distorted mesh must be
reproduced exactly (to round-off) inside, with the constant stress of that field everywhere.
"""

from __future__ import annotations

import numpy as np
import pytest

from icewall.materials.elastic import elastic_moduli
from icewall.mesh.structured import rectangle_mesh

E, NU = 30_000.0, 0.2
RTOL = 1e-10  # round-off level, relative to the largest displacement / stress component


def _boundary_nodes(mesh):
    return np.unique(np.concatenate([mesh.node_sets[s] for s in ("left", "right", "bottom",
                                                                 "top")]))


def _curve_interior_midsides(mesh, amount=0.15, seed=1):
    """Move the quad8 mid-side nodes off the boundary, curving the interior element edges."""
    points = mesh.points.copy()
    mids = np.setdiff1d(np.unique(mesh.cells[:, 4:]), _boundary_nodes(mesh))
    points[mids] += np.random.default_rng(seed).uniform(-amount, amount, (mids.size, 2)) * 0.5
    return points


def _field(points, formulation):
    """Linear displacement field (n, 2) and its strain [xx, yy, zz, xy]."""
    x, y = points[:, 0], points[:, 1]
    if formulation == "axisymmetric":  # u_r = a r, u_z = c z + d: exact away from the axis
        a, c, d = 1.2e-3, -0.7e-3, 0.3
        return np.column_stack([a * x, c * y + d]), np.array([a, c, a, 0.0])
    u = np.column_stack([0.1 + 2e-3 * x + 3e-3 * y, -0.2 + 0.5e-3 * x - 1.5e-3 * y])
    return u, np.array([2e-3, -1.5e-3, 0.0, 3.5e-3])


@pytest.mark.parametrize("formulation", ["plane_strain", "plane_stress", "axisymmetric"])
@pytest.mark.parametrize(("cell_type", "curved"),
                         [("quad4", False), ("quad8", False), ("quad8", True)])
def test_patch_test_distorted_mesh(solve_elastic, cell_type, formulation, curved):
    """Interior corner nodes moved by up to 30 % of the element size; optionally the interior
    quad8 mid-side nodes too (curved edges). With 3x3 Gauss B^T sigma dV is a polynomial of
    degree <= 5 per direction even then (also with the r factor), so the test is exact."""
    # r from 1 to 3 keeps the axisymmetric patch away from the axis
    mesh = rectangle_mesh(1.0, 3.0, 0.0, 2.0, 4, 3, cell_type, distort=0.3, seed=7)
    points = _curve_interior_midsides(mesh) if curved else mesh.points
    u_exact, eps_exact = _field(points, formulation)
    bnd = _boundary_nodes(mesh)
    nodes = np.repeat(bnd, 2)
    dirs = np.tile([0, 1], bnd.size)
    sol = solve_elastic(points, mesh.cells, cell_type, formulation, E, NU, nodes, dirs,
                        u_exact[bnd].ravel())
    interior = np.setdiff1d(np.arange(len(points)), bnd)
    assert interior.size > 0
    # Reference: the imposed linear field itself (exactly representable by the elements).
    np.testing.assert_allclose(sol.u[interior], u_exact[interior], rtol=0,
                               atol=RTOL * np.abs(u_exact).max())
    sig_exact = elastic_moduli(E, NU, formulation) @ eps_exact
    assert np.abs(sol.stress - sig_exact).max() <= RTOL * np.abs(sig_exact).max()
    if formulation == "plane_strain":  # sigma_zz = nu (sigma_xx + sigma_yy)
        assert sig_exact[2] == pytest.approx(NU * (sig_exact[0] + sig_exact[1]), rel=1e-12)
