"""Numba kernels of the concrete update and moduli, point by point (used by concrete_compiled).

The formulas of the law are concrete_formulas', the same functions the NumPy modules call on
arrays, compiled by numba (concrete_jit registers them) where these kernels call them. The
kernels only loop over points and directions, carry the state between the steps of Fig. 3.12
and reduce over a point's directions, without fastmath, so that the results are NumPy's bit
for bit. NumPy evaluates exp and arctan2 with SIMD code of its own (AVX-512F, SVML) that libm
does not reproduce, so the update runs in four passes over the points (trial, ray, strength,
finish) and concrete_compiled applies NumPy's exp and arctan2 in between. Copied here, as
they are NumPy's summation orders and no formulas: np.einsum's (a0 b0 + a2 b2) + a1 b1 (its
AVX2/AVX-512 lanes) in the trial stress, the 4x4 BLAS matmul (a chain of FMAs) in the moduli.
The Newton steps on the strength surface go in lockstep over the rays, as in NumPy, in a loop
free of branches that LLVM vectorises (4x faster than ray by ray).
This module imports numba; only concrete_compiled imports it. numba's on-disk cache does not
notice a change in a callee of another file: each kernel's cache key holds the digest of
concrete_formulas and concrete_jit (`concrete_jit.jit`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from icewall.materials import concrete_formulas as law
from icewall.materials.concrete_formulas import (
    add_shear_stress,
    changes_sign,
    decay_exponent,
    direction_state,
    envelope,
    envelope_stress,
    global_stress,
    keeps_peak,
    loads,
    loads_across_zero,
    local_normal,
    local_shear_strain,
    lode_angle,
    mode_rule_strength,
    mode_rule_weight,
    newton_start,
    newton_step,
    normal_stiffness,
    peak_strain,
    principal_angle,
    ray_function,
    ray_value,
    scaled_envelope,
    shear_modulus,
    zero_component,
)
from icewall.materials.concrete_jit import fma, jit

# parameter tuple (concrete_compiled.parameter_tuple), with the NumPy modules' constants: a
# cached kernel would keep the values of constants imported from other files
(P_E0, P_NU0, P_NU_MAX, P_FC, P_FT, P_EPS_C, P_EPS_T, P_SLOPE, P_RULE_EQUAL,
 P_A0, P_A1, P_A2, P_B0, P_B1, P_B2, P_LIMIT,
 P_LOADING_TOLERANCE, P_SECANT_FLOOR, P_PHI_MIN, P_ANGLE_TOLERANCE, P_MODE_BAND,
 P_KEEP_PEAK, P_SCALED, P_AXIS_PERIOD) = range(24)
# rows of the (n, N_WORK, 3) work array carried between the passes: per direction, then
# W_RAY: sigma_bar, tau_bar, max |p| of the unit ray; W_AXES: cos, sin of beta
W_TRIAL, W_EPS_U, W_STRENGTH, W_PEAK, W_LOCAL, W_RAY, W_AXES = range(7)
N_WORK = 7
# rows of the (n, N_FLAGS, 3) flags: per direction; B_RAY: any direction loads, theta defined
B_LOADING, B_SIGN_CHANGE, B_RAY = range(3)
N_FLAGS = 3


@njit(error_model="numpy", inline="always")
def stiffness(E1, E2, E3, nu1, nu2, nu3, phi_min, C):
    """normal_stiffness into C (3, 3)."""
    C[0, 0], C[1, 1], C[2, 2], C[0, 1], C[0, 2], C[1, 2] = normal_stiffness(
        E1, E2, E3, nu1, nu2, nu3, phi_min)
    C[1, 0], C[2, 0], C[2, 1] = C[0, 1], C[0, 2], C[1, 2]


@njit(error_model="numpy", inline="always")
def meridians(prm):
    """The meridian coefficients a, b (eq. 3.18) of the parameter tuple."""
    return ((prm[P_A0], prm[P_A1], prm[P_A2]), (prm[P_B0], prm[P_B1], prm[P_B2]))


@jit
def unit_ray(t1, t2, t3, fc):
    """concrete_formulas.unit_ray of the principal stresses t / f'c, sorted (the Lode angle is
    atan2(y, x) where defined)."""
    if t1 < t2:
        t1, t2 = t2, t1
    if t2 < t3:
        t2, t3 = t3, t2
    if t1 < t2:
        t1, t2 = t2, t1
    return law.unit_ray(t1 / fc, t2 / fc, t3 / fc)


@jit
def newton_sweep(sb, tb, c, x, lo, hi, step_old, step, done, prm):
    """One newton_step of ultimate_surface.strength_scale on every unit ray not done. Free of
    branches, so that the loop vectorises; returns how many rays remain."""
    remaining, (a, b), limit = 0, meridians(prm), prm[P_LIMIT]
    for j in range(x.size):
        xj = x[j]
        fx, dfx = ray_function(xj, sb[j], tb[j], c[j], a, b, limit)
        x_new, low, high, s_old, s_new, finished = newton_step(
            xj, fx, dfx, lo[j], hi[j], step_old[j], step[j], law.NEWTON_TOLERANCE)
        live = done[j] == 0.0
        hi[j], lo[j] = high if live else hi[j], low if live else lo[j]
        step_old[j], step[j] = s_old if live else step_old[j], s_new if live else step[j]
        x[j] = x_new if live else xj
        done[j] = 1.0 if live & finished else done[j]
        remaining += live & ~finished
    return remaining


@jit
def strength_scales(sb, tb, c, mag, prm):
    """ultimate_surface.strength_scale of unit rays (sigma_bar, tau_bar, cos theta, max |p|):
    the same cap, start, Newton steps and stopping rule, the steps in lockstep over the rays."""
    m, cap, (a, b), limit = sb.size, law.MAX_SCALE, meridians(prm), prm[P_LIMIT]
    x, lo, hi, done = np.empty(m), np.zeros(m), np.empty(m), np.zeros(m)
    step_old, step = np.full(m, cap), np.full(m, cap)
    for j in range(m):
        x[j], hi[j] = newton_start(sb[j], tb[j], c[j], a, b, limit, cap)
        if not ray_value(cap, sb[j], tb[j], c[j], a, b, limit) >= 0.0:  # misses below the cap
            x[j], done[j] = cap, 1.0
    for _ in range(law.NEWTON_ITERATIONS):
        if newton_sweep(sb, tb, c, x, lo, hi, step_old, step, done, prm) == 0:
            break
    for j in range(m):  # not converged: the bracket's midpoint
        x[j] = (x[j] if done[j] != 0.0 else 0.5 * (lo[j] + hi[j])) / mag[j]
    return x


@jit
def uniaxial_strengths(W, i, scale, prm):
    """mode_rules.equivalent_uniaxial_strengths of the trial stress of point i (strain_sign
    eps_iu, strength scale `scale`): the §3.2.5 mode rules (errata §3) into W[i, W_STRENGTH]."""
    fc, band = prm[P_FC], prm[P_MODE_BAND]
    p = W[i, W_TRIAL]
    largest = np.maximum(np.maximum(abs(p[0]), abs(p[1])), abs(p[2]))
    any_tension = any_compression = False
    tension = compression = 0.0  # the largest of each (mode_rules.mode_rule_weights)
    for k in range(3):
        nonzero = ~zero_component(p[k], largest, fc, law.ZERO_TOLERANCE)
        any_tension |= (p[k] > 0.0) & nonzero
        any_compression |= (p[k] < 0.0) & nonzero
        tension = np.maximum(tension, p[k]) if nonzero else tension
        compression = np.maximum(compression, -p[k]) if nonzero else compression
    in_tension = mode_rule_weight(tension, band) if band > 0.0 else 0.0
    in_compression = 1.0 - mode_rule_weight(compression, band) if band > 0.0 else 0.0
    for k in range(3):
        W[i, W_STRENGTH, k] = mode_rule_strength(
            p[k], scale * p[k], zero_component(p[k], largest, fc, law.ZERO_TOLERANCE),
            W[i, W_EPS_U, k], any_tension, any_compression, in_tension, in_compression, fc,
            prm[P_FT], prm[P_RULE_EQUAL] != 0.0, band > 0.0)


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
                 else principal_angle(xx, yy, xy, committed, major[i], prm[P_ANGLE_TOLERANCE],
                                      prm[P_AXIS_PERIOD]))
        o_angle[i] = angle
        o_strain[i, 0], o_strain[i, 1], o_strain[i, 2], o_strain[i, 3] = xx, yy, zz, xy
        # steps 1-2: committed stress and strain increment in the new axes (errata 1.3)
        c, s = math.cos(angle), math.sin(angle)
        W[i, W_AXES, 0], W[i, W_AXES, 1] = c, s
        if corotational:  # committed principal values carried with the axes
            c0, s0 = math.cos(committed), math.sin(committed)
            n1, n2, n3 = local_normal(xx, yy, zz, xy, c, s, 1.0)
            o1, o2, o3 = local_normal(s_strain[i, 0], s_strain[i, 1], s_strain[i, 2],
                                      s_strain[i, 3], c0, s0, 1.0)
            d1, d2, d3 = n1 - o1, n2 - o2, n3 - o3
        else:
            c0, s0 = c, s
            d1, d2, d3 = local_normal(xx - s_strain[i, 0], yy - s_strain[i, 1],
                                      zz - s_strain[i, 2], xy - s_strain[i, 3], c, s, 1.0)
        t1, t2, t3 = local_normal(s_stress[i, 0], s_stress[i, 1], s_stress[i, 2],
                                  s_stress[i, 3], c0, s0, 2.0)
        # step 3: trial stress (np.einsum's order); step 4: eps_iu = sigma_lt / E_i (errata 1.1)
        stiffness(s_secant[i, 0], s_secant[i, 1], s_secant[i, 2], s_poisson[i, 0],
                  s_poisson[i, 1], s_poisson[i, 2], prm[P_PHI_MIN], C)
        W[i, W_TRIAL, 0] = t1 + (C[0, 0] * d1 + C[0, 2] * d3 + C[0, 1] * d2)
        W[i, W_TRIAL, 1] = t2 + (C[1, 0] * d1 + C[1, 2] * d3 + C[1, 1] * d2)
        W[i, W_TRIAL, 2] = t3 + (C[2, 0] * d1 + C[2, 2] * d3 + C[2, 1] * d2)
        largest = np.maximum(np.maximum(abs(W[i, W_TRIAL, 0]), abs(W[i, W_TRIAL, 1])),
                             abs(W[i, W_TRIAL, 2]))
        for k in range(3):  # step 6: loading by max |eps_iu| (errata §3, Fig. 3.13)
            E = s_secant[i, k]
            eps_u = W[i, W_TRIAL, k] / E
            W[i, W_EPS_U, k] = eps_u
            B[i, B_LOADING, k] = loads(eps_u, s_max[i, k], largest, E,
                                       prm[P_LOADING_TOLERANCE])
            sign_change = changes_sign(eps_u, s_strength[i, k])
            B[i, B_SIGN_CHANGE, k] = sign_change
            tensile = eps_u > 0.0
            A[i, k] = 0.0 if not sign_change else decay_exponent(
                abs(eps_u), prm[P_EPS_T] if tensile else prm[P_EPS_C],
                k_t[i] if tensile else k_c[i])


@jit
def ray_pass(S, prm, W, B, decayed, lode_x, lode_y):
    """The loading test of a direction changing sign (where its secant line meets the uniaxial
    envelope; decayed = exp(-A); under P_SCALED the envelope on the ray, in finish_pass);
    where a direction loads or is so tested, the unit ray of the trial stress into W[:, W_RAY]
    and the arguments of its Lode angle's atan2 into lode_x, lode_y."""
    s_secant, s_cracked, s_crushed = S[5], S[10], S[11]
    E0, fc = prm[P_E0], prm[P_FC]
    for i in range(W.shape[0]):
        any_loading = False
        for k in range(3):
            loading = B[i, B_LOADING, k]
            if B[i, B_SIGN_CHANGE, k] and prm[P_SCALED] != 0.0:
                loading = True  # on the ray: finish_pass decides (concrete.loading_directions)
            elif B[i, B_SIGN_CHANGE, k]:
                eps_u = W[i, W_EPS_U, k]
                tensile = eps_u > 0.0
                uniaxial_stress = envelope(abs(eps_u), prm[P_FT] if tensile else fc,
                                           prm[P_EPS_T] if tensile else prm[P_EPS_C], E0,
                                           decayed[i, k], prm[P_SECANT_FLOOR])[0]
                loading = loads_across_zero(loading, True, s_cracked[i, k] | s_crushed[i, k],
                                            s_secant[i, k], eps_u, uniaxial_stress)
                B[i, B_LOADING, k] = loading
            any_loading |= loading
        B[i, B_RAY, 0], B[i, B_RAY, 1] = any_loading, False
        lode_x[i] = lode_y[i] = 0.0
        if any_loading:
            (W[i, W_RAY, 0], W[i, W_RAY, 1], W[i, W_RAY, 2], lode_x[i], lode_y[i],
             B[i, B_RAY, 1]) = unit_ray(W[i, W_TRIAL, 0], W[i, W_TRIAL, 1], W[i, W_TRIAL, 2], fc)


@jit
def strength_pass(S, prm, k_t, k_c, W, B, lode_atan, A, A_max):
    """Step 5 (errata 1.3) where a direction loads: sigma_ic on the ray (theta from lode_atan =
    arctan2(lode_y, lode_x)) with the mode rules, eps_ic (the committed ones past the peak
    where P_KEEP_PEAK: concrete.past_peak), the exponents of their envelopes into A (else 0),
    at max |eps_iu| into A_max where P_SCALED."""
    s_max, s_strength, s_peak, s_cracked, s_crushed = S[4], S[8], S[9], S[10], S[11]
    n = W.shape[0]
    rows, m = np.empty(n, np.int64), 0
    for i in range(n):
        A[i, 0] = A[i, 1] = A[i, 2] = 0.0
        if B[i, B_RAY, 0]:
            rows[m], m = i, m + 1
    sb, tb, c, mag = np.empty(m), np.empty(m), np.empty(m), np.empty(m)
    for j in range(m):
        i = rows[j]
        sb[j], tb[j], mag[j] = W[i, W_RAY, 0], W[i, W_RAY, 1], W[i, W_RAY, 2]
        c[j] = math.cos(lode_angle(lode_atan[i], B[i, B_RAY, 1]))
    scale = strength_scales(sb, tb, c, mag, prm)
    for j in range(m):
        i = rows[j]
        uniaxial_strengths(W, i, scale[j], prm)
        for k in range(3):
            eps_u = W[i, W_EPS_U, k]
            W[i, W_PEAK, k] = peak_strain(W[i, W_STRENGTH, k], prm[P_FC], prm[P_FT],
                                          prm[P_EPS_C], prm[P_EPS_T], prm[P_E0], prm[P_SLOPE])
            if prm[P_KEEP_PEAK] != 0.0 and keeps_peak(eps_u, B[i, B_SIGN_CHANGE, k],
                                                      s_cracked[i, k], s_crushed[i, k]):
                W[i, W_STRENGTH, k], W[i, W_PEAK, k] = s_strength[i, k], s_peak[i, k]
            A[i, k] = decay_exponent(abs(eps_u), abs(W[i, W_PEAK, k]),
                                     k_t[i] if eps_u > 0.0 else k_c[i])
            if prm[P_SCALED] != 0.0:
                A_max[i, k] = decay_exponent(s_max[i, k], abs(W[i, W_PEAK, k]),
                                             k_t[i] if eps_u > 0.0 else k_c[i])


@jit
def finish_pass(S, frozen, has_frozen, prm, W, B, decayed, decayed_max, O):
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
            if B[i, B_RAY, 0]:  # the parameters on the ray
                env_stress, env_secant = envelope(abs(eps_u), abs(W[i, W_STRENGTH, k]),
                                                  abs(W[i, W_PEAK, k]), E0, decayed[i, k],
                                                  prm[P_SECANT_FLOOR])
                if prm[P_SCALED] != 0.0 and B[i, B_SIGN_CHANGE, k]:  # ray_pass's deferral
                    B[i, B_LOADING, k] = loads_across_zero(
                        B[i, B_LOADING, k], True, s_cracked[i, k] | s_crushed[i, k], E,
                        eps_u, env_stress)
                if prm[P_SCALED] != 0.0:
                    at_max = envelope(s_max[i, k], abs(W[i, W_STRENGTH, k]),
                                      abs(W[i, W_PEAK, k]), E0, decayed_max[i, k],
                                      prm[P_SECANT_FLOOR])[0]
                    env_stress, env_secant = scaled_envelope(
                        env_stress, env_secant, at_max, E * s_max[i, k],
                        B[i, B_SIGN_CHANGE, k], prm[P_SECANT_FLOOR], E0)
            else:
                env_stress, env_secant = abs(trial), E
            loading, W[i, W_LOCAL, k], o_secant[i, k] = envelope_stress(
                trial, eps_u, E, B[i, B_LOADING, k], B[i, B_SIGN_CHANGE, k], held_point,
                env_stress, env_secant)
            (o_max[i, k], o_poisson[i, k], o_strength[i, k], o_peak[i, k], o_cracked[i, k],
             o_crushed[i, k]) = direction_state(
                eps_u, loading, held_point, s_max[i, k], s_poisson[i, k], s_strength[i, k],
                s_peak[i, k], s_cracked[i, k], s_crushed[i, k], W[i, W_STRENGTH, k],
                W[i, W_PEAK, k], nu0, prm[P_NU_MAX])
            o_eps_u[i, k] = eps_u
        G = shear_modulus(o_secant[i, 0], o_secant[i, 1], nu0)  # eq. 3.21
        o_shear[i] = G
        # sigma_g = T_eps^T [s1, s2, s3, tau], tau = 0 (§3.2.6) except in the held axes of a
        # frozen point: G12 times the shear strain there
        c, s = W[i, W_AXES, 0], W[i, W_AXES, 1]
        sxx, syy, o_stress[i, 2], sxy = global_stress(W[i, W_LOCAL, 0], W[i, W_LOCAL, 1],
                                                      W[i, W_LOCAL, 2], c, s)
        if has_frozen:
            tau = G * local_shear_strain(o_strain[i, 0], o_strain[i, 1], o_strain[i, 3], c,
                                         s) if held_point else 0.0
            sxx, syy, sxy = add_shear_stress(sxx, syy, sxy, tau, c, s)
        o_stress[i, 0], o_stress[i, 1], o_stress[i, 3] = sxx, syy, sxy


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
        stiffness(np.maximum(secant[i, 0], floor * E0), np.maximum(secant[i, 1], floor * E0),
                  np.maximum(secant[i, 2], floor * E0), poisson[i, 0], poisson[i, 1],
                  poisson[i, 2], phi_min, C)
        G = shear[i]
        if coaxial:  # errata §3: the G12 that keeps stress and strain co-axial
            s, e = stress[i], strain[i]
            G = law.coaxial_shear_modulus(s[0], s[1], s[3], e[0], e[1], e[3], G)
        G = law.clip(G, floor * G0, G0)
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
