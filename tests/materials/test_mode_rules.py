"""Thesis §3.2.5 rule (b) in compression-tension states: 'equal' (the default) and the errata's
signed 'floor' reading."""

from __future__ import annotations

import dataclasses

import numpy as np

from icewall.materials.parameters import derive_concrete_parameters
from icewall.materials.ultimate_surface import equivalent_uniaxial_strengths

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
