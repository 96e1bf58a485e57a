"""Willam-Warnke five-parameter ultimate surface and the strength scale on a stress ray.

Thesis §3.2.4 (eqs. 3.12-3.18) with the corrections of errata §1.1; calibration per
errata §2. Conventions: tension positive, principal stresses sigma1 >= sigma2 >= sigma3 (rows
are sorted here anyway), f'c > 0 a magnitude, units MPa.

Default calibration (errata §2.3, set B through f't = 0.33 sqrt(f'c)): convex and r2/2 < r1 <= r2
from the apex (sigma_bar ~ +0.04) down to sigma_bar = -2.35 (``sigma_limit``) for f'c = 20-120
MPa. Its f1 point (sigma_bar = -2.70) lies beyond that limit and is not reproduced. The
equivalent-uniaxial strengths and peak strains of §3.2.5 that use it are in `mode_rules`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from icewall.materials import concrete_formulas as formulas
from icewall.materials.concrete_formulas import (
    MAX_SCALE,
    NEWTON_ITERATIONS,
    NEWTON_TOLERANCE,
    elliptic_radius,
    elliptic_radius_slope,
    lode_arguments,
    meridian,
    newton_start,
    newton_step,
    ray_function,
    ray_value,
    unit_ray,
)

SQ215 = float(np.sqrt(2.0 / 15.0))  # tau_bar / sigma for a uniaxial state
Coef = tuple[float, float, float]


def hydrostatic_points(f1: float = 1.45, f2: float = 1.725, sigma_h: float = float(np.sqrt(3.0))
                       ) -> tuple[tuple[float, float], tuple[float, float]]:
    """(sigma_bar, tau_bar) of the ANSYS-style high-compression points (all / f'c).

    f1: equal-biaxial compression superposed on hydrostatic pressure sigma_h (tensile meridian);
    f2: uniaxial compression superposed on sigma_h (compressive meridian). Errata §2.2 set B.
    """
    return ((-sigma_h - 2.0 * f1 / 3.0, SQ215 * f1), (-sigma_h - f2 / 3.0, SQ215 * f2))


_P1, _P2 = hydrostatic_points()
#: Errata §2.2 set B / §2.3 recommendation (f_t supplied by the user: the thesis' own f't).
SET_B_CONTROL: dict[str, object] = {
    "fcb_ratio": 1.20, "f1": _P1, "f2": _P2, "name": "B: ANSYS TB,CONCR defaults",
    "source": "ANSYS TB,CONCR defaults attributed to Willam & Warnke (fcb=1.2, f1=1.45, "
              "f2=1.725 on sigma_h=sqrt(3) f'c); errata §2.2 set B, refitted through f't"}


def _real_roots(c: Coef) -> list[float]:
    r = np.roots([c[2], c[1], c[0]]) if abs(c[2]) > 1e-14 else np.roots([c[1], c[0]])
    return [float(v.real) for v in np.atleast_1d(r) if abs(v.imag) < 1e-12]


@dataclass(frozen=True)
class WillamWarnkeSurface:
    """Meridians r1 (tensile, theta = 0) = a0 + a1 s + a2 s^2 and r2 (compressive, 60 deg)
    = b0 + b1 s + b2 s^2 in the tau_bar form, s = sigma_bar (eq. 3.18), normalised by f'c.

    Below ``sigma_limit`` (the most compressive sigma_bar < -1/3 down to which r2/2 <= r1 <= r2
    and r2 > 0 hold; or ``sigma_cut`` if given) both meridians are held at their values there:
    an open cylinder, so rays such as hydrostatic compression never meet the surface. The
    extension is outside the calibration; it is continuous but not convex at the joint.
    """

    a: Coef
    b: Coef
    name: str = ""
    source: str = ""
    sigma_cut: float | None = None
    apex: float = field(init=False)
    sigma_limit: float = field(init=False)

    def __post_init__(self) -> None:
        a, b = self.a, self.b
        pos = [x for x in _real_roots(a) if x > 0.0]
        if a[0] <= 0.0 or b[0] <= 0.0 or not pos:
            raise ValueError(f"surface {self.name!r}: meridians must be > 0 at the origin "
                             "and r1 must close at a tensile apex")
        object.__setattr__(self, "apex", min(pos))
        diffs = [(a[0] - b[0], a[1] - b[1], a[2] - b[2]), b,
                 (a[0] - b[0] / 2, a[1] - b[1] / 2, a[2] - b[2] / 2)]
        lows = [x for c in diffs for x in _real_roots(c) if x < -1.0 / 3.0]
        lim = max(lows) if lows else -np.inf
        if self.sigma_cut is not None:
            lim = max(lim, float(self.sigma_cut))
        object.__setattr__(self, "sigma_limit", float(lim))

    def meridians(self, sigma_bar: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """(r1, r2) at sigma_bar (eq. 3.18), held constant below ``sigma_limit``."""
        s = np.maximum(np.asarray(sigma_bar, dtype=float), self.sigma_limit)
        return meridian(self.a, s), meridian(self.b, s)

    @classmethod
    def from_control_points(cls, ft_ratio: float, fcb_ratio: float = 1.20,
                            f1: tuple[float, float] = _P1, f2: tuple[float, float] = _P2,
                            name: str = "", source: str = "",
                            sigma_cut: float | None = None) -> WillamWarnkeSurface:
        """Solve eq. 3.18: r1 through f't (uniaxial tension), f_cb (equal biaxial compression)
        and f1 = (sigma_bar, tau_bar); r2 through f'c (uniaxial compression), f2 and the apex of
        r1 (common apex). All values / f'c."""
        pts1 = [(ft_ratio / 3.0, SQ215 * ft_ratio), (-2.0 * fcb_ratio / 3.0, SQ215 * fcb_ratio), f1]
        a = np.linalg.solve([[1.0, x, x * x] for x, _ in pts1], [y for _, y in pts1])
        apex = min(x for x in _real_roots(tuple(a)) if x > 0.0)
        pts2 = [(-1.0 / 3.0, SQ215), f2, (apex, 0.0)]
        b = np.linalg.solve([[1.0, x, x * x] for x, _ in pts2], [y for _, y in pts2])
        return cls(tuple(map(float, a)), tuple(map(float, b)), name, source, sigma_cut)


def default_surface(ft_ratio: float) -> WillamWarnkeSurface:
    """Errata §2.3 default: set B control points refitted through f't/f'c = ``ft_ratio``."""
    return WillamWarnkeSurface.from_control_points(ft_ratio, **SET_B_CONTROL)  # type: ignore[arg-type]


#: Errata §2.2 set A, fixed coefficients (implied f_t = 0.100 f'c, f_cb = 1.210 f'c).
SET_A_ELWI_MURRAY = WillamWarnkeSurface(
    (0.053627, -0.512079, -0.038226), (0.095248, -0.891175, -0.244420),
    name="A: Elwi & Murray (1979) fit to Schickert-Winkler",
    source="Mander, Priestley & Park (1988), coefficients via Mander.py (P. Zhang); errata §2.2")


def elwi_murray_refit(ft_ratio: float) -> WillamWarnkeSurface:
    """Set A's meridian values at sigma_bar = -1.5 and f_cb = 1.21, refitted through f't."""
    r1, r2 = SET_A_ELWI_MURRAY.meridians(-1.5)
    return WillamWarnkeSurface.from_control_points(
        ft_ratio, 1.21, (-1.5, float(r1)), (-1.5, float(r2)), name="A refitted to f't",
        source=SET_A_ELWI_MURRAY.source)


def _sorted(principal: ArrayLike) -> np.ndarray:
    p = np.atleast_2d(np.asarray(principal, dtype=float))
    return -np.sort(-p, axis=1)


def octahedral_invariants(principal: ArrayLike, fc: float) -> tuple[np.ndarray, np.ndarray]:
    """(sigma_bar, tau_bar): eq. 3.12a and eq. 3.12b corrected per errata §1.1,
    tau_bar = sqrt(s_ij s_ij / 5) / f'c (uniaxial compression -> (-1/3, sqrt(2/15)))."""
    p = _sorted(principal)  # columns, not axis-1 reductions: several times faster
    mean, tau = formulas.octahedral_invariants(p[:, 0], p[:, 1], p[:, 2])
    return mean / fc, tau / fc


def lode_angle(principal: ArrayLike) -> np.ndarray:
    """Angle of similarity theta in [0, 60 deg] (radians), eq. 3.13 corrected per errata §1.1:
    cos theta = (2 s1 - s2 - s3) / (sqrt2 sqrt((s1-s2)^2 + (s2-s3)^2 + (s3-s1)^2)).
    0 for uniaxial tension / equal biaxial compression, 60 deg for uniaxial compression.
    Computed as atan2(sqrt3 (s2 - s3), 2 s1 - s2 - s3); hydrostatic states return 0."""
    p = _sorted(principal)
    x, y, defined = lode_arguments(p[:, 0], p[:, 1], p[:, 2])
    return formulas.lode_angle(np.arctan2(y, x), defined)


def meridian_radius(theta: ArrayLike, r1: ArrayLike, r2: ArrayLike, *,
                    return_clamped: bool = False) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """Elliptic deviatoric trace r(theta), eq. 3.16 corrected per errata §1.1 (numerator
    2 r2 (r2^2 - r1^2) cos theta), r12 of eq. 3.17. r(0) = r1, r(60 deg) = r2.

    r1 is clamped into [r2/2, r2] (convexity; errata §3) and points so clamped are flagged.
    Where r2 <= 0 (beyond the apex) r = min(r1, r2) <= 0, i.e. outside the surface.
    """
    th, r1a, r2a = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (theta, r1, r2)))
    r = elliptic_radius(np.cos(th), r1a, r2a)
    if not return_clamped:
        return r
    tol = 1e-12 * np.abs(r2a)
    return r, (r2a > 0.0) & ((r1a < 0.5 * r2a - tol) | (r1a > r2a + tol))


def failure_function(principal: ArrayLike, fc: float, surface: WillamWarnkeSurface
                     ) -> np.ndarray:
    """f = tau_bar - r(theta, sigma_bar) (eq. 3.15): < 0 inside, 0 on the surface."""
    sb, tb = octahedral_invariants(principal, fc)
    r1, r2 = surface.meridians(sb)
    return tb - meridian_radius(lode_angle(principal), r1, r2)


def _ray_function(t: np.ndarray, sb: np.ndarray, tb: np.ndarray, c: np.ndarray,
                  surface: WillamWarnkeSurface, slope: bool = True
                  ) -> tuple[np.ndarray, np.ndarray | None]:
    """f(t) = t tau_bar - r(theta, r1(t sigma_bar), r2(t sigma_bar)) on the unit ray (sigma_bar,
    tau_bar, cos theta) and, with ``slope``, df/dt (the meridians are held below ``sigma_limit``:
    zero slope there)."""
    if not slope:
        return ray_value(t, sb, tb, c, surface.a, surface.b, surface.sigma_limit), None
    return ray_function(t, sb, tb, c, surface.a, surface.b, surface.sigma_limit)


def strength_scale(principal: ArrayLike, fc: float, surface: WillamWarnkeSurface,
                   max_scale: float = MAX_SCALE, iterations: int = NEWTON_ITERATIONS, *,
                   return_capped: bool = False, printed_lode: bool = False
                   ) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """s > 0 with f(s sigma) = 0 on the proportional ray (vectorised safeguarded Newton).

    ``max_scale`` caps the strength point: max_i |s sigma_i| <= max_scale f'c. Rays that do not
    meet the surface within it (f(cap) < 0: hydrostatic compression, the open cylinder) return
    the cap, as does a zero stress state (with |sigma| taken as 1e-12 f'c). Always finite. With
    ``return_capped`` also returns the mask of capped rays (for warnings).

    Along a ray theta is constant and sigma_bar, tau_bar scale with t: f(t) = t tau_bar -
    r(theta, r1(t sigma_bar), r2(t sigma_bar)), with an analytic df/dt. f(0) < 0 and f changes
    sign once (meridians concave down to ``sigma_limit``, constant beyond: f convex in t;
    checked by the property test). r1 <= r <= r2 (r <= r2 also beyond the apex), so the root of
    t tau_bar = r2 bounds it from above; the start is the root for the meridian r1 + w (r2 -
    r1), w = 2 (1 - cos theta) (exact at 0 and 60 deg; mostly within 5 %), and Newton converges
    in 2-5 steps. Safeguards as in rtsafe (Numerical Recipes): a bracket [lo, hi] with f(lo) <
    0 <= f(hi) (hi first the r2 bound) is kept, and a step leaving it, a non-positive slope or
    a step not halving on the one before last becomes a bisection, so non-convex cases (clamped
    r1, other calibrations) still converge. A ray stops at a Newton step below 1e-12 t (its
    error is then ~1e-24 t, i.e. round-off) or a bracket that narrow; ``iterations`` bounds
    the steps (each at worst a bisection; the bracket midpoint is returned after the last).
    ``printed_lode``: theta of eq. 3.13 as printed, 60 deg - theta (errata §1.1).
    """
    p = _sorted(principal) / fc
    sb, tb, mag, x, y, defined = unit_ray(p[:, 0], p[:, 1], p[:, 2])
    theta = formulas.lode_angle(np.arctan2(y, x), defined)
    # ``printed_lode``: eq. 3.13 as printed gives 60 deg - theta (errata §1.1: the meridians
    # swapped); theta is constant on a ray, so only cos theta changes
    c = np.cos(np.pi / 3.0 - theta if printed_lode else theta)
    cap = float(max_scale)
    meets = _ray_function(np.full_like(mag, cap), sb, tb, c, surface, slope=False)[0] >= 0.0
    t_out = np.full_like(mag, cap)
    rows = np.nonzero(meets)[0]
    sb, tb, c = sb[rows], tb[rows], c[rows]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        t, hi = newton_start(sb, tb, c, surface.a, surface.b, surface.sigma_limit, cap)
    lo = np.zeros_like(t)
    step_old, step = np.full_like(t, cap), np.full_like(t, cap)
    for _ in range(iterations):
        if rows.size == 0:
            break
        fx, dfx = _ray_function(t, sb, tb, c, surface)
        with np.errstate(divide="ignore", invalid="ignore"):
            t, lo, hi, step_old, step, done = newton_step(t, fx, dfx, lo, hi, step_old, step,
                                                          NEWTON_TOLERANCE)
        if done.any():
            t_out[rows[done]] = t[done]
            keep = ~done
            rows, sb, tb, c = rows[keep], sb[keep], tb[keep], c[keep]
            t, lo, hi, step_old, step = t[keep], lo[keep], hi[keep], step_old[keep], step[keep]
    t_out[rows] = 0.5 * (lo + hi)  # not converged within ``iterations``: bracket midpoint
    return (t_out / mag, ~meets) if return_capped else t_out / mag


def _radius_slope_in_cos(c: np.ndarray, r1: np.ndarray, r2: np.ndarray) -> np.ndarray:
    """d r / d cos theta of the elliptic trace (eq. 3.16 corrected, r1 clamped as in
    `meridian_radius`); zero beyond the apex (r2 <= 0), where r = min(r1, r2)."""
    r1c = np.clip(r1, 0.5 * r2, r2)
    r12 = r2 * r2 - r1c * r1c
    dq = 8.0 * r12 * c  # d q / d c, q = 4 r12 c^2
    root = np.sqrt(np.maximum(0.5 * dq * c + 5.0 * r1c * r1c - 4.0 * r1c * r2, 0.0))
    e = 2.0 * r1c - r2
    den = 0.5 * dq * c + e * e
    valid = (r2 > 0.0) & (den > 0.0)
    den = np.where(valid, den, 1.0)
    r = (2.0 * r2 * r12 * c + r2 * e * root) / den
    droot = np.where(root > 0.0, 0.5 * dq / np.where(root > 0.0, root, 1.0), 0.0)
    return np.where(valid, (2.0 * r2 * r12 + r2 * e * droot - r * dq) / den, 0.0)


def strength_scale_gradient(principal: ArrayLike, scale: ArrayLike, fc: float,
                            surface: WillamWarnkeSurface, capped: ArrayLike) -> np.ndarray:
    """d s / d sigma_k (n, 3), in the columns' own order, of s = `strength_scale(principal)`.

    On a ray that meets the surface, f(s sigma / f'c) = 0 (eq. 3.15) gives by implicit
    differentiation d s / d sigma = -s grad f / (grad f . sigma), grad f from eqs. 3.12-3.18
    (tau_bar, sigma_bar, cos theta and the meridians, held below ``sigma_limit``). A ray
    `capped` at max_scale has s = max_scale f'c / max |sigma_i|.
    """
    p = np.atleast_2d(np.asarray(principal, dtype=float))
    s = np.asarray(scale, dtype=float).reshape(-1)
    order = np.argsort(-p, axis=1, kind="stable")  # sorted as `_sorted`: sigma1 >= sigma2 >= sigma3
    q = np.take_along_axis(p, order, axis=1) * (s / fc)[:, None]  # on the surface, / f'c
    mean = q.mean(axis=1, keepdims=True)
    deviator = q - mean
    tau = np.sqrt((deviator * deviator).sum(axis=1) / 5.0)
    dtau = deviator / (5.0 * np.where(tau > 0.0, tau, 1.0))[:, None]
    x = 2.0 * q[:, 0] - q[:, 1] - q[:, 2]
    y = np.sqrt(3.0) * (q[:, 1] - q[:, 2])
    rho = np.hypot(x, y)
    ok = rho > 1e-12 * np.maximum(np.abs(q[:, 0]), np.abs(q[:, 2]))
    rho = np.where(ok, rho, 1.0)
    c = np.where(ok, x / rho, 1.0)
    dx, dy = np.array([2.0, -1.0, -1.0]), np.sqrt(3.0) * np.array([0.0, 1.0, -1.0])
    dc = np.where(ok, 1.0 / rho**3, 0.0)[:, None] * (
        (y * y)[:, None] * dx - (x * y)[:, None] * dy)
    sigma_bar = mean[:, 0]
    held = np.maximum(sigma_bar, surface.sigma_limit)
    above = sigma_bar >= surface.sigma_limit
    a, b = surface.a, surface.b
    _, dr_dsigma = elliptic_radius_slope(c, meridian(a, held), meridian(b, held),
                                    np.where(above, a[1] + 2.0 * a[2] * held, 0.0),
                                    np.where(above, b[1] + 2.0 * b[2] * held, 0.0))
    dr_dc = _radius_slope_in_cos(c, meridian(a, held), meridian(b, held))
    gradient_sorted = dtau - dr_dc[:, None] * dc - dr_dsigma[:, None] / 3.0  # type: ignore[index]
    gradient = np.empty_like(p)
    np.put_along_axis(gradient, order, gradient_sorted, axis=1)
    along_ray = (gradient * p).sum(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        implicit = -s[:, None] * gradient / along_ray[:, None]
    largest = np.argmax(np.abs(p), axis=1)
    cap_slope = np.zeros_like(p)
    rows = np.arange(p.shape[0])
    cap_slope[rows, largest] = -s * np.sign(p[rows, largest]) / np.maximum(
        np.abs(p[rows, largest]), 1e-300)
    result = np.where(np.asarray(capped, dtype=bool)[:, None], cap_slope, implicit)
    return np.where(np.isfinite(result), result, 0.0)
