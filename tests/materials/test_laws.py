"""The law objects the solver and the writer call (materials.law), at single Gauss points,
against hand computations."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from icewall.materials.concrete_law import ConcreteLaw
from icewall.materials.concrete_state import ConcreteState
from icewall.materials.elastic import ElasticLaw, elastic_moduli
from icewall.materials.parameters import derive_concrete_parameters
from icewall.materials.steel import SteelLaw, SteelState, steel_parameters

CONCRETE = derive_concrete_parameters(53.5, 100.0)


def _concrete_law(own_moduli: bool = False) -> ConcreteLaw:
    return ConcreteLaw(CONCRETE, "plane_stress", 0.5 * CONCRETE.eps_t, "corotational",
                       0.0, False, own_moduli)


def test_elastic_law_is_hookes_law_without_state():
    # E = 200, nu = 0.25, plane strain: lambda = E nu / ((1 + nu)(1 - 2 nu)) = 80, mu = 80
    law = ElasticLaw(elastic_moduli(200.0, 0.25, "plane_strain"))
    stress, moduli, state = law.update(np.array([[1e-3, 0.0, 0.0, 2e-3]]), None)
    np.testing.assert_allclose(stress, [[0.24, 0.08, 0.08, 0.16]], rtol=1e-12)
    assert moduli.shape == (1, 4, 4) and state is None and law.initial_state(3) is None
    assert law.constant_moduli[0, 0] == pytest.approx(240.0)
    assert not law.freezable and not law.secant_moduli
    assert law.flags(None) is None and law.counts(None) == {} and law.state_fields(None) == {}
    assert law.cracking(None) is None and law.crushed(None) is None
    assert law.yielded(None) is None
    strain = np.ones((1, 4))
    assert law.elastic_strain(strain, None) is strain


@pytest.fixture
def sheared_steel():
    """Pure shear past yield, perfectly plastic: E = 260, nu = 0.3 (G = 100), fy = sqrt(3)
    (shear yield tau_y = fy / sqrt(3) = 1), engineering shear gamma = 0.03 (3 gamma_y)."""
    law = SteelLaw(steel_parameters(260.0, 0.3, np.sqrt(3.0), hardening_ratio=0.0))
    state = law.initial_state(1)
    strain = np.array([[0.0, 0.0, 0.0, 0.03]])
    return law, state, strain, law.update(strain, state)


def test_steel_law_returns_to_the_shear_yield_stress(sheared_steel):
    law, _, _, (stress, moduli, trial) = sheared_steel
    np.testing.assert_allclose(stress, [[0.0, 0.0, 0.0, 1.0]], atol=1e-12)
    # gamma_p = gamma - tau / G = 0.02; eps_bar = sqrt(2/3 eps_p : eps_p) = gamma_p / sqrt(3)
    np.testing.assert_allclose(trial.plastic_strain, [[0.0, 0.0, 0.0, 0.02]], atol=1e-14)
    assert law.flags(trial).tolist() == [[True]] and law.counts(trial) == {"yielded": 1}
    assert law.yielded(trial).tolist() == [True]
    (peeq,) = law.state_fields(trial).values()
    assert peeq.shape == (1, 1) and peeq[0, 0] == pytest.approx(0.02 / np.sqrt(3.0))
    assert moduli[0, 3, 3] == pytest.approx(0.0, abs=1e-12)  # perfectly plastic: d tau / d gamma


def test_steel_law_stores_energy_of_its_elastic_strain_only(sheared_steel):
    """1/2 sigma : (eps - eps_p) = 1/2 tau (gamma - gamma_p) = 1/2 * 1 * 0.01."""
    law, _, strain, (stress, _, trial) = sheared_steel
    elastic = law.elastic_strain(strain, trial)
    np.testing.assert_allclose(elastic, [[0.0, 0.0, 0.0, 0.01]], atol=1e-14)
    assert 0.5 * float(stress[0] @ elastic[0]) == pytest.approx(0.005, rel=1e-12)


def test_steel_law_tangent_of_is_its_moduli(sheared_steel):
    law, state, strain, (stress, moduli, trial) = sheared_steel
    assert not law.freezable and not law.secant_moduli
    np.testing.assert_array_equal(law.tangent_of(strain, stress, trial, state), moduli)
    virgin = SteelState.initial(2)
    assert law.counts(virgin) == {"yielded": 0} and not law.flags(virgin).any()
    assert law.crushed(virgin) is None and law.cracking(virgin) is None


def test_concrete_law_is_isotropic_below_cracking():
    """Uniaxial strain a = 0.3 eps_t in plane stress from the virgin state: sigma_xx =
    E0 a / (1 - nu0^2), sigma_yy = nu0 sigma_xx, and the moduli are those of Hooke's law."""
    law, a = _concrete_law(), 0.3 * CONCRETE.eps_t
    E, nu = CONCRETE.E0, CONCRETE.nu0
    stress, moduli, trial = law.update(np.array([[a, 0.0, 0.0, 0.0]]), law.initial_state(1))
    c = E / (1.0 - nu * nu)
    np.testing.assert_allclose(stress, [[c * a, nu * c * a, 0.0, 0.0]], rtol=1e-10, atol=1e-12)
    hooke = np.array([[c, nu * c, 0, 0], [nu * c, c, 0, 0], [0, 0, 0, 0],
                      [0, 0, 0, E / (2 * (1 + nu))]])
    np.testing.assert_allclose(moduli[0], hooke, rtol=1e-10, atol=1e-9 * E)
    assert law.counts(trial) == {"cracked_in_plane": 0, "cracked_out_of_plane": 0, "crushed": 0}
    for own in (False, True):  # the floored moduli with floor 0 are the secant ones
        np.testing.assert_allclose(_concrete_law(own).update(
            np.array([[a, 0.0, 0.0, 0.0]]), law.initial_state(1))[1][0], hooke,
            rtol=1e-10, atol=1e-9 * E)


def _damaged(n: int = 2) -> ConcreteState:
    """Point 0 cracked normal to 1 and crushed along 3, at beta = 0.3 rad; point 1 virgin."""
    state = ConcreteState.initial(n, CONCRETE)
    cracked, crushed, angle = state.cracked.copy(), state.crushed.copy(), state.angle.copy()
    cracked[0, 0], crushed[0, 2], angle[0] = True, True, 0.3
    return replace(state, cracked=cracked, crushed=crushed, angle=angle)


def test_concrete_law_flags_counts_and_fields():
    law, state = _concrete_law(), _damaged()
    flags = law.flags(state)
    assert flags.shape == (2, 10)
    # cracked 1-3, crushed 1-3, no loading past a peak (no strain), labelling 1 >= 2 (0 >= 0)
    assert flags[0].tolist() == [True, False, False, False, False, True, False, False, False, True]
    assert flags[1].tolist() == [False] * 9 + [True]
    assert law.counts(state) == {"cracked_in_plane": 1, "cracked_out_of_plane": 0, "crushed": 1}
    fields = law.state_fields(state)
    assert fields["concrete_flags"].dtype == np.int8
    assert fields["concrete_flags"].tolist() == [[1, 0, 0, 0, 0, 1], [0] * 6]
    assert fields["orthotropy_angle"].tolist() == [[0.3], [0.0]]
    assert law.crushed(state).tolist() == [True, False] and law.yielded(state) is None
    eps_t, cracked = law.cracking(state)
    assert eps_t.tolist() == [CONCRETE.eps_t] * 2 and cracked.tolist() == [True, False]
    strain = np.ones((2, 4))
    assert law.elastic_strain(strain, state) is strain  # secant unloading to the origin


def test_concrete_law_freezes_but_has_no_tangent_at_frozen_points():
    law = _concrete_law()
    assert law.freezable and law.secant_moduli
    with pytest.raises(ValueError, match="frozen"):
        law.update(np.zeros((1, 4)), law.initial_state(1), frozen=np.ones(1, bool),
                   tangent=True)


def test_a_law_without_an_update_cannot_be_made():
    """`update` is the one method every law must give (MaterialLaw is abstract)."""
    from icewall.materials.law import MaterialLaw

    with pytest.raises(TypeError, match="update"):
        MaterialLaw()
