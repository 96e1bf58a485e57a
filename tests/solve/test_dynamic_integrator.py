"""The generalized-alpha time step of the dynamic drops (solve/integrator.py) on a single degree
of freedom m u'' + c u' + k u = 0, against its closed form and Chung & Hulbert's (1993)
published properties: second-order accuracy, the spectral radius rho_inf at infinite
frequency, no algorithmic damping at rho_inf = 1."""

from __future__ import annotations

import math

import numpy as np
import pytest

from icewall.solve.integrator import GeneralizedAlpha, Motion, TimeStep, ramp


def _integrate(m, c, k, u0, dt, n, rho_inf):
    """n time steps of the SDOF by TimeStep's force and shift: k u1 + force(u1) = 0 (linear in
    u1), history af / (1 - af) (c v0 - r0) with the static unbalance r0 = -k u0."""
    scheme = GeneralizedAlpha(rho_inf)
    mass, damping = np.array([m]), np.array([c])
    motion = Motion(np.array([u0]), np.array([0.0]), np.array([-k * u0 / m]))
    out = [motion]
    for _ in range(n):
        history = scheme.alpha_f / (1 - scheme.alpha_f) * (damping * motion.v + k * motion.u)
        step = TimeStep(mass, damping, dt, scheme, motion, history)
        shift = float(step.shift().diagonal()[0])
        # force(u) is affine: force(u) = force(0) + shift u
        u1 = -step.force(np.array([0.0])) / (k + shift)
        motion = step.motion(u1)
        out.append(motion)
    return out


def _damped_free_vibration(m, c, k, u0, t):
    omega = math.sqrt(k / m)
    xi = c / (2 * math.sqrt(k * m))
    omega_d = omega * math.sqrt(1 - xi ** 2)
    return u0 * np.exp(-xi * omega * t) * (np.cos(omega_d * t)
                                           + xi / math.sqrt(1 - xi ** 2) * np.sin(omega_d * t))


@pytest.mark.parametrize("rho_inf", [0.5, 0.8, 1.0])
def test_damped_free_vibration_converges_at_second_order(rho_inf):
    m, k, xi, u0 = 2.0e-5, 3.0e3, 0.05, 0.1  # t, N/mm: omega = 1.2e4 rad/s
    c = 2 * xi * math.sqrt(k * m)
    period = 2 * math.pi / math.sqrt(k / m)
    errors = []
    for per_period in (50, 100, 200):
        dt = period / per_period
        n = 5 * per_period  # five periods
        u = np.array([s.u[0] for s in _integrate(m, c, k, u0, dt, n, rho_inf)])
        exact = _damped_free_vibration(m, c, k, u0, dt * np.arange(n + 1))
        errors.append(np.max(np.abs(u - exact)) / u0)
    assert errors[0] < 0.05
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(orders > 1.8)  # second order (Chung & Hulbert 1993, eq. 25)


@pytest.mark.parametrize("rho_inf", [0.0, 0.5, 0.8, 1.0])
def test_spectral_radius_at_infinite_frequency_is_rho_inf(rho_inf):
    # an undamped SDOF with omega dt = 1e6: the amplification of (u, v dt, a dt^2) over one
    # step, from three independent starts, has spectral radius rho_inf (Chung & Hulbert
    # 1993: the high modes lose 1 - rho_inf per step)
    m, k, dt = 1.0, 1.0e12, 1.0
    scheme = GeneralizedAlpha(rho_inf)
    columns = []
    for u, v, a in np.eye(3):
        motion = Motion(np.array([u]), np.array([v / dt]), np.array([a / dt ** 2]))
        history = scheme.alpha_f / (1 - scheme.alpha_f) * (k * motion.u)
        step = TimeStep(np.array([m]), np.array([0.0]), dt, scheme, motion, history)
        u1 = -step.force(np.array([0.0])) / (k + float(step.shift().diagonal()[0]))
        end = step.motion(u1)
        columns.append([end.u[0], end.v[0] * dt, end.a[0] * dt ** 2])
    radius = max(abs(np.linalg.eigvals(np.array(columns).T)))
    assert radius == pytest.approx(rho_inf, abs=2e-3)


def test_no_algorithmic_damping_at_rho_inf_one():
    # undamped, rho_inf = 1 (the trapezoidal rule): the energy 1/2 (m v^2 + k u^2) is kept over
    # 100 periods to round-off; at rho_inf = 0.5 it is not (a period of 20 steps loses some)
    m, k, u0 = 1.0, 4.0 * math.pi ** 2, 1.0  # period 1
    kept = _integrate(m, 0.0, k, u0, 0.05, 2000, 1.0)
    energy = [0.5 * (m * s.v[0] ** 2 + k * s.u[0] ** 2) for s in kept]
    assert max(abs(e / energy[0] - 1.0) for e in energy) < 1e-10
    damped = _integrate(m, 0.0, k, u0, 0.05, 2000, 0.5)
    final = 0.5 * (m * damped[-1].v[0] ** 2 + k * damped[-1].u[0] ** 2)
    assert final < 0.99 * energy[0]


def test_ramp_is_smooth_and_ends_at_one():
    assert ramp(0.0, 2.0) == 0.0 and ramp(1.0, 2.0) == pytest.approx(0.5)
    assert ramp(2.0, 2.0) == 1.0 and ramp(5.0, 2.0) == 1.0
    h = 1e-6  # zero rate at both ends
    assert ramp(h, 2.0) / h == pytest.approx(0.0, abs=1e-5)
    assert (1.0 - ramp(2.0 - h, 2.0)) / h == pytest.approx(0.0, abs=1e-5)
