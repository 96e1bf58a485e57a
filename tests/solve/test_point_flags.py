"""The per-point flags whose switching the displacement-control solver damps as chatter."""

from __future__ import annotations

import numpy as np

from icewall.materials.concrete import update_concrete
from icewall.materials.concrete_law import ConcreteLaw
from icewall.materials.concrete_state import ConcreteState
from icewall.materials.orthotropic import global_strain
from icewall.materials.parameters import derive_concrete_parameters

PARAMS = derive_concrete_parameters(53.5, 100.0)
LAW = ConcreteLaw(PARAMS, "plane_stress", 0.5 * PARAMS.eps_t, "corotational", 0.0, False, False)


def _softening_flag(state: ConcreteState) -> np.ndarray:
    flags = LAW.flags(state)
    # cracked (3), crushed (3), loading past the peak (3), labelling of the principal axes
    assert flags.shape == (1, 10)
    return flags[0, 6:9]


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


def test_the_labelling_of_the_principal_axes_is_a_flag():
    """Past a 45-degree rotation of the principal strains the axis nearest the committed
    direction 1 carries the minor strain: the flag switches (a point whose iterates swap
    labellings is counted as chattering and then held, see test_concrete_solver_options)."""
    state = ConcreteState.initial(1, PARAMS)
    _, _, state = update_concrete(np.array([[-1e-3, 2e-4, 0.0, 0.0]]), state, PARAMS,
                                  "plane_strain", "corotational")
    labels = []
    for degrees in (30.0, 44.0, 46.0, 60.0):
        # the compressive principal strain along the angle
        strain = global_strain(np.array([[-1e-3, 2e-4, 0.0]]), np.radians([degrees]))
        _, _, trial = update_concrete(strain, state, PARAMS, "plane_strain", "corotational")
        flags = LAW.flags(trial)
        labels.append(bool(flags[0, 9]))
    committed = LAW.flags(state)
    assert labels[0] == labels[1] == bool(committed[0, 9])
    assert labels[2] == labels[3] != labels[1]
