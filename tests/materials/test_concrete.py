"""Orthotropic rotating-crack concrete update (thesis §3.2, Fig. 3.12) and its errata.

Reference numbers: errata.md §1.1 (isotropic check E = 30 000, nu = 0.2: lambda + 2G = 33 333;
phi for eta = (0.2, 0.3, 0.45): 0.614 corrected vs 0.485 printed) and §1.3 (beta = 27 deg).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from icewall.formulations import FORMULATIONS
from icewall.materials.concrete import concrete_tangent, update_concrete
from icewall.materials.concrete_state import ConcreteState
from icewall.materials.elastic import plane_stress_strain_zz
from icewall.materials.orthotropic import (
    global_moduli,
    global_stress,
    local_normal_components,
    orthotropic_normal_stiffness,
    principal_strain_angle,
    strain_rotation,
    uniaxial_coupling_matrix,
)
from icewall.materials.parameters import derive_concrete_parameters
from icewall.materials.ultimate_surface import failure_function

PARAMS = derive_concrete_parameters(53.5, 100.0)


def _compliance(E: np.ndarray, nu: np.ndarray) -> np.ndarray:
    eta = {(0, 1): np.sqrt(nu[0] * nu[1]), (1, 2): np.sqrt(nu[1] * nu[2]),
           (0, 2): np.sqrt(nu[2] * nu[0])}
    S = np.diag(1.0 / E)
    for (i, j), value in eta.items():
        S[i, j] = S[j, i] = -value / np.sqrt(E[i] * E[j])
    return S


def test_eq_3_2_and_3_3d_invert_the_orthotropic_compliance() -> None:
    # errata 1.1: 1/phi prefactor and phi = 1 - sum eta^2 - 2 eta12 eta23 eta31
    E = np.array([30000.0, 12000.0, 21000.0])
    nu = np.array([0.2, 0.45, 0.3])
    C = orthotropic_normal_stiffness(E[None], nu[None])[0]
    np.testing.assert_allclose(C @ _compliance(E, nu), np.eye(3), atol=1e-12)
    eta12, eta23, eta31 = np.sqrt(nu[0] * nu[1]), np.sqrt(nu[1] * nu[2]), np.sqrt(nu[2] * nu[0])
    phi = 1 - eta12**2 - eta23**2 - eta31**2 - 2 * eta12 * eta23 * eta31
    printed_phi = 1 - eta12**2 - eta23**2 - eta31**2 - 2 * eta31**3
    assert not np.allclose(C * phi, C * printed_phi)  # printed 3.3d gives another matrix
    assert not np.allclose((C * phi) @ _compliance(E, nu), np.eye(3), atol=1e-3)  # no 1/phi


def test_isotropic_limit_is_hooke() -> None:
    C = orthotropic_normal_stiffness(np.full((1, 3), 30000.0), np.full((1, 3), 0.2))[0]
    assert C[0, 0] == pytest.approx(33333.333333, rel=1e-9)  # lambda + 2G (printed: 28 800)
    assert C[0, 1] == pytest.approx(8333.333333, rel=1e-9)  # lambda


def test_eq_3_4_row_3_and_eq_3_7a() -> None:
    E = np.array([[30000.0, 12000.0, 21000.0]])
    nu = np.array([[0.2, 0.45, 0.3]])
    B = uniaxial_coupling_matrix(E, nu)[0]
    C = orthotropic_normal_stiffness(E, nu)[0]
    np.testing.assert_allclose(E[0, 2] * B[2, :2], C[2, :2])  # E3 B31, E3 B32 (errata 1.1)
    assert not np.allclose(E[0, 2] * B[:2, 2], C[2, :2])  # printed E3 B13, E3 B23
    # 3.7a without E_i: isotropic uniaxial stress increment gives d eps_1u = d eps_1 exactly
    Eiso, nuiso = np.full((1, 3), 30000.0), np.full((1, 3), 0.2)
    d_eps = np.array([1e-4, -0.2e-4, -0.2e-4])
    d_eps_u = uniaxial_coupling_matrix(Eiso, nuiso)[0] @ d_eps
    np.testing.assert_allclose(d_eps_u, [1e-4, 0.0, 0.0], atol=1e-18)  # printed: E times this


def test_fig_3_12_transformations_reproduce_global_stress() -> None:
    # errata 1.3: C_g = T_eps^T C_l T_eps, sigma_g = T_eps^T sigma_l (beta = 27 deg)
    angle = np.array([np.radians(27.0)])
    E, nu = np.array([[30000.0, 8000.0, 20000.0]]), np.array([[0.2, 0.1, 0.3]])
    C_l = orthotropic_normal_stiffness(E, nu)
    C_g = global_moduli(C_l, np.array([5000.0]), angle)
    eps_g = np.array([[1e-4, -3e-4, 2e-4, 5e-4]])
    T = strain_rotation(angle)[0]
    eps_l = T @ eps_g[0]
    sigma_l = np.append(C_l[0] @ eps_l[:3], 5000.0 * eps_l[3])
    np.testing.assert_allclose(C_g[0] @ eps_g[0], T.T @ sigma_l, rtol=1e-12)
    T_sigma = np.linalg.inv(T).T
    local_full = np.zeros((4, 4))
    local_full[:3, :3], local_full[3, 3] = C_l[0], 5000.0
    printed = T_sigma.T @ local_full @ T_sigma  # "C_g = T C_l T^T" read with T = T_sigma
    assert not np.allclose(printed @ eps_g[0], T.T @ sigma_l, rtol=1e-3)
    # local normal components and back, with zero shear
    sig = global_stress(sigma_l[None, :3], angle)
    np.testing.assert_allclose(local_normal_components(sig, angle, 2.0)[0], sigma_l[:3])


def test_principal_angle_keeps_labels_and_follows_rotation() -> None:
    theta = np.radians([10.0, 50.0, 100.0])
    e1, e2 = 1e-3, -2e-3
    c, s = np.cos(theta), np.sin(theta)
    strain = np.stack([c * c * e1 + s * s * e2, s * s * e1 + c * c * e2, 0 * c,
                       2 * c * s * (e1 - e2)], axis=1)
    angle = principal_strain_angle(strain, theta - np.radians(5.0))
    np.testing.assert_allclose(angle, theta, atol=1e-12)
    assert principal_strain_angle(np.zeros((1, 4)), np.array([0.3]))[0] == 0.3


def _loaded_state(strain: np.ndarray, formulation: str, params=PARAMS, steps: int = 10
                  ) -> ConcreteState:
    state = ConcreteState.initial(strain.shape[0], params)
    for t in np.linspace(0.0, 1.0, steps + 1)[1:]:
        _, _, state = update_concrete(t * strain, state, params, formulation)
    return state


@pytest.mark.parametrize("formulation", FORMULATIONS)
def test_zero_increment_returns_committed_stress_and_update_is_pure(formulation: str) -> None:
    rng = np.random.default_rng(3)
    strain = rng.uniform(-4e-3, 2e-3, size=(50, 4))
    state = _loaded_state(strain, formulation)
    before = {k: v.copy() for k, v in vars(state).items()}
    stress, _, trial = update_concrete(state.strain, state, PARAMS, formulation)
    np.testing.assert_allclose(stress, state.stress, rtol=1e-10, atol=1e-10 * PARAMS.fc)
    np.testing.assert_array_equal(trial.secant_modulus, state.secant_modulus)
    for name, value in before.items():
        np.testing.assert_array_equal(getattr(state, name), value)


def test_secant_capped_at_initial_modulus_for_high_strength() -> None:
    # errata §3: R_E < 2 for f'c > 30.25; raw Saenz secant peaks at 1.125 E0 for 68 MPa
    params = derive_concrete_parameters(68.0, 100.0)
    strain = np.array([[-1e-3, 0.2e-3, 0.0, 0.0]])
    state = _loaded_state(strain, "plane_stress", params)
    assert state.secant_modulus.max() <= params.E0
    stress, moduli, _ = update_concrete(strain, ConcreteState.initial(1, params), params,
                                        "plane_stress")
    assert np.all(np.isfinite(moduli)) and moduli[0, 3, 3] <= params.E0 / 2.4 + 1e-9


def test_poisson_cap_keeps_confined_plane_strain_finite() -> None:
    # errata §3: nu capped below 0.5 (nu_max = 0.49) and phi >= phi_min
    strain = np.array([[-0.02, -0.02, 0.0, 0.0], [-0.05, -0.01, 0.0, 0.0]])
    state = _loaded_state(strain, "plane_strain", steps=40)
    assert state.poisson_ratio.max() <= PARAMS.nu_max
    assert np.all(np.isfinite(state.stress)) and np.all(np.isfinite(state.secant_modulus))


def test_plane_stress_condenses_sigma_zz() -> None:
    strain = np.array([[-2e-4, 1e-4, 123.0, 3e-5]])  # zz input ignored
    stress, moduli, trial = update_concrete(strain, ConcreteState.initial(1, PARAMS), PARAMS,
                                            "plane_stress")
    assert stress[0, 2] == 0.0 and np.all(moduli[0, 2] == 0.0) and np.all(moduli[0, :, 2] == 0)
    # first increment from the virgin state: isotropic, eps_zz = -nu0/(1-nu0)(eps_xx + eps_yy)
    assert trial.strain[0, 2] == pytest.approx(plane_stress_strain_zz(strain[0], PARAMS.nu0))


def test_linear_range_is_secant_and_tangent_matches_differences() -> None:
    # small in-plane tension: E = E0, nu = nu0 (eq. 3.20a): sigma = C_g eps exactly
    strain = np.array([[1e-5, 0.3e-5, 0.0, 0.6e-5]])
    for formulation in FORMULATIONS:
        stress, moduli, trial = update_concrete(strain, ConcreteState.initial(1, PARAMS), PARAMS,
                                                formulation)
        np.testing.assert_array_equal(trial.poisson_ratio, PARAMS.nu0)
        np.testing.assert_allclose(moduli[0] @ trial.strain[0], stress[0], rtol=1e-10)
    # algorithmic tangent vs central differences on the ascending compression branch
    rng = np.random.default_rng(0)
    base = np.array([[-1.2e-3, -0.3e-3, 0.0, 0.4e-3]])
    state = _loaded_state(base, "plane_strain")
    strain = base * 1.05
    tangent = concrete_tangent(strain, state, PARAMS, "plane_strain")
    for _ in range(3):
        direction = rng.normal(size=4) * np.array([1, 1, 0, 1])
        h = 1e-8
        plus, _, _ = update_concrete(strain + h * direction, state, PARAMS, "plane_strain")
        minus, _, _ = update_concrete(strain - h * direction, state, PARAMS, "plane_strain")
        np.testing.assert_allclose(tangent[0] @ direction, (plus - minus)[0] / (2 * h),
                                   rtol=2e-3, atol=1e-3 * np.abs(tangent[0] @ direction).max())


def test_local_stress_is_secant_times_equivalent_uniaxial_strain() -> None:
    strain = np.array([[-2e-3, -0.5e-3, 0.0, 1e-3], [1e-4, -1e-3, 0.0, 0.0]])
    state = _loaded_state(strain, "plane_strain")
    local = local_normal_components(state.stress, state.angle, 2.0)
    np.testing.assert_allclose(local, state.secant_modulus * state.equivalent_uniaxial_strain,
                               rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("fc", [20.0, 53.5, 120.0])
@pytest.mark.parametrize("formulation", FORMULATIONS)
def test_extreme_inputs_stay_finite(fc: float, formulation: str) -> None:
    params = derive_concrete_parameters(fc, 100.0)
    rng = np.random.default_rng(1)
    big = rng.uniform(-1.0, 1.0, size=(200, 4))
    hydro_tension = np.array([[1e-3, 1e-3, 1e-3, 0.0], [1.0, 1.0, 1.0, 0.0]])
    hydro_compression = -20.0 * params.eps_c * np.array([[1.0, 1.0, 1.0, 0.0]])
    for strain in (big, hydro_tension, hydro_compression, np.zeros((3, 4))):
        state = ConcreteState.initial(strain.shape[0], params)
        for t in (0.1, 1.0, 1.0, 0.5, -1.0):
            stress, moduli, state = update_concrete(t * strain, state, params, formulation)
            assert np.all(np.isfinite(stress)) and np.all(np.isfinite(moduli))
            assert np.all(state.secant_modulus > 0.0)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(-1.0, 1.0), min_size=4, max_size=4),
       st.floats(1e-5, 0.02), st.sampled_from(FORMULATIONS), st.floats(20.0, 120.0))
def test_property_finite_and_monotone_secants(direction: list[float], size: float,
                                              formulation: str, fc: float) -> None:
    params = derive_concrete_parameters(fc, 100.0)
    d = np.array(direction)
    strain = size * d / max(np.abs(d).max(), 1e-12)
    state = ConcreteState.initial(1, params)
    previous = state.secant_modulus.copy()
    previous_sign = state.uniaxial_strength > 0
    for t in np.linspace(0.0, 1.0, 21)[1:]:
        stress, moduli, state = update_concrete(t * strain[None], state, params, formulation)
        assert np.all(np.isfinite(stress)) and np.all(np.isfinite(moduli))
        assert np.all(state.secant_modulus > 0.0)
        same_sign = (state.equivalent_uniaxial_strain > 0) == previous_sign
        # non-increasing on each branch (a crack closing in compression re-stiffens)
        assert np.all((state.secant_modulus <= previous * (1 + 1e-9)) | ~same_sign)
        previous = state.secant_modulus.copy()
        previous_sign = state.uniaxial_strength > 0  # branch of the committed secant


@settings(max_examples=40, deadline=None)
@given(st.floats(-1.0, 1.0), st.floats(-1.0, 1.0), st.floats(1e-4, 0.01))
def test_property_compressive_states_inside_ultimate_surface(a: float, b: float,
                                                             size: float) -> None:
    # plane strain, all principal strains compressive: triaxial compression, rule (a)
    strain = -size * np.array([[1.0, 0.5 + 0.5 * abs(a), 0.0, 0.3 * b]])
    state = _loaded_state(strain, "plane_strain", steps=20)
    c, r = 0.5 * (state.stress[0, 0] + state.stress[0, 1]), np.hypot(
        0.5 * (state.stress[0, 0] - state.stress[0, 1]), state.stress[0, 3])
    principal = np.array([[c + r, c - r, state.stress[0, 2]]])
    f = failure_function(principal, PARAMS.fc, PARAMS.surface)
    assert f[0] <= 1e-6
