"""Elastic moduli against the 3D isotropic law; solve_linear partitioning and singularity."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from icewall.errors import ConvergenceError
from icewall.fem.assembly import Assembler
from icewall.fem.kinematics import element_kinematics, stiffness_blocks
from icewall.fem.quadrature import gauss_rule
from icewall.materials.elastic import elastic_moduli, plane_stress_strain_zz, update_elastic
from icewall.mesh.structured import rectangle_mesh
from icewall.solve.linear import solve_linear

E, NU = 200_000.0, 0.3


def _stress_3d(eps):
    """sigma = lambda tr(eps) I + 2 mu eps, [xx, yy, zz, xy] with engineering shear."""
    lam, mu = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
    tr = eps[..., :3].sum(axis=-1, keepdims=True)
    return np.concatenate([lam * tr + 2 * mu * eps[..., :3], mu * eps[..., 3:]], axis=-1)


def test_plane_strain_and_axisymmetric_moduli_are_3d_isotropic():
    eps = np.random.default_rng(0).normal(size=(10, 4)) * 1e-3
    for formulation in ("plane_strain", "axisymmetric"):
        sig, D = update_elastic(eps, E, NU, formulation)
        np.testing.assert_allclose(sig, _stress_3d(eps), rtol=1e-13)
        assert D.shape == (10, 4, 4)
    eps[:, 2] = 0.0  # plane strain: sigma_zz = nu (sigma_xx + sigma_yy)
    sig, _ = update_elastic(eps, E, NU, "plane_strain")
    np.testing.assert_allclose(sig[:, 2], NU * (sig[:, 0] + sig[:, 1]), rtol=1e-13)


def test_plane_stress_is_3d_law_with_zero_sigma_zz():
    eps = np.random.default_rng(1).normal(size=(10, 4)) * 1e-3
    sig, _ = update_elastic(eps, E, NU, "plane_stress")  # eps_zz input is ignored
    full = eps.copy()
    full[:, 2] = plane_stress_strain_zz(eps, NU)
    ref = _stress_3d(full)
    np.testing.assert_allclose(ref[:, 2], 0.0, atol=1e-10)
    np.testing.assert_allclose(sig[:, [0, 1, 3]], ref[:, [0, 1, 3]], rtol=1e-13)
    assert np.all(sig[:, 2] == 0.0)
    D = elastic_moduli(E, NU, "plane_stress")
    assert np.all(D[2] == 0) and np.all(D[:, 2] == 0)


def test_moduli_accept_per_point_properties():
    D = elastic_moduli(np.array([1.0, 2.0]), 0.25, "plane_strain")
    assert D.shape == (2, 4, 4)
    np.testing.assert_allclose(D[1], 2 * D[0])


def _cantilever_system():
    mesh = rectangle_mesh(0.0, 100.0, 0.0, 20.0, 5, 2, "quad8")
    kin = element_kinematics(mesh.points, mesh.cells, "quad8", gauss_rule(3), "plane_stress")
    K = Assembler(kin.dofs, 2 * mesh.n_nodes).matrix(
        stiffness_blocks(kin, elastic_moduli(E, NU, "plane_stress")))
    return mesh, K


def test_solve_linear_matches_dense_solution_and_gives_reactions():
    mesh, K = _cantilever_system()
    f = np.zeros(K.shape[0])
    f[2 * mesh.node_sets["right"] + 1] = -10.0
    fixed = (2 * mesh.node_sets["left"][:, None] + np.arange(2)).ravel()
    values = np.where(fixed % 2 == 0, 1e-3, 0.0)  # prescribed x displacement on the root
    u, reactions = solve_linear(K, f, fixed, values, return_reactions=True)
    free = np.setdiff1d(np.arange(K.shape[0]), fixed)
    Kd = K.toarray()
    ref = np.linalg.solve(Kd[np.ix_(free, free)], f[free] - Kd[np.ix_(free, fixed)] @ values)
    np.testing.assert_allclose(u[free], ref, rtol=1e-10)
    np.testing.assert_array_equal(u[fixed], values)
    # global equilibrium: reactions balance the applied load
    assert reactions[1::2].sum() == pytest.approx(-f.sum(), rel=1e-10)
    assert abs(reactions[0::2].sum()) < 1e-8 * abs(f.sum())


@pytest.mark.parametrize("support", ["none", "x_only"])
def test_missing_supports_raise_singular_system(support):
    mesh, K = _cantilever_system()
    f = np.ones(K.shape[0])
    fixed = np.zeros(0, int) if support == "none" else 2 * mesh.node_sets["left"]
    with pytest.raises(ConvergenceError, match="check supports") as info:
        solve_linear(K, f, fixed)
    assert info.value.reason == "singular system"


def test_exactly_singular_matrix_raises():
    K = sp.csr_matrix(np.diag([1.0, 0.0, 2.0]))
    with pytest.raises(ConvergenceError) as info:
        solve_linear(K, np.ones(3))
    assert info.value.reason == "singular system"


def test_free_square_mesh_is_singular_but_slender_clamped_beam_is_not():
    """Pivot threshold: three rigid modes of a 30 x 30 mesh are caught; an L/h = 200 clamped
    cantilever (legitimately ill-conditioned) is still solved."""
    mesh = rectangle_mesh(0.0, 1000.0, 0.0, 1000.0, 30, 30, "quad8")
    kin = element_kinematics(mesh.points, mesh.cells, "quad8", gauss_rule(3), "plane_stress")
    K = Assembler(kin.dofs, 2 * mesh.n_nodes).matrix(
        stiffness_blocks(kin, elastic_moduli(E, NU, "plane_stress")))
    with pytest.raises(ConvergenceError, match="singular"):
        solve_linear(K, np.ones(K.shape[0]))
    beam = rectangle_mesh(0.0, 2000.0, 0.0, 10.0, 200, 1, "quad8")
    kin = element_kinematics(beam.points, beam.cells, "quad8", gauss_rule(3), "plane_stress")
    K = Assembler(kin.dofs, 2 * beam.n_nodes).matrix(
        stiffness_blocks(kin, elastic_moduli(E, NU, "plane_stress")))
    f = np.zeros(K.shape[0])
    f[2 * beam.node_sets["right"] + 1] = -1.0 / 3
    fixed = (2 * beam.node_sets["left"][:, None] + np.arange(2)).ravel()
    u = solve_linear(K, f, fixed)
    I = 10.0**3 / 12  # Euler-Bernoulli tip deflection P L^3 / (3 E I), shear negligible here
    assert u[2 * beam.node_sets["right"] + 1].mean() == pytest.approx(
        -2000.0**3 / (3 * E * I), rel=1e-3)
