"""Shape functions: partition of unity, Kronecker delta, completeness and derivatives."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from icewall.fem.shape import reference_nodes, shape_derivatives, shape_functions

TYPES = ["quad4", "quad8", "line2", "line3"]
coord = st.floats(-1.0, 1.0, allow_nan=False)


def _random_points(cell_type, n=50, seed=0):
    dim = reference_nodes(cell_type).shape[1]
    return np.random.default_rng(seed).uniform(-1, 1, (n, dim))


@pytest.mark.parametrize("cell_type", TYPES)
def test_partition_of_unity_and_zero_derivative_sum(cell_type):
    xi = _random_points(cell_type)
    np.testing.assert_allclose(shape_functions(cell_type, xi).sum(axis=1), 1.0, atol=1e-14)
    np.testing.assert_allclose(shape_derivatives(cell_type, xi).sum(axis=1), 0.0, atol=1e-14)


@pytest.mark.parametrize("cell_type", TYPES)
def test_kronecker_delta_at_nodes(cell_type):
    nodes = reference_nodes(cell_type)
    np.testing.assert_allclose(shape_functions(cell_type, nodes), np.eye(len(nodes)),
                               atol=1e-15)


@pytest.mark.parametrize("cell_type", TYPES)
def test_derivatives_match_central_differences(cell_type):
    xi = _random_points(cell_type, 20, seed=3) * 0.99
    dN = shape_derivatives(cell_type, xi)
    h = 1e-6
    for k in range(xi.shape[1]):
        step = np.zeros(xi.shape[1])
        step[k] = h
        fd = (shape_functions(cell_type, xi + step) - shape_functions(cell_type, xi - step))
        # central differences of polynomials of degree <= 3: truncation ~h^2, round-off ~1e-10
        np.testing.assert_allclose(dN[..., k], fd / (2 * h), atol=1e-8)


@pytest.mark.parametrize(("cell_type", "monomials"), [
    ("quad4", [(0, 0), (1, 0), (0, 1), (1, 1)]),
    ("quad8", [(0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2), (2, 1), (1, 2)]),
])
def test_interpolation_reproduces_the_element_basis(cell_type, monomials):
    """Serendipity quad8 spans {1, x, y, x^2, xy, y^2, x^2 y, x y^2}; quad4 the bilinears."""
    nodes, xi = reference_nodes(cell_type), _random_points(cell_type)
    N = shape_functions(cell_type, xi)
    for a, b in monomials:
        np.testing.assert_allclose(N @ (nodes[:, 0] ** a * nodes[:, 1] ** b),
                                   xi[:, 0] ** a * xi[:, 1] ** b, atol=1e-14)


@settings(max_examples=50, deadline=None)
@given(r=coord, s=coord)
def test_quad8_partition_of_unity_anywhere(r, s):
    N = shape_functions("quad8", np.array([[r, s]]))
    assert N.sum() == pytest.approx(1.0, abs=1e-13)


def test_line3_order_is_start_end_mid():
    N = shape_functions("line3", np.array([-1.0, 1.0, 0.0]))
    np.testing.assert_allclose(N, np.eye(3), atol=1e-15)


def test_unknown_cell_type_is_rejected():
    with pytest.raises(ValueError, match="unknown cell type"):
        shape_functions("tri3", np.zeros((1, 2)))
