"""Shared fixtures of the fem unit tests: single reference-shaped elements."""

from __future__ import annotations

import numpy as np
import pytest

from icewall.fem.shape import reference_nodes


def _element(cell_type: str, r0: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """One mildly distorted element (points (nn, 2), cells (1, nn)) lying in r0 <= x <= r0 + 2."""
    ref = reference_nodes(cell_type)
    # an affine map plus a small bilinear term: a general straight-edged quadrilateral
    x = r0 + 1.0 + 0.9 * ref[:, 0] + 0.2 * ref[:, 1] + 0.05 * ref[:, 0] * ref[:, 1]
    y = 2.0 + 0.1 * ref[:, 0] + 0.7 * ref[:, 1]
    return np.column_stack([x, y]), np.arange(len(ref))[None, :]


@pytest.fixture(params=["quad4", "quad8"])
def single_element(request):
    """(cell_type, points (nn, 2), cells (1, nn), n_gauss of full integration)."""
    cell_type = request.param
    points, cells = _element(cell_type)
    return cell_type, points, cells, 3 if cell_type == "quad8" else 2
