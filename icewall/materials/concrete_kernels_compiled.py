"""Numba kernels of the concrete update and moduli, point by point (used by concrete_compiled).

Each function repeats the arithmetic of its NumPy original (named in its docstring) in the
same order, without fastmath, so that the results are NumPy's bit for bit. NumPy evaluates exp
and arctan2 with SIMD code of its own (AVX-512F, SVML) that libm does not reproduce, so the
update runs in four passes over the points (trial, ray, strength, finish) and concrete_compiled
applies NumPy's exp and arctan2 in between. Also copied: np.einsum's summation order
(a0 b0 + a2 b2) + a1 b1 (its AVX2/AVX-512 lanes) and the 4x4 BLAS matmul, a chain of FMAs.
The Newton steps on the strength surface go in lockstep over the rays, as in NumPy, in a loop
free of branches that LLVM vectorises (4x faster than ray by ray).
This module imports numba; only concrete_compiled imports it. All the jitted code is in this
one file, since numba's on-disk cache does not notice a change in a callee of another file.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numba.core import types
from numba.extending import intrinsic

jit = njit(cache=True, error_model="numpy")  # NumPy's IEEE semantics: 1/0 = inf, no raise
inline = njit(cache=True, error_model="numpy", inline="always")  # lets loops vectorise

# parameter tuple (concrete_compiled.parameter_tuple), with the NumPy modules' constants: a
# cached kernel would keep the values of constants imported from other files
(P_E0, P_NU0, P_NU_MAX, P_FC, P_FT, P_EPS_C, P_EPS_T, P_SLOPE, P_RULE_EQUAL,
 P_A0, P_A1, P_A2, P_B0, P_B1, P_B2, P_LIMIT,
 P_LOADING_TOLERANCE, P_SECANT_FLOOR, P_PHI_MIN, P_ANGLE_TOLERANCE, P_MODE_BAND,
 P_KEEP_PEAK) = range(22)
# rows of the (n, N_WORK, 3) work array carried between the passes: per direction, then
# W_RAY: sigma_bar, tau_bar, max |p| of the unit ray; W_AXES: cos, sin of beta
W_TRIAL, W_EPS_U, W_STRENGTH, W_PEAK, W_LOCAL, W_RAY, W_AXES = range(7)
N_WORK = 7
# rows of the (n, N_FLAGS, 3) flags: per direction; B_RAY: any direction loads, theta defined
B_LOADING, B_SIGN_CHANGE, B_RAY = range(3)
N_FLAGS = 3
MAX_SCALE = 100.0  # strength_scale's cap on the ray
ZERO_TOL = 1e-6  # equivalent_uniaxial_strengths' zero components
SQRT3 = math.sqrt(3.0)


@intrinsic
def fma(typingctx, a, b, c):
    """a b + c rounded once (the BLAS kernels' vfmadd)."""
    def codegen(context, builder, signature, args):
        return builder.fma(*args)
    return types.float64(types.float64, types.float64, types.float64), codegen


@inline
def _max(a, b):
    """np.maximum of two floats (NaN propagates)."""
    return a if a >= b or a != a else b


@inline
def _min(a, b):
    """np.minimum of two floats (NaN propagates)."""
    return a if a <= b or a != a else b


@inline
def _clip(x, low, high):
    """np.clip of a float (max then min, NaN kept)."""
    x = x if x != x or x > low else low
    return x if x != x or x < high else high


@jit
def principal_angle(xx, yy, xy, previous, major, tolerance):
    """orthotropic.principal_strain_angle of one strain, given its major axis
    0.5 atan2(xy / 2, (xx - yy) / 2)."""
    half_difference, half_shear = 0.5 * (xx - yy), 0.5 * xy
    radius = math.hypot(half_difference, half_shear)
    size = _max(abs(xx), abs(yy)) + abs(half_shear)
    # numba's float % is CPython's: fmod, then + the period where the signs differ (npy_divmod)
    delta = (major - previous + 0.25 * np.pi) % (0.5 * np.pi) - 0.25 * np.pi
    return previous + delta if radius > tolerance * size else previous


@jit
def _local_normal(xx, yy, zz, xy, c, s, shear_factor):
    """orthotropic.local_normal_components of one 4-vector."""
    cc, ss, cs = c * c, s * s, shear_factor * c * s
    return cc * xx + ss * yy + cs * xy, ss * xx + cc * yy - cs * xy, zz


@jit
def stiffness(E1, E2, E3, nu1, nu2, nu3, phi_min, C):
    """orthotropic.orthotropic_normal_stiffness into C (3, 3): eq. 3.2 / 1/phi, eq. 3.3."""
    eta12, eta23, eta31 = np.sqrt(nu1 * nu2), np.sqrt(nu2 * nu3), np.sqrt(nu3 * nu1)
    phi = 1.0 - eta12 * eta12 - eta23 * eta23 - eta31 * eta31 - 2.0 * eta12 * eta23 * eta31
    inverse_phi = 1.0 / _max(phi, phi_min)  # eq. 3.3d, errata 1.1 and §3
    C[0, 0] = E1 * (1.0 - eta23 * eta23) * inverse_phi
    C[1, 1] = E2 * (1.0 - eta31 * eta31) * inverse_phi
    C[2, 2] = E3 * (1.0 - eta12 * eta12) * inverse_phi
    C[0, 1] = C[1, 0] = np.sqrt(E1 * E2) * (eta31 * eta23 + eta12) * inverse_phi
    C[0, 2] = C[2, 0] = np.sqrt(E1 * E3) * (eta12 * eta23 + eta31) * inverse_phi
    C[1, 2] = C[2, 1] = np.sqrt(E2 * E3) * (eta12 * eta31 + eta23) * inverse_phi


@jit
def decay_exponent(eps_u, peak_strain, decay):
    """The exponent decay (|eps_iu| - eps_ic) of eq. 3.11 (errata 1.1: magnitudes, from the
    branch's own peak; uniaxial.softening_stress) where past the peak, else 0."""
    eps, eps_p = abs(eps_u), abs(peak_strain)
    return 0.0 if eps <= eps_p else decay * _clip(eps - eps_p, 0.0, 1e300)


@jit
def envelope(eps_u, strength, peak_strain, E0, decayed, floor):
    """concrete._envelope of one direction: (stress, secant) at |eps_iu| (eqs. 3.9-3.11), with
    decayed = exp(-decay_exponent) on the descending branch, the secant >= floor E0."""
    eps, peak_stress, eps_p = abs(eps_u), abs(strength), abs(peak_strain)
    if eps <= eps_p:
        R_E = _max(E0 * eps_p / peak_stress, 1.0)  # eq. 3.10, >= 1 (errata §2.4)
        x = _min(eps, eps_p) / eps_p
        secant = _min(E0 / (1.0 + (R_E - 2.0) * x + x * x), E0)  # eq. 3.9, capped (errata §3)
        return secant * _min(eps, eps_p), _clip(secant, floor * E0, E0)
    falling = peak_stress * decayed
    return falling, _clip(falling / (eps if eps > 0.0 else 1.0), floor * E0, E0)


@inline
def elliptic_radius(c, r1, r2, dr1, dr2):
    """ultimate_surface._elliptic_radius: r(theta) (eq. 3.16 corrected per errata 1.1, r12 of
    eq. 3.17, r1 clamped into [r2/2, r2]) and its derivative for meridian slopes dr1, dr2."""
    half_r2 = 0.5 * r2
    r1c = _clip(r1, half_r2, r2)
    r12 = r2 * r2 - r1c * r1c
    q = 4.0 * r12 * c * c
    root = np.sqrt(_max(q + 5.0 * r1c * r1c - 4.0 * r1c * r2, 0.0))
    e = 2.0 * r1c - r2
    if not r2 > 0.0:  # beyond the apex
        return _min(r1, r2), dr1 if r1 < r2 else dr2
    den = q + e * e if q + e * e > 0.0 else 1.0
    r = (2.0 * r2 * r12 * c + r2 * e * root) / den
    dr1c = 0.5 * dr2 if r1 < half_r2 else (dr2 if r1 > r2 else dr1)
    dr12 = 2.0 * (r2 * dr2 - r1c * dr1c)
    dq = 4.0 * dr12 * c * c
    de = 2.0 * dr1c - dr2
    drad = dq + 10.0 * r1c * dr1c - 4.0 * (dr1c * r2 + r1c * dr2)
    droot = 0.5 * drad / root if root > 0.0 else 0.0
    dnum = 2.0 * c * (dr2 * r12 + r2 * dr12) + (dr2 * e + r2 * de) * root + r2 * e * droot
    return r, (dnum - r * (dq + 2.0 * e * de)) / den


@inline
def ray_function(t, sb, tb, c, prm):
    """ultimate_surface._ray_function: f(t) and df/dt on the unit ray (eq. 3.15, 3.18)."""
    x = t * sb
    s = _max(x, prm[P_LIMIT])
    ds = sb if x >= prm[P_LIMIT] else 0.0
    a0, a1, a2, b0, b1, b2 = (prm[P_A0], prm[P_A1], prm[P_A2], prm[P_B0], prm[P_B1],
                              prm[P_B2])
    r, dr = elliptic_radius(c, a0 + a1 * s + a2 * s * s, b0 + b1 * s + b2 * s * s,
                            (a1 + 2.0 * a2 * s) * ds, (b1 + 2.0 * b2 * s) * ds)
    return t * tb - r, tb - dr


@inline
def meridian_root(k0, k1, k2, sb, tb, limit, cap):
    """ultimate_surface._meridian_root: smallest t > 0 on the meridian k0 + k1 s + k2 s^2."""
    qa, qb = k2 * sb * sb, k1 * sb - tb
    t = 2.0 * k0 / (-qb + np.sqrt(qb * qb - 4.0 * qa * k0))
    held = (k0 + (k1 + k2 * limit) * limit) / tb
    if not t * sb >= limit:
        t = held if held * sb < limit else cap
    return t if t > 0.0 and t < cap else cap


@jit
def unit_ray(t1, t2, t3, fc):
    """strength_scale's unit ray of principal stresses: (sigma_bar, tau_bar, max |p|, x, y,
    defined), atan2(y, x) the Lode angle where defined (eqs. 3.12-3.13 corrected per errata
    1.1; octahedral_invariants, lode_angle)."""
    if t1 < t2:
        t1, t2 = t2, t1
    if t2 < t3:
        t2, t3 = t3, t2
    if t1 < t2:
        t1, t2 = t2, t1
    p1, p2, p3 = t1 / fc, t2 / fc, t3 / fc
    mag = _max(_max(abs(p1), abs(p3)), 1e-12)
    d1, d2, d3 = p1 / mag, p2 / mag, p3 / mag
    sb = (d1 + d2 + d3) / 3.0
    e1, e2, e3 = d1 - sb, d2 - sb, d3 - sb
    tb = np.sqrt((e1 * e1 + e2 * e2 + e3 * e3) / 5.0)
    x, y = 2.0 * d1 - d2 - d3, SQRT3 * (d2 - d3)
    return sb, tb, mag, x, y, math.hypot(x, y) > 1e-12 * _max(abs(d1), abs(d3))


@jit
def newton_sweep(sb, tb, c, x, lo, hi, step_old, step, done, prm):
    """One safeguarded Newton step of strength_scale on every unit ray not done (bracket
    [lo, hi], a step leaving it, with a non-positive slope or not halving on the one before
    last bisects; done at a step below 1e-12 x or a bracket that narrow). Free of branches,
    so that the loop vectorises; returns how many rays remain."""
    tol, remaining = 1e-12, 0
    for a in range(x.size):
        xa = x[a]
        fx, dfx = ray_function(xa, sb[a], tb[a], c[a], prm)
        above = fx >= 0.0
        high, low = xa if above else hi[a], lo[a] if above else xa
        newton = fx / dfx
        x_new = xa - newton
        positive = dfx > 0.0
        small = positive & (abs(newton) <= tol * xa)
        ok = (positive & (x_new > low) & (x_new < high)
              & (abs(newton) <= 0.5 * abs(step_old[a])))
        mid = 0.5 * (low + high)
        live = done[a] == 0.0
        finished = small | (high - low <= tol * high)
        hi[a], lo[a] = high if live else hi[a], low if live else lo[a]
        step_old[a], step[a] = (step[a] if live else step_old[a],
                                (newton if ok else xa - mid) if live else step[a])
        x[a] = (x_new if small | ok else mid) if live else xa
        done[a] = 1.0 if live & finished else done[a]
        remaining += live & ~finished
    return remaining


@jit
def strength_scales(sb, tb, c, mag, prm):
    """ultimate_surface.strength_scale of unit rays (sigma_bar, tau_bar, cos theta, max |p|):
    the same cap, start, Newton steps and stopping rule, the steps in lockstep over the rays."""
    m, cap, limit = sb.size, MAX_SCALE, prm[P_LIMIT]
    x, lo, hi, done = np.empty(m), np.zeros(m), np.empty(m), np.zeros(m)
    step_old, step = np.full(m, cap), np.full(m, cap)
    for a in range(m):
        w = 2.0 * (1.0 - c[a])  # start on the meridian r1 + w (r2 - r1), below the r2 bound
        hi[a] = meridian_root(prm[P_B0], prm[P_B1], prm[P_B2], sb[a], tb[a], limit, cap)
        x[a] = _min(meridian_root(prm[P_A0] + w * (prm[P_B0] - prm[P_A0]),
                                  prm[P_A1] + w * (prm[P_B1] - prm[P_A1]),
                                  prm[P_A2] + w * (prm[P_B2] - prm[P_A2]), sb[a], tb[a],
                                  limit, cap), hi[a])
        if not ray_function(cap, sb[a], tb[a], c[a], prm)[0] >= 0.0:  # misses below the cap
            x[a], done[a] = cap, 1.0
    for _ in range(60):
        if newton_sweep(sb, tb, c, x, lo, hi, step_old, step, done, prm) == 0:
            break
    for a in range(m):  # not converged: the bracket's midpoint
        x[a] = (x[a] if done[a] != 0.0 else 0.5 * (lo[a] + hi[a])) / mag[a]
    return x


@jit
def uniaxial_strengths(W, i, scale, prm):
    """mode_rules.equivalent_uniaxial_strengths of the trial stress of point i (strain_sign
    eps_iu, strength scale `scale`): the §3.2.5 mode rules (errata §3) into W[i, W_STRENGTH]."""
    fc, ft = prm[P_FC], prm[P_FT]
    mag = _max(_max(abs(W[i, W_TRIAL, 0]), abs(W[i, W_TRIAL, 1])), abs(W[i, W_TRIAL, 2]))
    any_tension = any_compression = False
    tension = compression = 0.0  # the largest of each (mode_rule_weights)
    for k in range(3):
        p = W[i, W_TRIAL, k]
        nonzero = not (abs(p) <= ZERO_TOL * mag or mag <= 1e-12 * fc)
        any_tension |= p > 0.0 and nonzero
        any_compression |= p < 0.0 and nonzero
        tension = _max(tension, p) if nonzero else tension
        compression = _max(compression, -p) if nonzero else compression
    band = prm[P_MODE_BAND]
    in_tension = _min(_max(tension / band, 0.0), 1.0) if band > 0.0 else 0.0
    in_compression = 1.0 - _min(_max(compression / band, 0.0), 1.0) if band > 0.0 else 0.0
    for k in range(3):
        p = W[i, W_TRIAL, k]
        strength = scale * p
        if abs(p) <= ZERO_TOL * mag or mag <= 1e-12 * fc:  # uniaxial fallback (errata §3)
            strength = -fc if W[i, W_EPS_U, k] < 0.0 else ft
        elif band > 0.0 and p < 0.0:  # rule (b) over the band
            rule = -fc if prm[P_RULE_EQUAL] != 0.0 else _min(strength, -fc)
            strength = (1.0 - in_tension) * strength + in_tension * rule
        elif band > 0.0 and p > 0.0:  # rule (c) over the band
            strength = (1.0 - in_compression) * strength + in_compression * _max(strength, ft)
        elif p < 0.0 and any_tension:  # rule (b)
            strength = -fc if prm[P_RULE_EQUAL] != 0.0 else _min(strength, -fc)
        elif p > 0.0 and not any_compression:  # rule (c)
            strength = _max(strength, ft)
        W[i, W_STRENGTH, k] = strength


@jit
def peak_strain(sigma, prm):
    """mode_rules.equivalent_uniaxial_peak_strains of one signed strength (errata §2.4)."""
    R = abs(sigma) / prm[P_FC]
    if R >= 1.0:
        ratio = 1.0 + prm[P_SLOPE] * (R - 1.0)
    else:
        ratio = (-1.6 * R + 2.25) * R * R + 0.35 * R
    mag = ratio * prm[P_EPS_C] if sigma < 0.0 else sigma * prm[P_EPS_T] / prm[P_FT]
    mag = _max(mag, abs(sigma) / prm[P_E0])
    return -mag if sigma < 0.0 else mag


@jit
def trial_pass(strain, major, S, frozen, has_frozen, corotational, plane_strain, prm, k_t, k_c,
               O, W, B, A):
    """concrete.update_concrete, Fig. 3.12 steps 1-4 and the loading test of step 6: the axes
    and strain into O, trial stress and eps_iu into W, loading and sign changes into B, the
    exponents of the uniaxial envelopes of the directions changing sign into A (else 0)."""
    s_strain, s_stress, s_angle, s_max = S[0], S[1], S[2], S[4]
    s_secant, s_poisson, s_strength = S[5], S[6], S[8]
    o_strain, o_angle = O[0], O[2]
    C = np.empty((3, 3))
    for i in range(strain.shape[0]):
        xx, yy, xy = strain[i, 0], strain[i, 1], strain[i, 3]
        zz = 0.0 if plane_strain else strain[i, 2]
        committed = s_angle[i]
        angle = (committed if has_frozen and frozen[i]  # a frozen point keeps its axes
                 else principal_angle(xx, yy, xy, committed, major[i], prm[P_ANGLE_TOLERANCE]))
        o_angle[i] = angle
        o_strain[i, 0], o_strain[i, 1], o_strain[i, 2], o_strain[i, 3] = xx, yy, zz, xy
        # steps 1-2: committed stress and strain increment in the new axes (errata 1.3)
        c, s = math.cos(angle), math.sin(angle)
        W[i, W_AXES, 0], W[i, W_AXES, 1] = c, s
        if corotational:  # committed principal values carried with the axes
            c0, s0 = math.cos(committed), math.sin(committed)
            n1, n2, n3 = _local_normal(xx, yy, zz, xy, c, s, 1.0)
            o1, o2, o3 = _local_normal(s_strain[i, 0], s_strain[i, 1], s_strain[i, 2],
                                       s_strain[i, 3], c0, s0, 1.0)
            d1, d2, d3 = n1 - o1, n2 - o2, n3 - o3
        else:
            c0, s0 = c, s
            d1, d2, d3 = _local_normal(xx - s_strain[i, 0], yy - s_strain[i, 1],
                                       zz - s_strain[i, 2], xy - s_strain[i, 3], c, s, 1.0)
        t1, t2, t3 = _local_normal(s_stress[i, 0], s_stress[i, 1], s_stress[i, 2],
                                   s_stress[i, 3], c0, s0, 2.0)
        # step 3: trial stress (np.einsum's order); step 4: eps_iu = sigma_lt / E_i (errata 1.1)
        stiffness(s_secant[i, 0], s_secant[i, 1], s_secant[i, 2], s_poisson[i, 0],
                  s_poisson[i, 1], s_poisson[i, 2], prm[P_PHI_MIN], C)
        W[i, W_TRIAL, 0] = t1 + (C[0, 0] * d1 + C[0, 2] * d3 + C[0, 1] * d2)
        W[i, W_TRIAL, 1] = t2 + (C[1, 0] * d1 + C[1, 2] * d3 + C[1, 1] * d2)
        W[i, W_TRIAL, 2] = t3 + (C[2, 0] * d1 + C[2, 2] * d3 + C[2, 1] * d2)
        largest = _max(_max(abs(W[i, W_TRIAL, 0]), abs(W[i, W_TRIAL, 1])),
                       abs(W[i, W_TRIAL, 2]))
        for k in range(3):  # step 6: loading by max |eps_iu| (errata §3, Fig. 3.13)
            E = s_secant[i, k]
            eps_u = W[i, W_TRIAL, k] / E
            W[i, W_EPS_U, k] = eps_u
            slack = prm[P_LOADING_TOLERANCE] * (s_max[i, k] + largest / E)
            B[i, B_LOADING, k] = abs(eps_u) > s_max[i, k] + slack
            tensile = eps_u > 0.0
            sign_change = tensile != (s_strength[i, k] > 0.0)
            B[i, B_SIGN_CHANGE, k] = sign_change
            A[i, k] = 0.0 if not sign_change else decay_exponent(
                eps_u, prm[P_EPS_T] if tensile else -prm[P_EPS_C], k_t[i] if tensile else k_c[i])


@jit
def ray_pass(S, prm, W, B, decayed, lode_x, lode_y):
    """The loading test of a direction changing sign (where its secant line meets the uniaxial
    envelope; decayed = exp(-A)); where a direction loads, the unit ray of the trial stress
    into W[:, W_RAY] and the arguments of its Lode angle's atan2 into lode_x, lode_y."""
    s_secant, s_cracked, s_crushed = S[5], S[10], S[11]
    E0, fc = prm[P_E0], prm[P_FC]
    for i in range(W.shape[0]):
        any_loading = False
        for k in range(3):
            loading = B[i, B_LOADING, k]
            if B[i, B_SIGN_CHANGE, k]:
                eps_u = W[i, W_EPS_U, k]
                tensile = eps_u > 0.0
                uniaxial_stress = envelope(eps_u, prm[P_FT] if tensile else -fc,
                                           prm[P_EPS_T] if tensile else -prm[P_EPS_C], E0,
                                           decayed[i, k], prm[P_SECANT_FLOOR])[0]
                crossing = s_secant[i, k] * abs(eps_u) > uniaxial_stress * (1 + 1e-9)
                loading = loading and not (s_cracked[i, k] or s_crushed[i, k]) or crossing
                B[i, B_LOADING, k] = loading
            any_loading |= loading
        B[i, B_RAY, 0], B[i, B_RAY, 1] = any_loading, False
        lode_x[i] = lode_y[i] = 0.0
        if any_loading:
            (W[i, W_RAY, 0], W[i, W_RAY, 1], W[i, W_RAY, 2], lode_x[i], lode_y[i],
             B[i, B_RAY, 1]) = unit_ray(W[i, W_TRIAL, 0], W[i, W_TRIAL, 1], W[i, W_TRIAL, 2], fc)


@jit
def strength_pass(S, prm, k_t, k_c, W, B, lode_atan, A):
    """Step 5 (errata 1.3) where a direction loads: sigma_ic on the ray (theta from lode_atan =
    arctan2(lode_y, lode_x)) with the mode rules, eps_ic (the committed ones past the peak
    where P_KEEP_PEAK: concrete.past_peak), the exponents of their envelopes into A (else 0)."""
    s_strength, s_peak, s_cracked, s_crushed = S[8], S[9], S[10], S[11]
    n = W.shape[0]
    rows, m = np.empty(n, np.int64), 0
    for i in range(n):
        A[i, 0] = A[i, 1] = A[i, 2] = 0.0
        if B[i, B_RAY, 0]:
            rows[m], m = i, m + 1
    sb, tb, c, mag = np.empty(m), np.empty(m), np.empty(m), np.empty(m)
    for a in range(m):
        i = rows[a]
        theta = _clip(lode_atan[i], 0.0, np.pi / 3.0) if B[i, B_RAY, 1] else 0.0
        sb[a], tb[a], c[a], mag[a] = W[i, W_RAY, 0], W[i, W_RAY, 1], math.cos(theta), W[i, W_RAY, 2]
    scale = strength_scales(sb, tb, c, mag, prm)
    for a in range(m):
        i = rows[a]
        uniaxial_strengths(W, i, scale[a], prm)
        for k in range(3):
            eps_u = W[i, W_EPS_U, k]
            W[i, W_PEAK, k] = peak_strain(W[i, W_STRENGTH, k], prm)
            if prm[P_KEEP_PEAK] != 0.0 and not B[i, B_SIGN_CHANGE, k] and (
                    s_cracked[i, k] if eps_u > 0.0 else s_crushed[i, k]):
                W[i, W_STRENGTH, k], W[i, W_PEAK, k] = s_strength[i, k], s_peak[i, k]
            A[i, k] = decay_exponent(eps_u, W[i, W_PEAK, k], k_t[i] if eps_u > 0.0 else k_c[i])


@jit
def finish_pass(S, frozen, has_frozen, prm, W, B, decayed, O):
    """Step 6: the envelope (eqs. 3.9-3.11, decayed = exp(-A)) where loading, the secant kept
    where unloading (Fig. 3.13), nu (eqs. 3.19-3.20), G12 (eq. 3.21); the stress (steps 7-8
    without moduli) and the rest of the trial state into O."""
    s_max, s_secant, s_poisson, s_strength, s_peak = S[4], S[5], S[6], S[8], S[9]
    s_cracked, s_crushed = S[10], S[11]
    (o_strain, o_stress, o_angle, o_eps_u, o_max, o_secant, o_poisson, o_shear, o_strength,
     o_peak, o_cracked, o_crushed) = O
    E0, nu0 = prm[P_E0], prm[P_NU0]
    for i in range(W.shape[0]):
        held_point = has_frozen and frozen[i]
        for k in range(3):
            E, trial, eps_u = s_secant[i, k], W[i, W_TRIAL, k], W[i, W_EPS_U, k]
            magnitude = abs(eps_u)
            if B[i, B_RAY, 0]:  # the parameters on the ray
                env_stress, env_secant = envelope(eps_u, W[i, W_STRENGTH, k], W[i, W_PEAK, k],
                                                  E0, decayed[i, k], prm[P_SECANT_FLOOR])
            else:
                env_stress, env_secant = abs(trial), E
            loading = B[i, B_LOADING, k]
            heal = not B[i, B_SIGN_CHANGE, k] and env_secant > E  # the secant never grows
            held = held_point and loading and not heal  # no damage grows at a frozen point
            loading = loading and not held
            on_envelope = loading and not heal
            local = math.copysign(env_stress, eps_u) if on_envelope else trial
            if held:  # a held direction never rises above its envelope
                local = math.copysign(_min(abs(trial), env_stress), eps_u)
            W[i, W_LOCAL, k] = local
            o_secant[i, k] = env_secant if on_envelope else E
            peak = W[i, W_PEAK, k] if loading else s_peak[i, k]
            ratio = magnitude / abs(peak)
            if eps_u > 0.0:  # eq. 3.20
                nu_new = nu0 * _clip(2.0 * (1.0 - ratio), 0.0, 1.0)
            else:  # eq. 3.19
                a = _min(ratio, 10.0)
                nu_new = nu0 * (1.0 + a * (1.3763 + a * (-5.36 + a * 8.586)))
            o_poisson[i, k] = _min(nu_new, prm[P_NU_MAX]) if loading else s_poisson[i, k]
            o_eps_u[i, k] = eps_u
            o_max[i, k] = _max(s_max[i, k], 0.0 if held_point else magnitude)
            o_strength[i, k] = W[i, W_STRENGTH, k] if loading else s_strength[i, k]
            o_peak[i, k] = peak
            beyond_peak = loading and magnitude > abs(peak)
            o_cracked[i, k] = s_cracked[i, k] or beyond_peak and eps_u > 0.0
            o_crushed[i, k] = s_crushed[i, k] or beyond_peak and eps_u < 0.0
        G = _min(o_secant[i, 0], o_secant[i, 1]) / (2.0 * (1.0 + nu0))  # eq. 3.21
        o_shear[i] = G
        # sigma_g = T_eps^T [s1, s2, s3, tau], tau = 0 (§3.2.6) except in the held axes of a
        # frozen point: G12 times the shear strain there
        l1, l2 = W[i, W_LOCAL, 0], W[i, W_LOCAL, 1]
        c, s = W[i, W_AXES, 0], W[i, W_AXES, 1]
        cc, ss, cs = c * c, s * s, c * s
        sxx, syy, sxy = cc * l1 + ss * l2, ss * l1 + cc * l2, cs * (l1 - l2)
        if has_frozen:
            xx, yy, xy = o_strain[i, 0], o_strain[i, 1], o_strain[i, 3]
            shear = G * (2.0 * c * s * (yy - xx) + (c * c - s * s) * xy) if held_point else 0.0
            sxx -= 2.0 * cs * shear
            syy += 2.0 * cs * shear
            sxy += (cc - ss) * shear
        o_stress[i, 0], o_stress[i, 1], o_stress[i, 3] = sxx, syy, sxy
        o_stress[i, 2] = W[i, W_LOCAL, 2]


@jit
def floored_moduli_points(secant, poisson, shear, stress, strain, angle, E0, nu0, floor,
                          coaxial, phi_min):
    """concrete_law.floored_moduli (with coaxial_shear_modulus): C_g = T^T C_l T (Fig. 3.12
    step 8, errata 1.3) with E_i, G12 floored. The products are BLAS's chains of FMAs over
    the inner index, less the terms with a zero factor of C_l or T (signed zeros aside)."""
    n = secant.shape[0]
    out = np.empty((n, 4, 4))
    C, LT = np.empty((3, 3)), np.empty((4, 4))
    G0 = E0 / (2.0 * (1.0 + nu0))
    for i in range(n):
        stiffness(_max(secant[i, 0], floor * E0), _max(secant[i, 1], floor * E0),
                  _max(secant[i, 2], floor * E0), poisson[i, 0], poisson[i, 1],
                  poisson[i, 2], phi_min, C)
        G = shear[i]
        if coaxial:  # errata §3: the G12 that keeps stress and strain co-axial
            s, e = stress[i], strain[i]
            turn = (s[0] - s[1]) * (e[0] - e[1]) + s[3] * e[3]
            strain_radius = math.hypot(e[0] - e[1], e[3])
            if strain_radius > 1e-12:
                G = np.sign(turn) * math.hypot(s[0] - s[1], 2.0 * s[3]) / (2.0 * strain_radius)
        G = _clip(G, floor * G0, G0)
        c, sn = math.cos(angle[i]), math.sin(angle[i])
        cc, ss, cs = c * c, sn * sn, c * sn
        # T_eps rows 0, 1, 3 in columns 0, 1, 3 (strain_rotation); row and column 2: e_zz
        t00, t01, t03, t10, t11, t13 = cc, ss, cs, ss, cc, -cs
        t30, t31, t33 = -2.0 * cs, 2.0 * cs, cc - ss
        for r in range(3):  # C_l T: rows of C_l, then the shear row
            LT[r, 0] = fma(C[r, 1], t10, C[r, 0] * t00)
            LT[r, 1] = fma(C[r, 1], t11, C[r, 0] * t01)
            LT[r, 2] = C[r, 2]
            LT[r, 3] = fma(C[r, 1], t13, C[r, 0] * t03)
        LT[3, 0], LT[3, 1], LT[3, 2], LT[3, 3] = G * t30, G * t31, 0.0, G * t33
        for q in range(4):  # T^T (C_l T)
            out[i, 0, q] = fma(t30, LT[3, q], fma(t10, LT[1, q], t00 * LT[0, q]))
            out[i, 1, q] = fma(t31, LT[3, q], fma(t11, LT[1, q], t01 * LT[0, q]))
            out[i, 2, q] = LT[2, q]
            out[i, 3, q] = fma(t33, LT[3, q], fma(t13, LT[1, q], t03 * LT[0, q]))
    return out
