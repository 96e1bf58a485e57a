"""Single-point paths of the von Mises steel (icewall.materials.steel), no mesh.

Closed forms (small-strain J2 plasticity, linear isotropic hardening kappa = fy + H eps_bar):
uniaxial stress slope E H / (E + H); uniaxial strain sigma_xx = K eps + 2/3 kappa with
eps_bar = (2 G eps - fy) / (3 G + H); pure shear yield tau = fy / sqrt(3), then
tau = kappa / sqrt(3) with eps_bar = (sqrt(3) G gamma - fy) / (3 G + H)
(e.g. Simo & Hughes 1998, §2.3 and Box 3.2; de Souza Neto et al. 2008, §7.3).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from icewall.formulations import FORMULATIONS
from icewall.materials import steel
from icewall.materials.steel import (
    SteelState,
    plane_strain_fy_reduction,
    steel_parameters,
    update_steel,
    von_mises_stress,
    yield_stress,
)

E, NU, FY = 200_000.0, 0.3, 300.0
G, K = E / (2 * (1 + NU)), E / (3 * (1 - 2 * NU))


def params(formulation: str, **kw):
    return steel_parameters(E, NU, FY, formulation=formulation, **kw)


def mixed_path(p, driven: np.ndarray, free: list[int], targets: np.ndarray):
    """Drive strain component `driven` through `targets` with zero stress in `free` components
    (local Newton on the free strains with the consistent moduli). Returns (strains, stresses,
    states) per step."""
    state, e, out = SteelState.initial(1), np.zeros(4), []
    for target in targets:
        e[driven] = target
        for _ in range(50):
            s, C, trial = update_steel(e[None], state, p)
            r = s[0, free]
            if np.abs(r).max() <= 1e-10 * FY:
                break
            e[free] -= np.linalg.solve(C[0][np.ix_(free, free)], r)
        state = trial
        out.append((e.copy(), s[0].copy(), trial))
    return out


def test_plane_stress_uniaxial_load_unload_reload():
    p = params("plane_stress")
    Et, ey = E * p.hardening_modulus / (E + p.hardening_modulus), FY / E
    path = np.array([0.5, 1.0, 3.0, 8.0, 6.0, 8.0, 10.0]) * ey
    res = mixed_path(p, 0, [1], path)
    sxx = np.array([s[0] for _, s, _ in res])
    expected = [0.5 * FY, FY, FY + Et * 2 * ey, FY + Et * 7 * ey,
                FY + Et * 7 * ey - 2 * FY, FY + Et * 7 * ey, FY + Et * 9 * ey]
    np.testing.assert_allclose(sxx, expected, rtol=1e-10)
    assert [r[2].yielded[0] for r in res] == [False, False] + [True] * 5
    eps_bar = np.array([r[2].equivalent_plastic_strain[0] for r in res])
    assert eps_bar[4] == eps_bar[3] == eps_bar[5]  # unloading and reloading are elastic
    _, s, state = res[-1]
    ez = -NU * s[0] / E - 0.5 * state.plastic_strain[0, 0]  # elastic + plastic eps_zz
    assert state.strain[0, 2] == pytest.approx(ez, rel=1e-10)
    assert state.out_of_plane_strain[0] == state.strain[0, 2]
    assert s[2] == 0.0 and abs(s[1]) <= 1e-10 * FY


@pytest.mark.parametrize("formulation, axis", [("plane_strain", 0), ("axisymmetric", 2)])
def test_uniaxial_strain_closed_form(formulation: str, axis: int):
    """eps only in xx (plane strain) or in the hoop direction (axisymmetric ring)."""
    p = params(formulation)
    H = p.hardening_modulus
    ey = FY / (2 * G)  # onset: q = 2 G eps
    state = SteelState.initial(1)
    for f in (0.5, 1.0, 1.7, 4.0, 25.0):
        strain = np.zeros((1, 4))
        strain[0, axis] = f * ey
        stress, _, state = update_steel(strain, state, p)
        eps_bar = max(0.0, (2 * G * f * ey - FY) / (3 * G + H))
        kappa = FY + H * eps_bar
        q = min(kappa, 2 * G * f * ey)
        expected = np.full(4, K * f * ey - q / 3)
        expected[axis], expected[3] = K * f * ey + 2 * q / 3, 0.0
        np.testing.assert_allclose(stress[0], expected, rtol=1e-12, atol=1e-12 * FY)
        assert state.equivalent_plastic_strain[0] == pytest.approx(eps_bar, abs=1e-15)
        assert state.yielded[0] == (f > 1.0)


@pytest.mark.parametrize("reduction", [0.0, "cf8"])
@pytest.mark.parametrize("ratio", [0.0, 0.02])
def test_plane_strain_plate_yield_onset_and_hardening(reduction, ratio: float):
    """sigma_yy = 0, eps_zz = 0: sigma_zz = nu sigma_xx, yield at sigma_xx = fy / sqrt(1-nu+nu^2);
    with the thesis' CF-8 reduction (11.1 % for nu = 0.3) at sigma_xx = fy. Then q = kappa and
    sigma_xx rises; without hardening, under large plastic flow sigma_zz -> sigma_xx / 2 and
    sigma_xx -> 2 fy / sqrt(3) (plastic incompressibility, s_zz -> 0)."""
    cut = plane_strain_fy_reduction(NU) if reduction == "cf8" else 0.0
    p = params("plane_strain", fy_reduction=cut, hardening_ratio=ratio)
    s_onset = p.fy / np.sqrt(1 - NU + NU * NU)
    e_onset = s_onset * (1 - NU * NU) / E
    (_, s0, st0), (_, s1, st1) = mixed_path(p, 0, [1], [e_onset, e_onset * (1 + 1e-6)])
    assert s0[0] == pytest.approx(s_onset, rel=1e-12) and s0[2] == pytest.approx(NU * s0[0])
    assert not st0.yielded[0] and st1.yielded[0]
    if reduction == "cf8":
        assert cut == pytest.approx(0.111, abs=5e-4) and s_onset == pytest.approx(FY, rel=1e-12)
    res = mixed_path(p, 0, [1], np.linspace(e_onset, 200 * e_onset, 400))
    sxx = np.array([s[0] for _, s, _ in res])
    assert np.all(np.diff(sxx) > 0) if ratio else np.all(np.diff(sxx) > -1e-9)
    _, s, state = res[-1]
    assert von_mises_stress(s) == pytest.approx(yield_stress(state, p)[0], rel=1e-10)
    if ratio == 0.0:
        assert s[2] / s[0] == pytest.approx(0.5, abs=1e-6)
        assert s[0] == pytest.approx(2 * p.fy / np.sqrt(3), rel=1e-6)


@pytest.mark.parametrize("formulation", FORMULATIONS)
def test_pure_shear(formulation: str):
    p = params(formulation)
    H, gy = p.hardening_modulus, FY / (np.sqrt(3) * G)
    state = SteelState.initial(1)
    for f in (0.9, 1.0, 1.5, 10.0):
        stress, _, state = update_steel(np.array([[0, 0, 0, f * gy]]), state, p)
        eps_bar = max(0.0, (np.sqrt(3) * G * f * gy - FY) / (3 * G + H))
        tau = min(G * f * gy, (FY + H * eps_bar) / np.sqrt(3))
        np.testing.assert_allclose(stress[0], [0, 0, 0, tau], rtol=1e-12, atol=1e-10)
        assert state.equivalent_plastic_strain[0] == pytest.approx(eps_bar, abs=1e-15)
    assert stress[0, 3] > FY / np.sqrt(3)  # hardened


def _random_states(p, rng, n: int, plastic: bool):
    """(trial strain, committed state): plastic = a random plastic step from a random plastic
    state; elastic = small strains (<= ~0.2 eps_y) of virgin steel."""
    ey = FY / E
    if not plastic:
        return rng.normal(size=(n, 4)) * 0.05 * ey, SteelState.initial(n)
    e0 = rng.normal(size=(n, 4)) * 3 * ey
    _, _, state = update_steel(e0, SteelState.initial(n), p)
    return 2 * e0 + rng.normal(size=(n, 4)) * ey, state


@pytest.mark.parametrize("plastic", [False, True])
@pytest.mark.parametrize("formulation", FORMULATIONS)
def test_consistent_tangent_matches_finite_differences(formulation: str, plastic: bool):
    p = params(formulation)
    e, state = _random_states(p, np.random.default_rng(7), 40, plastic)
    stress, C, trial = update_steel(e, state, p)
    assert np.all(trial.yielded == plastic)
    h = 1e-7
    C_fd = np.zeros_like(C)
    for j in range(4):
        d = np.zeros(4)
        d[j] = h
        plus, minus = update_steel(e + d, state, p)[0], update_steel(e - d, state, p)[0]
        C_fd[:, :, j] = (plus - minus) / (2 * h)
    # measured max |C - C_fd| / E: 1e-13 elastic, 5e-11 (3D) and 1e-9 (plane stress) plastic;
    # h = 1e-7 ~ 7e-4 eps_y. A wrong plastic tangent errs by O(G) (the hardening is 0.02 E).
    np.testing.assert_allclose(C, C_fd, atol=1e-7 * E)
    if formulation == "plane_stress":
        assert np.all(C[:, 2, :] == 0) and np.all(C[:, :, 2] == 0) and np.all(stress[:, 2] == 0)
    else:
        np.testing.assert_allclose(C, np.swapaxes(C, 1, 2), atol=1e-9 * E)  # symmetric


def test_zero_increment_returns_same_state():
    for formulation in FORMULATIONS:
        p = params(formulation)
        e, state = _random_states(p, np.random.default_rng(3), 30, True)
        s1, _, committed = update_steel(e, state, p)
        s2, _, again = update_steel(committed.strain, committed, p)
        np.testing.assert_allclose(s2, s1, rtol=1e-13, atol=1e-13 * FY)  # D (eps - eps_p)
        for name in ("plastic_strain", "equivalent_plastic_strain", "yielded"):  # history: exact
            np.testing.assert_array_equal(getattr(again, name), getattr(committed, name))
        for name in ("strain", "out_of_plane_strain"):  # plane stress eps_zz from the stress
            np.testing.assert_allclose(getattr(again, name), getattr(committed, name),
                                       rtol=1e-14, atol=1e-18)


def test_return_mapping_only_on_yielded_points(monkeypatch):
    calls = []
    real = steel._return_3d
    monkeypatch.setattr(steel, "_return_3d", lambda s, k, p: calls.append(len(s)) or real(s, k, p))
    p = params("plane_strain")
    e = np.zeros((100, 4))
    e[:7, 0] = 10 * FY / E  # 7 of 100 points yield
    update_steel(e, SteelState.initial(100), p)
    update_steel(e * 0.1, SteelState.initial(100), p)  # all elastic: no call
    assert calls == [7]


def test_parameters_and_fy_reduction():
    p = steel_parameters(E, NU, 355.0, fy_reduction=0.111)
    assert p.fy == pytest.approx(355.0 * 0.889) and p.hardening_modulus == pytest.approx(0.02 * E)
    assert p.formulation == "plane_strain"
    for bad in (dict(fy_reduction=1.0), dict(formulation="3d"), dict(hardening_ratio=-0.1)):
        with pytest.raises(ValueError):
            steel_parameters(E, NU, 355.0, **bad)
    with pytest.raises(ValueError):
        update_steel(np.zeros((3, 3)), SteelState.initial(3), p)


strain_paths = st.lists(st.lists(st.floats(-50, 50), min_size=4, max_size=4), min_size=1,
                        max_size=6)


@settings(max_examples=150, deadline=None)
@given(path=strain_paths, formulation=st.sampled_from(FORMULATIONS),
       ratio=st.sampled_from([0.0, 0.02, 0.5]))
def test_stress_never_outside_the_yield_surface(path, formulation, ratio):
    """Random strain paths (units of fy / E, up to 50 eps_y per component): the von Mises stress
    never exceeds the current yield stress, all outputs finite, committed states untouched."""
    p = params(formulation, hardening_ratio=ratio)
    state = SteelState.initial(1)
    for increment in path:
        strain = np.array([increment]) * FY / E
        before = [getattr(state, f.name).copy() for f in dataclasses.fields(state)]
        stress, C, trial = update_steel(strain, state, p)
        for f, old in zip(dataclasses.fields(state), before, strict=True):
            np.testing.assert_array_equal(getattr(state, f.name), old)
        assert np.all(np.isfinite(stress)) and np.all(np.isfinite(C))
        assert von_mises_stress(stress)[0] <= yield_stress(trial, p)[0] * (1 + 1e-9)
        assert trial.equivalent_plastic_strain[0] >= state.equivalent_plastic_strain[0]
        assert abs(trial.plastic_strain[0, :3].sum()) <= 1e-12 * (1 + abs(strain).max())
        state = trial


@pytest.mark.parametrize("formulation", FORMULATIONS)
def test_huge_strains_stay_finite(formulation: str):
    for ratio in (0.0, 0.02):
        p = params(formulation, hardening_ratio=ratio)
        e = np.random.default_rng(1).normal(size=(50, 4)) * 1e3
        stress, C, trial = update_steel(e, SteelState.initial(50), p)
        assert np.all(np.isfinite(stress)) and np.all(np.isfinite(C))
        assert np.all(von_mises_stress(stress) <= yield_stress(trial, p) * (1 + 1e-9))
