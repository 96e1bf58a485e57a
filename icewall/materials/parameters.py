"""Concrete material parameters (thesis §4.3.1, eqs. 3.29-3.34, 4.1-4.3; errata §1.1, §2, §3).

Units: N, mm, MPa (G in N/mm). Eqs. 3.31 and 3.34 are dimensional fits valid only in these
units. Thesis values of Table 4.4 are kept in the tests, not here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, is_dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy.interpolate import PchipInterpolator

from icewall.materials.ultimate_surface import SET_B_CONTROL, WillamWarnkeSurface

#: Effectiveness factor alpha at 1.5 % strain (thesis Fig. 3.10, lost) as back-solved from the
#: k_c column of Table 4.4 with the corrected eq. 3.34 (errata §1.1; specimens.md):
#: (f'c MPa, alpha) = CF-5, TF-1, VTT-3, CF-4, CF-8, TF-4 (CF-13 56.0 and TF-2 55.0 also 0.30).
ALPHA_DATA = ((36.3, 0.40), (50.0, 0.32), (52.7, 0.31), (53.5, 0.30), (59.5, 0.30), (68.0, 0.28))
ALPHA_RANGE = (20.0, 120.0)


def _alpha_nodes() -> tuple[list[float], list[float]]:
    (x0, y0), (x1, y1) = ALPHA_DATA[0], ALPHA_DATA[1]
    (xm, ym), (xn, yn) = ALPHA_DATA[-2], ALPHA_DATA[-1]
    lo = y0 + (y1 - y0) / (x1 - x0) * (ALPHA_RANGE[0] - x0)  # end-secant extrapolation
    hi = yn + (yn - ym) / (xn - xm) * (ALPHA_RANGE[1] - xn)
    xs = [ALPHA_RANGE[0], *(x for x, _ in ALPHA_DATA), ALPHA_RANGE[1]]
    return xs, [lo, *(y for _, y in ALPHA_DATA), hi]


_ALPHA = PchipInterpolator(*_alpha_nodes(), extrapolate=False)


def effectiveness_factor(fc: ArrayLike) -> float | np.ndarray:
    """alpha(f'c): monotone (non-increasing) C1 PCHIP interpolant through ALPHA_DATA.

    The data points are matched exactly (so Table 4.4 k_c is reproduced). Outside 36.3-68 MPa
    the end secants are extended linearly to anchor nodes at 20 MPa (0.495) and 120 MPa
    (0.158), both extrapolations, not data; f'c is clamped into [20, 120] MPa, so alpha stays
    in [0.158, 0.495] and A_c of eq. 3.33 stays positive (alpha > 0.111 needed for eps_c 0.0025).
    """
    x = np.clip(np.asarray(fc, dtype=float), *ALPHA_RANGE)
    out = _ALPHA(x)
    return float(out) if np.ndim(out) == 0 else out


def crushing_energy(fc: float, alpha: float, eps_c: float = 0.0025) -> float:
    """G_cr (N/mm) = 209.2 A_c^1.25 (eq. 3.31), A_c = f'c (0.015 alpha - 0.667 eps_c) (3.33
    with eps_u = 0.015 and 2/3 written 0.667 as in 3.34)."""
    A_c = fc * (0.015 * alpha - 0.667 * eps_c)
    if A_c <= 0.0:
        raise ValueError(f"descending area A_c = {A_c:.4g} <= 0 (alpha={alpha}, eps_c={eps_c})")
    return 209.2 * A_c**1.25


@dataclass(frozen=True)
class ConcreteParameters:
    """Complete concrete description for one material/mesh (h_c) combination.

    fc, ft, E0 (MPa); eps_c uniaxial compressive peak strain; eps_t tensile peak strain
    (ft/E0: linear ascending branch, errata §3 "Tension peak strain is undefined"); nu0, nu_max
    (Poisson cap < 0.5, errata §3); Gf, G_cr (N/mm); alpha effectiveness factor; h_c crack-band
    width (mm, eq. 4.3); k_t, k_c decay parameters (1/strain); surface: Willam-Warnke strength
    surface; peak_strain_slope: m in eps_ic/eps_c = 1 + m (R - 1) (Darwin-Pecknold 3R - 2).
    """

    fc: float
    E0: float
    ft: float
    eps_c: float
    eps_t: float
    nu0: float
    Gf: float
    alpha: float
    G_cr: float
    h_c: float
    k_t: float
    k_c: float
    nu_max: float
    surface: WillamWarnkeSurface
    peak_strain_slope: float = 3.0
    # §3.2.5 rule (b) in compression-tension states: "equal" = the compressive parameters are
    # the uniaxial f'c, eps_c; "floor" = at least those (errata §3's signed reading); "cap" =
    # at most those (the rule read in magnitudes)
    compression_tension_rule: str = "equal"
    # width of the band of a principal stress, as a fraction of f't, over which rules (b) and
    # (c) of §3.2.5 blend in as it changes sign (0: the thesis' sharp rules, a jump)
    mode_rule_band: float = 0.0
    # sigma_ic, eps_ic of a direction past its peak: "ray" = read again on the trial stress's
    # ray at every update (errata 1.3, step 5); "peak" = kept from where it passed its peak
    post_peak_strength: str = "ray"
    # a loading direction whose envelope on the ray lies below its secant line at max |eps_iu|:
    # "envelope" = onto that envelope (Fig. 3.12 step 6; the stress jumps), "scaled" = the
    # envelope scaled through the committed point (continuous; concrete_formulas.scaled_envelope)
    fallen_strength: str = "envelope"
    # the principal axes' labelling and rotation stiffness: "nearest" = the labelling nearest
    # the committed axes; "continuous" = direction 1 on the major principal strain and the
    # rotating crack's shear stiffness bounded by G0 (rotation.py)
    rotating_axes: str = "nearest"
    # errata §1 corrections replaced by the printed form (deck printed_forms; PRINTED_FORMS)
    printed_forms: tuple[str, ...] = ()
    # descending branch in compression: "exponential" (eq. 3.11b) or "linear" (App. A)
    compression_branch: str = "exponential"

    def __post_init__(self) -> None:
        for name in ("fc", "E0", "ft", "eps_c", "eps_t", "Gf", "G_cr", "h_c", "k_t", "k_c"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0.0):
                raise ValueError(f"concrete parameter {name} must be finite and > 0, got {v}")
        if not 0.0 <= self.nu0 < self.nu_max <= 0.5:
            raise ValueError(f"need 0 <= nu0 < nu_max <= 0.5, got {self.nu0}, {self.nu_max}")
        if unknown := set(self.printed_forms) - set(PRINTED_FORMS):
            raise ValueError(f"unknown printed form(s) {sorted(unknown)}")
        if self.compression_branch not in ("exponential", "linear"):
            raise ValueError("compression_branch must be 'exponential' or 'linear'")
        if self.peak_strain_slope < 0.0:
            raise ValueError("peak_strain_slope must be >= 0")
        if self.compression_tension_rule not in ("equal", "floor", "cap"):
            raise ValueError("compression_tension_rule must be 'equal', 'floor' or 'cap'")
        if not (math.isfinite(self.mode_rule_band) and 0.0 <= self.mode_rule_band <= 10.0):
            raise ValueError(f"mode_rule_band must be in [0, 10], got {self.mode_rule_band}")
        if self.post_peak_strength not in ("ray", "peak"):
            raise ValueError("post_peak_strength must be 'ray' or 'peak', got "
                             f"{self.post_peak_strength!r}")
        if self.fallen_strength not in ("envelope", "scaled"):
            raise ValueError("fallen_strength must be 'envelope' or 'scaled', got "
                             f"{self.fallen_strength!r}")
        if self.rotating_axes not in ("nearest", "continuous"):
            raise ValueError("rotating_axes must be 'nearest' or 'continuous', got "
                             f"{self.rotating_axes!r}")

    @property
    def snap_back_tension(self) -> bool:
        """Softening slope k_t f't steeper than E0; with k_t = f't h_c/G_f (3.29) this is
        h_c > E0 G_f / f't^2."""
        return self.k_t * self.ft > self.E0

    @property
    def snap_back_compression(self) -> bool:
        """Softening slope k_c f'c steeper than E0, i.e. k_c > E0/f'c."""
        return self.k_c * self.fc > self.E0


PRINTED_FORMS = ("eq3.2", "eq3.3d", "eq3.11a", "eq3.13", "eq3.26", "eq3.34", "fig3.12_step5")
"""The errata §1 corrections whose printed form can run (deck materials.concrete.printed_forms)."""
POINT_FORMS = ("eq3.2", "eq3.3d", "eq3.11a", "eq3.13", "fig3.12_step5")
"""Printed forms of the point update (the NumPy kernel only; the others set k_t, k_c)."""

_DEFAULTS = ("E0", "ft", "eps_c", "eps_t", "nu0", "Gf", "alpha", "G_cr", "k_t", "k_c",
             "nu_max", "surface", "peak_strain_slope", "compression_tension_rule",
             "mode_rule_band", "post_peak_strength", "fallen_strength", "rotating_axes",
             "printed_forms",
             "compression_branch")


def printed_lower_limit_decay(k: ArrayLike, eps_peak: ArrayLike) -> np.ndarray:
    """Decay of eq. 3.26 as printed (lower limit 0, errata §1.1): the k with
    (sigma / k) exp(k eps_peak) = sigma / `k`, i.e. k exp(-k eps_peak) = k_corrected, the root
    below 1 / eps_peak (fixed point k <- k_corrected exp(k eps_peak), contracting there)."""
    target = np.asarray(k, dtype=float)
    eps = np.asarray(eps_peak, dtype=float)
    if np.any(target * eps >= 1.0 / math.e):
        raise ValueError("eq. 3.26 as printed has no decay for k eps_peak >= 1/e")
    out = target.copy()
    for _ in range(200):
        out = target * np.exp(out * eps)
    return out
_SURFACE_KEYS = ("fcb_ratio", "f1", "f2")


def derive_concrete_parameters(fc: float, h_c: float, **overrides: object) -> ConcreteParameters:
    """Thesis §4.3.1 parameters for f'c (MPa) and crack-band width h_c (mm).

    E0 = 4400 sqrt(f'c) (eq. 4.1 with MacGregor's 4400), ft = 0.33 sqrt(f'c) (4.2),
    eps_c = 0.0025, eps_t = ft/E0, nu0 = 0.2, nu_max = 0.49, Gf = 0.10 N/mm,
    alpha = effectiveness_factor(f'c), G_cr from eqs. 3.31/3.33, k_t = ft h_c/Gf (3.29),
    k_c = h_c / (209.2 f'c^0.25 (0.015 alpha - 0.667 eps_c)^1.25) (eq. 3.34 corrected per
    errata §1.1: exponent 1.25), surface = errata §2.3 set B through f't.

    Any of these may be overridden by keyword (dependants then use the override); also
    ``fcb_ratio``, ``f1``, ``f2`` (set-B-style control points) to refit the surface. Overriding
    k_t (k_c) alone sets Gf (G_cr) to the implied energy ft h_c/k_t (fc h_c/k_c).
    Unknown keywords raise TypeError.
    """
    unknown = sorted(set(overrides) - set(_DEFAULTS) - set(_SURFACE_KEYS))
    if unknown:
        raise TypeError(f"derive_concrete_parameters: unknown override(s) {', '.join(unknown)}")
    if fc <= 0.0 or h_c <= 0.0:
        raise ValueError(f"need fc > 0 and h_c > 0, got fc={fc}, h_c={h_c}")
    ov = dict(overrides)
    get = ov.get
    E0 = float(get("E0", 4400.0 * math.sqrt(fc)))  # eq. 4.1 (4400, MacGregor 1988)
    ft = float(get("ft", 0.33 * math.sqrt(fc)))  # eq. 4.2
    eps_c = float(get("eps_c", 0.0025))
    eps_t = float(get("eps_t", ft / E0))  # errata §3: linear branch to f't
    alpha = float(get("alpha", effectiveness_factor(fc)))
    if "k_t" in ov:
        k_t = float(ov["k_t"])  # type: ignore[arg-type]
        Gf = float(get("Gf", ft * h_c / k_t))
    else:
        Gf = float(get("Gf", 0.10))
        k_t = ft * h_c / Gf  # eq. 3.29 (from 3.27 corrected: sigma_t / k_t = G_f / h_c)
    printed = tuple(get("printed_forms", ()))  # type: ignore[arg-type]
    if "k_c" in ov:
        k_c = float(ov["k_c"])  # type: ignore[arg-type]
        G_cr = float(get("G_cr", fc * h_c / k_c))
    elif "G_cr" in ov:
        G_cr = float(ov["G_cr"])  # type: ignore[arg-type]
        k_c = fc * h_c / G_cr  # eq. 3.30
    else:
        G_cr = crushing_energy(fc, alpha, eps_c)  # eqs. 3.31, 3.33
        # eq. 3.34, corrected per errata §1.1 (exponent 1.25 on the bracket); "eq3.34": printed
        power = 1.0 if "eq3.34" in printed else 1.25
        k_c = h_c / (209.2 * fc**0.25 * (0.015 * alpha - 0.667 * eps_c) ** power)
        G_cr = fc * h_c / k_c if "eq3.34" in printed else G_cr
    if "eq3.26" in printed:  # the descending areas integrated from 0 (errata §1.1, eq. 3.26)
        if "k_t" not in ov:
            k_t = float(printed_lower_limit_decay(k_t, eps_t))
        if "k_c" not in ov:
            k_c = float(printed_lower_limit_decay(k_c, eps_c))
    surface = get("surface")
    if surface is None:
        ctrl = {**SET_B_CONTROL, **{k: ov[k] for k in _SURFACE_KEYS if k in ov}}
        surface = WillamWarnkeSurface.from_control_points(ft / fc, **ctrl)  # type: ignore[arg-type]
    elif any(k in ov for k in _SURFACE_KEYS):
        raise TypeError("give either surface or fcb_ratio/f1/f2, not both")
    return ConcreteParameters(
        fc=float(fc), E0=E0, ft=ft, eps_c=eps_c, eps_t=eps_t, nu0=float(get("nu0", 0.2)),
        Gf=Gf, alpha=alpha, G_cr=G_cr, h_c=float(h_c), k_t=k_t, k_c=k_c,
        nu_max=float(get("nu_max", 0.49)), surface=surface,  # type: ignore[arg-type]
        peak_strain_slope=float(get("peak_strain_slope", 3.0)),
        compression_tension_rule=str(get("compression_tension_rule", "equal")),
        mode_rule_band=float(get("mode_rule_band", 0.0)),
        post_peak_strength=str(get("post_peak_strength", "ray")),
        fallen_strength=str(get("fallen_strength", "envelope")),
        rotating_axes=str(get("rotating_axes", "nearest")), printed_forms=printed,
        compression_branch=str(get("compression_branch", "exponential")))


def take_parameters(params: Any, index: np.ndarray, n_points: int) -> Any:
    """The parameters of the points `index`: per-point arrays (n,) are indexed, scalars kept."""
    if not is_dataclass(params):
        return params
    changes = {}
    for f in fields(params):
        value = getattr(params, f.name)
        if isinstance(value, np.ndarray) and value.shape[:1] == (n_points,):
            changes[f.name] = value[index]
    return replace(params, **changes) if changes else params
