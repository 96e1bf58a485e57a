"""Material groups of a model: which cells use which constitutive law, with what parameters.

Every law is called the same way, `law(strain (n, 4), state, params) -> (stress, moduli,
trial_state)`, over all Gauss points of its group at once.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, fields, make_dataclass
from typing import Any

import numpy as np

from icewall.deck.schema import Deck
from icewall.materials.elastic import elastic_moduli
from icewall.materials.parameters import ConcreteParameters, derive_concrete_parameters

Law = Callable[[np.ndarray, Any, Any], tuple[np.ndarray, np.ndarray, Any]]


@dataclass(frozen=True)
class MaterialGroup:
    """The cells of one deck material and the law that updates their Gauss points."""

    name: str  # deck material key: concrete, steel, bearing_plates, legs
    model: str  # elastic | rotating_crack | von_mises
    cells: np.ndarray  # (n_cells,) element indices, sorted
    law: Law
    params: Any
    initial_state: Any  # None for elastic groups
    freezable: bool = False  # law accepts frozen=(n,) bool: those points may not load further
    # law accepts tangent=True and then returns the consistent tangent as moduli (the other
    # laws' moduli already are their tangents: steel's elastoplastic one, elastic D)
    tangent_switch: bool = False
    # (strain, stress, trial, committed, params) -> the consistent tangent of the law's update
    # that gave stress and trial at strain: the tangent of an evaluation already made
    # (Structure.with_tangent), where computing it costs less than updating again
    tangent_of: Callable[..., np.ndarray] | None = None
    kernel: str = "numpy"  # concrete update: numpy, or numba (concrete_compiled)


@dataclass(frozen=True)
class ElasticParameters:
    moduli: np.ndarray  # (4, 4)


def _elastic_law(strain: np.ndarray, state: None, params: ElasticParameters):
    moduli = np.broadcast_to(params.moduli, strain.shape[:-1] + (4, 4))
    return strain @ params.moduli.T, moduli, state


# ConcreteParameters with the crack-band quantities (h_c, k_t, k_c) as per-point arrays; the
# same fields, without the scalar validation of ConcreteParameters.
ConcretePointParameters = make_dataclass(
    "ConcretePointParameters", [(f.name, Any) for f in fields(ConcreteParameters)], frozen=True)


def concrete_point_parameters(params: ConcreteParameters, h_c: np.ndarray,
                              fixed_decay: dict[str, float]) -> ConcretePointParameters:
    """Scale k_t, k_c (both proportional to h_c, eqs. 3.29, 3.34) to every point's h_c.

    `fixed_decay` holds deck overrides of k_t / k_c, which then apply to every point as given.
    """
    values = {f.name: getattr(params, f.name) for f in fields(ConcreteParameters)}
    scale = np.asarray(h_c, dtype=float) / params.h_c
    values["h_c"] = np.asarray(h_c, dtype=float)
    for key in ("k_t", "k_c"):
        values[key] = (np.full_like(scale, fixed_decay[key]) if key in fixed_decay
                       else getattr(params, key) * scale)
    return ConcretePointParameters(**values)


def concrete_parameters(deck: Deck, h_c: float) -> ConcreteParameters:
    """The deck's concrete with every thesis 4.3.1 default and the deck's overrides."""
    c = deck.materials.concrete
    overrides: dict[str, Any] = {"eps_c": c.eps_c, "nu0": c.nu, "Gf": c.Gf,
                                 "fcb_ratio": c.surface.biaxial_ratio,
                                 "compression_tension_rule": c.compression_tension_rule,
                                 "mode_rule_band": c.mode_rule_band,
                                 "post_peak_strength": c.post_peak_strength}
    for deck_key, key in (("E", "E0"), ("ft", "ft"), ("alpha", "alpha"), ("k_t", "k_t"),
                          ("k_c", "k_c")):
        if getattr(c, deck_key) is not None:
            overrides[key] = getattr(c, deck_key)
    overrides["f1"], overrides["f2"] = _surface_points(c.surface.f1_ratio, c.surface.f2_ratio)
    if "k_t" in overrides:
        overrides.pop("Gf")
    return derive_concrete_parameters(c.fc, h_c, **overrides)


def _surface_points(f1_ratio: float, f2_ratio: float):
    from icewall.materials.ultimate_surface import hydrostatic_points

    return hydrostatic_points(f1=f1_ratio, f2=f2_ratio)


def build_groups(deck: Deck, cell_material: np.ndarray, gauss_spacing: np.ndarray,
                 n_gauss_points: int, linear: bool = False) -> tuple[MaterialGroup, ...]:
    """One group per deck material present in the mesh; `linear` makes every law elastic."""
    formulation = deck.analysis.formulation
    groups = []
    for name in ("concrete", "steel", "bearing_plates", "legs"):
        cells = np.flatnonzero(cell_material == name)
        if cells.size == 0:
            continue
        n_points = cells.size * n_gauss_points
        if name == "concrete":
            params = concrete_parameters(deck, float(np.mean(gauss_spacing[cells])))
            model = deck.materials.concrete.model
            if model == "rotating_crack" and not linear:
                groups.append(_concrete_group(deck, cells, params, gauss_spacing, n_gauss_points))
                continue
            E, nu = params.E0, deck.materials.concrete.nu
        elif name == "steel":
            steel = deck.materials.steel
            if steel.model == "von_mises" and not linear:
                groups.append(_steel_group(deck, cells, n_points))
                continue
            E, nu, model = steel.E, steel.nu, "elastic"
        else:
            props = getattr(deck.materials, name)
            E, nu, model = props.E, props.nu, "elastic"
        groups.append(MaterialGroup(name, "elastic", cells, _elastic_law,
                                    ElasticParameters(elastic_moduli(E, nu, formulation)), None))
    return tuple(groups)


def _concrete_group(deck: Deck, cells: np.ndarray, params: ConcreteParameters,
                    gauss_spacing: np.ndarray, n_gauss_points: int) -> MaterialGroup:
    from icewall.materials.concrete import ConcreteState, concrete_tangent
    from icewall.materials.concrete_compiled import (
        choose_kernel,
        compiled_floored_moduli,
        compiled_substepped,
    )
    from icewall.materials.concrete_tangent import tangent_of_update, update_with_tangent
    from icewall.materials.substep import update_concrete_substepped

    c = deck.materials.concrete
    fixed = {key: getattr(c, key) for key in ("k_t", "k_c") if getattr(c, key) is not None}
    h_points = np.repeat(gauss_spacing[cells], n_gauss_points)
    point_params = concrete_point_parameters(params, h_points, fixed)
    formulation = deck.analysis.formulation
    max_step = c.substep_ratio * params.eps_t  # sub-steps of a fraction of the cracking strain
    floor = deck.analysis.iteration_stiffness_floor
    trial_kind = c.trial_stress
    tangent = deck.analysis.concrete_stiffness == "tangent"
    coaxial = deck.analysis.concrete_stiffness == "secant-coaxial"

    own_moduli = not tangent and (floor > 0.0 or coaxial)  # built here from the trial state
    # $ICEWALL_CONCRETE_KERNEL: the same update and moduli compiled (the deck's differenced
    # `tangent` stays NumPy; law(..., tangent=True) differentiates the compiled update)
    kernel = choose_kernel(formulation, trial_kind) if own_moduli else "numpy"

    def compiled_update(strain, state, p, formulation, trial_stress, with_moduli=False):
        stress, trial = compiled_substepped(strain, state, p, formulation, max_step,
                                            trial_stress=trial_stress)
        return stress, None, trial

    def numpy_update(strain, state, p, formulation, trial_stress, with_moduli=False):
        return update_concrete_substepped(strain, state, p, formulation, max_step,
                                          trial_stress=trial_stress, with_moduli=with_moduli)

    def consistent(strain, state, p, frozen, update):
        """The same update, with its consistent tangent as moduli (concrete_tangent)."""
        if frozen is not None:
            raise ValueError("the consistent concrete tangent is not defined for frozen points")
        return update_with_tangent(strain, state, p, formulation, trial_kind, update)

    def tangent_of(strain, stress, trial, state, p):
        """The consistent tangent at an update already made (concrete_tangent)."""
        return tangent_of_update(strain, stress, trial, state, p, formulation, trial_kind,
                                 compiled_update if kernel == "numba" else numpy_update)

    def compiled_law(strain, state, p, frozen=None, returned_secant=False, tangent=False):
        if tangent:
            return consistent(strain, state, p, frozen, compiled_update)
        stress, trial = compiled_substepped(strain, state, p, formulation, max_step,
                                            trial_stress=trial_kind, frozen=frozen)
        return stress, compiled_floored_moduli(trial, p, formulation, floor, coaxial,
                                               returned_secant), trial

    def law(strain, state, p, frozen=None, returned_secant=False, tangent=False):
        if tangent:
            return consistent(strain, state, p, frozen, numpy_update)
        stress, moduli, trial = update_concrete_substepped(strain, state, p, formulation,
                                                           max_step, trial_stress=trial_kind,
                                                           frozen=frozen,
                                                           with_moduli=not (tangent or own_moduli))
        if tangent:
            moduli = concrete_tangent(strain, state, p, formulation, trial_stress=trial_kind,
                                      frozen=frozen)
        elif own_moduli:
            moduli = floored_moduli(trial, p, formulation, floor, coaxial, returned_secant)
        return stress, moduli, trial

    return MaterialGroup("concrete", "rotating_crack", cells,
                         compiled_law if kernel == "numba" else law, point_params,
                         ConcreteState.initial(h_points.size, params), freezable=True,
                         kernel=kernel, tangent_switch=True,
                         tangent_of=tangent_of)


def coaxial_shear_modulus(state: Any) -> np.ndarray:
    """G = (sigma_1 - sigma_2) / (2 (eps_1 - eps_2)) (errata §3): the shear stiffness that keeps
    stress and strain co-axial, i.e. the one the rotating-crack stress update really has."""
    s, e = state.stress, state.strain
    sign = np.sign((s[:, 0] - s[:, 1]) * (e[:, 0] - e[:, 1]) + s[:, 3] * e[:, 3])
    stress_radius = np.hypot(s[:, 0] - s[:, 1], 2.0 * s[:, 3])
    strain_radius = np.hypot(e[:, 0] - e[:, 1], e[:, 3])
    with np.errstate(divide="ignore", invalid="ignore"):
        G = sign * stress_radius / (2.0 * strain_radius)
    return np.where(strain_radius > 1e-12, G, state.shear_modulus)


def floored_moduli(state: Any, params: Any, formulation: str, floor: float,
                   coaxial: bool = False, returned_secant: bool = False) -> np.ndarray:
    """Secant moduli of `state` with E_i and G12 held above `floor` times their initial values.

    Only the iteration matrix changes, never the stresses: a fully cracked point (E_i, and by
    eq. 3.21 G12, near zero) would otherwise leave the secant stiffness matrix nearly singular
    and the iteration wandering through near-mechanisms. `returned_secant`: E_i no stiffer than
    the secant of the stress the update returned (concrete.matrix_secant; a fallback of the
    solver, solve.control._schemes).
    """
    from icewall.materials.concrete import matrix_secant
    from icewall.materials.orthotropic import (
        condense_plane_stress,
        global_moduli,
        orthotropic_normal_stiffness,
    )

    E0, nu0 = float(params.E0), float(params.nu0)
    secant = matrix_secant(state) if returned_secant else state.secant_modulus
    normal = orthotropic_normal_stiffness(np.maximum(secant, floor * E0), state.poisson_ratio)
    if formulation == "plane_stress":
        normal = condense_plane_stress(normal)
    G0 = E0 / (2.0 * (1.0 + nu0))
    shear = coaxial_shear_modulus(state) if coaxial else state.shear_modulus
    shear = np.clip(shear, floor * G0, G0)
    return global_moduli(normal, shear, state.angle)


def _steel_group(deck: Deck, cells: np.ndarray, n_points: int) -> MaterialGroup:
    from icewall.materials.steel import SteelState, steel_parameters, update_steel

    s = deck.materials.steel
    formulation = deck.analysis.formulation if s.formulation == "same" else s.formulation
    params = steel_parameters(s.E, s.nu, s.fy, hardening_ratio=s.hardening,
                              formulation=formulation, fy_reduction=s.fy_reduction)
    return MaterialGroup("steel", "von_mises", cells, update_steel, params,
                         SteelState.initial(n_points))
