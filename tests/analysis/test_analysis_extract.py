"""The result extractor on synthetic curves with known answers and on a small HDF5 file."""

from __future__ import annotations

import json

import numpy as np
import pytest

from icewall.analysis.extract import extract, first_maximum
from icewall.mesh.mesh import Mesh, Region
from icewall.results import ResultWriter, StepRecord


def softening(step: float = 0.5, end: float = 40.0, odd: bool = False):
    """Rise p = d to 10 at 10 mm, drop to 4 at 20 mm, then rise by 0.1 per mm (6 at 40 mm).
    odd: steps that miss 40 mm (the breakpoints 10 and 20 mm stay on the grid)."""
    d = np.arange(step, end + 1e-9, step)
    if odd:
        d = np.union1d(np.arange(0.7, 39.9, 0.7), [10.0, 20.0, 41.3])
    p = np.interp(d, [0.0, 10.0, 20.0, 50.0], [0.0, 10.0, 4.0, 7.0])
    return d, p


def test_bilinear_hardening_never_peaks():
    d = np.arange(1.0, 41.0)
    p = np.where(d <= 5.0, 2.0 * d, 10.0 + 0.1 * (d - 5.0))
    r = extract((d, p))
    assert r["peak_load"] == pytest.approx(13.5) and r["deflection_at_peak"] == 40.0
    assert r["peaked"] is False
    assert r["residual_load_40"] == pytest.approx(13.5)
    assert r["residual_plateau"] is None and r["plateau_window"] is None  # no post-peak range
    assert r["initial_stiffness"] == pytest.approx(2.0)
    assert r["first_step_stiffness"] == pytest.approx(2.0)
    assert r["first_cracking"] is None and r["tension_plate_yielded"] is None


@pytest.mark.parametrize(("step", "odd"), [(0.5, False), (1.0, False), (None, True)])
def test_softening_curve(step, odd):
    d, p = softening(step or 1.0, 40.0, odd)
    r = extract((d, p))
    assert r["peak_load"] == pytest.approx(10.0) and r["deflection_at_peak"] == pytest.approx(10.0)
    assert r["peaked"] is True
    assert r["residual_load_40"] == pytest.approx(6.0)
    assert r["plateau_window"] == [20.0, 40.0]
    # mean of the straight line 4 -> 6 over [20, 40]; independent of the step size
    assert r["residual_plateau"] == pytest.approx(5.0)
    assert r["residual_ratio_40"] == pytest.approx(0.6)
    assert r["initial_stiffness"] == pytest.approx(1.0)
    json.dumps(r)  # JSON-ready


def test_the_first_peak_of_a_curve_with_two_humps():
    """The first maximum is the largest load before the curve first falls 5 % below its
    running maximum (CF-4's second hump: docs/solver.md item 29); on one hump it is the
    peak, and a dip of less than 5 % does not end it."""
    d = np.arange(1.0, 41.0)
    two = np.interp(d, [0.0, 7.0, 8.0, 12.0, 14.0, 40.0], [0.0, 6.25, 5.9, 6.46, 2.0, 1.0])
    r = extract({"deflection": d, "load": two})
    assert r["peak_load"] == pytest.approx(6.46) and r["deflection_at_peak"] == 12.0
    assert r["first_peak_load"] == pytest.approx(6.25)
    assert r["deflection_at_first_peak"] == 7.0 and r["first_peak_settled"]
    dip = np.interp(d, [0.0, 7.0, 8.0, 12.0, 14.0, 40.0], [0.0, 6.25, 6.0, 6.46, 2.0, 1.0])
    stopped = extract({"deflection": d[:8], "load": dip[:8]})  # at 8 mm: 6.0 > 0.95 x 6.25
    assert stopped["first_peak_load"] == pytest.approx(6.25)
    assert not stopped["first_peak_settled"]
    assert extract({"deflection": d, "load": dip})["first_peak_load"] == pytest.approx(6.46)
    one = extract(softening(1.0, 40.0, False))
    assert one["first_peak_load"] == one["peak_load"]
    assert first_maximum(np.array([1.0, 3.0, 2.0, 4.0])) == 1  # 2 < 0.95 * 3
    assert first_maximum(np.array([1.0, 2.0, 3.0])) == 2  # never softens: the largest
    assert first_maximum(np.array([])) == -1


def test_plateau_window_follows_a_late_peak():
    d = np.arange(1.0, 41.0)
    p = np.interp(d, [0.0, 15.0, 25.0, 40.0], [0.0, 15.0, 5.0, 5.0])
    r = extract({"deflection": d, "load": p})
    assert r["plateau_window"] == [25.0, 40.0]
    assert r["residual_plateau"] == pytest.approx(5.0)


def test_run_too_short_for_the_residual():
    d, p = softening(1.0, 25.0)
    r = extract((d, p))
    assert r["peak_load"] == pytest.approx(10.0) and r["final_deflection"] == 25.0
    assert r["residual_load_40"] is None and r["residual_plateau"] is None
    assert r["residual_ratio_40"] is None


def test_preload_steps_and_failure_sequence_from_history_columns():
    d = np.array([0.05, 0.1, 1.1, 2.1, 3.1, 4.1, 5.1])
    p = np.array([0.0, 0.0, 3.0, 5.0, 6.0, 4.0, 3.5])
    hist = {"control_displacement": d, "load": p, "step": np.arange(1, 8),
            "preload_stage": np.array([1, 1, 0, 0, 0, 0, 0]),
            "cracked_in_plane": np.array([0, 0, 4, 9, 12, 20, 25]),
            "crushed": np.array([0, 0, 0, 0, 2, 8, 9]),
            "yielded": np.array([0, 0, 0, 0, 0, 3, 5])}
    r = extract(hist)
    assert r["n_steps"] == 5 and r["start_deflection"] == pytest.approx(0.1)
    assert r["peak_load"] == 6.0 and r["peak_step"] == 5
    assert r["first_step_stiffness"] == pytest.approx(3.0)  # measured from the preload end
    assert r["initial_stiffness"] == pytest.approx(3.0)  # 30 % of 6 lies in the first step
    assert r["first_cracking"] == {"step": 3, "deflection": 1.1, "load": 3.0,
                                   "stage": "control", "relative_to_peak": "before_peak"}
    assert r["first_crushing"]["relative_to_peak"] == "at_peak"
    assert r["first_yield"]["step"] == 6
    # no Gauss field: falls back to the count of all steel and says so
    assert r["tension_plate_yielded"] == "after_peak"
    assert "all steel" in r["tension_plate_yield"]["source"]


def tiny_mesh() -> Mesh:
    """Steel bottom plate (cell 0) under a concrete core (cell 1), double nodes at y = 10."""
    points = np.array([[0, 0], [50, 0], [50, 10], [0, 10],
                       [0, 10], [50, 10], [50, 60], [0, 60]], dtype=float)
    return Mesh(
        points=points, cells=np.array([[0, 1, 2, 3], [4, 5, 6, 7]]), cell_type="quad4",
        cell_region=np.array([2, 1]),
        regions=(Region("core_1", "concrete", 1), Region("bottom_plate", "steel", 2)),
        node_sets={"support": np.array([0])}, edge_sets={"top": np.array([[6, 7]])},
        interface_pairs=np.array([[3, 4], [2, 5]]),
        interface_normals=np.array([[0.0, 1.0], [0.0, 1.0]]),
        interface_corner=np.array([False, True]),
    )


def write_result(path, *, yield_step: int | None, every: int = 1, fields: bool = True,
                 n: int = 40):
    """Softening curve at 1 mm steps; the bottom plate yields from `yield_step` on; concrete
    crushes in the core from step 8."""
    d, p = softening(1.0, float(n))
    with ResultWriter(path, deck_text="specimen: T\n", deck_path="t.yaml", mesh=tiny_mesh(),
                      attrs={"specimen": "T", "load_measure": "w", "load_unit": "MPa"}) as w:
        for i, (di, pi) in enumerate(zip(d, p, strict=True), start=1):
            yielded = yield_step is not None and i >= yield_step
            gauss = {}
            if fields and i % every == 0:
                peeq = np.zeros((2, 4, 1))
                peeq[0] = 1e-3 if yielded else 0.0
                flags = np.zeros((2, 4, 6), np.int8)
                flags[1, :, 0] = 1
                flags[1, :2, 3] = int(i >= 8)
                gauss = {"equivalent_plastic_strain": peeq, "concrete_flags": flags}
            w.write_step(StepRecord(
                step=i, control_displacement=float(di), load=float(pi), load_factor=float(pi),
                iterations=3, displacement_norm=1e-4, load_norm=1e-4, wall_time=0.1 * i,
                gauss=gauss, scalars={"cracked_in_plane": 4, "crushed": 2 * int(i >= 8),
                                      "yielded": int(yielded), "preload_stage": 0}))
    return path


@pytest.mark.parametrize(("yield_step", "every", "verdict"), [
    (6, 1, "before_peak"), (10, 1, "before_peak"), (14, 1, "after_peak"),
    (14, 5, "after_peak"),  # stored at 10 (the peak, no yield yet) and 15
    (12, 7, "undetermined"),  # stored at 7 (no yield) and 14: the peak (10) lies between
    (None, 1, "no"),
])
def test_hdf5_tension_plate(tmp_path, yield_step, every, verdict):
    path = write_result(tmp_path / "run.h5", yield_step=yield_step, every=every)
    r = extract(path)
    assert r["specimen"] == "T" and r["status"] == "completed" and r["load_unit"] == "MPa"
    assert r["peak_load"] == pytest.approx(10.0) and r["peak_step"] == 10
    assert r["residual_load_40"] == pytest.approx(6.0)
    assert r["residual_plateau"] == pytest.approx(5.0)
    assert r["tension_plate_yielded"] == verdict
    assert r["tension_plate_yield"]["source"] == "equivalent_plastic_strain"
    assert r["first_cracking"]["step"] == 1
    crush = r["first_crushing"]
    assert crush["step"] == 8 and crush["relative_to_peak"] == "before_peak"
    assert crush["location"]["region"] == "core_1"
    assert crush["location"]["x"] == pytest.approx(25.0)
    json.dumps(r)


def test_hdf5_without_fields_falls_back_to_the_yield_count(tmp_path):
    path = write_result(tmp_path / "run.h5", yield_step=12, fields=False, n=30)
    r = extract(str(path))
    assert r["tension_plate_yielded"] == "after_peak"
    assert "all steel" in r["tension_plate_yield"]["source"]
    assert r["residual_load_40"] is None and r["final_deflection"] == 30.0
    assert "location" not in r["first_crushing"]


def test_bad_input():
    with pytest.raises(TypeError):
        extract(42)
    with pytest.raises(ValueError):
        extract(([1.0, 2.0], [1.0]))


def test_tension_plate_from_its_history_column():
    """Issue 20: the bottom plate's own yield count, recorded every step, beats the count of
    all steel (here the diaphragms yield first, at step 3; the plate at step 12)."""
    d, p = softening(1.0, 20.0)
    n = len(d)
    hist = {"deflection": d, "load": p,
            "yielded": (np.arange(1, n + 1) >= 3).astype(int),
            "tension_plate_yielded": 4 * (np.arange(1, n + 1) >= 12).astype(int)}
    r = extract(hist)
    assert r["first_yield"]["step"] == 3
    assert r["tension_plate_yield"]["step"] == 12
    assert r["tension_plate_yielded"] == "after_peak"
    assert "tension_plate_yielded" in r["tension_plate_yield"]["source"]
