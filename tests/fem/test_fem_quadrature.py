"""Gauss-Legendre rules: exact to degree 2n - 1 per variable and not beyond."""

from __future__ import annotations

import numpy as np
import pytest

from icewall.fem.quadrature import gauss_rule, line_rule


def _exact_1d(a: int) -> float:
    """int_{-1}^{1} x^a dx."""
    return 0.0 if a % 2 else 2.0 / (a + 1)


@pytest.mark.parametrize("n", [1, 2, 3, 4, 5])
def test_line_rule_exact_to_degree_2n_minus_1(n):
    rule = line_rule(n)
    assert rule.points.shape == (n, 1) and rule.weights.shape == (n,)
    x = rule.points[:, 0]
    for a in range(2 * n):
        assert rule.weights @ x**a == pytest.approx(_exact_1d(a), abs=1e-14)
    # degree 2n is not integrated exactly: the rule is not over-claimed
    assert abs(rule.weights @ x ** (2 * n) - _exact_1d(2 * n)) > 1e-3


@pytest.mark.parametrize("n", [1, 2, 3, 4])
def test_tensor_rule_exact_to_degree_2n_minus_1_per_variable(n):
    rule = gauss_rule(n)
    assert rule.points.shape == (n * n, 2) and rule.n_points == n * n
    x, y = rule.points.T
    for a in range(2 * n):
        for b in range(2 * n):
            exact = _exact_1d(a) * _exact_1d(b)  # reference: product of 1D integrals
            assert rule.weights @ (x**a * y**b) == pytest.approx(exact, abs=1e-14)
    for a, b in [(2 * n, 0), (0, 2 * n), (2 * n, 2 * n - 2)]:
        assert abs(rule.weights @ (x**a * y**b) - _exact_1d(a) * _exact_1d(b)) > 1e-3


def test_rules_are_frozen_and_validated():
    rule = gauss_rule(2)
    with pytest.raises(AttributeError):
        rule.points = np.zeros((1, 2))
    with pytest.raises(ValueError):
        gauss_rule(0)
