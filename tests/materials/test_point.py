"""Single material-point paths through the concrete model (no mesh).

Reference values: eqs. 3.9-3.11 via icewall.materials.uniaxial; G_f / h_c and G_cr / h_c from
eqs. 3.28, 3.30 (errata 1.1 on 3.26-3.27: area from the peak); equal-biaxial strength 1.16-1.2 f'c
(Kupfer 1969; errata §2.3 set B has f_cb = 1.20).
"""

from __future__ import annotations

import io
import json

import numpy as np
import pytest

from icewall.materials.parameters import derive_concrete_parameters
from icewall.materials.point import control_schedule, run_path
from icewall.materials.uniaxial import compression_envelope, tension_envelope

PARAMS = derive_concrete_parameters(53.5, 100.0)


@pytest.mark.parametrize("kind", ["compression", "tension"])
def test_uniaxial_path_follows_envelope_with_secant_unloading(kind: str) -> None:
    compression = kind == "compression"
    envelope = compression_envelope if compression else tension_envelope
    peak, peak_strain, decay = ((PARAMS.fc, PARAMS.eps_c, PARAMS.k_c) if compression
                                else (PARAMS.ft, PARAMS.eps_t, PARAMS.k_t))
    unload = [0.6 * peak_strain, 2.0 * peak_strain]
    result = run_path(f"uniaxial-{kind}", PARAMS, "plane_stress", 200, 4.0 * peak_strain,
                      unload_at=unload)
    strain, stress = np.abs(result.strain[:, 0]), np.abs(result.stress[:, 0])
    running_max = np.maximum.accumulate(strain)
    on_envelope = strain >= running_max * (1 - 1e-12)
    expected, _ = envelope(strain, PARAMS.E0, peak, peak_strain, decay)
    np.testing.assert_allclose(stress[on_envelope], expected[on_envelope], rtol=1e-8,
                               atol=1e-10 * peak)
    # off the envelope: along the secant of the largest strain so far (Fig. 3.13)
    max_stress, _ = envelope(running_max, PARAMS.E0, peak, peak_strain, decay)
    secant = np.divide(max_stress, running_max, out=np.zeros_like(strain), where=running_max > 0)
    np.testing.assert_allclose(stress[~on_envelope], (secant * strain)[~on_envelope], rtol=1e-8,
                               atol=1e-10 * peak)
    assert (~on_envelope).sum() > 100  # both cycles were run
    np.testing.assert_allclose(result.stress[:, 1], 0.0, atol=1e-9 * PARAMS.fc)
    assert result.summary()["failure_mode"] == ("crushed" if compression else "cracked in plane")


@pytest.mark.parametrize("kind", ["compression", "tension"])
def test_softening_energy_equals_fracture_energy_over_band(kind: str) -> None:
    compression = kind == "compression"
    peak_strain, decay = (PARAMS.eps_c, PARAMS.k_c) if compression else (PARAMS.eps_t, PARAMS.k_t)
    energy = (PARAMS.G_cr if compression else PARAMS.Gf) / PARAMS.h_c
    step = peak_strain / 10.0  # the peak lies on the grid
    n_steps = int(np.ceil((peak_strain + 12.0 / decay) / step))  # tail exp(-12) < 1e-5
    result = run_path(f"uniaxial-{kind}", PARAMS, "plane_stress", n_steps, n_steps * step)
    strain, stress = np.abs(result.strain[:, 0]), np.abs(result.stress[:, 0])
    beyond = strain >= peak_strain * (1 - 1e-12)
    area = np.trapezoid(stress[beyond], strain[beyond])
    assert area == pytest.approx(energy, rel=0.01)


def test_equal_biaxial_strength_and_falling_tension_compression_branch() -> None:
    equal = run_path("biaxial:1", PARAMS, "plane_stress", 150, 0.005).summary()
    assert 1.16 <= -equal["peak_stress_xx"] / PARAMS.fc <= 1.2 + 1e-6
    strain_controlled = run_path("biaxial-strain:1", PARAMS, "plane_stress", 150, 0.005)
    assert -strain_controlled.summary()["peak_stress_xx"] / PARAMS.fc == pytest.approx(
        -equal["peak_stress_xx"] / PARAMS.fc, rel=1e-6)
    peaks = [-run_path(f"biaxial:{r}", PARAMS, "plane_stress", 150, 0.005).summary()[
        "peak_stress_xx"] / PARAMS.fc for r in (0.0, -0.02, -0.05, -0.1, -0.2)]
    assert peaks[0] == pytest.approx(1.0, rel=1e-9)
    assert np.all(np.diff(peaks) < 0.0), peaks


def _principal_angle(tensor: np.ndarray, shear_factor: float) -> np.ndarray:
    return 0.5 * np.arctan2(shear_factor * tensor[:, 3], tensor[:, 0] - tensor[:, 1])


def test_pure_shear_is_coaxial() -> None:
    result = run_path("pure-shear", PARAMS, "plane_stress", 100, 0.003)
    loaded = np.abs(result.stress[:, 3]) > 1e-6
    np.testing.assert_allclose(_principal_angle(result.stress[loaded], 2.0),
                               _principal_angle(result.strain[loaded], 1.0), atol=1e-9)
    np.testing.assert_allclose(result.stress[:, 0], result.stress[:, 1], atol=1e-9)
    assert result.summary()["failure_mode"].startswith("cracked in plane")


def test_rotating_strain_axes_rotate_the_orthotropy() -> None:
    n = 200
    result = run_path("rotating", PARAMS, "plane_stress", n, 0.002)
    turn = np.clip(2.0 * np.arange(n + 1) / n - 1.0, 0.0, 1.0)
    # direction 1 is the tensile principal strain, rotating with theta = 90 deg * turn
    np.testing.assert_allclose(result.angle[1:], 0.5 * np.pi * turn[1:], atol=1e-9)
    np.testing.assert_allclose(_principal_angle(result.stress[-1:], 2.0) % np.pi,
                               0.5 * np.pi, atol=1e-6)
    assert result.cracked_in_plane[-1]


def test_plane_strain_confinement_and_out_of_plane_crack() -> None:
    result = run_path("uniaxial-compression", PARAMS, "plane_strain", 100, 0.002)
    ratio = result.stress[1:, 2] / result.stress[1:, 0]
    assert ratio[0] == pytest.approx(PARAMS.nu0, rel=0.05)  # sigma_3 = nu sigma_1 at start
    assert np.all(np.diff(ratio) > 0.0)  # nu grows with eq. 3.19
    # biaxial in-plane compression, then release to zero strain: the hypoelastic increments
    # (larger nu on the way back) leave sigma_3 in tension under eps_3 = 0 -> out-of-plane crack
    released = run_path("biaxial-strain:1", PARAMS, "plane_strain", 200, 0.005,
                        unload_at=[0.004])
    back = int(np.argmin(np.abs(released.control[5:]))) + 5
    assert released.control[back] == 0.0
    assert released.cracked_out_of_plane[back] and not released.cracked_out_of_plane[100]
    assert released.stress[:back, 2].min() < -PARAMS.fc  # confined before the release


def test_control_schedule_and_outputs() -> None:
    schedule = control_schedule(1.0, 4, [0.5])
    np.testing.assert_allclose(schedule, [0, .25, .5, .25, 0, .25, .5, .75, 1.0])
    result = run_path("uniaxial-compression", PARAMS, "axisymmetric", 20, 0.005)
    np.testing.assert_allclose(result.stress[:, 1:3], 0.0, atol=1e-9 * PARAMS.fc)
    buffer = io.StringIO()
    result.to_csv(buffer)
    lines = buffer.getvalue().splitlines()
    assert len(lines) == 22 and lines[0].startswith("control,eps_xx")
    summary = result.summary()
    json.dumps(summary)
    assert summary["peak_stress_xx"] == pytest.approx(-PARAMS.fc, rel=1e-9)
    with pytest.raises(ValueError):
        run_path("twisting", PARAMS)
