"""Options of the concrete update the structural solver relies on: the total trial stress,
frozen points (chatter damping) and sub-stepping."""

from __future__ import annotations

import numpy as np

from icewall.materials.concrete import update_concrete
from icewall.materials.concrete_state import ConcreteState
from icewall.materials.parameters import derive_concrete_parameters
from icewall.materials.substep import update_concrete_substepped

PARAMS = derive_concrete_parameters(53.5, 100.0)
TENSION = np.array([[3.0 * PARAMS.eps_t, 0.0, 0.0, 0.0]])  # beyond the cracking strain


def _uniaxial_tension_path(trial: str, steps: int = 30, peak_factor: float = 4.0):
    state = ConcreteState.initial(1, PARAMS)
    stresses = []
    for t in np.linspace(0.0, peak_factor * PARAMS.eps_t, steps)[1:]:
        strain = np.array([[t, -PARAMS.nu0 * t, 0.0, 0.0]])
        stress, _, state = update_concrete(strain, state, PARAMS, "plane_stress", trial)
        stresses.append(stress[0, 0])
    return np.array(stresses), state


def test_total_and_incremental_trial_agree_on_a_fixed_axis_path():
    """Without rotation both trial forms coincide while E and nu are constant (the linear
    branch) and stay close after (they differ only by how a changing nu is integrated)."""
    total, s_total = _uniaxial_tension_path("total")
    incremental, s_incr = _uniaxial_tension_path("incremental")
    linear = total < 0.5 * PARAMS.ft  # eq. 3.20a: nu = nu0 below half the tensile peak
    assert np.allclose(total[linear], incremental[linear], rtol=1e-9)
    assert np.allclose(total, incremental, rtol=0.03)
    assert s_total.cracked[0, 0] and s_incr.cracked[0, 0]
    assert max(total.max(), incremental.max()) <= 1.01 * PARAMS.ft


def test_total_trial_leaks_no_committed_stress_into_a_cracked_direction_on_rotation():
    """A fully cracked point under large compression along the crack: rotating the axes must
    not push the compressive stress into the open crack (the incremental trial does)."""
    state = ConcreteState.initial(1, PARAMS)
    # open a crack along x, then compress along y
    for strain in ([4e-3, 0.0, 0.0, 0.0], [4e-3, -1.5e-3, 0.0, 0.0]):
        _, _, state = update_concrete(np.array([strain]), state, PARAMS, "plane_stress",
                                      "total")
    assert state.cracked[0, 0]
    rotated = np.array([[4e-3, -1.5e-3, 0.0, 4e-4]])  # a little shear rotates the axes
    stress_total, _, _ = update_concrete(rotated, state, PARAMS, "plane_stress", "total")
    c = 0.5 * (stress_total[0, 0] + stress_total[0, 1])
    major = c + np.hypot(0.5 * (stress_total[0, 0] - stress_total[0, 1]), stress_total[0, 3])
    assert major <= 0.05 * PARAMS.ft  # no spurious tension or compression across the crack


def test_frozen_points_only_unload_and_reload():
    state = ConcreteState.initial(1, PARAMS)
    half = 0.3 * TENSION  # 0.9 eps_t: still on the linear branch
    committed, _, state = update_concrete(half, state, PARAMS, "plane_stress", "total")
    free, _, free_state = update_concrete(TENSION, state, PARAMS, "plane_stress", "total")
    frozen, _, frozen_state = update_concrete(TENSION, state, PARAMS, "plane_stress", "total",
                                              frozen=np.array([True]))
    assert free_state.cracked[0, 0] and not frozen_state.cracked[0, 0]
    # the frozen point keeps its committed moduli: no damage grows within the increment
    assert np.array_equal(frozen_state.secant_modulus, state.secant_modulus)
    assert np.array_equal(frozen_state.poisson_ratio, state.poisson_ratio)
    assert np.array_equal(frozen_state.max_equivalent_uniaxial_strain,
                          state.max_equivalent_uniaxial_strain)
    assert frozen[0, 0] > committed[0, 0]  # it reloads along the secant
    assert free[0, 0] < PARAMS.ft


def test_substepping_converges_to_the_fine_path():
    """One big increment with sub-steps is close to a path of many small increments."""
    big = np.array([[6e-4, -3e-3, 0.0, 1e-3]])
    fine_state = ConcreteState.initial(1, PARAMS)
    for t in np.linspace(0, 1, 201)[1:]:
        fine, _, fine_state = update_concrete(t * big, fine_state, PARAMS, "plane_strain")
    coarse, _, _ = update_concrete(big, ConcreteState.initial(1, PARAMS), PARAMS, "plane_strain")
    sub, _, _ = update_concrete_substepped(big, ConcreteState.initial(1, PARAMS), PARAMS,
                                           "plane_strain", max_strain_step=0.5 * PARAMS.eps_t,
                                           max_substeps=64)
    assert np.abs(sub - fine).max() < np.abs(coarse - fine).max()
    assert np.abs(sub - fine).max() < 0.1 * np.abs(fine).max()
