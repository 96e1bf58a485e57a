"""Deck format v1: every option with its type, default, unit and one-line doc, in one place.

Positions along the wall (diaphragms, supports, legs, load patches, control point) are
distances x >= 0 from midspan; v1 specimens are symmetric about midspan and every list is
mirrored (x and -x; x = 0 once). Units: N, mm, MPa.
"""

from __future__ import annotations

from dataclasses import dataclass

from icewall.deck.analysis_options import Analysis
from icewall.deck.fields import option

FORMAT_VERSION = 1


@dataclass(frozen=True, kw_only=True)
class Reference:
    """Reference values in the deck's load measure (optional; withheld values stay absent)."""

    ultimate_test: float | None = option(None, doc="ultimate load measured in the test")
    residual_test: float | None = option(None, doc="residual load measured in the test")
    ultimate_thesis: float | None = option(None, doc="ultimate load of the thesis' FEA")
    residual_thesis: float | None = option(None, doc="residual load of the thesis' FEA")
    source: str = option("", doc="where these numbers come from")


@dataclass(frozen=True, kw_only=True)
class Specimen:
    name: str = option(doc="specimen name, e.g. CF-4; also names the result file")
    series: str = option("custom", doc="test series", choices=("CF", "TF", "VTT", "custom"))
    description: str = option("", doc="free text")
    reference: Reference = option(Reference(), doc="test and thesis reference values")


@dataclass(frozen=True, kw_only=True)
class Diaphragms:
    thickness: float = option(doc="diaphragm plate thickness t_d", unit="mm",
                              exclusive_minimum=0.0)
    positions: tuple[float, ...] = option([], doc="centreline x of each diaphragm from midspan "
                                          "(mirrored)", unit="mm", minimum=0.0)


@dataclass(frozen=True, kw_only=True)
class Support:
    x: float = option(doc="support centreline from midspan (mirrored)", unit="mm", minimum=0.0)
    bearing_plate_width: float = option(75.0, doc="width of the stiff bearing plate under the "
                                        "support (0 = none)", unit="mm", minimum=0.0)
    bearing_plate_thickness: float = option(25.0, doc="thickness of the bearing plate",
                                            unit="mm", exclusive_minimum=0.0)
    restraint: str = option("roller", doc="roller: u_y = 0; pin: u_x = u_y = 0",
                            choices=("roller", "pin"))
    level: str = option("underside", doc="underside: lowest material at x (bearing plate or "
                        "leg); wall: underside of the bottom plate (tie-downs)",
                        choices=("underside", "wall"))


@dataclass(frozen=True, kw_only=True)
class Leg:
    x: float = option(doc="leg centreline from midspan (mirrored)", unit="mm", minimum=0.0)
    length: float = option(doc="leg length along the wall (L_2)", unit="mm",
                           exclusive_minimum=0.0)
    height: float = option(doc="leg height below the wall (h_2)", unit="mm",
                           exclusive_minimum=0.0)


@dataclass(frozen=True, kw_only=True)
class Geometry:
    """Steel-concrete-steel sandwich beam; y = 0 is the underside of the bottom plate."""

    model: str = option("half", doc="half model (symmetry at midspan) or full model",
                        choices=("half", "full"))
    depth: float = option(doc="overall depth h (plate to plate, outside faces)", unit="mm",
                          exclusive_minimum=0.0)
    width: float = option(doc="width b = out-of-plane thickness of the 2D model", unit="mm",
                          exclusive_minimum=0.0)
    top_plate: float = option(doc="top (loaded) plate thickness", unit="mm",
                              exclusive_minimum=0.0)
    bottom_plate: float = option(doc="bottom plate thickness", unit="mm", exclusive_minimum=0.0)
    span: float = option(doc="distance between the support centrelines", unit="mm",
                         exclusive_minimum=0.0)
    overhang: float = option(doc="from a support centreline to the outer face of the wall end",
                             unit="mm", minimum=0.0)
    end_plate: float = option(0.0, doc="thickness of the steel end plate / end cap closing "
                              "each end (0 = open end)", unit="mm", minimum=0.0)
    diaphragms: Diaphragms | None = option(None, doc="vertical diaphragm plates")
    supports: tuple[Support, ...] = option(doc="supports and tie-downs")
    legs: tuple[Leg, ...] = option([], doc="legs under the wall (TF series), linear elastic")

    @property
    def half_length(self) -> float:
        return 0.5 * self.span + self.overhang


@dataclass(frozen=True, kw_only=True)
class Surface:
    """Willam-Warnke five-parameter surface control points (errata §2.3, set B)."""

    name: str = option("willam-warnke-B", doc="calibration name (see materials docs)")
    calibration: str = option(
        "control_points", doc="control_points: r1 through f't, f_cb (biaxial_ratio) and f1, r2 "
        "through f'c and f2 (errata §2.3; set B by default); A_refit: errata §2.2 set A (Elwi & "
        "Murray 1979, the thesis 4.3.1's source) through its meridian values at sigma_bar = -1.5 "
        "and f_cb = 1.21, refitted through f't (biaxial_ratio, f1_ratio, f2_ratio unused); A: set "
        "A's fixed coefficients (implied f_t = 0.10 f'c, not the f't of the uniaxial curves)",
        choices=("control_points", "A_refit", "A"))
    biaxial_ratio: float = option(1.20, doc="equal-biaxial strength f_cb / f'c",
                                  exclusive_minimum=1.0)
    f1_ratio: float = option(1.45, doc="biaxial high-compression point f1/f'c on "
                             "hydrostatic stress sqrt(3) f'c (tensile meridian)",
                             exclusive_minimum=0.0)
    f2_ratio: float = option(1.725, doc="uniaxial high-compression point f2/f'c on "
                             "hydrostatic stress sqrt(3) f'c (compressive meridian)",
                             exclusive_minimum=0.0)


@dataclass(frozen=True, kw_only=True)
class Concrete:
    fc: float = option(doc="uniaxial compressive strength f'c", unit="MPa", minimum=10.0,
                       maximum=150.0)
    model: str = option("rotating_crack", doc="constitutive model",
                        choices=("rotating_crack", "elastic"))
    E: float | None = option(None, doc="initial modulus (default 4400 sqrt(f'c), eq. 4.1 mod.)",
                             unit="MPa", exclusive_minimum=0.0)
    ft: float | None = option(None, doc="tensile strength (default 0.33 sqrt(f'c), eq. 4.2)",
                              unit="MPa", exclusive_minimum=0.0)
    eps_c: float = option(0.0025, doc="strain at the uniaxial peak", exclusive_minimum=0.0,
                          maximum=0.02)
    nu: float = option(0.2, doc="initial Poisson's ratio", minimum=0.0, maximum=0.49)
    Gf: float = option(0.10, doc="tensile fracture energy G_f", unit="N/mm",
                       exclusive_minimum=0.0)
    alpha: float | None = option(None, doc="effectiveness factor at 1.5 % strain (default: "
                                 "fitted function of f'c)", exclusive_minimum=0.0, maximum=1.0)
    k_t: float | None = option(None, doc="tensile decay (default f't h_c / G_f, eq. 3.29)",
                               exclusive_minimum=0.0)
    k_c: float | None = option(None, doc="compressive decay (default eq. 3.34 corrected)",
                               exclusive_minimum=0.0)
    surface: Surface = option(Surface(), doc="ultimate-surface calibration")
    compression_tension_rule: str = option(
        "equal", doc="thesis 3.2.5 rule (b): in compression-tension states the compressive "
        "strength and strain are the uniaxial f'c, eps_c (equal), or at least those (floor: the "
        "errata's signed reading, under which out-of-plane confinement in plane strain raises "
        "them again), or at most those (cap: the rule read in magnitudes, 'set equal to ... if "
        "the calculated values ... are greater', a confined strut held at f'c; NumPy kernel, "
        "attribution runs)", choices=("equal", "floor", "cap"))
    mode_rule_band: float = option(
        0.0, doc="width of the band, as a fraction of f't, over which the 3.2.5 mode rules "
        "(b) and (c) blend in as a principal stress changes sign: a compressive strength "
        "moves from the surface's value to rule (b)'s as the largest tension grows from 0 to "
        "the band, a tensile one from rule (c)'s to the surface's as the largest compression "
        "does. 0 = the thesis' sharp rules, under which the strengths jump at a sign change "
        "and the converged (newton) scheme may find no equilibrium next to such a point",
        minimum=0.0, maximum=10.0)
    post_peak_strength: str = option(
        "ray", doc="the strength sigma_ic and peak strain eps_ic of a principal direction "
        "past its peak (cracked in tension, crushed in compression, on the same branch): ray "
        "= read again on the ray of the trial stress to the 3.2.4 ultimate surface at every "
        "update, as for a direction before its peak (Fig. 3.12 step 5, errata 1.3); peak = "
        "kept from where the direction passed its peak, so its softening branch (eq. 3.11, "
        "whose area sigma_ic / k is the energy of eqs. 3.26-3.30) no longer moves with the "
        "other stresses and its stress is continuous where it turns from unloading to "
        "loading", choices=("ray", "peak"))
    fallen_strength: str = option(
        "envelope", doc="a principal direction that loads again (|eps_iu| past its maximum) "
        "where the envelope on its new ray lies below its secant line at that maximum (its "
        "strength has fallen since it was committed): envelope = onto that envelope, as Fig. "
        "3.12 step 6 reads (the stress jumps down where it turns from unloading to loading, "
        "and no equilibrium need exist next to that point); scaled = along the new envelope "
        "scaled through the committed point (sigma = sigma_env(eps) E_i max|eps_iu| / "
        "sigma_env(max|eps_iu|)): continuous, the same law on a fixed ray, and past the peak "
        "the exponential decay of eq. 3.11 from the stress the point has, so that the energy "
        "it dissipates is sigma / k of eqs. 3.26-3.30; and a closing crack (a crushed "
        "direction in tension) leaves its secant line where it meets the envelope on its ray, "
        "the one it then follows (under envelope: where it meets the uniaxial envelope, and "
        "the stress jumps onto the ray's)", choices=("envelope", "scaled"))
    rotating_axes: str = option(
        "nearest", doc="the rotating axes of orthotropy (3.2.2: they follow the principal "
        "strain axes, stress and strain co-axial): nearest = of the two labellings of the new "
        "axes the one nearest the committed axes keeps directions 1 and 2 and their damage "
        "(where the axes turn by 45 degrees within an increment the labelling swaps and the "
        "stress jumps; where the in-plane strain is nearly isotropic the stress of a point "
        "damaged in one direction turns with axes the strain hardly defines, a shear stiffness "
        "(s1 - s2) / (2 (e1 - e2)) without bound); continuous = direction 1 on the major "
        "principal strain (the crack normal to it) and that shear stiffness bounded by the "
        "virgin G0 = E0 / (2 (1 + nu0)), the principal stresses drawn together, their mean "
        "kept: the stress is a continuous function of the strain",
        choices=("nearest", "continuous"))
    trial_stress: str = option(
        "corotational", doc="trial stress of Fig. 3.12 step 3: corotational = committed "
        "principal stresses carried with the rotating axes plus C dEps between the committed "
        "and the new principal strains (consistent: a zero increment returns the committed "
        "stress; no committed stress leaks into an open crack); incremental = committed "
        "stress rotated into the new axes plus C dEps (as printed, forward Euler, "
        "sub-stepped); total = committed secant matrix times the total strain (older default: "
        "not consistent once nu has grown by eq. 3.19, which can let the iteration jump to "
        "spurious all-cracked states)", choices=("corotational", "incremental", "total"))
    density: float = option(2.4e-9, doc="mass density (normal-weight concrete, 2400 kg/m^3) "
                            "for the inertia of dynamic drops; N, mm, s, t: 1 N = 1 t mm/s^2",
                            unit="t/mm^3", minimum=0.0, maximum=1e-7)
    nu_max: float = option(0.49, doc="limit of Poisson's ratio, eqs. 3.19-3.20 (3.2.6: 'the "
                           "incompressible limit of 0.5 is retained'; default below it, errata "
                           "§3: at 0.5 eq. 3.3d's phi vanishes in triaxial compression and "
                           "eq. 3.2 is singular, phi then floored at 1e-3)", minimum=0.25,
                           maximum=0.5)
    printed_forms: tuple[str, ...] = option(
        [], doc="errata §1 corrections replaced by the thesis' printed form (attribution runs, "
        "docs/thesis_reproduction.md): eq3.2 (the orthotropic matrix without its 1/phi), eq3.3d "
        "(phi with 2 eta31^3), eq3.11a (tension branch decays from the compressive "
        "peak strain eps_c, a plateau at f't up to it), eq3.13 (printed Lode angle, 60 deg - "
        "theta: the meridians swapped), eq3.26 (descending area integrated from 0: k solves "
        "k exp(-k eps_peak) = sigma h_c / G), eq3.34 (k_c without the exponent 1.25), "
        "fig3.12_step5 (strengths on the ray of the committed stress, not the trial stress); "
        "the point-update forms run on the NumPy kernel",
        choices=("eq3.2", "eq3.3d", "eq3.11a", "eq3.13", "eq3.26", "eq3.34", "fig3.12_step5"))
    compression_branch: str = option(
        "exponential", doc="descending branch in compression: exponential (eq. 3.11b) or linear "
        "(Appendix A, Fig. A.5: 'A linear descending branch was used in all analyses'), to zero "
        "at eps_ic + 2 sigma_ic / k_c, the same area sigma_ic / k_c (NumPy kernel)",
        choices=("exponential", "linear"))
    substep_ratio: float = option(0.5, doc="largest strain sub-step of the stress update, as a "
                                  "fraction of the cracking strain f't/E (forward-Euler "
                                  "accuracy of Fig. 3.12 over large increments); only "
                                  "trial_stress incremental is sub-stepped",
                                  exclusive_minimum=0.0, maximum=1000.0)


@dataclass(frozen=True, kw_only=True)
class Steel:
    fy: float = option(doc="yield stress f_y", unit="MPa", exclusive_minimum=0.0,
                       maximum=2000.0)
    E: float = option(200000.0, doc="Young's modulus E_s", unit="MPa", exclusive_minimum=0.0)
    nu: float = option(0.3, doc="Poisson's ratio", minimum=0.0, maximum=0.49)
    hardening: float = option(0.02, doc="hardening slope as a fraction of E_s (thesis 4.3.2)",
                              minimum=0.0, maximum=1.0)
    model: str = option("von_mises", doc="constitutive model", choices=("von_mises", "elastic"))
    formulation: str = option("same", doc="same: the analysis formulation; plane_stress: "
                              "plates free to expand out of plane while the concrete is plane "
                              "strain (thesis 5.3, CF-8)", choices=("same", "plane_stress"))
    fy_reduction: float = option(0.0, doc="fraction by which f_y is reduced (the thesis' "
                                 "CF-8 work-around for plane-stress plates: 0.111)",
                                 minimum=0.0, maximum=0.9)
    density: float = option(7.85e-9, doc="mass density (steel, 7850 kg/m^3) for the inertia "
                            "of dynamic drops; N, mm, s, t: 1 N = 1 t mm/s^2", unit="t/mm^3",
                            minimum=0.0, maximum=1e-7)


@dataclass(frozen=True, kw_only=True)
class Elastic:
    E: float = option(200000.0, doc="Young's modulus", unit="MPa", exclusive_minimum=0.0)
    nu: float = option(0.3, doc="Poisson's ratio", minimum=0.0, maximum=0.49)
    density: float = option(7.85e-9, doc="mass density (steel, 7850 kg/m^3) for the inertia "
                            "of dynamic drops; N, mm, s, t: 1 N = 1 t mm/s^2", unit="t/mm^3",
                            minimum=0.0, maximum=1e-7)


FIXED_POINT_PLACEMENTS = ("top", "corners", "bottom_support", "station")
"""Where `Interface.fixed_point_placement` may put fixed pairs (icewall.interface.fixed_points)."""


@dataclass(frozen=True, kw_only=True)
class Interface:
    model: str = option("gap", doc="gap: double nodes with gap elements (thesis 3.3); "
                        "bonded: steel and concrete share nodes", choices=("gap", "bonded"))
    friction: float = option(0.5773, doc="Coulomb friction coefficient (30 deg)", minimum=0.0,
                             maximum=2.0)
    reset_slip_each_step: bool = option(True, doc="slipped pairs start every step fixed "
                                        "(thesis 3.3.4)")
    max_state_changes: int = option(6, doc="state changes a pair may make within one step "
                                    "before it is frozen for the rest of the step (limit "
                                    "cycles); the equilibrium norms still decide convergence",
                                    minimum=1)
    fixed_points_per_core: int = option(0, doc="permanently fixed pairs per core (per face "
                                        "of it: fixed_point_placement) (thesis 4.3.2's way to "
                                        "keep a core from "
                                        "floating; they act as shear connectors and carry far "
                                        "more shear than friction allows)", minimum=0,
                                        maximum=10)
    fixed_point_placement: tuple[str, ...] = option(
        ["top"], doc="where fixed pairs stand, any of: top (fixed_points_per_core pairs at "
        "each core's top-face mid-length), corners (every core corner at the diaphragm-plate "
        "junctions), bottom_support (fixed_points_per_core bottom-face pairs each side of "
        "each support), station (fixed_points_per_core pairs on each core's top face and as "
        "many on its bottom face, at its mid-length: the core held at one station); thesis "
        "4.3.2, Fig. 4.15 lost (icewall.interface.fixed_points)")
    stabilization: float = option(1e-6, doc="weak springs between paired nodes in the "
                                  "iteration matrix only (relative to the largest stiffness "
                                  "diagonal): keep a core whose pairs all open in an iterate "
                                  "from floating, without changing the converged state",
                                  minimum=0.0, maximum=1e-2)
    friction_update: str = option("implicit", doc="implicit: the Coulomb condition of a "
                                  "slipping pair is a row of the augmented system; lagged: the "
                                  "thesis' T = sign(lam_T) mu |lam_N| - lam_T from the previous "
                                  "iterate (eq. 3.41, errata)", choices=("implicit", "lagged"))
    slip_reversal: str = option("stick", doc="a slipping pair whose slip in the step opposes "
                                "its friction force: stick (back to fixed where it is), reverse "
                                "(flip the friction force) or none (the thesis: 3.41 keeps the "
                                "sign for the whole step, which can dissipate negative work)",
                                choices=("stick", "reverse", "none"))


@dataclass(frozen=True, kw_only=True)
class Materials:
    concrete: Concrete = option(doc="concrete infill")
    steel: Steel = option(doc="plates and diaphragms")
    bearing_plates: Elastic = option(Elastic(), doc="bearing plates (linear elastic steel)")
    legs: Elastic = option(Elastic(), doc="legs, idealised linear elastic (thesis 4.3.2)")
    interface: Interface = option(Interface(), doc="steel-concrete interface")


@dataclass(frozen=True, kw_only=True)
class Patches:
    positions: tuple[float, ...] = option(doc="centre x of each jack/pressure patch on the top "
                                          "plate (mirrored)", unit="mm", minimum=0.0)
    width: float = option(50.0, doc="patch width along the span", unit="mm",
                          exclusive_minimum=0.0)


@dataclass(frozen=True, kw_only=True)
class Measure:
    kind: str = option("total", doc="intensity: w = P / (b * tributary_length) (CF); total: "
                       "sum of all patch loads of the whole specimen (TF, VTT)",
                       choices=("intensity", "total"))
    tributary_length: float | None = option(None, doc="jack spacing for kind = intensity",
                                            unit="mm", exclusive_minimum=0.0)


@dataclass(frozen=True, kw_only=True)
class Preload:
    axial_force: float = option(doc="in-plane axial force N on the wall ends (negative = "
                                "compression), applied first and held", unit="N")


@dataclass(frozen=True, kw_only=True)
class Control:
    x: float = option(0.0, doc="control point on the top surface, from midspan", unit="mm",
                      minimum=0.0)
    increment: float = option(1.0, doc="control displacement increment", unit="mm",
                              exclusive_minimum=0.0)
    target: float = option(40.0, doc="final control displacement (downward)", unit="mm",
                           exclusive_minimum=0.0)
    drop_held: str = option(
        "deflection", doc="scheme newton: what a drop past a snap-back holds while the load "
        "falls, as the test's loading system does: deflection (the control deflection, eq. "
        "3.48) or stroke (the load-weighted mean deflection under the patches, sum P_i u_i / "
        "sum P_i: the stroke of a loading head that drives the patches through a distribution "
        "beam, as in the TF tests, thesis 4.2.2: 'Stroke control was used')",
        choices=("deflection", "stroke"))
    head_mass: float = option(0.0, doc="mass of the loading head or distribution beam that "
                              "moves with the patches (0: none), lumped on the loaded nodes in "
                              "proportion to their load; it acts in dynamic drops only (N, "
                              "mm, s, t)", unit="t", minimum=0.0)


@dataclass(frozen=True, kw_only=True)
class Loads:
    patches: Patches = option(doc="jack loads as pressure patches, all with the same load P")
    measure: Measure = option(Measure(), doc="how the reported load is computed from P")
    preload: Preload | None = option(None, doc="in-plane preload (TF series)")
    control: Control = option(Control(), doc="displacement control")


@dataclass(frozen=True, kw_only=True)
class Outputs:
    fields: tuple[str, ...] = option(["displacement", "stress", "strain"],
                                     doc="what is written per step (state: concrete "
                                     "crack/crush flags and orthotropy angle, steel plastic "
                                     "strain and the interface pair arrays; needed by the crack, "
                                     "deformed-shape and interface plots)",
                                     choices=("displacement", "stress", "strain", "state"))
    every: int = option(1, doc="write the fields every N steps (history: every step)",
                        minimum=1)
    directory: str = option("results", doc="output directory (relative to the working dir)")


@dataclass(frozen=True, kw_only=True)
class Deck:
    version: int = option(doc="deck format version", choices=(FORMAT_VERSION,))
    specimen: Specimen = option(doc="identification and reference values")
    geometry: Geometry = option(doc="section geometry")
    materials: Materials = option(doc="material parameters")
    loads: Loads = option(doc="loads and displacement control")
    analysis: Analysis = option(Analysis(), doc="analysis settings")
    outputs: Outputs = option(Outputs(), doc="what to write")
