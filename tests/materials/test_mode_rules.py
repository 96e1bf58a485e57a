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
