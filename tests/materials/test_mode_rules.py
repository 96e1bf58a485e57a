"""Thesis §3.2.5 rule (b) in compression-tension states: 'equal' (the default) and the errata's
signed 'floor' reading."""

from __future__ import annotations

import dataclasses

import numpy as np

from icewall.materials.mode_rules import equivalent_uniaxial_strengths
from icewall.materials.parameters import derive_concrete_parameters
from icewall.materials.ultimate_surface import strength_scale

FLOOR = derive_concrete_parameters(53.5, 25.0, compression_tension_rule="floor")
EQUAL = dataclasses.replace(FLOOR, compression_tension_rule="equal")


def test_equal_reading_gives_the_uniaxial_compressive_parameters():
    # cracked tension in 1, compression in 2, out-of-plane (plane strain) confinement in 3:
    # the surface's ray gives a confined compressive strength beyond f'c
    state = np.array([[0.5, -60.0, -25.0]])
    floor = equivalent_uniaxial_strengths(state, FLOOR)
    equal = equivalent_uniaxial_strengths(state, EQUAL)
    assert floor[0, 1] < -53.5 * 1.05  # confinement kept under the floor reading
    assert np.allclose(equal[0, 1:], -53.5)  # "set equal to the uniaxial strength"
    assert equal[0, 0] == floor[0, 0] > 0  # tension from the surface in both readings


def test_both_readings_raise_a_low_surface_value_to_fc():
    state = np.array([[2.0, -10.0, 0.0]])  # high tension, low compression (the §3.2.5 case)
    for params in (FLOOR, EQUAL):
        assert equivalent_uniaxial_strengths(state, params)[0, 1] == -53.5


def test_triaxial_compression_is_untouched():
    state = np.array([[-5.0, -60.0, -25.0]])
    assert np.allclose(equivalent_uniaxial_strengths(state, FLOOR),
                       equivalent_uniaxial_strengths(state, EQUAL))


def test_where_a_principal_stress_changes_sign_floor_keeps_the_confined_strength():
    """A triaxial compression state whose middle stress crosses zero (as at TF-1's preload,
    element 100: sigma = (-4.4, +-2e-4, -9.1) MPa). The major compression's strength from the
    surface (beyond f'c) is kept across the sign change under 'floor'; under 'equal' it drops
    to f'c, a jump of a third for a stress change of 4e-4 MPa: no equilibrium need exist near
    such a state (the Newton scheme then cycles: docs/solver.md). Both readings raise a
    component whose surface value is below f'c to f'c on the tension side: that jump is rule
    (b) itself."""
    below = np.array([[-4.4, -2e-4, -9.1]])
    above = np.array([[-4.4, +2e-4, -9.1]])
    for params, kept in ((FLOOR, True), (EQUAL, False)):
        a = equivalent_uniaxial_strengths(below, params)[0]
        b = equivalent_uniaxial_strengths(above, params)[0]
        assert a[2] < -1.4 * 53.5  # the confined major compression
        assert (abs(b[2] - a[2]) < 1e-3 * abs(a[2])) == kept
        assert a[0] > -53.5 and b[0] == -53.5  # the minor one, raised to f'c in both


BAND = dataclasses.replace(FLOOR, mode_rule_band=0.1)


def _sweep(params, middle: np.ndarray) -> np.ndarray:
    """The strengths of (-4.4, m, -9.1) MPa (TF-1's preload point) for each middle stress m."""
    states = np.column_stack([np.full_like(middle, -4.4), middle, np.full_like(middle, -9.1)])
    return equivalent_uniaxial_strengths(states, params)


def test_the_band_makes_the_strengths_continuous_where_a_stress_changes_sign():
    """Across the sign change of the middle stress the sharp rules jump (the major compression
    by a third under 'equal', the minor one from its surface value to f'c under both); over a
    band of 0.1 f't the strengths move by at most their own scale times the step over the
    band (the slope of the blend), and by nothing where no stress lies inside it."""
    band = 0.1 * FLOOR.ft
    middle = np.linspace(-0.5, 0.5, 20001)  # steps of 5e-5 MPa, the band 5e3 steps wide
    step = middle[1] - middle[0]
    for params, sharp in ((EQUAL, 2), (FLOOR, 0)):
        jumps = np.abs(np.diff(_sweep(params, middle)[:, [0, 2]], axis=0)).max(axis=0)
        assert jumps[0] > 0.2 * 53.5  # the minor compression: rule (b) itself
        assert jumps[1] > 0.2 * 53.5 if sharp else jumps[1] < 1e-2
    for params in (BAND, dataclasses.replace(EQUAL, mode_rule_band=0.1)):
        strengths = _sweep(params, middle)[:, [0, 2]]
        bound = np.abs(strengths).max(axis=0) * step / band * 1.5 + 1e-2
        assert np.all(np.abs(np.diff(strengths, axis=0)) <= bound)
    outside = np.abs(middle) > 1.001 * band
    np.testing.assert_array_equal(_sweep(BAND, middle)[outside], _sweep(FLOOR, middle)[outside])


def test_the_band_blends_each_rule_by_the_stress_of_the_other_sign():
    band = 0.1 * FLOOR.ft
    equal_band = dataclasses.replace(EQUAL, mode_rule_band=0.1)
    # rule (b) ('equal': f'c): a compressive component, a tension of half the band: half-way
    # from the surface's value to f'c
    state = np.array([[0.5 * band, -10.0, -4.0]])
    ray = strength_scale(state, EQUAL.fc, EQUAL.surface) * state[0]
    assert equivalent_uniaxial_strengths(state, EQUAL)[0, 1] == -53.5 != ray[1]
    np.testing.assert_allclose(equivalent_uniaxial_strengths(state, equal_band)[0, 1],
                               0.5 * ray[1] - 0.5 * 53.5, rtol=1e-12)
    # rule (c): a tensile component, a compression of a quarter of the band: 3/4 of the way
    # from the surface's value to the f't floor
    state = np.array([[0.3, -0.25 * band, 0.2]])
    ray = strength_scale(state, EQUAL.fc, EQUAL.surface) * state[0]
    assert ray[0] < FLOOR.ft
    np.testing.assert_allclose(equivalent_uniaxial_strengths(state, BAND)[0, 0],
                               0.75 * FLOOR.ft + 0.25 * ray[0], rtol=1e-12)
