"""Point-wise formulas of the concrete law (thesis §3.2, Fig. 3.12), written once for both kernels.

Each function is plain arithmetic on floats or on broadcastable arrays. The NumPy modules
(uniaxial, ultimate_surface, mode_rules, orthotropic, concrete) call them on arrays of points;
concrete_kernels_compiled compiles these same functions with numba and calls them point by
point, so that the two agree bit for bit by executing the same operations. Branches are
`select` (np.where; under numba a ternary, both sides evaluated as in NumPy), `clip` (np.clip)
and `remainder` (np.mod); bool masks combine with & | ~, which NumPy and numba read alike.
Magnitudes in, magnitudes out where the docstring says so. Floating-point warnings are the
NumPy callers' (np.errstate around the call). No numba import here: `import icewall` stays
free of it.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

SQRT3 = math.sqrt(3.0)
MAX_SCALE = 100.0
"""Cap of the strength scale on a ray: max_i |s sigma_i| <= MAX_SCALE f'c."""
NEWTON_TOLERANCE = 1e-12
"""A ray's Newton steps stop at a step (or bracket) below this times the scale."""
NEWTON_ITERATIONS = 60
"""At most this many Newton steps on a ray (each at worst a bisection)."""
FALLEN_RANGE = 1e-280
"""An envelope at max |eps_iu| below this fraction of the secant line there counts as gone, not
as fallen: the scale line / envelope would overflow (NumPy's floating-point errors in runs whose
results were finite). Only a crack opened hundreds of decay lengths wide gets there (k_t
|eps_iu| > 640); such a direction loads onto its envelope (nothing) instead of the scaled one,
a step of at most its secant line's stress (0.02 MPa for a crack opened to eps_iu 0.6)."""
ZERO_TOLERANCE = 1e-6
"""A principal stress within this of the largest counts as zero (§3.2.5 mode counts)."""


def select(condition: Any, if_true: Any, if_false: Any) -> Any:
    """np.where (numba: `if_true if condition else if_false`)."""
    return np.where(condition, if_true, if_false)


def clip(x: Any, low: Any, high: Any) -> Any:
    """np.clip: max with `low`, then min with `high`, NaN kept (numba has none for floats)."""
    return np.clip(x, low, high)


def remainder(x: Any, y: Any) -> Any:
    """np.mod, the sign of `y` (numba: the float %, the same npy_divmod rule)."""
    return np.mod(x, y)


# --- §3.2.2: axes and orthotropic stiffness -----------------------------------------------

def principal_angle(xx: Any, yy: Any, xy: Any, previous: Any, major: Any, tolerance: float,
                    period: float = 0.5 * np.pi) -> Any:
    """beta of the principal strain axes, unwrapped next to `previous`: `period` pi/2, of the
    labellings (major, major + pi/2) the one nearest `previous` (mod pi), which swaps where
    the axes turn by 45 degrees from it; pi, the one with direction 1 on the major principal
    strain (`rotating_axes: continuous`). `previous` where the in-plane strain is isotropic
    within `tolerance` of its size. major = 0.5 atan2(xy / 2, (xx - yy) / 2)."""
    half_difference, half_shear = 0.5 * (xx - yy), 0.5 * xy
    radius = np.hypot(half_difference, half_shear)
    size = np.maximum(abs(xx), abs(yy)) + abs(half_shear)
    delta = remainder(major - previous + 0.5 * period, period) - 0.5 * period
    return select(radius > tolerance * size, previous + delta, previous)


def local_normal(xx: Any, yy: Any, zz: Any, xy: Any, c: Any, s: Any, shear_factor: float
                 ) -> tuple[Any, Any, Any]:
    """Normal components in axes at cos c, sin s: T_eps rows 1-3 (shear_factor 1, engineering
    strain) or T_sigma rows 1-3 (2, stress)."""
    cc, ss, cs = c * c, s * s, shear_factor * c * s
    return cc * xx + ss * yy + cs * xy, ss * xx + cc * yy - cs * xy, zz


def local_shear_strain(xx: Any, yy: Any, xy: Any, c: Any, s: Any) -> Any:
    """Engineering shear strain in the axes at cos c, sin s (T_eps row 4)."""
    return 2.0 * c * s * (yy - xx) + (c * c - s * s) * xy


def global_stress(s1: Any, s2: Any, s3: Any, c: Any, s: Any) -> tuple[Any, Any, Any, Any]:
    """(xx, yy, zz, xy) = T_eps^T [s1, s2, s3, 0] (Fig. 3.12 step 8, errata 1.3)."""
    cc, ss, cs = c * c, s * s, c * s
    return cc * s1 + ss * s2, ss * s1 + cc * s2, s3, cs * (s1 - s2)


def add_shear_stress(xx: Any, yy: Any, xy: Any, tau: Any, c: Any, s: Any
                     ) -> tuple[Any, Any, Any]:
    """(xx, yy, xy) plus T_eps^T of a local shear stress tau."""
    cc, ss, cs = c * c, s * s, c * s
    return xx - 2.0 * cs * tau, yy + 2.0 * cs * tau, xy + (cc - ss) * tau


def normal_stiffness(E1: Any, E2: Any, E3: Any, nu1: Any, nu2: Any, nu3: Any, phi_min: float
                     ) -> tuple[Any, Any, Any, Any, Any, Any]:
    """(C11, C22, C33, C12, C13, C23) of eq. 3.2 with its 1/phi (errata 1.1); eta_ij^2 =
    nu_i nu_j (eq. 3.3a-c), phi of eq. 3.3d per errata 1.1, floored at phi_min (errata §3)."""
    eta12, eta23, eta31 = np.sqrt(nu1 * nu2), np.sqrt(nu2 * nu3), np.sqrt(nu3 * nu1)
    phi = 1.0 - eta12 * eta12 - eta23 * eta23 - eta31 * eta31 - 2.0 * eta12 * eta23 * eta31
    inverse_phi = 1.0 / np.maximum(phi, phi_min)
    return (E1 * (1.0 - eta23 * eta23) * inverse_phi, E2 * (1.0 - eta31 * eta31) * inverse_phi,
            E3 * (1.0 - eta12 * eta12) * inverse_phi,
            np.sqrt(E1 * E2) * (eta31 * eta23 + eta12) * inverse_phi,
            np.sqrt(E1 * E3) * (eta12 * eta23 + eta31) * inverse_phi,
            np.sqrt(E2 * E3) * (eta12 * eta31 + eta23) * inverse_phi)


def shear_modulus(E1: Any, E2: Any, nu0: float) -> Any:
    """G12 of eq. 3.21: G12,0 min(E_1 / E_0, E_2 / E_0) over the in-plane directions."""
    return np.minimum(E1, E2) / (2.0 * (1.0 + nu0))


def coaxial_shear_modulus(s_xx: Any, s_yy: Any, s_xy: Any, e_xx: Any, e_yy: Any, g_xy: Any,
                          committed: Any) -> Any:
    """G12 = (sigma_1 - sigma_2) / (2 (eps_1 - eps_2)) (errata §3), the shear stiffness that
    keeps stress and strain co-axial, from the global components (engineering shear strain);
    `committed` where the strain circle has no radius (1e-12)."""
    turn = (s_xx - s_yy) * (e_xx - e_yy) + s_xy * g_xy
    strain_radius = np.hypot(e_xx - e_yy, g_xy)
    G = np.sign(turn) * np.hypot(s_xx - s_yy, 2.0 * s_xy) / (2.0 * strain_radius)
    return select(strain_radius > 1e-12, G, committed)


# --- §3.2.3: equivalent-uniaxial curves, Poisson ratios -----------------------------------

def saenz_secant(strain: Any, E0: Any, peak_stress: Any, peak_strain: Any) -> Any:
    """sigma / eps of the Saenz curve, eq. 3.9 (magnitudes, uncapped), R_E of eq. 3.10 held
    >= 1 (errata §2.4: below 1 the denominator can vanish)."""
    R_E = np.maximum(E0 * peak_strain / peak_stress, 1.0)
    x = strain / peak_strain
    return E0 / (1.0 + (R_E - 2.0) * x + x * x)


def decay_exponent(strain: Any, peak_strain: Any, decay: Any) -> Any:
    """decay (eps - eps_peak) of eq. 3.11 per errata 1.1 (magnitudes, from the branch's own
    peak strain), 0 before the peak; exp(-it) is the decay past the peak."""
    return decay * clip(strain - peak_strain, 0.0, 1e300)


def envelope(strain: Any, peak_stress: Any, peak_strain: Any, E0: Any, decayed: Any,
             floor: float) -> tuple[Any, Any]:
    """(stress, secant) magnitudes on the envelope at |eps|: the Saenz branch with its secant
    capped at E0 (eqs. 3.9-3.10, errata §3) up to the peak, then peak_stress decayed (eq.
    3.11, decayed = exp(-decay_exponent)); the secant clipped into [floor E0, E0]."""
    rising = strain <= peak_strain
    held = np.minimum(strain, peak_strain)
    rising_secant = np.minimum(saenz_secant(held, E0, peak_stress, peak_strain), E0)
    falling = peak_stress * decayed
    stress = select(rising, rising_secant * held, falling)
    secant = select(rising, rising_secant, falling / select(strain > 0.0, strain, 1.0))
    return stress, clip(secant, floor * E0, E0)


def compression_poisson_ratio(strain_ratio: Any, nu0: Any) -> Any:
    """Eq. 3.19: nu = nu0 (1 + 1.3763 a - 5.36 a^2 + 8.586 a^3), a = |eps_iu| / |eps_ic|."""
    a = np.minimum(strain_ratio, 10.0)  # nu is capped below 0.5 long before (3.19 at a=1: 2.6 nu0)
    return nu0 * (1.0 + a * (1.3763 + a * (-5.36 + a * 8.586)))


def tension_poisson_ratio(strain_ratio: Any, nu0: Any) -> Any:
    """Eq. 3.20: nu0 up to a = 0.5, then linear to zero at a = 1, zero beyond."""
    return nu0 * clip(2.0 * (1.0 - strain_ratio), 0.0, 1.0)


# --- §3.2.4: ultimate surface on a ray ----------------------------------------------------

def octahedral_invariants(s1: Any, s2: Any, s3: Any) -> tuple[Any, Any]:
    """(sigma_oct, tau_oct) of principal stresses: eq. 3.12a, eq. 3.12b per errata 1.1
    (sqrt(s_ij s_ij / 5), deviator of eq. 3.14), not yet divided by f'c."""
    m = (s1 + s2 + s3) / 3.0
    d1, d2, d3 = s1 - m, s2 - m, s3 - m
    return m, np.sqrt((d1 * d1 + d2 * d2 + d3 * d3) / 5.0)


def lode_arguments(s1: Any, s2: Any, s3: Any) -> tuple[Any, Any, Any]:
    """(x, y, defined) of sorted principal stresses: theta = atan2(y, x), eq. 3.13 per errata
    1.1 (2 s1 - s2 - s3 over sqrt2 sqrt(q)), undefined for a hydrostatic state."""
    x, y = 2.0 * s1 - s2 - s3, SQRT3 * (s2 - s3)
    return x, y, np.hypot(x, y) > 1e-12 * np.maximum(abs(s1), abs(s3))


def lode_angle(atan: Any, defined: Any) -> Any:
    """theta in [0, 60 deg] from atan2(y, x) of `lode_arguments`; 0 where undefined."""
    return select(defined, clip(atan, 0.0, np.pi / 3.0), 0.0)


def unit_ray(p1: Any, p2: Any, p3: Any) -> tuple[Any, Any, Any, Any, Any, Any]:
    """(sigma_bar, tau_bar, max |p|, x, y, defined) of the ray of sorted p = sigma / f'c scaled
    to a max-norm of 1 (a zero state as |p| = 1e-12)."""
    mag = np.maximum(np.maximum(abs(p1), abs(p3)), 1e-12)
    d1, d2, d3 = p1 / mag, p2 / mag, p3 / mag
    sb, tb = octahedral_invariants(d1, d2, d3)
    x, y, defined = lode_arguments(d1, d2, d3)
    return sb, tb, mag, x, y, defined


def meridian(k: Any, s: Any) -> Any:
    """Meridian k0 + k1 s + k2 s^2 at sigma_bar = s (eq. 3.18)."""
    return k[0] + k[1] * s + k[2] * s * s


def _elliptic_terms(c: Any, r1: Any, r2: Any) -> tuple[Any, ...]:
    """r of `elliptic_radius` and its terms (r1 clamped, r2^2 - r1^2, q, root, e, denominator)."""
    r1c = clip(r1, 0.5 * r2, r2)  # r1 = minimum radius (glossary corrected, errata §1.1)
    r12 = r2 * r2 - r1c * r1c  # eq. 3.17
    q = 4.0 * r12 * c * c
    root = np.sqrt(np.maximum(q + 5.0 * r1c * r1c - 4.0 * r1c * r2, 0.0))
    # eq. 3.16 corrected per errata §1.1 (numerator 2 r2 (r2^2 - r1^2) cos theta, not 2 r1 r2)
    e = 2.0 * r1c - r2
    den = select((r2 > 0.0) & (q + e * e > 0.0), q + e * e, 1.0)
    r = select(r2 > 0.0, (2.0 * r2 * r12 * c + r2 * e * root) / den, np.minimum(r1, r2))
    return r, r1c, r12, q, root, e, den


def elliptic_radius(c: Any, r1: Any, r2: Any) -> Any:
    """r(theta) at c = cos theta: eq. 3.16 per errata 1.1, r12 of eq. 3.17, r1 clamped into
    [r2/2, r2] (convexity, errata §3); min(r1, r2) <= 0 beyond the apex (r2 <= 0)."""
    return _elliptic_terms(c, r1, r2)[0]


def elliptic_radius_slope(c: Any, r1: Any, r2: Any, dr1: Any, dr2: Any) -> tuple[Any, Any]:
    """(r, dr): `elliptic_radius` and its derivative for meridian derivatives dr1, dr2 (one-
    sided at the clamps; the 1/sqrt term dropped where the root vanishes, only at r1 = r2/2
    and theta = 60 deg, where its factor 2 r1 - r2 is 0 too)."""
    r, r1c, r12, q, root, e, den = _elliptic_terms(c, r1, r2)
    dr1c = select(r1 < 0.5 * r2, 0.5 * dr2, select(r1 > r2, dr2, dr1))
    dr12 = 2.0 * (r2 * dr2 - r1c * dr1c)
    dq = 4.0 * dr12 * c * c
    de = 2.0 * dr1c - dr2
    drad = dq + 10.0 * r1c * dr1c - 4.0 * (dr1c * r2 + r1c * dr2)
    droot = select(root > 0.0, 0.5 * drad / select(root > 0.0, root, 1.0), 0.0)
    dnum = 2.0 * c * (dr2 * r12 + r2 * dr12) + (dr2 * e + r2 * de) * root + r2 * e * droot
    return r, select(r2 > 0.0, (dnum - r * (dq + 2.0 * e * de)) / den,
                     select(r1 < r2, dr1, dr2))


def ray_value(t: Any, sb: Any, tb: Any, c: Any, a: Any, b: Any, limit: float) -> Any:
    """f(t) = t tau_bar - r(theta, r1(t sigma_bar), r2(t sigma_bar)) (eq. 3.15) on the unit ray
    (sigma_bar, tau_bar, cos theta), meridians a, b (eq. 3.18) held below `limit`."""
    s = np.maximum(t * sb, limit)
    return t * tb - elliptic_radius(c, meridian(a, s), meridian(b, s))


def ray_function(t: Any, sb: Any, tb: Any, c: Any, a: Any, b: Any, limit: float
                 ) -> tuple[Any, Any]:
    """`ray_value` and df/dt (zero meridian slopes below `limit`)."""
    x = t * sb
    s = np.maximum(x, limit)
    ds = select(x >= limit, sb, 0.0)
    r, dr = elliptic_radius_slope(c, meridian(a, s), meridian(b, s),
                                  (a[1] + 2.0 * a[2] * s) * ds, (b[1] + 2.0 * b[2] * s) * ds)
    return t * tb - r, tb - dr


def meridian_root(k: Any, sb: Any, tb: Any, limit: float, cap: float) -> Any:
    """Smallest t > 0 with t tau_bar = m(t sigma_bar) for the meridian m = k0 + k1 s + k2 s^2
    (k0 > 0), held at `limit` below it; `cap` where there is none below the cap."""
    k0, k1, k2 = k
    qa, qb = k2 * sb * sb, k1 * sb - tb  # qa t^2 + qb t + k0 = 0 above the limit
    t = 2.0 * k0 / (-qb + np.sqrt(qb * qb - 4.0 * qa * k0))  # the smaller root, if real
    held = (k0 + (k1 + k2 * limit) * limit) / tb  # t tau_bar = m(limit)
    t = select(t * sb >= limit, t, select(held * sb < limit, held, cap))
    return select((t > 0.0) & (t < cap), t, cap)  # NaN -> cap


def newton_start(sb: Any, tb: Any, c: Any, a: Any, b: Any, limit: float, cap: float
                 ) -> tuple[Any, Any]:
    """(start, upper bound) of the Newton steps on the unit ray: the root for the meridian
    r1 + w (r2 - r1), w = 2 (1 - cos theta), below the root for r2, which bounds it."""
    upper = meridian_root(b, sb, tb, limit, cap)
    w = 2.0 * (1.0 - c)
    blend = (a[0] + w * (b[0] - a[0]), a[1] + w * (b[1] - a[1]), a[2] + w * (b[2] - a[2]))
    return np.minimum(meridian_root(blend, sb, tb, limit, cap), upper), upper


def newton_step(x: Any, fx: Any, dfx: Any, lo: Any, hi: Any, step_old: Any, step: Any,
                tol: float) -> tuple[Any, Any, Any, Any, Any, Any]:
    """(x, lo, hi, step_old, step, done) after one safeguarded Newton step on f (rtsafe):
    the bracket [lo, hi] kept; a step leaving it, with a non-positive slope or not halving on
    the one before last bisects; done at a step below tol x or a bracket that narrow."""
    above = fx >= 0.0
    hi, lo = select(above, x, hi), select(above, lo, x)
    newton = fx / dfx
    x_new = x - newton
    positive = dfx > 0.0
    # a step below tol x may round onto lo or hi: take it before the bracket test, and stop
    small = positive & (abs(newton) <= tol * x)
    ok = positive & (x_new > lo) & (x_new < hi) & (abs(newton) <= 0.5 * abs(step_old))
    mid = 0.5 * (lo + hi)
    return (select(small | ok, x_new, mid), lo, hi, step, select(ok, newton, x - mid),
            small | (hi - lo <= tol * hi))


# --- §3.2.5: mode rules, peak strains -----------------------------------------------------

def zero_component(p: Any, largest: Any, fc: float, tolerance: float) -> Any:
    """Whether a principal stress counts as zero: within `tolerance` of the largest |p|, or
    all of a zero state (largest <= 1e-12 f'c); such components fall back to the uniaxial
    values (errata §3, "Using the strength surface")."""
    return (abs(p) <= tolerance * largest) | (largest <= 1e-12 * fc)


def mode_rule_weight(stress: Any, band: float) -> Any:
    """How far a §3.2.5 rule applies, min(stress / band, 1) for the largest stress of the
    other sign (`mode_rules.mode_rule_weights`)."""
    return clip(stress / band, 0.0, 1.0)


def mode_rule_strength(p: Any, scaled: Any, zero: Any, hint: Any, any_tension: Any,
                       any_compression: Any, in_tension: Any, in_compression: Any, fc: float,
                       ft: float, rule_equal: bool, banded: bool) -> Any:
    """Signed sigma_ic of a component p with the surface's scaled = s p: rule (b) (a
    compressive component with some tension: -f'c, or at most -f'c unless `rule_equal`),
    rule (c) (all-tension: at least f't), sharp or blended by in_tension, in_compression
    when `banded`; zero components the uniaxial value of the sign of `hint` (errata §3)."""
    rule_b = -fc if rule_equal else np.minimum(scaled, -fc)
    rule_c = np.maximum(scaled, ft)
    compressive, tensile = (p < 0.0) & ~zero, (p > 0.0) & ~zero
    if banded:
        out = select(compressive, (1.0 - in_tension) * scaled + in_tension * rule_b, scaled)
        out = select(tensile, (1.0 - in_compression) * scaled + in_compression * rule_c, out)
    else:
        out = select(compressive & any_tension, rule_b, scaled)
        out = select(tensile & ~any_compression, rule_c, out)
    return select(zero, select(hint < 0.0, -fc, ft), out)


def peak_strain(strength: Any, fc: float, ft: float, eps_c: float, eps_t: float, E0: float,
                slope: float) -> Any:
    """Signed eps_ic of a signed sigma_ic (errata §2.4): R = |sigma_ic| / f'c, eps_c (1 +
    slope (R - 1)) for R >= 1, eps_c (-1.6 R^3 + 2.25 R^2 + 0.35 R) below; eps_t sigma_ic / f't
    in tension; at least |sigma_ic| / E0 (R_E >= 1)."""
    R = abs(strength) / fc
    ratio = select(R >= 1.0, 1.0 + slope * (R - 1.0), (-1.6 * R + 2.25) * R * R + 0.35 * R)
    magnitude = np.maximum(select(strength < 0.0, ratio * eps_c, strength * eps_t / ft),
                           abs(strength) / E0)
    return select(strength < 0.0, -magnitude, magnitude)


# --- Fig. 3.12 step 6, per direction -----------------------------------------------------

def changes_sign(eps_u: Any, strength: Any) -> Any:
    """Whether eps_iu has left the sign of the committed uniaxial strength."""
    return (eps_u > 0.0) != (strength > 0.0)


def loads(eps_u: Any, max_eps_u: Any, largest_stress: Any, secant: Any, tolerance: float
          ) -> Any:
    """Whether |eps_iu| passes its maximum (Fig. 3.13) by more than `tolerance` of the point's
    strain scale (the rotation's round-off is relative to its largest stress)."""
    return abs(eps_u) > max_eps_u + tolerance * (max_eps_u + largest_stress / secant)


def loads_across_zero(loading: Any, sign_change: Any, damaged: Any, secant: Any,
                      eps_u: Any, uniaxial_stress: Any) -> Any:
    """Loading of a direction whose eps_iu changed sign: where its secant line meets the
    uniaxial envelope of the new sign (`uniaxial_stress` at |eps_iu|); a damaged one only
    there (its max |eps_iu| belongs to the other branch)."""
    crossing = secant * abs(eps_u) > uniaxial_stress * (1 + 1e-9)
    return loading & ~(damaged & sign_change) | sign_change & crossing


def keeps_peak(eps_u: Any, sign_change: Any, cracked: Any, crushed: Any) -> Any:
    """Past its peak on the branch it is on, without a change of sign (post_peak_strength:
    peak keeps its sigma_ic, eps_ic)."""
    return ~sign_change & select(eps_u > 0.0, cracked, crushed)


def scaled_envelope(stress: Any, secant: Any, at_max: Any, line_at_max: Any, sign_change: Any,
                    floor: float, E0: Any) -> tuple[Any, Any]:
    """(stress, secant) magnitudes of a loading direction's envelope scaled through its
    committed point (deck `fallen_strength: scaled`): where the envelope on the new ray at
    max |eps_iu| (`at_max`) lies below the secant line there (`line_at_max` = E_i max|eps_iu|),
    sigma = sigma_env line_at_max / at_max. Continuous where the direction turns from
    unloading to loading, equal to the envelope on a fixed ray, and past the peak the decay
    of eq. 3.11 from the stress the point has (its area sigma / k, eqs. 3.26-3.30). A risen
    envelope (and a change of sign) keeps Fig. 3.12 step 6: the secant line until it meets
    the envelope (`envelope_stress`'s heal), continuous too."""
    fallen = ~sign_change & (at_max > FALLEN_RANGE * line_at_max) & (line_at_max > at_max)
    scale = select(fallen, line_at_max / select(fallen, at_max, 1.0), 1.0)
    return scale * stress, select(fallen, clip(scale * secant, floor * E0, E0), secant)


def envelope_stress(trial: Any, eps_u: Any, secant: Any, loading: Any, sign_change: Any,
                    frozen: Any, stress: Any, envelope_secant: Any) -> tuple[Any, Any, Any]:
    """(loading, sigma_i, E_i) of step 6: on the envelope (stress, envelope_secant) where
    loading, along the secant otherwise (Fig. 3.13). On the same branch the secant never
    grows (it heals: loads along the current secant); a `frozen` point grows no damage and
    never rises above its envelope."""
    heal = ~sign_change & (envelope_secant > secant)
    held = loading & ~heal & frozen
    loading = loading & ~held
    on_envelope = loading & ~heal
    local = select(on_envelope, np.copysign(stress, eps_u), trial)
    local = select(held, np.copysign(np.minimum(abs(trial), stress), eps_u), local)
    return loading, local, select(on_envelope, envelope_secant, secant)


def direction_state(eps_u: Any, loading: Any, frozen: Any, max_eps_u: Any, poisson: Any,
                    strength: Any, peak: Any, cracked: Any, crushed: Any, new_strength: Any,
                    new_peak: Any, nu0: float, nu_max: float
                    ) -> tuple[Any, Any, Any, Any, Any, Any]:
    """(max |eps_iu|, nu_i, sigma_ic, eps_ic, cracked, crushed) after step 6: a loading
    direction takes the new sigma_ic, eps_ic and nu of eq. 3.20 (tension) or 3.19, capped at
    nu_max, and is cracked (crushed) once past its peak in tension (compression); a frozen
    point's max |eps_iu| does not grow."""
    magnitude = abs(eps_u)
    peak = select(loading, new_peak, peak)
    ratio = magnitude / abs(peak)
    nu = select(eps_u > 0.0, tension_poisson_ratio(ratio, nu0),
                compression_poisson_ratio(ratio, nu0))
    beyond_peak = loading & (magnitude > abs(peak))
    return (np.maximum(max_eps_u, select(frozen, 0.0, magnitude)),
            select(loading, np.minimum(nu, nu_max), poisson),
            select(loading, new_strength, strength), peak,
            cracked | beyond_peak & (eps_u > 0.0), crushed | beyond_peak & (eps_u < 0.0))
