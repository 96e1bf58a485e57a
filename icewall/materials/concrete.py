"""Hypoelastic orthotropic rotating-crack concrete (thesis §3.2, Fig. 3.12), batched over points.

`update_concrete(strain, committed, params, formulation)` is pure: it returns the stress, the
secant moduli and a trial state, and never touches `committed`. One call is one pass of
Fig. 3.12 from the committed state to the given total strain:

1-2. beta of the new principal strains (`rotating_axes`: the labelling nearest the committed
     axes, or direction 1 on the major strain); committed stress and the strain increment in
     those axes.
3.   Trial stress sigma_lt = sigma_l + C_l(E, nu) d eps_l, with C_l rebuilt from the stored E, nu
     in the new axes (errata §3, instead of rotating the old C_g). `trial_stress`:
     "incremental" rotates the committed stress into the new axes (as printed); "corotational"
     (deck default) carries the committed principal stresses with the axes, d eps_l being the
     change of the principal strains, so that no committed stress leaks into an open crack
     and a zero increment returns the committed stress; "total" is C_l eps_l (not consistent
     once nu has grown, see tests/materials/test_concrete_solver_options.py).
4.   eps_iu = sigma_lt,i / E_i with the secant E_i (errata 1.1 on eq. 3.8: step 4, not 3.8).
5.   sigma_ic, eps_ic from the ultimate surfaces on the ray of the trial stress (errata 1.3);
     with `post_peak_strength: peak` a direction past its peak keeps its committed ones; with
     `fallen_strength: scaled` an envelope that has fallen below the direction's secant line
     at its max |eps_iu| is scaled through that point (continuous reloading).
6.   Per direction: loading (|eps_iu| beyond its maximum) follows eqs. 3.9-3.11 and updates the
     secant E_i, nu_i (3.19-3.20); unloading keeps E_i, nu_i (Fig. 3.13). A direction past
     its peak on the other sign's branch (a closing crack, a crushed direction in tension)
     loads where its secant line meets the new envelope, so its stress stays continuous.
     The local shear stress is reset to zero (§3.2.6), G12 from eq. 3.21.
7-8. Secant C_l from the new E, nu, G12, back to global axes (errata 1.3). Under
     `rotating_axes: continuous` the returned stress takes out the cone of the rotating
     axes at an isotropic in-plane strain (rotation.py); the trial state keeps the law's.

Secant relation: per direction sigma_i = E_i eps_iu (except below the secant floor); in global
components sigma = C_g eps holds exactly only while nu and the ratios E_i/E_j stay fixed between the
committed and the new state (e.g. the linear tension range); otherwise C_g is the thesis'
iteration (secant) matrix. `concrete_tangent` gives the algorithmic tangent by differences.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from icewall.formulations import check_formulation
from icewall.materials.concrete_formulas import (
    changes_sign,
    direction_state,
    envelope_stress,
    keeps_peak,
    loads,
    loads_across_zero,
    scaled_envelope,
    shear_modulus,
)
from icewall.materials.concrete_state import ConcreteState
from icewall.materials.mode_rules import (
    equivalent_uniaxial_peak_strains,
    equivalent_uniaxial_strengths,
)
from icewall.materials.orthotropic import (
    condense_plane_stress,
    global_moduli,
    global_stress,
    local_normal_components,
    local_shear_strain,
    orthotropic_normal_stiffness,
    principal_strain_angle,
)
from icewall.materials.parameters import take_parameters
from icewall.materials.rotation import continuous_axes, resolved_stress
from icewall.materials.uniaxial import SECANT_FLOOR, compression_envelope, tension_envelope

LOADING_TOLERANCE = 1e-10
"""Margin on max |eps_iu| (relative to the point's stress / E_i): a zero increment unloads and
returns the same stress."""

__all__ = ["ConcreteState", "concrete_tangent", "update_concrete"]


def _point_column(value: Any, rows: np.ndarray | None) -> np.ndarray:
    """A scalar or per-point (n,) parameter as a column broadcastable to (n, 3) (or its rows)."""
    column = np.asarray(value, dtype=float).reshape(-1, 1)
    return column if rows is None or column.shape[0] == 1 else column[rows]


def _envelope(eps_u: np.ndarray, strength: np.ndarray, peak_strain: np.ndarray,
              params: Any, rows: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Envelope stress and secant magnitudes (n, 3) at |eps_iu| (eqs. 3.9-3.11).

    The tension or compression curve is chosen by the sign of eps_iu, which the strengths share
    (they are passed strain_sign). Eq. 3.11 / errata 1.1: both decay branches in magnitudes,
    each from its own peak strain (in `uniaxial`). The secant is capped at E_i0 (errata §3).
    """
    magnitude = np.abs(eps_u)
    tensile = eps_u > 0.0
    peak_stress, peak_magnitude = np.abs(strength), np.abs(peak_strain)
    k_t, k_c = _point_column(params.k_t, rows), _point_column(params.k_c, rows)
    printed = getattr(params, "printed_forms", ())
    start = params.eps_c if "eq3.11a" in printed else None  # eq. 3.11a as printed
    t_stress, t_secant = tension_envelope(magnitude, params.E0, peak_stress, peak_magnitude, k_t,
                                          start)
    c_stress, c_secant = compression_envelope(
        magnitude, params.E0, peak_stress, peak_magnitude, k_c,
        getattr(params, "compression_branch", "exponential") == "linear")
    return np.where(tensile, t_stress, c_stress), np.where(tensile, t_secant, c_secant)


def loading_directions(trial: np.ndarray, eps_u: np.ndarray, state: ConcreteState, params: Any
                       ) -> tuple[np.ndarray, np.ndarray]:
    """(loading, sign_change) (n, 3) bool of Fig. 3.12 step 6 for the trial stress and its
    eps_iu: loading where |eps_iu| passes its maximum (Fig. 3.13); sign_change where eps_iu
    has left the sign of the committed uniaxial strength."""
    sign_change = changes_sign(eps_u, state.uniaxial_strength)
    # round-off of the rotation is relative to the point's largest stress, not to sigma_i
    loading = loads(eps_u, state.max_equivalent_uniaxial_strain,
                    np.abs(trial).max(axis=1, keepdims=True), state.secant_modulus,
                    LOADING_TOLERANCE)
    rows = np.nonzero(sign_change.any(axis=1))[0]
    if rows.size:
        # a direction past its peak on the other sign's branch (cracked, now closing in
        # compression, or crushed, now in tension) loads only where its secant line meets the
        # envelope: its max |eps_iu| belongs to the other branch, and loading onto this branch
        # at that magnitude makes the stress jump (a closing crack leapt from its crack secant
        # to the compression envelope: VTT1 cycled between the two at 38.6 mm). The continuous
        # reading (`fallen_strength: scaled`) takes the envelope the direction then follows,
        # sigma_ic, eps_ic on the trial stress's ray (step 5); the uniaxial one, which a crack
        # closing under lateral compression meets where the ray's envelope stands far higher,
        # lets the stress jump there (docs/solver.md item 42: CF-4, 24 MPa at 9.48 mm)
        if getattr(params, "fallen_strength", "envelope") == "scaled":
            strength, peak_strain = _ray_strengths(trial, eps_u, state, params, rows)
        else:  # the uniaxial envelope (as before item 42)
            tensile = eps_u[rows] > 0.0
            strength = np.where(tensile, params.ft, -params.fc)
            peak_strain = np.where(tensile, params.eps_t, -params.eps_c)
        envelope, _ = _envelope(eps_u[rows], strength, peak_strain, params, rows)
        loading[rows] = loads_across_zero(loading[rows], sign_change[rows],
                                          state.cracked[rows] | state.crushed[rows],
                                          state.secant_modulus[rows], eps_u[rows], envelope)
    return loading, sign_change


def _ray_strengths(trial: np.ndarray, eps_u: np.ndarray, state: ConcreteState, params: Any,
                   rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Step 5 at the points `rows`: sigma_ic, eps_ic (each (m, 3)) on the ray of the trial
    stress (errata 1.3); "fig3.12_step5": as printed, the stress known before step 6, the
    committed one in the committed axes."""
    on_ray = (local_normal_components(state.stress[rows], state.angle[rows], 2.0)
              if "fig3.12_step5" in getattr(params, "printed_forms", ()) else trial[rows])
    strength = equivalent_uniaxial_strengths(on_ray, params, strain_sign=eps_u[rows])
    return strength, equivalent_uniaxial_peak_strains(strength, params)


def past_peak(eps_u: np.ndarray, cracked: np.ndarray, crushed: np.ndarray,
              sign_change: np.ndarray, params: Any) -> np.ndarray:
    """(n, 3) bool: directions that keep their committed sigma_ic, eps_ic (deck
    `post_peak_strength: peak`): past their peak on the branch they are on (cracked in
    tension, crushed in compression) without a change of sign. All False under "ray"."""
    if getattr(params, "post_peak_strength", "ray") != "peak":
        return np.zeros(eps_u.shape, dtype=bool)
    return keeps_peak(eps_u, sign_change, cracked, crushed)


def _strain_and_axes(strain: np.ndarray, state: ConcreteState, formulation: str,
                     frozen_column: np.ndarray | None, rotating_axes: str = "nearest"
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Steps 1-2: the total strain (n, 4) (zz imposed or, in plane stress, the committed one
    until step 3 solves it) and the angle beta (n,) of its principal axes."""
    strain = np.array(strain, dtype=float, copy=True).reshape(-1, 4)
    if formulation == "plane_strain":
        strain[:, 2] = 0.0
    elif formulation == "plane_stress":
        strain[:, 2] = state.strain[:, 2]
    angle = principal_strain_angle(strain, state.angle, rotating_axes)
    if frozen_column is not None:
        # a frozen point keeps its axes for the rest of the increment (a fixed crack with shear
        # retention, below): near a 45-degree rotation the nearest labelling of the principal
        # axes swaps between iterates and, with it, the committed stresses and damage
        angle = np.where(frozen_column[:, 0], state.angle, angle)
    return strain, angle


def _trial_stress(strain: np.ndarray, angle: np.ndarray, state: ConcreteState,
                  plane_stress: bool, trial_stress: str, printed: tuple[str, ...] = ()
                  ) -> np.ndarray:
    """Steps 2-3: committed stress and strain increment in the new axes (errata 1.3), trial
    stress sigma_lt (n, 3) with C_l of the committed E, nu. Plane stress: sigma_3t = 0 fixes
    the out-of-plane strain (errata §3), solved into strain[:, 2]."""
    if trial_stress == "corotational":  # committed principal values carried with the axes
        strain_increment = (local_normal_components(strain, angle, 1.0)
                            - local_normal_components(state.strain, state.angle, 1.0))
        committed_stress = local_normal_components(state.stress, state.angle, 2.0)
    else:
        strain_increment = local_normal_components(strain - state.strain, angle, 1.0)
        committed_stress = local_normal_components(state.stress, angle, 2.0)
    stiffness = orthotropic_normal_stiffness(state.secant_modulus, state.poisson_ratio, printed)
    if plane_stress:
        strain_increment[:, 2] = -(committed_stress[:, 2]
                                   + stiffness[:, 2, 0] * strain_increment[:, 0]
                                   + stiffness[:, 2, 1] * strain_increment[:, 1]
                                   ) / stiffness[:, 2, 2]
        strain[:, 2] += strain_increment[:, 2]
    if trial_stress == "total":  # C_l(E^i) eps_l: the secant relation of the committed moduli
        local_strain = local_normal_components(strain, angle, 1.0)
        if plane_stress:
            local_strain[:, 2] = -(stiffness[:, 2, 0] * local_strain[:, 0]
                                   + stiffness[:, 2, 1] * local_strain[:, 1]) / stiffness[:, 2, 2]
            strain[:, 2] = local_strain[:, 2]
        trial = np.einsum("nij,nj->ni", stiffness, local_strain)
    else:
        trial = committed_stress + np.einsum("nij,nj->ni", stiffness, strain_increment)
    if plane_stress:
        trial[:, 2] = 0.0
    return trial


def _curve_parameters(trial: np.ndarray, eps_u: np.ndarray, loading: np.ndarray,
                      sign_change: np.ndarray, state: ConcreteState, params: Any
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Step 5: sigma_ic, eps_ic on the ray of the trial stress (errata 1.3), and the envelope
    (stress, secant) at eps_iu, each (n, 3). Only a loading direction reads them: the points
    with none keep their committed values (every use is masked by `loading`), and skip the
    surface."""
    strength = state.uniaxial_strength.copy()
    peak_strain = state.uniaxial_peak_strain.copy()
    envelope_stress, envelope_secant = np.abs(trial), state.secant_modulus.copy()
    loads = np.nonzero(loading.any(axis=1))[0]
    if loads.size:
        strength[loads], peak_strain[loads] = _ray_strengths(trial, eps_u, state, params,
                                                             loads)
        kept = past_peak(eps_u[loads], state.cracked[loads], state.crushed[loads],
                         sign_change[loads], params)
        strength[loads] = np.where(kept, state.uniaxial_strength[loads], strength[loads])
        peak_strain[loads] = np.where(kept, state.uniaxial_peak_strain[loads],
                                      peak_strain[loads])
        envelope_stress[loads], envelope_secant[loads] = _envelope(
            eps_u[loads], strength[loads], peak_strain[loads], params, loads)
        if getattr(params, "fallen_strength", "envelope") == "scaled":
            max_eps_u = state.max_equivalent_uniaxial_strain[loads]
            at_max, _ = _envelope(np.copysign(max_eps_u, eps_u[loads]), strength[loads],
                                  peak_strain[loads], params, loads)
            envelope_stress[loads], envelope_secant[loads] = scaled_envelope(
                envelope_stress[loads], envelope_secant[loads], at_max,
                state.secant_modulus[loads] * max_eps_u, sign_change[loads], SECANT_FLOOR,
                _point_column(params.E0, loads))
    return strength, peak_strain, envelope_stress, envelope_secant


def _update_directions(trial: np.ndarray, eps_u: np.ndarray, loading: np.ndarray,
                       sign_change: np.ndarray, frozen_column: np.ndarray | None,
                       curve: tuple[np.ndarray, ...], state: ConcreteState, params: Any
                       ) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Step 6: per direction the stress on the envelope (eqs. 3.9-3.11) where loading, along
    the secant where unloading (Fig. 3.13), the secant E_i, nu_i (eqs. 3.19-3.20), G12 (eq.
    3.21). Returns the local stresses (n, 3) and the trial state's fields of the directions.
    A frozen point (the solver's chatter damping) grows no damage."""
    strength, peak_strain, envelope_stress_, envelope_secant = curve
    frozen = False if frozen_column is None else frozen_column
    loading, local_stress, secant = envelope_stress(
        trial, eps_u, state.secant_modulus, loading, sign_change, frozen, envelope_stress_,
        envelope_secant)
    max_eps_u, poisson, strength, peak_strain, cracked, crushed = direction_state(
        eps_u, loading, frozen, state.max_equivalent_uniaxial_strain, state.poisson_ratio,
        state.uniaxial_strength, state.uniaxial_peak_strain, state.cracked, state.crushed,
        strength, peak_strain, float(params.nu0), params.nu_max)
    return local_stress, {
        "equivalent_uniaxial_strain": eps_u, "max_equivalent_uniaxial_strain": max_eps_u,
        "secant_modulus": secant, "poisson_ratio": poisson,
        "shear_modulus": shear_modulus(secant[:, 0], secant[:, 1], float(params.nu0)),
        "uniaxial_strength": strength, "uniaxial_peak_strain": peak_strain,
        "cracked": cracked, "crushed": crushed}


def update_concrete(strain: np.ndarray, state: ConcreteState, params: Any, formulation: str,
                    trial_stress: str = "incremental", frozen: np.ndarray | None = None,
                    with_moduli: bool = True
                    ) -> tuple[np.ndarray, np.ndarray | None, ConcreteState]:
    """Stress (n, 4), secant moduli (n, 4, 4; None unless `with_moduli`) and trial state at
    total strain (n, 4).

    plane_strain: eps_zz = 0 is imposed and sigma_zz tracked. plane_stress: sigma_zz = 0 is
    condensed, the input eps_zz is ignored and the solved one stored in the trial state (moduli
    have zero zz row/column). axisymmetric: zz is the hoop direction, taken from the input.
    """
    check_formulation(formulation)
    plane_stress = formulation == "plane_stress"
    frozen_column = None if frozen is None else np.asarray(frozen, dtype=bool)[:, None]
    strain, angle = _strain_and_axes(strain, state, formulation, frozen_column,
                                     getattr(params, "rotating_axes", "nearest"))
    printed = tuple(getattr(params, "printed_forms", ()))
    trial = _trial_stress(strain, angle, state, plane_stress, trial_stress, printed)
    eps_u = trial / state.secant_modulus  # step 4: secant (errata 1.1 on eq. 3.8)
    # step 6 first: loading vs unloading, which does not depend on the strength surface
    loading, sign_change = loading_directions(trial, eps_u, state, params)
    curve = _curve_parameters(trial, eps_u, loading, sign_change, state, params)  # step 5
    local_stress, directions = _update_directions(trial, eps_u, loading, sign_change,
                                                  frozen_column, curve, state, params)
    if plane_stress:  # direction 3 carries no stress: it keeps its virgin properties
        local_stress[:, 2] = 0.0
    # step 8: the held axes of a frozen point keep a shear stress, G12 times their shear strain
    stress = global_stress(local_stress, angle, None if frozen_column is None else np.where(
        frozen_column[:, 0], directions["shear_modulus"] * local_shear_strain(strain, angle),
        0.0))
    moduli = None  # steps 7-8 (skipped where the caller builds its own)
    if with_moduli:
        new_stiffness = orthotropic_normal_stiffness(directions["secant_modulus"],
                                                     directions["poisson_ratio"], printed)
        if plane_stress:
            new_stiffness = condense_plane_stress(new_stiffness)
        moduli = global_moduli(new_stiffness, directions["shear_modulus"], angle)
    trial = ConcreteState(strain=strain, stress=stress, angle=angle, **directions)
    if continuous_axes(params):  # the returned stress; the state keeps the law's
        stress = resolved_stress(trial, state, params, formulation, update_concrete,
                                 trial_stress, frozen)
    return stress, moduli, trial


def matrix_secant(state: ConcreteState) -> np.ndarray:
    """Secant moduli (n, 3) for the iteration matrix: E_i, but never above |sigma_i| / |eps_iu|,
    the secant of the stress the update returned. The two differ where the update caps the
    stress below E_i eps_iu: a frozen point held at its envelope (its E_i stays the committed
    one), and a direction far down a softening branch (uniaxial.SECANT_FLOOR). With E_i there
    the matrix is stiffer than the points it stands for, and the iteration crawls: CF-8 at
    11.5 mm kept a load norm of 0.08-0.12 for 200 iterations with 80 points held."""
    local = np.abs(local_normal_components(state.stress, state.angle, 2.0))
    eps_u = np.abs(state.equivalent_uniaxial_strain)
    with np.errstate(divide="ignore", invalid="ignore"):
        actual = np.where(eps_u > 1e-12, local / eps_u, state.secant_modulus)
    return np.minimum(state.secant_modulus, actual)


def concrete_tangent(strain: np.ndarray, state: ConcreteState, params: Any, formulation: str,
                     relative_step: float = 1e-7, trial_stress: str = "incremental",
                     frozen: np.ndarray | None = None) -> np.ndarray:
    """Algorithmic tangent d sigma / d eps (n, 4, 4) of `update_concrete` by forward differences.

    Vectorised: one batched update of 4n (plane stress: 3n) perturbed points. The step is
    relative_step times the strain size (at least 1e-10). Plane stress: zz row/column zero.
    `trial_stress` and `frozen` as in `update_concrete`: the tangent of the same map.
    """
    strain = np.asarray(strain, dtype=float).reshape(-1, 4)
    n = strain.shape[0]
    columns = [0, 1, 3] if formulation == "plane_stress" else [0, 1, 2, 3]
    if formulation == "plane_strain":
        columns = [0, 1, 3]
    step = relative_step * np.maximum(np.abs(strain).max(axis=1), 1e-3)
    base, _, _ = update_concrete(strain, state, params, formulation, trial_stress, frozen,
                                 with_moduli=False)
    perturbed = np.repeat(strain[None], len(columns), axis=0)  # (k, n, 4)
    for k, j in enumerate(columns):
        perturbed[k, :, j] += step
    index = np.tile(np.arange(n), len(columns))
    stressed, _, _ = update_concrete(perturbed.reshape(-1, 4), state.take(index),
                                     take_parameters(params, index, n), formulation,
                                     trial_stress, None if frozen is None
                                     else np.asarray(frozen, dtype=bool)[index],
                                     with_moduli=False)
    difference = (stressed.reshape(len(columns), n, 4) - base[None]) / step[None, :, None]
    tangent = np.zeros((n, 4, 4))
    for k, j in enumerate(columns):
        tangent[:, :, j] = difference[k]
    if formulation == "plane_stress":
        tangent[:, 2, :] = 0.0
    return tangent
