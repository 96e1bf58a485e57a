"""CSA S474 clause 8.4.4 on synthetic curves with hand-computed answers, and in the summary."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from icewall.analysis.ductility import csa_ductility
from icewall.analysis.summary import format_summary, summarize
from icewall.mesh.mesh import Mesh, Region
from icewall.results import ResultWriter, StepRecord

DECK = Path(__file__).resolve().parents[2] / "decks" / "cf4.yaml"


def elastic_plastic(end: float) -> tuple[np.ndarray, np.ndarray]:
    """K = 2 per mm up to P = 6 at d = 3 mm, then flat to `end` (1 mm steps)."""
    d = np.arange(1.0, end + 0.5)
    return d, np.minimum(2.0 * d, 6.0)


def test_bilinear_curve_passes_with_known_yield_point():
    d, p = elastic_plastic(30.0)
    r = csa_ductility(d, p)
    assert r.verdict == "pass"
    assert r.initial_stiffness == pytest.approx(2.0)
    assert (r.yield_load, r.yield_deflection) == (pytest.approx(6.0), pytest.approx(3.0))
    assert r.ductility_ratio == pytest.approx(10.0) and r.ratio_is_lower_bound  # 30 / 3
    assert r.energy == pytest.approx(0.5 * 3 * 6 + 6 * 27)  # 171
    assert r.energy_to_required == pytest.approx(0.5 * 3 * 6 + 6 * 15)  # up to 6 d_y = 18


def test_softening_curve_fails_at_the_ratio_reached():
    d = np.arange(1.0, 12.0)
    p = np.where(d <= 3, 2.0 * d, np.where(d <= 5, 6.0, 6.0 - (d - 5.0)))  # 0.5 P_y at 8 mm
    r = csa_ductility(d, p)
    assert r.verdict == "fail"
    assert r.ductility_ratio == pytest.approx(8.0 / 3.0) and not r.ratio_is_lower_bound
    assert "2.67" in r.message
    assert r.energy_to_required is None


def test_drop_between_steps_is_interpolated():
    d = np.array([1.0, 2.0, 3.0, 10.0, 30.0])
    p = np.array([2.0, 4.0, 6.0, 6.0, 1.0])  # 3.0 = 0.5 P_y at d = 10 + 20 * 3/5 = 22
    r = csa_ductility(d, p)
    assert r.verdict == "pass"  # 22 mm > 6 d_y = 18 mm
    assert r.ductility_ratio == pytest.approx(22.0 / 3.0) and not r.ratio_is_lower_bound


def test_too_short_is_undecided_with_a_message():
    d, p = elastic_plastic(12.0)
    r = csa_ductility(d, p)
    assert r.verdict == "undecided"
    assert r.ductility_ratio == pytest.approx(4.0) and r.ratio_is_lower_bound
    assert "cannot decide" in r.message and "18" in r.message  # 6 d_y = 18 mm


def test_rising_curve_is_undecided():
    d = np.arange(1.0, 40.0)
    r = csa_ductility(d, np.minimum(2.0 * d, 6.0 + 0.1 * (d - 3.0)))
    assert r.verdict == "undecided" and "still rising" in r.message


def test_origin_offset_and_least_squares_start():
    d, p = elastic_plastic(30.0)
    shifted = csa_ductility(d + 0.7, p, origin=0.7)
    assert shifted.yield_deflection == pytest.approx(3.0)
    assert shifted.ductility_ratio == pytest.approx(10.0)
    # through-origin least squares over the first 3 points (1, 2), (2, 4), (3, 6): K = 2
    assert csa_ductility(d, p, initial_points=3).initial_stiffness == pytest.approx(2.0)
    # a softer second point lowers the fitted K: sum(d p) / sum(d^2) = (2 + 6) / 5
    assert csa_ductility([1.0, 2.0, 9.0], [2.0, 3.0, 3.0],
                         initial_points=2).initial_stiffness == pytest.approx(1.6)


def synthetic_file(path: Path, d: np.ndarray, p: np.ndarray) -> str:
    pts = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]])
    mesh = Mesh(points=pts, cells=np.array([[0, 1, 2, 3]]), cell_type="quad4",
                cell_region=np.array([1]), regions=(Region("core", "concrete", 1),))
    w = ResultWriter(path, deck_text=DECK.read_text(), deck_path=str(DECK), mesh=mesh,
                     attrs={"specimen": "CF-4", "load_measure": "w", "load_unit": "MPa",
                            "deck_overrides": "[]"})
    for i, (di, pi) in enumerate(zip(d, p, strict=True)):
        w.write_step(StepRecord(i + 1, float(di), float(pi), float(pi), 3, 1e-9, 1e-9, 0.1))
    return w.finish()


def test_summary_and_sweep_table_report_ductility(tmp_path):
    d, p = elastic_plastic(30.0)
    path = synthetic_file(tmp_path / "epp.h5", d, p)
    s = summarize(path)["ductility"]
    assert s["verdict"] == "pass" and s["ductility_ratio"] == pytest.approx(10.0)
    assert s["energy_unit"] == "MPa mm"
    # CF-4: w = P / (b L/5), five jacks (0, +-300, +-1058): total = 5 * 381 * 300 w
    assert s["energy_Nmm"] == pytest.approx(171.0 * 5 * 381 * 300)
    text = format_summary(summarize(path))
    assert "ductility (CSA S474)   : pass: mu = >= 10.00" in text
    from icewall.analysis.sweep_table import build_rows, format_table, ratio_stats

    job = SimpleNamespace(name="epp", varied=(), output=path, deck=str(DECK), overrides=())
    rows = build_rows([job], {"epp": {"status": "completed", "path": path}})
    assert rows[0]["ductility_ratio"] == pytest.approx(10.0)
    assert rows[0]["ductility"] == "pass (mu>=)"
    assert rows[0]["energy_Nmm"] == pytest.approx(171.0 * 5 * 381 * 300)
    assert "pass (mu>=)" in format_table(rows, ratio_stats(rows))


def test_summary_of_an_unreadable_deck_gives_no_joules(tmp_path):
    d, p = elastic_plastic(12.0)
    path = synthetic_file(tmp_path / "short.h5", d, p)
    import h5py

    with h5py.File(path, "r+") as f:  # a deck that no longer parses
        del f["deck"]
        f.create_dataset("deck", data="not: [a deck", dtype=h5py.string_dtype())
    s = summarize(path)["ductility"]
    assert s["verdict"] == "undecided" and s["energy_Nmm"] is None
    assert s["energy"] == pytest.approx(0.5 * 3 * 6 + 6 * 9)
