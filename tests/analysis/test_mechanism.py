"""Mechanism checks of issue 20 §1: the tension plate at the peak against f_y, where the first
crushing occurs, the residual mechanism; from history columns or from the stress field."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from icewall.analysis.mechanism import format_mechanism, mechanism_check
from icewall.results.probe import MechanismProbe
from icewall.results.writer import ResultWriter, StepRecord
from tests.analysis.test_analysis_extract import softening, tiny_mesh

CF4_TEXT = (Path(__file__).resolve().parents[2] / "decks" / "cf4.yaml").read_text()
G = 0.5 / np.sqrt(3.0)  # quad4, 2x2 Gauss: stations at 25 -+ 50 G
# tiny mesh: bottom plate = cell 0 (x 0..50); Gauss point order (-,-), (-,+), (+,-), (+,+)


def plate_stress(level: float) -> np.ndarray:
    """sigma_xx of the plate: `level` at the station nearest x = 0, 2 level at the far one,
    with a through-thickness gradient that averages out."""
    stress = np.zeros((2, 4, 4))
    stress[0, :, 0] = [level - 5.0, level + 5.0, 2 * level - 5.0, 2 * level + 5.0]
    return stress


def test_probe_means_over_thickness_and_the_largest_station():
    probe = MechanismProbe(tiny_mesh(), 2)
    out = probe.plate_stress(plate_stress(100.0))
    assert out["tension_plate_stress_mid"] == pytest.approx(100.0)
    assert out["tension_plate_stress_max"] == pytest.approx(200.0)
    assert out["tension_plate_stress_max_x"] == pytest.approx(25.0 + 50.0 * G)


def test_probe_crushing_location():
    probe = MechanismProbe(tiny_mesh(), 2)
    crushed = np.zeros((2, 4), bool)
    assert probe.crushing(crushed) == {}
    crushed[1, [0, 1]] = True  # the two points nearest x = 0 of the core
    yielded = np.zeros((2, 4), bool)
    yielded[0, 3] = yielded[1, 0] = True  # one plate point; the core's flag is not counted
    one = probe.scalars(np.zeros((2, 4, 4)), None, yielded)
    assert one["tension_plate_yielded"] == 1  # one face only: no section through the thickness
    assert one["tension_plate_sections_yielded"] == 0
    assert "tension_plate_section_yield_x" not in one
    yielded[0, 2] = True  # now both points of the far station
    full = probe.scalars(np.zeros((2, 4, 4)), None, yielded)
    assert full["tension_plate_sections_yielded"] == 1
    assert full["tension_plate_section_yield_x"] == pytest.approx(25.0 + 50.0 * G)
    out = probe.crushing(crushed)
    assert out["crushed_x_min"] == pytest.approx(25.0 - 50.0 * G)
    assert out["crushed_x_max"] == pytest.approx(25.0 - 50.0 * G)
    assert out["crushed_y_mean"] == pytest.approx(35.0)
    assert out["crushed_region"] == 1  # core_1's tag


def write_run(path, *, history: bool, field_every: int = 1, n: int = 40, yield_step: int = 12,
              specimen: str = "CF-4"):
    """Softening curve peaking at step 10 (10 MPa); the plate's midspan stress rises 40 MPa a
    step and its points yield from `yield_step`; the core crushes from step 8, and from step 20
    also at its far points."""
    d, p = softening(1.0, float(n))
    probe = MechanismProbe(tiny_mesh(), 2)
    with ResultWriter(path, deck_text=CF4_TEXT, deck_path="cf4.yaml", mesh=tiny_mesh(),
                      attrs={"specimen": specimen, "load_measure": "w", "load_unit": "MPa",
                             "gauss_order": 2}) as w:
        for i, (di, pi) in enumerate(zip(d, p, strict=True), start=1):
            stress = plate_stress(40.0 * i)
            crushed = np.zeros((2, 4), bool)
            crushed[1, [0, 1]] = i >= 8
            crushed[1, [2, 3]] = i >= 20
            yielded = np.zeros((2, 4), bool)
            yielded[0, 2:] = i >= yield_step
            scalars = {"crushed": int(crushed.sum()), "preload_stage": 0}
            if history:
                scalars.update(probe.scalars(stress, crushed, yielded))
            gauss = {"stress": stress} if i % field_every == 0 else {}
            w.write_step(StepRecord(
                step=i, control_displacement=float(di), load=float(pi), load_factor=float(pi),
                iterations=3, displacement_norm=1e-4, load_norm=1e-4, wall_time=0.1 * i,
                gauss=gauss, scalars=scalars))
    return path


def test_check_from_history(tmp_path):
    check = mechanism_check(write_run(tmp_path / "r.h5", history=True, field_every=100))
    assert check["source"] == "history" and check["f_y"] == pytest.approx(371.0)
    assert check["peak_step"] == 10
    assert check["stress_mid"] == pytest.approx(400.0)
    assert check["mid_over_fy"] == pytest.approx(400.0 / 371.0)
    assert check["max_over_fy"] == pytest.approx(800.0 / 371.0)
    assert check["plate_reached_fy_before_peak"] is True  # 2 x 40 x 5 = 400 >= 371 at step 5
    first = check["first_crushing"]
    assert first["step"] == 8 and first["relative_to_peak"] == "before_peak"
    assert first["region"] == "core_1"
    res = check["residual"]
    assert res["deflection"] == pytest.approx(40.0) and res["load_over_peak"] == pytest.approx(0.6)
    assert res["crushing"]["x_max"] == pytest.approx(25.0 + 50.0 * G)  # spread by then
    assert "60% of the peak" in check["residual_mechanism"]
    assert "core_1" in check["residual_mechanism"]
    json.dumps(check)
    assert check["plate_yielded_at_peak"] is False
    assert check["plate_first_yield"] == {"step": 12, "deflection": 12.0,
                                          "x": pytest.approx(25.0 + 50.0 * G)}
    assert check["plate_first_point_yield"]["step"] == 12
    assert check["thesis_plate_yielded"] is False and check["plate_vs_thesis"] == "agrees"
    labels = [label for label, _ in format_mechanism(check)]
    assert labels == ["bottom plate at peak", "bottom plate yielded", "first crushing",
                      "residual mechanism"]


@pytest.mark.parametrize(("specimen", "yield_step", "verdict"), [
    ("CF-4", 10, "contradicts"),  # yielded at the peak step: 4.2.1 says it had not
    ("CF-8", 10, "agrees"),
    ("CF-8", 11, "contradicts"),
    ("TF-1", 5, None),  # the text says nothing of the TF plates
])
def test_plate_yield_against_4_2_1(tmp_path, specimen, yield_step, verdict):
    check = mechanism_check(write_run(tmp_path / "r.h5", history=True, field_every=100,
                                      yield_step=yield_step, specimen=specimen))
    assert check["plate_yielded_at_peak"] is (yield_step <= 10)
    assert check["plate_vs_thesis"] == verdict
    text = dict(format_mechanism(check))["bottom plate yielded"]
    assert ("not by the peak" in text) is (yield_step > 10)
    assert (verdict or "thesis") in text if verdict else "thesis" not in text


def test_check_falls_back_to_the_stress_field_at_the_peak(tmp_path):
    check = mechanism_check(write_run(tmp_path / "r.h5", history=False, field_every=5))
    assert check["source"] == "stress field at step 10"
    assert check["stress_mid"] == pytest.approx(400.0)
    assert check["plate_reached_fy_before_peak"] is None  # needs the history
    assert check["first_crushing"]["step"] == 8  # from the crushed count
    assert "no location" in check["first_crushing"]["source"]


def test_check_without_stress_at_the_peak_says_so(tmp_path):
    check = mechanism_check(write_run(tmp_path / "r.h5", history=False, field_every=3))
    assert check["stress_mid"] is None and check["mid_over_fy"] is None
    assert "outputs.fields" in check["source"]
