"""The per-point flags whose switching the displacement-control solver damps as chatter."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from icewall.materials.concrete import update_concrete
from icewall.materials.concrete_state import ConcreteState
from icewall.materials.parameters import derive_concrete_parameters
from icewall.solve.nonlinear import point_flags

PARAMS = derive_concrete_parameters(53.5, 100.0)
GROUP = (SimpleNamespace(model="rotating_crack"),)


def _softening_flag(state: ConcreteState) -> np.ndarray:
    (flags,) = point_flags(GROUP, (state,))
    assert flags.shape == (1, 9)  # cracked (3), crushed (3), loading past the peak (3)
    return flags[0, 6:]


def test_loading_past_the_peak_is_flagged_and_unloading_is_not():
    """Direction 1 in uniaxial compression: loading before the peak is not flagged, loading
    on the descending branch is, and unloading from there is not (that switch is the limit
    cycle of a secant iteration on softening which the solver counts)."""
    state = ConcreteState.initial(1, PARAMS)
    path = [0.5, 3.0, 4.0]  # times eps_c; eps_yy = 0 confines: the peak is near 2.4 eps_c
    flags = []
    for factor in path:
        _, _, state = update_concrete(np.array([[-factor * PARAMS.eps_c, 0, 0, 0]]), state,
                                      PARAMS, "plane_stress")
        flags.append(bool(_softening_flag(state)[0]))
    _, _, unloaded = update_concrete(np.array([[-3.9 * PARAMS.eps_c, 0, 0, 0]]), state,
                                     PARAMS, "plane_stress")
    assert flags == [False, True, True]
    assert not _softening_flag(unloaded)[0]
    assert state.crushed[0, 0] and unloaded.crushed[0, 0]  # the crush flag alone cannot tell
