"""Round trip, failure handling and crash safety of the HDF5 result writer and reader."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import h5py
import numpy as np
import pytest

import icewall
from icewall.errors import ResultError
from icewall.mesh.mesh import Mesh, Region
from icewall.results import ResultWriter, StepRecord, open_result

ATTRS = {"specimen": "S1", "formulation": "plane_stress", "gauss_order": 3,
         "load_measure": "w", "load_unit": "MPa", "thickness": 150.0}


def tiny_mesh() -> Mesh:
    """Two quad4 cells: steel (0) below concrete (1), double nodes on the interface y = 10."""
    points = np.array([[0, 0], [50, 0], [50, 10], [0, 10],  # steel
                       [0, 10], [50, 10], [50, 60], [0, 60]], dtype=float)  # concrete
    return Mesh(
        points=points, cells=np.array([[0, 1, 2, 3], [4, 5, 6, 7]]), cell_type="quad4",
        cell_region=np.array([2, 1]),
        regions=(Region("core", "concrete", 1), Region("bottom_plate", "steel", 2)),
        node_sets={"support": np.array([0, 4]), "load_point": np.array([6])},
        edge_sets={"top": np.array([[6, 7]]), "bottom": np.array([[0, 1]])},
        interface_pairs=np.array([[3, 4], [2, 5]]),
        interface_normals=np.array([[0.0, 1.0], [0.0, 1.0]]),
        interface_corner=np.array([False, True]),
    )


def record(step: int, *, fields: bool = True, **kw) -> StepRecord:
    rng = np.random.default_rng(step)
    rec = StepRecord(step=step, control_displacement=0.5 * step, load=10.0 * step,
                     load_factor=0.1 * step, iterations=2 + step % 3,
                     displacement_norm=1e-7, load_norm=2e-6, wall_time=0.25 * step)
    if fields:
        rec.displacement = rng.normal(size=(8, 2))
        rec.gauss = {"stress": rng.normal(size=(2, 4, 4)), "strain": rng.normal(size=(2, 4, 4)),
                     "cracked": rng.integers(0, 2, size=(2, 4, 2)).astype(np.int8)}
    for key, val in kw.items():
        setattr(rec, key, val)
    return rec


def writer(path, **kw) -> ResultWriter:
    return ResultWriter(path, deck_text="specimen: S1\nload: w # MPa\n", deck_path="decks/s1.yaml",
                        mesh=tiny_mesh(), attrs=ATTRS, **kw)


def test_round_trip(tmp_path):
    path = tmp_path / "run.h5"
    recs = [record(1), record(2, fields=False), record(3)]
    with writer(path) as w:
        for rec in recs:
            w.write_step(rec)
        assert w.finish() == str(path)
    with open_result(path) as r:
        a = r.attrs
        assert a["format"] == "icewall-result" and a["format_version"] == 1
        assert a["software_version"] == icewall.__version__
        assert (a["units"], a["length_unit"], a["force_unit"], a["stress_unit"]) == (
            "N, mm, MPa", "mm", "N", "MPa")
        assert a["created"] and a["status"] == r.status == "completed"
        assert a["stop_reason"] == "" and a["n_steps"] == 3 and a["run_time_s"] >= 0
        for key, val in ATTRS.items():
            assert a[key] == val and type(a[key]) is type(val)
        assert r.deck_text == "specimen: S1\nload: w # MPa\n"
        m, ref = r.mesh, tiny_mesh()
        for name in ("points", "cells", "cell_region", "interface_pairs", "interface_normals",
                     "interface_corner"):
            np.testing.assert_array_equal(getattr(m, name), getattr(ref, name))
        assert m.interface_corner.dtype == bool
        assert m.cell_type == "quad4" and m.regions == ref.regions
        for sets in ("node_sets", "edge_sets"):
            got, want = getattr(m, sets), getattr(ref, sets)
            assert got.keys() == want.keys()
            for k in want:
                np.testing.assert_array_equal(got[k], want[k])
        h = r.history
        np.testing.assert_array_equal(h["step"], [1, 2, 3])
        for col in ("control_displacement", "load", "load_factor", "iterations",
                    "displacement_norm", "load_norm", "wall_time"):
            np.testing.assert_array_equal(h[col], [getattr(x, col) for x in recs])
        assert h["iterations"].dtype.kind == "i"
        assert r.steps == [1, 3]
        for rec in (recs[0], recs[2]):
            np.testing.assert_array_equal(r.displacement(rec.step), rec.displacement)
            assert r.gauss_fields(rec.step) == ["cracked", "strain", "stress"]
            for name, arr in rec.gauss.items():
                got = r.gauss(rec.step, name)
                np.testing.assert_array_equal(got, arr)
                assert got.dtype == arr.dtype
        with pytest.raises(ResultError, match="step 2"):
            r.displacement(2)
        with pytest.raises(ResultError, match="no Gauss field 'damage'"):
            r.gauss(1, "damage")
    with h5py.File(path, "r") as f:  # the documented layout, read with plain h5py
        assert f["deck"].attrs["path"] == "decks/s1.yaml"
        assert f["mesh/cells"].attrs["cell_type"] == "quad4"
        assert f["history/control_displacement"].attrs["unit"] == "mm"
        assert f["history/load"].attrs["unit"] == "MPa"
        assert f["history/wall_time"].attrs["unit"] == "s"
        assert f["history/load"].maxshape == (None,)
        g = f["steps/00003"]
        assert (g.attrs["step"], g.attrs["control_displacement"], g.attrs["load"]) == (3, 1.5, 30)
        assert g["displacement"].attrs["unit"] == "mm"
        assert g["gauss/stress"].attrs["unit"] == "MPa"


def test_file_appears_only_after_finish(tmp_path):
    path = tmp_path / "run.h5"
    w = writer(path)
    w.write_step(record(1))
    assert not path.exists() and (tmp_path / "run.h5.partial").exists()
    with open_result(tmp_path / "run.h5.partial") as r:  # readable while the run goes on
        assert r.status == "running" and r.steps == [1]
    with pytest.raises(ResultError, match="run.h5.partial"):
        open_result(path)
    assert w.finish() == str(path)
    assert path.exists() and not (tmp_path / "run.h5.partial").exists()
    with pytest.raises(RuntimeError):
        w.write_step(record(2))


def test_exception_keeps_partial_with_finished_steps(tmp_path):
    path = tmp_path / "run.h5"
    with pytest.raises(ZeroDivisionError, match="singular stiffness"):
        with writer(path) as w:
            w.write_step(record(1))
            w.write_step(record(2))
            raise ZeroDivisionError("singular stiffness at step 3")
    assert not path.exists()
    with open_result(str(path) + ".partial") as r:
        assert r.status == "failed"
        assert r.attrs["stop_reason"] == "singular stiffness at step 3"
        assert r.steps == [1, 2] and list(r.history["step"]) == [1, 2]
        assert r.attrs["n_steps"] == 2


def test_stopped_run_is_renamed(tmp_path):
    path = tmp_path / "run.h5"
    with writer(path) as w:
        w.write_step(record(1))
        w.finish(status="stopped", reason="load dropped below 80% of peak")
    assert path.exists() and not (tmp_path / "run.h5.partial").exists()
    with open_result(path) as r:
        assert r.status == "stopped"
        assert r.attrs["stop_reason"] == "load dropped below 80% of peak"


def test_normal_exit_without_finish_completes(tmp_path):
    with writer(tmp_path / "run.h5") as w:
        w.write_step(record(1))
    with open_result(tmp_path / "run.h5") as r:
        assert r.status == "completed"


@pytest.mark.parametrize("field, change", [
    ("displacement", lambda r: r.displacement.__setitem__((3, 1), np.nan)),
    ("stress", lambda r: r.gauss["stress"].__setitem__((1, 2, 0), np.inf)),
    ("n_cracked", lambda r: r.scalars.__setitem__("n_cracked", float("nan"))),
    ("load", lambda r: setattr(r, "load", float("nan"))),
    ("wall_time", lambda r: setattr(r, "wall_time", -np.inf)),
])
def test_non_finite_step_is_refused_and_not_written(tmp_path, field, change):
    path = tmp_path / "run.h5"
    with writer(path) as w:
        w.write_step(record(1, scalars={"n_cracked": 0}))
        bad = record(2, scalars={"n_cracked": 3, "new_col": 1.5})
        change(bad)
        with pytest.raises(ValueError, match=field):
            w.write_step(bad)
        w.write_step(record(2, scalars={"n_cracked": 4}))  # same step number, now valid
    with open_result(path) as r:
        assert r.steps == [1, 2] and list(r.history["step"]) == [1, 2]
        assert "new_col" not in r.history
        np.testing.assert_array_equal(r.history["n_cracked"], [0, 4])
        for col in r.history.values():
            assert col.dtype.kind != "f" or np.isfinite(col).all()
        np.testing.assert_array_equal(r.displacement(2), record(2).displacement)


def test_bad_records_are_refused(tmp_path):
    with writer(tmp_path / "run.h5") as w:
        w.write_step(record(1))
        with pytest.raises(ValueError, match="step"):
            w.write_step(record(1))
        with pytest.raises(ValueError, match="displacement: shape"):
            w.write_step(record(2, displacement=np.zeros((7, 2))))
        with pytest.raises(ValueError, match="stress"):
            w.write_step(record(2, gauss={"stress": np.zeros((3, 4, 4))}))
        with pytest.raises(ValueError, match="clashes"):
            w.write_step(record(2, scalars={"load": 1.0}))
        with pytest.raises(ValueError, match="name"):
            w.write_step(record(2, gauss={"a/b": np.zeros((2, 4, 1))}))
        w.write_step(record(2))
    with pytest.raises(ValueError, match="reserved"):
        ResultWriter(tmp_path / "x.h5", deck_text="", deck_path="", mesh=tiny_mesh(),
                     attrs={"status": "ok"})


def test_history_columns_added_mid_run(tmp_path):
    path = tmp_path / "run.h5"
    with writer(path) as w:
        w.write_step(record(1))
        w.write_step(record(2, scalars={"n_cracked": 5}))
        w.write_step(record(3, scalars={"n_cracked": 7, "max_slip": 0.02}))
        w.write_step(record(4, scalars={"max_slip": 0.03, "n_cracked": 8.0}))
        w.write_step(record(5, scalars={"n_cracked": np.int64(9)}))
    with open_result(path) as r:
        h = r.history
        assert h["n_cracked"].dtype.kind == "i" and h["max_slip"].dtype.kind == "f"
        np.testing.assert_array_equal(h["n_cracked"], [-1, 5, 7, 8, 9])
        np.testing.assert_array_equal(h["max_slip"], [np.nan, np.nan, 0.02, 0.03, np.nan])
        assert all(len(c) == 5 for c in h.values())
    with h5py.File(path, "r") as f:
        assert f["history/n_cracked"].attrs["first_step"] == 2
        assert f["history/n_cracked"].attrs["fill_value"] == -1
        assert np.isnan(f["history/max_slip"].attrs["fill_value"])
    with writer(tmp_path / "b.h5") as w:
        w.write_step(record(1, scalars={"n_cracked": 5}))
        with pytest.raises(ValueError, match="n_cracked"):
            w.write_step(record(2, scalars={"n_cracked": 5.5}))  # int column stays int


def test_unwritable_output_raises_at_construction(tmp_path):
    with pytest.raises(ResultError, match="does not exist"):
        writer(tmp_path / "missing" / "run.h5")
    (tmp_path / "a_file").write_text("x")
    with pytest.raises(ResultError, match="does not exist"):
        writer(tmp_path / "a_file" / "run.h5")
    (tmp_path / "dir.h5").mkdir()
    with pytest.raises(ResultError, match="is a directory"):
        writer(tmp_path / "dir.h5")


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0, reason="root ignores permissions")
def test_read_only_directory_raises_at_construction(tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    try:
        with pytest.raises(ResultError, match="not writable"):
            writer(ro / "run.h5")
    finally:
        ro.chmod(0o700)


def test_reader_refuses_foreign_files(tmp_path):
    with pytest.raises(ResultError, match="not found"):
        open_result(tmp_path / "nothing.h5")
    (tmp_path / "text.h5").write_text("not hdf5")
    with pytest.raises(ResultError, match="not an HDF5 file"):
        open_result(tmp_path / "text.h5")
    with h5py.File(tmp_path / "other.h5", "w") as f:
        f["x"] = np.arange(3)
    with pytest.raises(ResultError, match="not an icewall result"):
        open_result(tmp_path / "other.h5")
    with writer(tmp_path / "future.h5") as w:
        w.write_step(record(1))
    with h5py.File(tmp_path / "future.h5", "a") as f:
        f.attrs["format_version"] = 99
    with pytest.raises(ResultError, match="format_version 99"):
        open_result(tmp_path / "future.h5")


KILL_SCRIPT = """
import os, sys
sys.path.insert(0, {testdir!r})
from test_results_io import record, writer
w = writer({path!r})
for i in range(1, {n} + 1):
    w.write_step(record(i, scalars={{"n_cracked": i}}))
print("written", flush=True)
{after}
"""


def test_hard_kill_leaves_readable_partial(tmp_path):
    path = tmp_path / "run.h5"
    script = KILL_SCRIPT.format(testdir=os.path.dirname(__file__), path=str(path), n=4,
                                after="os._exit(1)")
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert proc.returncode == 1 and "written" in proc.stdout, proc.stderr
    assert not path.exists()
    with open_result(str(path) + ".partial") as r:
        assert r.status == "running"
        assert r.steps == [1, 2, 3, 4]
        np.testing.assert_array_equal(r.history["n_cracked"], [1, 2, 3, 4])
        np.testing.assert_array_equal(r.displacement(4), record(4).displacement)
        np.testing.assert_array_equal(r.gauss(3, "stress"), record(3).gauss["stress"])


def test_sigkill_while_writing_leaves_consistent_partial(tmp_path):
    """Kill at an arbitrary moment of a long run: every step the file reports is complete."""
    path = tmp_path / "run.h5"
    loop = textwrap.dedent("""
        i = {n}
        while True:
            i += 1
            w.write_step(record(i, scalars={{"n_cracked": i}}))
    """).format(n=3)
    script = KILL_SCRIPT.format(testdir=os.path.dirname(__file__), path=str(path), n=3,
                                after=loop)
    proc = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    assert proc.stdout.readline().strip() == "written"
    proc.kill()
    proc.wait()
    proc.stdout.close()
    with open_result(str(path) + ".partial") as r:
        n = r.attrs["n_steps"]
        assert n >= 3 and r.steps == list(range(1, n + 1))
        np.testing.assert_array_equal(r.history["step"], r.steps)
        np.testing.assert_array_equal(r.history["n_cracked"], r.steps)
        last = r.steps[-1]
        np.testing.assert_array_equal(r.gauss(last, "strain"), record(last).gauss["strain"])
