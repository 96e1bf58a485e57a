"""Consistent tangent of the rotating-crack concrete update (concrete_tangent, issue 19).

Every check is against central differences of `update_concrete` itself in GLOBAL components,
at single points on each branch of Fig. 3.12; each case first asserts that the point really is
on that branch.
"""

from __future__ import annotations

import dataclasses
from functools import partial

import numpy as np
import pytest

from icewall.formulations import FORMULATIONS
from icewall.materials.concrete import update_concrete
from icewall.materials.concrete_state import ConcreteState
from icewall.materials.concrete_tangent import consistent_tangent, update_with_tangent
from icewall.materials.orthotropic import local_normal_components
from icewall.materials.parameters import derive_concrete_parameters
from icewall.materials.substep import update_concrete_substepped
from icewall.materials.ultimate_surface import strength_scale, strength_scale_gradient

PARAMS = derive_concrete_parameters(53.5, 50.0)
ET = PARAMS.ft / PARAMS.E0  # cracking strain
EC = PARAMS.eps_c
TRIALS = ("corotational", "incremental")

# committed strain path (each row committed in turn), then the strain the tangent is taken at
CASES: dict[str, list[list[float]]] = {
    "uncracked elastic": [[0.3 * ET, -0.2 * ET, 0.0, 0.1 * ET]],
    "tension before peak": [[0.3 * ET, 0.0, 0.0, 0.0], [0.6 * ET, 0.05 * ET, 0.0, 0.03 * ET]],
    "tension after peak": [[0.6 * ET, 0.0, 0.0, 0.0], [1.6 * ET, 0.1 * ET, 0.0, 0.1 * ET]],
    "softening": [[ET, 0.0, 0.0, 0.0], [3 * ET, 0.0, 0.0, 0.0], [4 * ET, 0.2 * ET, 0.0, 0.3 * ET]],
    "unloading cracked": [[ET, 0.0, 0.0, 0.0], [5 * ET, 0.0, 0.0, 0.0],
                          [3 * ET, 0.1 * ET, 0.0, 0.2 * ET]],
    "reloading cracked": [[ET, 0.0, 0.0, 0.0], [5 * ET, 0.0, 0.0, 0.0], [2 * ET, 0.0, 0.0, 0.0],
                          [6 * ET, 0.1 * ET, 0.0, 0.2 * ET]],
    "compression loading": [[-0.15 * EC, 0.0, 0.0, 0.0], [-0.6 * EC, 0.08 * EC, 0.0, 0.04 * EC]],
    "crushing": [[-0.5 * EC, 0.15 * EC, 0.0, 0.0], [-1.3 * EC, 0.4 * EC, 0.0, 0.0],
                 [-1.6 * EC, 0.5 * EC, 0.0, 0.1 * EC]],
    "biaxial compression": [[-0.2 * EC, -0.16 * EC, 0.0, 0.0],
                            [-0.6 * EC, -0.48 * EC, 0.0, 0.04 * EC]],
    "rotating axes, cracked": [[5 * ET, -ET, 0.0, 0.0], [4 * ET, -ET, 0.0, 4 * ET]],
    "equal principal strains": [[-0.2 * EC, -0.2 * EC, 0.0, 0.0], [-0.4 * EC, -0.4 * EC, 0.0, 0.0]],
    "nearly equal principal strains": [[-0.2 * EC, -0.2 * EC, 0.0, 0.0],
                                       [-0.4 * EC, -0.4 * EC * (1.0 - 1e-7), 0.0, 0.0]],
}


def _case(name: str, formulation: str, trial_stress: str
          ) -> tuple[np.ndarray, ConcreteState, ConcreteState]:
    """(strain (1, 4), committed state, trial state at strain) of a CASES path."""
    rows = [list(row) for row in CASES[name]]
    if formulation == "axisymmetric":  # a hoop strain as well
        for row in rows:
            row[2] = 0.2 * row[1]
    state = ConcreteState.initial(1, PARAMS)
    for row in rows[:-1]:
        _, _, state = update_concrete(np.array([row]), state, PARAMS, formulation, trial_stress)
    strain = np.array([rows[-1]])
    _, _, trial = update_concrete(strain, state, PARAMS, formulation, trial_stress)
    return strain, state, trial


def _differences(update, strain: np.ndarray, state: ConcreteState, formulation: str,
                 direction: np.ndarray, h: float) -> np.ndarray:
    plus = update(strain + h * direction, state, PARAMS, formulation)[0]
    minus = update(strain - h * direction, state, PARAMS, formulation)[0]
    return (plus - minus)[0] / (2.0 * h)


def _directions(formulation: str, size: float, count: int = 5) -> np.ndarray:
    """Random strain directions (count, 4) of magnitude ~size (zz only where it is an input)."""
    directions = np.random.default_rng(7).normal(size=(count, 4)) * size
    if formulation != "axisymmetric":
        directions[:, 2] = 0.0
    return directions


def _branch_holds(name: str, state: ConcreteState, trial: ConcreteState, strain: np.ndarray,
                  formulation: str) -> None:
    """The case is on the branch its name says (so that the comparison means something)."""
    loads = trial.max_equivalent_uniaxial_strain[0] > state.max_equivalent_uniaxial_strain[0]
    principal = local_normal_components(trial.strain, trial.angle, 1.0)[0]
    checks = {
        "uncracked elastic": not trial.cracked.any() and np.all(
            trial.secant_modulus == PARAMS.E0),
        "tension before peak": not trial.cracked.any() and loads[0],
        "tension after peak": trial.cracked[0, 0] and not state.cracked[0, 0] and loads[0],
        "softening": state.cracked[0, 0] and loads[0],
        "unloading cracked": (state.cracked[0, 0] and not loads[0]
                              and trial.equivalent_uniaxial_strain[0, 0] > 0),
        "reloading cracked": (state.max_equivalent_uniaxial_strain[0, 0]
                              > state.equivalent_uniaxial_strain[0, 0] > 0 and loads[0]
                              and trial.secant_modulus[0, 0] < state.secant_modulus[0, 0]),
        "compression loading": (not trial.crushed.any() and loads[0]
                                and trial.secant_modulus[0, 0] < PARAMS.E0),
        "crushing": state.crushed[0, 0] and loads[0],
        "biaxial compression": (loads[:2].all()
                                and np.all(trial.uniaxial_strength[0, :2] < -1.05 * PARAMS.fc)),
        "rotating axes, cracked": state.cracked.any() and abs(trial.angle[0]
                                                              - state.angle[0]) > 0.3,
        "equal principal strains": principal[0] == principal[1],
        "nearly equal principal strains": 0 < abs(principal[0] - principal[1])
        < 1e-6 * abs(principal[0]),
    }
    assert checks[name], f"{name} ({formulation}) is not on its branch"


METHODS = [("corotational", "analytic"), ("corotational", "differences"), ("total", "analytic"),
           ("incremental", "differences")]


@pytest.mark.parametrize(("trial_stress", "method"), METHODS)
@pytest.mark.parametrize("formulation", FORMULATIONS)
@pytest.mark.parametrize("name", list(CASES))
def test_tangent_matches_central_differences_on_every_branch(name, formulation, trial_stress,
                                                             method):
    strain, state, trial = _case(name, formulation, trial_stress)
    _branch_holds(name, state, trial, strain, formulation)
    tangent = consistent_tangent(strain, state, PARAMS, formulation, trial_stress,
                                 method=method)[0]
    update = partial(update_concrete, trial_stress=trial_stress, with_moduli=False)
    for direction in _directions(formulation, float(np.abs(strain).max())):
        expected = _differences(update, strain, state, formulation, direction, 1e-7)
        scale = np.abs(expected).max()
        assert np.abs(tangent @ direction - expected).max() <= 1e-6 * scale, (
            name, formulation, trial_stress, tangent @ direction, expected)


def test_returns_the_stress_and_trial_state_of_the_update():
    strain, state, _ = _case("rotating axes, cracked", "plane_strain", "corotational")
    stress, _, trial = update_concrete(strain, state, PARAMS, "plane_strain", "corotational")
    same_stress, _, same_trial = update_with_tangent(strain, state, PARAMS, "plane_strain")
    np.testing.assert_array_equal(same_stress, stress)
    np.testing.assert_array_equal(same_trial.secant_modulus, trial.secant_modulus)


def test_formulation_zeros():
    """plane strain: eps_zz no input (zz column 0); plane stress: sigma_zz condensed (zz row and
    column 0); axisymmetric: the hoop column is live."""
    tangents = {}
    for formulation in FORMULATIONS:
        strain, state, _ = _case("softening", formulation, "corotational")
        tangents[formulation] = consistent_tangent(strain, state, PARAMS, formulation)[0]
    assert np.all(tangents["plane_strain"][:, 2] == 0.0)
    assert np.abs(tangents["plane_strain"][2]).max() > 0.0  # sigma_zz reacts
    assert np.all(tangents["plane_stress"][2] == 0.0)
    assert np.all(tangents["plane_stress"][:, 2] == 0.0)
    assert np.abs(tangents["axisymmetric"][:, 2]).max() > 0.0


@pytest.mark.parametrize("name", ["compression loading", "biaxial compression"])
def test_tangent_is_not_symmetrised(name):
    """The rotating-crack tangent is unsymmetric in general: on a nonlinear compressive branch
    d s_i / d e_j = (d s_i / d trial_i) C_ij differs from d s_j / d e_i (Poisson coupling), and
    the strength surface couples the directions on the ray of the trial stress."""
    strain, state, _ = _case(name, "plane_strain", "corotational")
    tangent = consistent_tangent(strain, state, PARAMS, "plane_strain")[0]
    in_plane = tangent[np.ix_([0, 1, 3], [0, 1, 3])]
    assert np.abs(in_plane - in_plane.T).max() > 1e-3 * np.abs(in_plane).max()


def test_softening_tangent_is_indefinite():
    strain, state, _ = _case("softening", "plane_strain", "corotational")
    tangent = consistent_tangent(strain, state, PARAMS, "plane_strain")[0]
    in_plane = tangent[np.ix_([0, 1, 3], [0, 1, 3])]
    assert np.linalg.eigvalsh(0.5 * (in_plane + in_plane.T)).min() < 0.0


def test_equal_principal_strains_take_the_isotropic_shear_limit():
    """At a virgin point e_1 = e_2 = 0: the tangent is Hooke's (G = E / (2 (1 + nu))), not 0/0."""
    state = ConcreteState.initial(1, PARAMS)
    tangent = consistent_tangent(np.zeros((1, 4)), state, PARAMS, "plane_strain")[0]
    assert np.all(np.isfinite(tangent))
    assert tangent[3, 3] == pytest.approx(PARAMS.E0 / (2.0 * (1.0 + PARAMS.nu0)), rel=1e-8)
    _, secant, _ = update_concrete(np.zeros((1, 4)), state, PARAMS, "plane_strain")
    live = [0, 1, 3]  # the secant matrix also has a zz column; eps_zz = 0 is imposed here
    np.testing.assert_allclose(tangent[:, live], secant[0][:, live], rtol=1e-7,
                               atol=1e-7 * PARAMS.E0)


def test_batched_points_equal_single_points():
    """One batched call over many points gives each point's own tangent (per-point k_t, k_c)."""
    strains, states = [], []
    for name in CASES:
        strain, state, _ = _case(name, "plane_strain", "corotational")
        strains.append(strain)
        states.append(state)
    strain = np.concatenate(strains)
    state = ConcreteState(**{f: np.concatenate([getattr(s, f) for s in states])
                             for f in ConcreteState.__dataclass_fields__})
    batched = consistent_tangent(strain, state, PARAMS, "plane_strain")
    for k, (one, committed) in enumerate(zip(strains, states, strict=True)):
        np.testing.assert_allclose(batched[k], consistent_tangent(one, committed, PARAMS,
                                                                  "plane_strain")[0],
                                   rtol=1e-12, atol=1e-9)


def test_tangent_of_the_substepped_incremental_update():
    """With `update` the sub-stepped update the solver calls (incremental trial, a large
    increment split into many sub-steps), the tangent is that map's derivative."""
    strain, state, _ = _case("rotating axes, cracked", "plane_strain", "incremental")
    # 13.3 sub-steps (the update jumps where the count does, at whole numbers)
    update = partial(update_concrete_substepped, max_strain_step=0.3 * ET)
    tangent = consistent_tangent(strain, state, PARAMS, "plane_strain", "incremental",
                                 update=update)[0]
    single = consistent_tangent(strain, state, PARAMS, "plane_strain", "incremental")[0]
    assert np.abs(tangent - single).max() > 1e-3 * np.abs(single).max()  # sub-steps matter
    call = partial(update, trial_stress="incremental", with_moduli=False)
    for direction in _directions("plane_strain", float(np.abs(strain).max()), 3):
        expected = _differences(call, strain, state, "plane_strain", direction, 1e-7)
        assert np.abs(tangent @ direction - expected).max() <= 1e-6 * np.abs(expected).max()


def random_damaged_points(params, formulation: str, n: int, rng: np.random.Generator
                          ) -> tuple[ConcreteState, np.ndarray]:
    """(committed state, next strain) of n points driven along random proportional paths that
    turn at 60 % (cracked, crushed, closing and rotating points), corotational trial."""
    state = ConcreteState.initial(n, params)
    base = rng.normal(size=(n, 4)) * rng.choice([3e-4, 1e-3, 3e-3], size=(n, 1))
    turn = rng.normal(size=(n, 4)) * 3e-4
    if formulation != "axisymmetric":
        base[:, 2] = turn[:, 2] = 0.0
    for t in np.linspace(0.1, 1.0, 8):
        _, _, state = update_concrete(t * base + (t > 0.6) * t * turn, state, params,
                                      formulation, "corotational")
    return state, 1.05 * base + turn


def test_analytic_and_differenced_principal_moduli_agree_on_random_states():
    """Over many random damaged points (cracked, crushed, closing, rotating; both §3.2.5 rule-b
    readings) the analytic tangent equals the differenced one except at the few points whose
    loading test flips within the difference step (a kink: the analytic one keeps the branch
    the update took)."""
    rng = np.random.default_rng(5)
    n = 600
    for rule in ("equal", "floor"):
        params = derive_concrete_parameters(53.5, 50.0, compression_tension_rule=rule)
        for formulation in FORMULATIONS:
            state, strain = random_damaged_points(params, formulation, n, rng)
            analytic = consistent_tangent(strain, state, params, formulation, method="analytic")
            differenced = consistent_tangent(strain, state, params, formulation,
                                             method="differences")
            error = (np.abs(analytic - differenced).max(axis=(1, 2))
                     / np.abs(differenced).max(axis=(1, 2)))
            assert state.cracked.any(axis=1).mean() > 0.5 and state.crushed.any()
            assert np.sum(error > 1e-6) <= 0.005 * n, (rule, formulation, np.sort(error)[-5:])


def test_zero_increment_takes_the_unloading_branch():
    """At the committed strain the update unloads (a zero increment returns the committed
    stress); the analytic tangent is that branch's: the one-sided difference into unloading."""
    strain, state, _ = _case("softening", "plane_strain", "corotational")
    _, _, committed = update_concrete(strain, state, PARAMS, "plane_strain", "corotational")
    tangent = consistent_tangent(strain, committed, PARAMS, "plane_strain")[0]
    update = partial(update_concrete, trial_stress="corotational", with_moduli=False)
    back = -np.array([1.0, 0.1, 0.0, 0.05]) * np.abs(strain).max()  # closing the crack
    h = 1e-7
    base = update(strain, committed, PARAMS, "plane_strain")[0]
    one_sided = (update(strain + h * back, committed, PARAMS, "plane_strain")[0] - base)[0] / h
    np.testing.assert_allclose(tangent @ back, one_sided, rtol=1e-5,
                               atol=1e-6 * np.abs(one_sided).max())
    forward = (update(strain - h * back, committed, PARAMS, "plane_strain")[0] - base)[0] / h
    assert np.abs(tangent @ back + forward).max() > 0.1 * np.abs(forward).max()  # a kink


def test_strength_scale_gradient_matches_differences():
    """d s / d sigma of the strength surface scale (implicit differentiation of eq. 3.15)."""
    rng = np.random.default_rng(11)
    principal = rng.normal(size=(400, 3)) * 30.0
    principal[:5] = [[-50.0, -40.0, -10.0], [-50.0, -50.0, -10.0], [3.0, 1.0, -20.0],
                     [-120.0, -100.0, -90.0], [-50.0, -50.01, -50.02]]
    scale, capped = strength_scale(principal, PARAMS.fc, PARAMS.surface, return_capped=True)
    assert capped[4] and not capped[:4].any()  # near-hydrostatic: the ray misses the surface
    gradient = strength_scale_gradient(principal, scale, PARAMS.fc, PARAMS.surface, capped)
    step = 1e-6 * np.abs(principal).max(axis=1)
    expected = np.empty_like(principal)
    for k in range(3):
        shift = np.zeros_like(principal)
        shift[:, k] = step
        expected[:, k] = (strength_scale(principal + shift, PARAMS.fc, PARAMS.surface)
                          - strength_scale(principal - shift, PARAMS.fc, PARAMS.surface)
                          ) / (2.0 * step)
    error = np.abs(gradient - expected).max(axis=1) / np.abs(expected).max(axis=1)
    assert error.max() < 1e-6


def test_near_hydrostatic_compression_on_the_capped_ray():
    """Axisymmetric near-hydrostatic compression: the ray of the trial stress misses the open
    surface and sigma_ic is the cap (100 f'c on the ray); the tangent follows that too."""
    strain = np.array([[-1e-3, -1.0001e-3, -1.0002e-3, 0.0]])
    _, _, state = update_concrete(0.5 * strain, ConcreteState.initial(1, PARAMS), PARAMS,
                                  "axisymmetric", "corotational")
    _, _, trial = update_concrete(strain, state, PARAMS, "axisymmetric", "corotational")
    assert np.abs(trial.uniaxial_strength).max() == pytest.approx(100.0 * PARAMS.fc)
    tangent = consistent_tangent(strain, state, PARAMS, "axisymmetric")[0]
    update = partial(update_concrete, trial_stress="corotational", with_moduli=False)
    for direction in _directions("axisymmetric", 1e-3, 3):
        expected = _differences(update, strain, state, "axisymmetric", direction, 1e-7)
        assert np.abs(tangent @ direction - expected).max() <= 1e-6 * np.abs(expected).max()


BANDED = derive_concrete_parameters(53.5, 50.0, compression_tension_rule="floor",
                                    mode_rule_band=0.5)


@pytest.mark.parametrize("stress", [[0.3, -10.0, -4.0], [1.0, -0.4, 0.6], [-0.2, 0.9, -30.0],
                                    [0.5, -45.0, -80.0]])
def test_blended_strengths_slope_matches_differences(stress):
    """d sigma_ic / d trial with the mode rules blended over a band (0.5 f't): states inside
    it (a tension or compression below 1.2 MPa against components of the other sign)."""
    from icewall.materials.concrete_tangent import _strength_jacobian
    from icewall.materials.mode_rules import equivalent_uniaxial_strengths

    trial = np.array([stress])
    loading = np.ones((1, 3), dtype=bool)
    slope = _strength_jacobian(trial, equivalent_uniaxial_strengths(trial, BANDED), loading,
                               BANDED)[0]
    h = 1e-6
    for j in range(3):
        step = h * np.eye(3)[j]
        expected = (equivalent_uniaxial_strengths(trial + step, BANDED)
                    - equivalent_uniaxial_strengths(trial - step, BANDED))[0] / (2.0 * h)
        np.testing.assert_allclose(slope[:, j], expected, rtol=1e-6, atol=1e-6)


@pytest.mark.parametrize("rule", ["equal", "floor"])
@pytest.mark.parametrize("formulation", ["plane_strain", "axisymmetric"])
def test_tangent_matches_differences_inside_the_mode_rule_band(formulation, rule):
    """A compressed point whose lateral principal stress is a small tension, inside the band
    of rule (b): the whole consistent tangent against central differences of the update."""
    params = dataclasses.replace(BANDED, compression_tension_rule=rule)
    band = params.mode_rule_band * params.ft

    def lateral_stress(a: float) -> tuple[float, np.ndarray, ConcreteState]:
        strain = np.array([[-0.6 * EC, a, 0.0, 0.0]])
        if formulation == "axisymmetric":
            strain[0, 2] = -0.1 * EC
        state = ConcreteState.initial(1, params)
        _, _, state = update_concrete(0.3 * strain, state, params, formulation)
        stress = update_concrete(strain, state, params, formulation, with_moduli=False)[0]
        return float(np.sort(stress[0, :3])[-1]), strain, state

    low, high = 0.0, 0.6 * EC  # lateral stress rises with the lateral strain: bisect to band/2
    for _ in range(60):
        mid = 0.5 * (low + high)
        low, high = (mid, high) if lateral_stress(mid)[0] < 0.5 * band else (low, mid)
    largest, strain, state = lateral_stress(0.5 * (low + high))
    assert 0.2 * band < largest < 0.8 * band
    tangent = consistent_tangent(strain, state, params, formulation, "corotational")[0]
    update = partial(update_concrete, trial_stress="corotational", with_moduli=False)
    for direction in _directions(formulation, 1e-3 * float(np.abs(strain).max())):
        plus = update(strain + 1e-4 * direction, state, params, formulation)[0]
        minus = update(strain - 1e-4 * direction, state, params, formulation)[0]
        expected = (plus - minus)[0] / 2e-4
        assert np.abs(tangent @ direction - expected).max() <= 1e-5 * np.abs(expected).max()
