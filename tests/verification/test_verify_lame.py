"""Thick-walled cylinder under internal pressure (Lame) in plane strain, two models.

Reference (e.g. Timoshenko & Goodier, Theory of Elasticity, sec. 28), inner radius a, outer b:
  sigma_r = A - C / r^2, sigma_theta = A + C / r^2, A = p a^2 / (b^2 - a^2), C = A b^2,
  sigma_z = nu (sigma_r + sigma_theta) (eps_z = 0), u_r = r eps_theta.
"""

from __future__ import annotations

import numpy as np

from icewall.fem.loads import edge_pressure_loads
from icewall.mesh.structured import rectangle_mesh

E, NU, P_IN, A_IN, B_OUT = 30_000.0, 0.2, 10.0, 100.0, 200.0
N_RADIAL = 8  # quad8 elements through the wall
STRESS_TOL = 0.01  # Gauss-point stress error / p
DISP_TOL = 1e-4  # nodal radial displacement error / u_r(a)


def _lame(r):
    A = P_IN * A_IN**2 / (B_OUT**2 - A_IN**2)
    C = A * B_OUT**2
    s_r, s_t = A - C / r**2, A + C / r**2
    s_z = NU * (s_r + s_t)
    u_r = r / E * (s_t - NU * (s_r + s_z))
    return u_r, s_r, s_t, s_z


def test_lame_axisymmetric_strip(solve_elastic):
    """Strip a <= r <= b, 0 <= z <= 20 with u_z = 0 on top and bottom (eps_z = 0)."""
    mesh = rectangle_mesh(A_IN, B_OUT, 0.0, 20.0, N_RADIAL, 1, "quad8")
    f = edge_pressure_loads(mesh.points, mesh.edge_sets["left"], P_IN, "axisymmetric")
    ends = np.concatenate([mesh.node_sets["bottom"], mesh.node_sets["top"]])
    sol = solve_elastic(mesh.points, mesh.cells, "quad8", "axisymmetric", E, NU, ends,
                        np.ones_like(ends), np.zeros(ends.size), f)
    u_ref = _lame(mesh.points[:, 0])[0]
    # measured: 3.0e-6
    assert np.abs(sol.u[:, 0] - u_ref).max() <= DISP_TOL * _lame(A_IN)[0]
    _, s_r, s_t, s_z = _lame(sol.kin.x[..., 0])
    # stress components [rr, zz, theta theta, rz]; measured errors / p: 5.5e-3, 1.4e-3, 1.4e-3
    for fe, ref in ((sol.stress[..., 0], s_r), (sol.stress[..., 2], s_t),
                    (sol.stress[..., 1], s_z)):
        assert np.abs(fe - ref).max() <= STRESS_TOL * P_IN
    assert np.abs(sol.stress[..., 3]).max() <= 1e-9 * P_IN


def test_lame_plane_strain_quarter_annulus(solve_elastic):
    """Quarter annulus mapped from an (r, theta) rectangle; quad8 mid-side nodes on the arcs;
    symmetry u_y = 0 on theta = 0 and u_x = 0 on theta = pi / 2."""
    mesh = rectangle_mesh(A_IN, B_OUT, 0.0, np.pi / 2, N_RADIAL, 2 * N_RADIAL, "quad8")
    r, theta = mesh.points.T
    points = np.column_stack([r * np.cos(theta), r * np.sin(theta)])
    f = edge_pressure_loads(points, mesh.edge_sets["left"], P_IN, "plane_strain", 5.0)
    # resultant of p on the quarter arc r = a: p a t in x and in y (exact for any edge shape)
    np.testing.assert_allclose([f[0::2].sum(), f[1::2].sum()], P_IN * A_IN * 5.0, rtol=1e-12)
    bottom, top = mesh.node_sets["bottom"], mesh.node_sets["top"]
    nodes = np.concatenate([bottom, top])
    dirs = np.concatenate([np.ones(bottom.size, int), np.zeros(top.size, int)])
    sol = solve_elastic(points, mesh.cells, "quad8", "plane_strain", E, NU, nodes, dirs,
                        np.zeros(nodes.size), f, thickness=5.0)
    u_r = np.hypot(*sol.u.T)
    # measured: 3.7e-6
    assert np.abs(u_r - _lame(r)[0]).max() <= DISP_TOL * _lame(A_IN)[0]
    xg = sol.kin.x
    rg = np.hypot(xg[..., 0], xg[..., 1])
    c, s = xg[..., 0] / rg, xg[..., 1] / rg
    sxx, syy, szz, sxy = np.moveaxis(sol.stress, -1, 0)
    s_r = sxx * c * c + syy * s * s + 2 * sxy * s * c
    s_t = sxx * s * s + syy * c * c - 2 * sxy * s * c
    _, ref_r, ref_t, ref_z = _lame(rg)
    # measured errors / p: 5.5e-3, 1.4e-3, 1.4e-3
    for fe, ref in ((s_r, ref_r), (s_t, ref_t), (szz, ref_z)):
        assert np.abs(fe - ref).max() <= STRESS_TOL * P_IN
