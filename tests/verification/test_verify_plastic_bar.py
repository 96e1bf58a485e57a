"""Elastic-plastic bar (plate strip) under imposed end displacement, von Mises steel.

Strip 0 <= x <= L, 0 <= y <= h (distorted quad8 mesh, uniform exact stress state): u_x = 0 at
x = 0, u_y = 0 on y = 0 (symmetry line), u_x = delta at x = L. Closed forms (J2 plasticity with
linear isotropic hardening, e.g. Simo & Hughes 1998 §2.3; de Souza Neto et al. 2008 §7.3):
- plane stress, free top (uniaxial stress): F = E eps h t up to fy h t, then slope
  E H / (E + H) h t / L;
- plane strain, top fixed in y (uniaxial strain): yield at eps = fy / (2 G), then
  sigma_xx = K eps + 2/3 kappa, eps_bar = (2 G eps - fy) / (3 G + H);
- plane strain, free top ("plate"): sigma_zz = nu sigma_xx, yield at sigma_xx = fy / sqrt(1 -
  nu + nu^2).
`PlasticFE` is a minimal Newton-Raphson driver on icewall.fem kernels for these tests.
"""

from __future__ import annotations

import numpy as np
import pytest

from icewall.fem.assembly import Assembler
from icewall.fem.kinematics import (
    element_kinematics,
    internal_force_blocks,
    stiffness_blocks,
    strain,
)
from icewall.fem.quadrature import gauss_rule
from icewall.materials.steel import SteelParameters, SteelState, steel_parameters, update_steel
from icewall.mesh.structured import rectangle_mesh
from icewall.solve.linear import solve_linear

E, NU, FY, L, H_STRIP, T = 200_000.0, 0.3, 350.0, 400.0, 40.0, 10.0
G, K = E / (2 * (1 + NU)), E / (3 * (1 - 2 * NU))
LOAD_TOL = 1e-6  # relative error of the end force and slope (measured: <= 1e-14)


class PlasticFE:
    """Full Newton-Raphson with the consistent tangent: commit the state per converged step."""

    def __init__(self, mesh, params: SteelParameters, n_gauss: int = 3, thickness: float = 1.0):
        self.params, self.n_dofs = params, 2 * len(mesh.points)
        self.kin = element_kinematics(mesh.points, mesh.cells, mesh.cell_type,
                                      gauss_rule(n_gauss), params.formulation, thickness)
        self.assembler = Assembler(self.kin.dofs, self.n_dofs)
        self.state = SteelState.initial(self.kin.dV.size)
        self.u = np.zeros(self.n_dofs)
        self.f_int = np.zeros(self.n_dofs)

    def evaluate(self, u: np.ndarray):
        """Internal forces, tangent matrix and trial state at displacement u."""
        eps = strain(self.kin, u).reshape(-1, 4)
        stress, moduli, trial = update_steel(eps, self.state, self.params)
        shape = self.kin.dV.shape
        f_int = self.assembler.vector(internal_force_blocks(self.kin, stress.reshape(shape + (4,))))
        K = self.assembler.matrix(stiffness_blocks(self.kin, moduli.reshape(shape + (4, 4))))
        return f_int, K, trial

    def step(self, fixed: np.ndarray, values: np.ndarray, f_ext: np.ndarray | None = None,
             tol: float = 1e-11, max_iter: int = 25) -> list[float]:
        """Solve one increment to u[fixed] = values; returns the relative residual history."""
        f_ext = np.zeros(self.n_dofs) if f_ext is None else f_ext
        free = np.setdiff1d(np.arange(self.n_dofs), fixed)
        u, f_int = self.u.copy(), self.f_int
        K = self.evaluate(u)[1]
        history = []
        for _ in range(max_iter):
            du = solve_linear(K, f_ext - f_int, fixed, values - u[fixed])
            u += du
            f_int, K, trial = self.evaluate(u)
            ref = max(np.linalg.norm(f_ext), np.linalg.norm(f_int[fixed]), 1e-30)
            history.append(float(np.linalg.norm((f_ext - f_int)[free]) / ref))
            if history[-1] <= tol:
                self.u, self.f_int, self.state = u, f_int, trial
                return history
        raise AssertionError(f"Newton did not converge: {history}")


def convergence_orders(history: list[float], floor: float = 1e-12) -> list[float]:
    """Observed orders log(r_k+1 / r_k) / log(r_k / r_k-1) of residuals above round-off."""
    r = np.log([h for h in history if h > floor])
    return [float((r[k + 1] - r[k]) / (r[k] - r[k - 1])) for k in range(1, len(r) - 1)]


def run_strip(formulation: str, top_fixed: bool, delta_over_yield: list[float], eps_y: float):
    p = steel_parameters(E, NU, FY, formulation=formulation)
    mesh = rectangle_mesh(0.0, L, 0.0, H_STRIP, 8, 2, "quad8", distort=0.2, seed=3)
    fe = PlasticFE(mesh, p, 3, T)
    left, right = mesh.node_sets["left"], mesh.node_sets["right"]
    top = mesh.node_sets["top"] if top_fixed else np.zeros(0, int)
    y_fixed = np.union1d(mesh.node_sets["bottom"], top)
    fixed = np.concatenate([2 * left, 2 * right, 2 * y_fixed + 1])
    forces, histories, yielded = [], [], []
    for f in delta_over_yield:
        values = np.concatenate([np.zeros(left.size), np.full(right.size, f * eps_y * L),
                                 np.zeros(y_fixed.size)])
        histories.append(fe.step(fixed, values))
        print(formulation, f"delta/delta_y = {f}: residuals", [f"{r:.1e}" for r in histories[-1]],
              "orders", np.round(convergence_orders(histories[-1]), 2))
        forces.append(fe.f_int[2 * right].sum())
        yielded.append(float(fe.state.yielded.mean()))
    return p, np.array(forces), histories, yielded


def test_plane_stress_bar_yield_load_hardening_and_quadratic_newton():
    eps_y, steps = FY / E, [0.5, 1.0, 1.5, 2.5, 4.0]
    p, F, histories, yielded = run_strip("plane_stress", False, steps, eps_y)
    Et = E * p.hardening_modulus / (E + p.hardening_modulus)
    eps = np.array(steps) * eps_y
    expected = np.where(eps <= eps_y, E * eps, FY + Et * (eps - eps_y)) * H_STRIP * T
    np.testing.assert_allclose(F, expected, rtol=LOAD_TOL)
    slope = (F[-1] - F[-2]) / ((eps[-1] - eps[-2]) * L)
    assert slope == pytest.approx(Et * H_STRIP * T / L, rel=LOAD_TOL)
    assert yielded == [0.0, 0.0, 1.0, 1.0, 1.0]
    # elastic steps: 1 iteration; plastic steps: Newton finds the uniform eps_yy; measured
    # residuals 4.3e-1, 1.2e-3, 4.5e-8, 1.5e-14 (order 1.74 pre-asymptotic; the last is round-off)
    assert all(len(h) == 1 for h in histories[:2])
    for h in histories[2:]:
        assert len(h) <= 5 and min(convergence_orders(h), default=2.0) > 1.5, h


def test_plane_strain_bar_uniaxial_strain():
    eps_y, steps = FY / (2 * G), [0.5, 1.0, 2.0, 5.0]
    p, F, _, yielded = run_strip("plane_strain", True, steps, eps_y)
    eps = np.array(steps) * eps_y
    eps_bar = np.maximum(0.0, (2 * G * eps - FY) / (3 * G + p.hardening_modulus))
    sxx = K * eps + 2 / 3 * np.minimum(2 * G * eps, FY + p.hardening_modulus * eps_bar)
    np.testing.assert_allclose(F, sxx * H_STRIP * T, rtol=LOAD_TOL)
    slope = (F[-1] - F[-2]) / ((eps[-1] - eps[-2]) * L)
    Kt = K + 4 / 3 * G * p.hardening_modulus / (3 * G + p.hardening_modulus)
    assert slope == pytest.approx(Kt * H_STRIP * T / L, rel=LOAD_TOL)
    assert yielded == [0.0, 0.0, 1.0, 1.0]


def test_plane_strain_plate_yield_onset():
    s_y = FY / np.sqrt(1 - NU + NU * NU)  # sigma_xx at first yield, sigma_zz = nu sigma_xx
    eps_y = s_y * (1 - NU * NU) / E
    _, F, histories, yielded = run_strip("plane_strain", False, [1 - 1e-9, 1 + 1e-6, 3.0], eps_y)
    assert F[0] == pytest.approx(s_y * H_STRIP * T, rel=LOAD_TOL) and F[1] > F[0]
    assert yielded == [0.0, 1.0, 1.0] and F[2] < 3 * F[0]
    # measured residuals 8.5e-1, 5.8e-2, 1.7e-5, 1.4e-12: orders 3.0, 2.0
    assert min(convergence_orders(histories[2]), default=2.0) > 1.5, histories[2]
