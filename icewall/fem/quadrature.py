"""Gauss-Legendre quadrature on [-1, 1] (edges) and its tensor rule on [-1, 1]^2 (quads)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Quadrature:
    """Integration points in the reference domain and their weights."""

    points: np.ndarray  # (nq, dim) reference coordinates
    weights: np.ndarray  # (nq,)

    @property
    def n_points(self) -> int:
        return int(self.weights.shape[0])


def gauss_legendre(n: int) -> tuple[np.ndarray, np.ndarray]:
    """1D n-point Gauss-Legendre abscissae and weights on [-1, 1] (exact to degree 2n - 1)."""
    if n < 1:
        raise ValueError(f"number of Gauss points must be >= 1, got {n}")
    xi, w = np.polynomial.legendre.leggauss(n)
    return xi, w


def line_rule(n: int) -> Quadrature:
    """n-point Gauss rule on the reference edge [-1, 1]; points shaped (n, 1)."""
    xi, w = gauss_legendre(n)
    return Quadrature(points=xi[:, None], weights=w)


def gauss_rule(n: int) -> Quadrature:
    """n x n tensor Gauss rule on [-1, 1]^2; point index q = i * n + j (xi_i, eta_j)."""
    xi, w = gauss_legendre(n)
    xx, yy = np.meshgrid(xi, xi, indexing="ij")
    points = np.column_stack([xx.ravel(), yy.ravel()])
    weights = np.outer(w, w).ravel()
    return Quadrature(points=points, weights=weights)
