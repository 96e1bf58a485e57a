"""Options of the concrete update the structural solver relies on: the total trial stress,
frozen points (chatter damping) and sub-stepping."""

from __future__ import annotations

import numpy as np
import pytest

from icewall.materials.concrete import concrete_tangent, update_concrete
from icewall.materials.concrete_state import ConcreteState
from icewall.materials.orthotropic import global_strain
from icewall.materials.parameters import derive_concrete_parameters
from icewall.materials.point import run_path
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


def test_corotational_trial_leaks_no_committed_stress_into_a_cracked_direction():
    """The co-rotational trial carries the committed principal stresses with the axes: the
    open crack stays (nearly) stress free when a little shear rotates the axes, and without
    rotation it is the incremental trial of Fig. 3.12."""
    state = ConcreteState.initial(1, PARAMS)
    for strain in ([4e-3, 0.0, 0.0, 0.0], [4e-3, -1.5e-3, 0.0, 0.0]):
        _, _, state = update_concrete(np.array([strain]), state, PARAMS, "plane_stress",
                                      "corotational")
    assert state.cracked[0, 0]
    rotated = np.array([[4e-3, -1.5e-3, 0.0, 4e-4]])
    stress, _, new = update_concrete(rotated, state, PARAMS, "plane_stress", "corotational")
    c = 0.5 * (stress[0, 0] + stress[0, 1])
    radius = np.hypot(0.5 * (stress[0, 0] - stress[0, 1]), stress[0, 3])
    assert c + radius <= 0.05 * PARAMS.ft
    fixed = np.array([[4e-3, -1.6e-3, 0.0, 0.0]])
    a, _, _ = update_concrete(fixed, state, PARAMS, "plane_stress", "corotational")
    b, _, _ = update_concrete(fixed, state, PARAMS, "plane_stress", "incremental")
    assert np.allclose(a, b, rtol=1e-12, atol=1e-12)


def _uniaxial_compression_state(trial: str, strain: float = 0.0017) -> ConcreteState:
    """Axisymmetric uniaxial compression (hoop and radial stress free) to `strain`, where the
    compression Poisson ratio of eq. 3.19 has grown from 0.2 to about 0.45."""
    result = run_path("uniaxial-compression", PARAMS, "axisymmetric", n_steps=34,
                      max_strain=strain, tolerance=1e-7, trial_stress=trial)
    assert not result.stopped
    state = ConcreteState.initial(1, PARAMS)
    for step_strain in result.strain[1:]:
        _, _, state = update_concrete(step_strain[None], state, PARAMS, "axisymmetric", trial)
    assert np.allclose(state.stress[0], result.stress[-1])
    return state


@pytest.mark.parametrize("trial", ["incremental", "corotational"])
def test_a_zero_increment_returns_the_committed_stress(trial):
    """Re-evaluating the committed strain gives the committed stress back (the total trial
    gives C(E, nu) eps instead, which differs once nu has grown by eq. 3.19)."""
    state = _uniaxial_compression_state(trial)
    assert state.poisson_ratio[0, 0] > 0.4
    again, _, same = update_concrete(state.strain, state, PARAMS, "axisymmetric", trial)
    assert np.allclose(again, state.stress, rtol=1e-9, atol=1e-9 * PARAMS.fc)
    assert np.array_equal(same.secant_modulus, state.secant_modulus)


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
    assert free[0, 0] < PARAMS.ft
    # it reloads along the secant, but not above the envelope, which it meets here
    assert frozen[0, 0] == pytest.approx(free[0, 0], rel=1e-9)
    inside, _, _ = update_concrete(0.32 * TENSION, state, PARAMS, "plane_stress", "total",
                                   frozen=np.array([True]))
    linear, _, _ = update_concrete(0.32 * TENSION, state, PARAMS, "plane_stress", "total")
    assert committed[0, 0] < inside[0, 0] == pytest.approx(linear[0, 0], rel=1e-12)


def test_matrix_secant_is_the_secant_of_the_returned_stress():
    """A point frozen at half its compressive peak strain and driven to 4 eps_c keeps its
    committed E_1 (no damage grows), but its stress is capped at the envelope: the iteration
    matrix takes sigma_1 / eps_1u, the secant of that stress, not E_1. A free point loading on
    its envelope, and an unloading one, keep E_i exactly."""
    from icewall.materials.concrete import matrix_secant

    state = ConcreteState.initial(1, PARAMS)
    half = np.array([[-0.5 * PARAMS.eps_c, 0.0, 0.0, 0.0]])
    _, _, state = update_concrete(half, state, PARAMS, "plane_stress", "incremental")
    far = np.array([[-4.0 * PARAMS.eps_c, 0.0, 0.0, 0.0]])
    stress, _, held = update_concrete(far, state, PARAMS, "plane_stress", "incremental",
                                      frozen=np.array([True]))
    secant = matrix_secant(held)
    assert secant[0, 0] == pytest.approx(-stress[0, 0] / -held.equivalent_uniaxial_strain[0, 0],
                                         rel=1e-12)
    assert secant[0, 0] < 0.5 * held.secant_modulus[0, 0]
    assert secant[0, 2] == held.secant_modulus[0, 2]  # sigma_3 = 0 = eps_3u (plane stress)
    _, _, loading = update_concrete(0.9 * half, state, PARAMS, "plane_stress", "incremental")
    _, _, free = update_concrete(far, state, PARAMS, "plane_stress", "incremental")
    for trial in (loading, free):
        assert matrix_secant(trial)[0, 0] == pytest.approx(trial.secant_modulus[0, 0],
                                                           rel=1e-12)


def test_frozen_points_never_reload_above_their_envelope():
    """A point frozen at half its compressive peak strain and driven far past it in one step
    (as the solver's chatter damping does) keeps its secant and history but its stress is
    capped at the envelope, softened beyond the peak; it used to rise along the secant."""
    state = ConcreteState.initial(1, PARAMS)
    half = np.array([[-0.5 * PARAMS.eps_c, 0.0, 0.0, 0.0]])
    _, _, state = update_concrete(half, state, PARAMS, "plane_stress", "incremental")
    peak = 0.0
    for factor in (1.0, 2.0, 4.0):
        strain = np.array([[-factor * PARAMS.eps_c, 0.0, 0.0, 0.0]])
        stress, _, held = update_concrete(strain, state, PARAMS, "plane_stress", "incremental",
                                          frozen=np.array([True]))
        free, _, _ = update_concrete(strain, state, PARAMS, "plane_stress", "incremental")
        assert np.array_equal(held.secant_modulus, state.secant_modulus)
        assert stress[0, 0] == pytest.approx(free[0, 0], rel=1e-9)  # capped at the envelope
        peak = max(peak, -stress[0, 0])
    assert -stress[0, 0] < 0.8 * peak  # the softened envelope at 4 eps_c, not the secant line


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


def test_tangent_differentiates_the_chosen_trial_form():
    """concrete_tangent(trial_stress=...) is the derivative of that form's update (on a
    cracked point whose axes rotate, where the forms differ)."""
    state = ConcreteState.initial(1, PARAMS)
    for strain in ([4e-3, 0.0, 0.0, 0.0], [4e-3, -1.0e-3, 0.0, 0.0]):
        _, _, state = update_concrete(np.array([strain]), state, PARAMS, "plane_stress",
                                      "corotational")
    strain = np.array([[4e-3, -1.0e-3, 0.0, 6e-4]])
    step = np.array([[0.0, 0.0, 0.0, 1e-9]])
    tangents = {}
    for trial in ("corotational", "incremental"):
        tangent = concrete_tangent(strain, state, PARAMS, "plane_stress", trial_stress=trial)
        a, _, _ = update_concrete(strain, state, PARAMS, "plane_stress", trial)
        b, _, _ = update_concrete(strain + step, state, PARAMS, "plane_stress", trial)
        assert np.allclose((b - a)[0] / 1e-9, tangent[0, :, 3], rtol=1e-3, atol=1.0)
        tangents[trial] = tangent
    assert not np.allclose(tangents["corotational"], tangents["incremental"], rtol=1e-3)


def _rotated(principal: tuple[float, float], angle_deg: float) -> np.ndarray:
    """Global strain (1, 4) with in-plane principal strains `principal`, the first along
    `angle_deg`."""
    return global_strain(np.array([[*principal, 0.0]]), np.radians([angle_deg]))


def test_frozen_point_keeps_its_axes_across_the_45_degree_swap():
    """Past a 45-degree rotation the nearest labelling of the principal axes swaps: the
    corotational trial stress jumps (the committed principal stresses change axes), a
    discontinuity that made the secant iteration cycle (VTT1 at 12.7 mm). A frozen point keeps
    its committed axes, carries the shear strain in them with G12 (eq. 3.21), and its stress is
    continuous across the swap."""
    state = ConcreteState.initial(1, PARAMS)
    committed_strain = np.array([[-0.6 * PARAMS.eps_c, 0.1 * PARAMS.eps_c, 0.0, 0.0]])
    _, _, state = update_concrete(committed_strain, state, PARAMS, "plane_strain", "corotational")
    principal = (-0.6 * PARAMS.eps_c, 0.1 * PARAMS.eps_c)

    def path(frozen=None):  # stresses at 42, 44 and 46 degrees, and the states
        out = [update_concrete(_rotated(principal, a), state, PARAMS, "plane_strain",
                               "corotational", frozen=frozen) for a in (42.0, 44.0, 46.0)]
        return np.array([o[0][0] for o in out]), [o[2] for o in out]

    def kink(stresses):  # second difference: zero on a smooth path sampled evenly
        return np.abs(stresses[2] - 2.0 * stresses[1] + stresses[0]).max()

    free, _ = path()
    held, held_states = path(np.array([True]))
    assert kink(free) > 1.0  # MPa: the swap (sigma_zz alone jumps by 2 MPa)
    assert kink(held) < 0.1
    assert all(s.angle[0] == state.angle[0] for s in held_states)
    # the held point's shear stress is the shear strain in its committed axes times G12
    a = np.radians(46.0)
    gamma = 2.0 * (principal[0] - principal[1]) * np.cos(a) * np.sin(a)
    assert held[2, 3] == pytest.approx(held_states[2].shear_modulus[0] * gamma, rel=1e-9)


def test_a_closing_crack_meets_the_compression_envelope_continuously():
    """A direction cracked far past its tensile peak and then compressed follows its crack
    secant until that line meets the compression envelope. Its max |eps_iu| was reached in
    tension, so loading onto the compression envelope at that magnitude made the stress jump
    from the crack secant to about E0 eps (40 MPa here); the secant iteration then cycled
    between the two."""
    state = ConcreteState.initial(1, PARAMS)
    opened = 20.0 * PARAMS.eps_t
    _, _, state = update_concrete(np.array([[opened, 0.0, 0.0, 0.0]]), state, PARAMS,
                                  "plane_stress", "corotational")
    assert state.cracked[0, 0]
    closing = np.linspace(0.5, 1.5, 201) * opened  # compressive strain, through |eps_iu| = max
    stresses = np.array([update_concrete(np.array([[-c, 0.0, 0.0, 0.0]]), state, PARAMS,
                                         "plane_stress", "corotational")[0][0, 0]
                         for c in closing])
    assert np.all(stresses < 0.0)
    assert np.abs(np.diff(stresses)).max() < 0.05  # MPa per step of 0.005 x the opening
    assert -stresses.min() < 0.2 * PARAMS.fc  # still on the crack secant, far below f'c
