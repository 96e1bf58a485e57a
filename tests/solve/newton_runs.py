"""What the tests that run a shipped deck under the converged scheme share."""

from __future__ import annotations

import numpy as np

MAKEFILE_NEWTON = ["analysis.scheme=newton", "materials.concrete.mode_rule_band=0.1",
                   "materials.concrete.post_peak_strength=peak"]
"""The Makefile's NEWTON settings (its own limits are the scheme's defaults: 1e-4, 40
iterations, 6 step cuts)."""


def assert_every_step_converged(history, tolerance: float = 1e-4) -> None:
    """Every stored step an equilibrium within `tolerance` on both norms, none jumped."""
    assert np.all(np.asarray(history["load_norm"]) <= tolerance)
    assert np.all(np.asarray(history["displacement_norm"]) <= tolerance)
    assert not np.any(np.asarray(history["jumped"]))
