"""ResultWriter.reopen (icewall run --resume): the .partial of an interrupted run is cut back to
the steps its checkpoint holds and written on; the checkpoint sidecar's life cycle."""

from __future__ import annotations

import os

import numpy as np
import pytest
from test_results_io import record, writer

from icewall.errors import ResultError
from icewall.results import ResultWriter, open_result
from icewall.results.checkpoint import checkpoint_path, read_checkpoint


def _interrupted_run(path, n_steps: int) -> None:
    w = writer(path)
    for step in range(1, n_steps + 1):
        extra = {"late_column": 7} if step == n_steps else {}
        w.write_step(record(step, scalars=extra, forensics={"gap_flips": np.array([1, 0])}))
        w.write_checkpoint({"u": np.full(3, float(step))})
    w.finish("failed", "interrupted by SIGTERM")


def test_reopen_drops_later_steps_and_goes_on(tmp_path):
    path = tmp_path / "run.h5"
    _interrupted_run(path, 3)
    assert int(read_checkpoint(checkpoint_path(path))["step"]) == 3
    w = ResultWriter.reopen(path, 2)  # e.g. killed after step 3 was written, before its checkpoint
    with open_result(str(path) + ".partial") as r:
        assert r.status == "running" and r.attrs["n_steps"] == 2
        assert list(r.history["step"]) == [1, 2] and r.steps == [1, 2]
        assert "late_column" not in r.history  # it first appeared in the dropped step
        assert r.forensics(3) == {} and r.attrs["resumed_at"] == [2]
    w.write_step(record(3))
    w.write_step(record(4))
    assert w.finish() == str(path)
    assert not os.path.exists(checkpoint_path(path))
    with open_result(path) as r:
        assert r.status == "completed" and list(r.history["step"]) == [1, 2, 3, 4]
        np.testing.assert_array_equal(r.displacement(3), record(3).displacement)


def test_reopen_refuses_more_steps_than_stored(tmp_path):
    path = tmp_path / "run.h5"
    _interrupted_run(path, 2)
    with pytest.raises(ResultError, match="cannot keep 3 of 2 steps"):
        ResultWriter.reopen(path, 3)


def test_new_run_removes_a_stale_checkpoint(tmp_path):
    path = tmp_path / "run.h5"
    _interrupted_run(path, 2)
    assert os.path.exists(checkpoint_path(path))
    writer(path).finish("failed", "x")  # a fresh run of the same name starts clean
    assert not os.path.exists(checkpoint_path(path))


def test_checkpoint_round_trip_is_exact(tmp_path):
    from icewall.results.checkpoint import write_checkpoint

    arrays = {"group0/strain": np.random.default_rng(1).normal(size=(5, 4)),
              "gap/state": np.array([0, 2, 1], np.int8), "group0/cracked": np.eye(3, dtype=bool),
              "path/stage": np.array("control"), "path/load_factor": np.asarray(0.1 + 0.2)}
    write_checkpoint(tmp_path / "c.npz", arrays)
    back = read_checkpoint(tmp_path / "c.npz")
    assert sorted(back) == sorted(arrays)
    for name, value in arrays.items():
        assert back[name].dtype == value.dtype
        np.testing.assert_array_equal(back[name], value)
    with pytest.raises(ResultError, match="cannot read the checkpoint"):
        read_checkpoint(tmp_path / "missing.npz")
