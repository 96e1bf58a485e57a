"""`icewall run --resume`: an interrupted run goes on from its last converged step and ends
with the same result, to the last bit, as a run that was never interrupted."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from icewall.cli import main
from icewall.deck.load import load_deck
from icewall.errors import Interrupted, ResultError
from icewall.pipeline import run_deck
from icewall.results.checkpoint import checkpoint_path
from icewall.results.reader import open_result
from icewall.results.writer import ResultWriter

DECKS = Path(__file__).resolve().parents[2] / "decks"
FIELDS = "outputs.fields=[displacement, stress, strain, state]"
CF4_SMALL = ["analysis.element_size=150", "loads.control.target=5", FIELDS]
TF1_SMALL = ["analysis.element_size=150", "loads.control.target=3", FIELDS]


def _interrupt_after(k: int):
    """A progress callback that stops the run like SIGINT right after step k is written."""
    seen = []

    def say(message: str) -> None:
        if message.lstrip().startswith("step"):
            seen.append(message)
            if len(seen) == k:
                raise Interrupted("SIGINT", 130)

    return say


def assert_identical(path_a: str, path_b: str) -> None:
    """Same history (but wall time) and same stored arrays, bit for bit."""
    with open_result(path_a) as a, open_result(path_b) as b:
        assert a.status == b.status and a.attrs["stop_reason"] == b.attrs["stop_reason"]
        assert sorted(a.history) == sorted(b.history)
        for name in a.history:
            if name != "wall_time":
                np.testing.assert_array_equal(a.history[name], b.history[name], err_msg=name)
        assert a.steps == b.steps
    with h5py.File(path_a, "r") as fa, h5py.File(path_b, "r") as fb:
        for group in ("steps", "forensics"):
            names = _datasets(fa[group])
            assert names
            for name in names:
                np.testing.assert_array_equal(fa[group][name][()], fb[group][name][()],
                                              err_msg=f"{group}/{name}")


def _datasets(group: h5py.Group) -> list[str]:
    names: list[str] = []
    group.visititems(lambda n, o: names.append(n) if isinstance(o, h5py.Dataset) else None)
    return names


@pytest.fixture(scope="module")
def cf4_uninterrupted(tmp_path_factory):
    loaded = load_deck(DECKS / "cf4.yaml", CF4_SMALL)
    return loaded, run_deck(loaded, tmp_path_factory.mktemp("whole") / "cf4.h5")


def test_resume_ends_bit_identical(cf4_uninterrupted, tmp_path):
    loaded, whole = cf4_uninterrupted
    assert whole.status == "completed" and whole.n_steps == 5
    out = tmp_path / "cf4.h5"
    with pytest.raises(Interrupted):
        run_deck(loaded, out, progress=_interrupt_after(2))
    with open_result(str(out) + ".partial") as res:
        assert res.status == "failed" and res.attrs["stop_reason"] == "interrupted by SIGINT"
        assert len(res.history["step"]) == 2
    assert os.path.exists(checkpoint_path(out))
    resumed = run_deck(loaded, out, resume=True)
    assert resumed.status == "completed" and resumed.n_steps == 5
    assert_identical(whole.path, resumed.path)
    with open_result(resumed.path) as res:
        assert res.attrs["resumed_at"] == [2]
    assert not os.path.exists(checkpoint_path(out))  # a finished run keeps no checkpoint


def test_resume_when_killed_between_the_step_and_its_checkpoint(cf4_uninterrupted, tmp_path,
                                                                monkeypatch):
    loaded, whole = cf4_uninterrupted
    out = tmp_path / "cf4.h5"
    real = ResultWriter.write_checkpoint

    def stop_at_step_3(self, arrays):
        if self._last_step == 3:  # step 3 is in the file, its checkpoint not yet
            raise Interrupted("SIGTERM", 143)
        real(self, arrays)

    monkeypatch.setattr(ResultWriter, "write_checkpoint", stop_at_step_3)
    with pytest.raises(Interrupted):
        run_deck(loaded, out)
    monkeypatch.undo()
    with open_result(str(out) + ".partial") as res:
        assert len(res.history["step"]) == 3
    resumed = run_deck(loaded, out, resume=True)  # drops step 3 and computes it again
    assert_identical(whole.path, resumed.path)


NEWTON = ["analysis.scheme=newton", "analysis.tolerance_load=1e-4",
          "analysis.tolerance_displacement=1e-4", "loads.control.target=5.3", FIELDS]


def test_newton_resume_ends_bit_identical(tmp_path):
    """The Newton path's own state (step size, snap-back control, the predictor's direction,
    the augmentation of the semismooth pair decisions) is in the checkpoint: a run resumed
    at step 13 of 21 (after a snap-back at 5.3 mm) ends on the same bits."""
    loaded = load_deck(DECKS / "cf4.yaml", NEWTON)
    whole = run_deck(loaded, tmp_path / "whole" / "cf4.h5")
    assert whole.status == "completed"
    out = tmp_path / "cut" / "cf4.h5"
    with pytest.raises(Interrupted):
        run_deck(loaded, out, progress=_interrupt_after(13))
    assert_identical(whole.path, run_deck(loaded, out, resume=True).path)


DYNAMIC = ["analysis.element_size=150", "analysis.scheme=newton", "analysis.drops=dynamic",
           "materials.concrete.mode_rule_band=0.1", "materials.concrete.post_peak_strength=peak",
           "materials.concrete.fallen_strength=scaled", "loads.control.target=1.5", FIELDS]


def test_resume_after_a_dynamic_drop_ends_bit_identical(tmp_path):
    """The drops' energy terms are in the checkpoint: a coarse CF-4 with dynamic drops (one at
    1.37 mm, 110 time steps), resumed right after its first drop, ends on the same bits, its
    numerical dissipation (solve/energy.py) included."""
    loaded = load_deck(DECKS / "cf4.yaml", DYNAMIC)
    whole = run_deck(loaded, tmp_path / "whole" / "cf4.h5")
    assert whole.status == "completed"
    with open_result(whole.path) as res:
        drops = np.flatnonzero(res.history["dynamic_time_steps"] > 0)
        assert drops.size and drops[0] + 1 < len(res.history["step"])
        numerical = res.history["numerical_dissipation"]
        assert numerical[drops[0]] > 0.0 and numerical[drops[0] - 1] == 0.0
    out = tmp_path / "cut" / "cf4.h5"
    with pytest.raises(Interrupted):
        run_deck(loaded, out, progress=_interrupt_after(int(drops[0]) + 1))
    assert_identical(whole.path, run_deck(loaded, out, resume=True).path)


def test_resume_of_a_run_interrupted_inside_a_dynamic_drop_ends_bit_identical(
        tmp_path, monkeypatch):
    """A drop is one step of the result (its time steps are its path, not results), so the
    checkpoint before it is the last one an interruption inside it leaves: SIGINT at the
    drop's 40th time step (of 110), and the resumed run takes the whole drop again from the
    step before it and ends on the same bits as the uninterrupted run."""
    from icewall.solve import dynamic

    loaded = load_deck(DECKS / "cf4.yaml", DYNAMIC)
    whole = run_deck(loaded, tmp_path / "whole" / "cf4.h5")
    with open_result(whole.path) as res:
        drop = int(np.flatnonzero(res.history["dynamic_time_steps"] > 0)[0])
        assert res.history["dynamic_time_steps"][drop] > 40
    real = dynamic._Drop.advance

    def interrupted(self):
        if self.steps == 40:
            raise Interrupted("SIGINT", 130)
        return real(self)

    monkeypatch.setattr(dynamic._Drop, "advance", interrupted)
    out = tmp_path / "cut" / "cf4.h5"
    with pytest.raises(Interrupted):
        run_deck(loaded, out)
    monkeypatch.undo()
    with open_result(str(out) + ".partial") as res:
        assert len(res.history["step"]) == drop  # every step before the drop, not the drop
    resumed = run_deck(loaded, out, resume=True)
    assert_identical(whole.path, resumed.path)
    with open_result(resumed.path) as res:
        assert res.attrs["resumed_at"] == [drop]


@pytest.mark.slow
@pytest.mark.parametrize("k", [2, 5, 6])  # in the preload stage, at its end, after it
def test_resume_through_the_preload_stage(tmp_path, k):
    loaded = load_deck(DECKS / "tf1.yaml", TF1_SMALL)
    whole = run_deck(loaded, tmp_path / "whole" / "tf1.h5")
    out = tmp_path / "cut" / "tf1.h5"
    with pytest.raises(Interrupted):
        run_deck(loaded, out, progress=_interrupt_after(k))
    assert_identical(whole.path, run_deck(loaded, out, resume=True).path)


@pytest.mark.slow
def test_resume_after_sigkill(tmp_path):
    """A real kill -9 at an arbitrary moment: the partial file and checkpoint on disk are enough
    to end with the uninterrupted result."""
    overrides = CF4_SMALL + ["loads.control.increment=0.25"]  # 20 steps: time to kill it
    whole = run_deck(load_deck(DECKS / "cf4.yaml", overrides), tmp_path / "whole" / "cf4.h5")
    out = tmp_path / "cf4.h5"
    args = ["run", str(DECKS / "cf4.yaml"), "-o", str(out), "-q"]
    for assignment in overrides:
        args += ["--set", assignment]
    proc = subprocess.Popen([sys.executable, "-c", "from icewall.cli import main; main()",
                             *args])
    deadline = time.time() + 120
    while time.time() < deadline and proc.poll() is None:
        if os.path.exists(checkpoint_path(out)):
            try:
                with open_result(str(out) + ".partial") as res:
                    if len(res.history["step"]) >= 2:
                        break
            except ResultError:
                pass
        time.sleep(0.05)
    assert proc.poll() is None, "the run ended before it could be killed"
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=60)
    result = CliRunner().invoke(main, [*args, "--resume"])
    assert result.exit_code == 0, result.output
    assert_identical(whole.path, str(out))


def test_resume_refuses_what_it_cannot_continue(cf4_uninterrupted, tmp_path):
    loaded, whole = cf4_uninterrupted
    with pytest.raises(ResultError, match="the run finished"):
        run_deck(loaded, whole.path, resume=True)
    with pytest.raises(ResultError, match="nothing to resume"):
        run_deck(loaded, tmp_path / "never.h5", resume=True)
    out = tmp_path / "cf4.h5"
    with pytest.raises(Interrupted):
        run_deck(loaded, out, progress=_interrupt_after(1))
    other = load_deck(DECKS / "cf4.yaml", CF4_SMALL + ["materials.concrete.fc=40"])
    with pytest.raises(ResultError, match="other --set overrides"):
        run_deck(other, out, resume=True)


def test_cli_resume_error_is_one_line_exit_2(tmp_path):
    result = CliRunner().invoke(main, ["run", str(DECKS / "cf4.yaml"), "-o",
                                       str(tmp_path / "x.h5"), "--resume"])
    assert result.exit_code == 2
    assert result.output.startswith("error: nothing to resume")
    assert "Traceback" not in result.output and result.output.count("\n") == 1
