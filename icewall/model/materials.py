"""Material groups of a model: which cells use which constitutive law (materials.law), with
what parameters; the deck's material models are mapped to law objects here, once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, make_dataclass
from typing import Any

import numpy as np

from icewall.deck.analysis_options import Analysis
from icewall.deck.schema import Concrete, Steel
from icewall.materials.concrete_compiled import choose_kernel
from icewall.materials.concrete_law import ConcreteLaw
from icewall.materials.elastic import ElasticLaw, elastic_moduli
from icewall.materials.law import MaterialLaw
from icewall.materials.parameters import (
    POINT_FORMS,
    ConcreteParameters,
    derive_concrete_parameters,
    printed_lower_limit_decay,
)
from icewall.materials.steel import SteelLaw, steel_parameters
from icewall.materials.ultimate_surface import (
    SET_A_ELWI_MURRAY,
    elwi_murray_refit,
    hydrostatic_points,
)
from icewall.model.description import MATERIAL_KEYS, ModelDescription


@dataclass(frozen=True)
class MaterialGroup:
    """The cells of one deck material and the law that updates their Gauss points."""

    name: str  # deck material key: concrete, steel, bearing_plates, legs
    cells: np.ndarray  # (n_cells,) element indices, sorted
    law: MaterialLaw


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
    printed = "eq3.26" in params.printed_forms  # k not proportional to h_c (errata §1.1)
    for key, eps in (("k_t", params.eps_t), ("k_c", params.eps_c)):
        k = getattr(params, key)
        if key in fixed_decay:
            values[key] = np.full_like(scale, fixed_decay[key])
        elif printed:  # back to the corrected k, scaled, then eq. 3.26 as printed per point
            values[key] = printed_lower_limit_decay(k * np.exp(-k * eps) * scale, eps)
        else:
            values[key] = k * scale
    return ConcretePointParameters(**values)


def concrete_parameters(c: Concrete, h_c: float) -> ConcreteParameters:
    """A deck's concrete section with every thesis 4.3.1 default and the section's overrides."""
    overrides: dict[str, Any] = {"eps_c": c.eps_c, "nu0": c.nu, "Gf": c.Gf,
                                 "fcb_ratio": c.surface.biaxial_ratio,
                                 "compression_tension_rule": c.compression_tension_rule,
                                 "mode_rule_band": c.mode_rule_band,
                                 "post_peak_strength": c.post_peak_strength,
                                 "fallen_strength": c.fallen_strength,
                                 "rotating_axes": c.rotating_axes,
                                 "nu_max": c.nu_max, "printed_forms": tuple(c.printed_forms),
                                 "compression_branch": c.compression_branch}
    for deck_key, key in (("E", "E0"), ("ft", "ft"), ("alpha", "alpha"), ("k_t", "k_t"),
                          ("k_c", "k_c")):
        if getattr(c, deck_key) is not None:
            overrides[key] = getattr(c, deck_key)
    overrides["f1"], overrides["f2"] = _surface_points(c.surface.f1_ratio, c.surface.f2_ratio)
    if c.surface.calibration != "control_points":  # errata §2.2 set A, refitted or as fitted
        for key in ("fcb_ratio", "f1", "f2"):
            overrides.pop(key)
        ft = c.ft if c.ft is not None else 0.33 * math.sqrt(c.fc)  # eq. 4.2, as derived
        overrides["surface"] = (elwi_murray_refit(ft / c.fc) if c.surface.calibration == "A_refit"
                                else SET_A_ELWI_MURRAY)
    if "k_t" in overrides:
        overrides.pop("Gf")
    return derive_concrete_parameters(c.fc, h_c, **overrides)


def _surface_points(f1_ratio: float, f2_ratio: float):
    return hydrostatic_points(f1=f1_ratio, f2=f2_ratio)


def build_groups(description: ModelDescription, cell_material: np.ndarray,
                 gauss_spacing: np.ndarray, n_gauss_points: int, linear: bool = False
                 ) -> tuple[MaterialGroup, ...]:
    """One group per material present in the mesh; `linear` makes every law elastic."""
    groups = []
    for name in MATERIAL_KEYS:
        cells = np.flatnonzero(cell_material == name)
        if cells.size == 0:
            continue
        section = description.materials[name]
        h_c = float(np.mean(gauss_spacing[cells]))
        if name == "concrete" and section.model == "rotating_crack" and not linear:
            h_points = np.repeat(gauss_spacing[cells], n_gauss_points)
            law = _concrete_law(section, description.analysis,
                                concrete_parameters(section, h_c), h_points)
        elif name == "steel" and section.model == "von_mises" and not linear:
            law = _steel_law(section, description.analysis.formulation)
        else:
            E, nu = initial_elastic(name, section, h_c)
            law = ElasticLaw(elastic_moduli(E, nu, description.analysis.formulation))
        groups.append(MaterialGroup(name, cells, law))
    return tuple(groups)


def initial_elastic(name: str, section: Any, h_c: float) -> tuple[float, float]:
    """Initial E and nu of a material section (concrete: E0 of thesis 4.3.1, or the
    section's override, at the mean crack-band width `h_c` of its cells)."""
    if name == "concrete":
        return concrete_parameters(section, h_c).E0, section.nu
    return section.E, section.nu


def _concrete_law(c: Concrete, analysis: Analysis, params: ConcreteParameters,
                  h_points: np.ndarray) -> MaterialLaw:
    """A rotating-crack concrete section at points of crack-band widths `h_points`."""
    fixed = {key: getattr(c, key) for key in ("k_t", "k_c") if getattr(c, key) is not None}
    floor = analysis.iteration_stiffness_floor
    tangent = analysis.concrete_stiffness == "tangent"
    coaxial = analysis.concrete_stiffness == "secant-coaxial"
    own_moduli = not tangent and (floor > 0.0 or coaxial)  # built by the law from the trial state
    # $ICEWALL_CONCRETE_KERNEL: the same update and moduli compiled (the deck's differenced
    # `tangent` stays NumPy; update(..., tangent=True) differentiates the compiled update)
    # the printed point forms, the linear branch (App. A) and rule (b)'s cap: NumPy only
    numpy_only = (bool(set(c.printed_forms) & set(POINT_FORMS))
                  or c.compression_branch != "exponential" or c.compression_tension_rule == "cap")
    kernel = (choose_kernel(analysis.formulation, c.trial_stress)
              if own_moduli and not numpy_only else "numpy")
    return ConcreteLaw(concrete_point_parameters(params, h_points, fixed), analysis.formulation,
                       c.substep_ratio * params.eps_t,  # sub-steps of the cracking strain
                       c.trial_stress, floor, coaxial, own_moduli, kernel)


def _steel_law(s: Steel, analysis_formulation: str) -> MaterialLaw:
    formulation = analysis_formulation if s.formulation == "same" else s.formulation
    return SteelLaw(steel_parameters(s.E, s.nu, s.fy, hardening_ratio=s.hardening,
                                     formulation=formulation, fy_reduction=s.fy_reduction))
