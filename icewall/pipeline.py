"""deck -> mesh -> model -> solve -> HDF5, as one function the CLI and the sweep call."""

from __future__ import annotations

import functools
import hashlib
import json
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from icewall import __version__, safe_write
from icewall.deck.load import LoadedDeck
from icewall.deck.profile import Profile
from icewall.errors import ConvergenceError, ResultError
from icewall.mesh.build import build_mesh, region_materials
from icewall.model.build import build_model
from icewall.model.params_report import concrete_parameter_rows
from icewall.preflight import check_initial_system, floating_point_guard, floating_point_note
from icewall.results.checkpoint import checkpoint_path, read_checkpoint
from icewall.results.output_safety import OutputLock
from icewall.results.probe import MechanismProbe, crushed_points, yielded_points
from icewall.results.reader import open_result
from icewall.results.writer import (
    PARTIAL_SUFFIX,
    RESULT,
    ResultWriter,
    StepRecord,
    check_writable,
    refuse_output_links,
)
from icewall.solve.linear_static import run_linear
from icewall.solve.nonlinear import run_nonlinear


@dataclass
class RunReport:
    """What a run produced and where its time went (seconds)."""

    path: str
    status: str
    n_steps: int
    n_nodes: int
    n_elements: int
    n_equations: int
    timings: dict[str, float] = field(default_factory=dict)
    reason: str = ""
    warnings: list[str] = field(default_factory=list)  # for stderr (preflight's note)


HDF5_SUFFIXES = (".h5", ".hdf5", ".he5", ".hdf")
"""An output path ending in one of these (any case) is the result file, never a directory."""


def result_stem(loaded: LoadedDeck) -> str:
    """File name stem of a deck's result: the specimen name, lower case, with '/', '\\',
    blanks and control characters as '_' and no leading dot; the deck file's stem where that
    leaves nothing (an empty name must not write a hidden '.h5')."""
    def clean(text: str) -> str:
        text = "".join("_" if c in "/\\ " or not c.isprintable() else c for c in text)
        return text.lstrip(".").lower()

    return clean(loaded.deck.specimen.name) or clean(Path(loaded.path).stem) or "result"


def result_path(loaded: LoadedDeck, output: str | Path | None = None) -> Path:
    """Where a deck's result goes: `output` (a file if it ends in an HDF5 suffix, else a
    directory) or outputs.directory."""
    name = result_stem(loaded)
    if output is None:
        return Path(loaded.deck.outputs.directory) / f"{name}.h5"
    output = Path(output)
    return output if output.suffix.lower() in HDF5_SUFFIXES else output / f"{name}.h5"


@functools.cache
def code_version() -> str:
    """icewall's version and a digest of its Python sources: two runs with the same value ran
    the same code."""
    root = Path(__file__).resolve().parent
    digest = hashlib.sha256()
    for source in sorted(root.rglob("*.py")):
        digest.update(source.relative_to(root).as_posix().encode() + b"\0")
        digest.update(source.read_bytes())
    return f"{__version__}+{digest.hexdigest()[:12]}"


def run_stamp(deck_text: str, overrides, profile: Profile | None = None) -> str:
    """What makes a run the same run: deck text, overrides (a profile's assignments, then
    --set), the profile (name and text digest, where one is applied) and code (JSON, stored as
    the result's `run_stamp` attribute; a sweep reuses a result only if it matches)."""
    stamp = {"deck_sha256": hashlib.sha256(deck_text.encode()).hexdigest(),
             "overrides": list(overrides), "code": code_version()}
    if profile is not None:
        stamp["profile"] = f"{profile.name} {profile.sha256}"
    return json.dumps(stamp)


def profile_attrs(profile: Profile | None) -> dict[str, str]:
    """The result attributes naming the profile of a run (none without one)."""
    if profile is None:
        return {}
    return {"profile": profile.name, "profile_path": profile.path, "profile_text": profile.text}


@dataclass(frozen=True)
class ResumePoint:
    """Where an interrupted run goes on: its checkpoint (None: from the start), the number of
    steps kept in its result file and the wall time they took."""

    checkpoint: dict[str, np.ndarray] | None
    n_steps: int
    wall_time: float
    file: str = ""  # the checkpoint's file


def resume_point(loaded: LoadedDeck, path: Path) -> ResumePoint:
    """Check that `path`.partial is an interrupted run of `loaded` (same deck text and --set)
    and find the last step its checkpoint can go on from; ResultError otherwise."""
    partial = Path(str(path) + PARTIAL_SUFFIX)
    if not partial.exists():
        done = f" ({path} exists: the run finished)" if path.exists() else ""
        raise ResultError(f"nothing to resume: no interrupted run {partial}{done}")
    with open_result(partial) as res:
        overrides = json.loads(res.attrs.get("deck_overrides", "[]"))
        if res.deck_text != loaded.text or overrides != list(loaded.overrides):
            raise ResultError(f"cannot resume {partial}: it was run with another deck text or "
                              f"other --set overrides ({overrides}); resume with the same")
        stamp = json.loads(res.attrs.get("run_stamp", "{}"))
        if stamp.get("code", code_version()) != code_version():
            raise ResultError(f"cannot resume {partial}: it was run by other code "
                              f"({stamp['code']}, this is {code_version()}); run it anew "
                              f"without --resume")
        n_stored = len(res.history["step"])
        wall = res.history["wall_time"]
    ckpt_file = checkpoint_path(path)
    if not Path(ckpt_file).exists():  # linear, or stopped before its first checkpoint
        return ResumePoint(None, 0, 0.0)  # (e.g. a full disk): start the run again
    checkpoint = read_checkpoint(ckpt_file)
    n_steps = int(checkpoint["step"])  # == n_stored, or one less if killed in between
    if n_steps > n_stored:
        raise ResultError(f"cannot resume {partial}: its checkpoint {ckpt_file} is of step "
                          f"{n_steps}, the file holds {n_stored} steps")
    return ResumePoint(checkpoint, n_steps, float(wall[n_steps - 1]) if n_steps else 0.0,
                       ckpt_file)


def run_deck(loaded: LoadedDeck, output: str | Path | None = None,
             progress: Callable[[str], None] | None = None, resume: bool = False,
             replace: bool = False, attrs: dict[str, str | float | int] | None = None
             ) -> RunReport:
    """Run one deck and write its HDF5 result; returns where and how long. `resume` goes on
    with the interrupted run of the same deck at the same path from its last checkpoint;
    `replace` removes an earlier result at the path first; `attrs` are stored with the run's.
    The output's lock is held from before anything is written until the result is in place:
    a second run on the same output is refused (ResultError) and touches nothing."""
    path = result_path(loaded, output)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ResultError(f"cannot create the output directory {path.parent}: {exc}") from None
    check_writable(path)  # before any computing
    with OutputLock(path) as lock:
        refuse_output_links(str(path))
        if replace:  # a rerun: no stale result if this one fails (an icewall result only)
            safe_write.remove(path, RESULT)
        with floating_point_guard() as counts:  # NumPy's warnings: one line, not hundreds
            report = _run_locked(loaded, path, lock, progress, resume, attrs or {})
        report.warnings += [note] if (note := floating_point_note(counts)) else []
        return report


def _drop_columns(inc, energy: dict[str, float]) -> dict[str, float]:
    """History columns of a run that takes dynamic drops (its energy has damping_work): the
    time steps of the step's drop (0 for a static step) and its largest kinetic energy."""
    if "damping_work" not in energy:
        return {}
    drop = inc.path_energy
    return {"dynamic_time_steps": int(inc.forensics.get("time_steps", [0])[0]),
            "largest_kinetic_energy": 0.0 if drop is None else drop.largest_kinetic}


def _run_locked(loaded: LoadedDeck, path: Path, lock: OutputLock,
                progress: Callable[[str], None] | None, resume: bool, extra: dict
                ) -> RunReport:
    deck = loaded.deck
    say = progress or (lambda message: None)
    restart = resume_point(loaded, path) if resume else None
    if restart is not None and restart.checkpoint is None and deck.analysis.solver != "linear":
        say("no checkpoint: the run starts again from its first step")
    timings: dict[str, float] = {}
    start = time.perf_counter()
    mesh = build_mesh(deck)
    timings["mesh"] = time.perf_counter() - start
    tic = time.perf_counter()
    materials = region_materials(deck)
    model = build_model(deck, mesh, materials)
    check_initial_system(deck, mesh, materials, model)  # every scheme alike, nothing written
    timings["model"] = time.perf_counter() - tic
    say(f"{deck.specimen.name}: {mesh.n_nodes} nodes, {mesh.n_cells} {mesh.cell_type} "
        f"elements, {model.dof_map.n_equations} equations")
    warnings = softening_warnings(deck, mesh)
    for warning in warnings:
        say(f"warning: {warning}")
    fields = set(deck.outputs.fields)
    attrs = {"specimen": deck.specimen.name, "formulation": deck.analysis.formulation,
             "gauss_order": deck.analysis.gauss, "solver": deck.analysis.solver,
             "load_measure": model.measure_name, "load_unit": model.measure_unit,
             "icewall_version": __version__,
             "deck_overrides": json.dumps(list(loaded.overrides)),
             "run_stamp": run_stamp(loaded.text, loaded.overrides, loaded.profile),
             **profile_attrs(loaded.profile),
             "warnings": json.dumps(warnings), **extra}
    if restart is None or restart.checkpoint is None:
        writer = ResultWriter(path, deck_text=loaded.text, deck_path=loaded.path, mesh=mesh,
                              attrs=attrs, lock=lock)
    else:
        writer = ResultWriter.reopen(path, restart.n_steps, lock=lock)
        say(f"resuming after step {restart.n_steps}")
    with writer:
        if deck.analysis.solver == "linear":
            n_steps = _write_linear(model, writer, fields, say, timings)
            status, reason = "completed", ""
        else:
            n_steps, status, reason = _write_nonlinear(model, writer, fields, say, timings,
                                                       restart)
        timings["total"] = time.perf_counter() - start
        final = writer.finish(status=status, reason=reason)
    return RunReport(path=str(final), status=status, n_steps=n_steps, reason=reason,
                     n_nodes=mesh.n_nodes, n_elements=mesh.n_cells,
                     n_equations=model.dof_map.n_equations, timings=timings)


def softening_warnings(deck, mesh) -> list[str]:
    """Concrete regions whose crack band is too wide for the softening branches (they snap
    back at the material level; `icewall params`), for a nonlinear concrete analysis."""
    if deck.analysis.solver != "nonlinear" or deck.materials.concrete.model != "rotating_crack":
        return []
    return [f"{row['region']}: {warning}" for row in concrete_parameter_rows(deck, mesh)
            for warning in row["warnings"]]


def _fields_due(deck, step: int) -> bool:
    return step % deck.outputs.every == 0


def _write_linear(model, writer: ResultWriter, fields: set[str], say, timings) -> int:
    deck, n_steps, write_time = model.deck, 0, 0.0
    solve_times: dict[str, float] = {}
    for step in run_linear(model, want_fields=bool(fields & {"stress", "strain"}),
                           timings=solve_times):
        tic = time.perf_counter()
        due = _fields_due(deck, step.step)
        gauss = {name: getattr(step, name) for name in ("stress", "strain")
                 if due and name in fields}
        writer.write_step(StepRecord(
            step=step.step, control_displacement=step.control_displacement, load=step.load,
            load_factor=step.load_factor, iterations=1, displacement_norm=0.0, load_norm=0.0,
            wall_time=step.wall_time, gauss=gauss,
            displacement=step.displacement if due and "displacement" in fields else None))
        write_time += time.perf_counter() - tic
        n_steps = step.step
        say(f"  step {step.step:3d}  deflection {step.control_displacement:7.3f} mm  "
            f"{model.measure_name} = {step.load:.5g} {model.measure_unit}")
    timings.update(solve_times)
    timings["write"] = write_time
    return n_steps


def _write_nonlinear(model, writer: ResultWriter, fields: set[str], say, timings,
                     restart: ResumePoint | None = None) -> tuple[int, str, str]:
    restart = restart if restart is not None and restart.checkpoint is not None else None
    deck, write_time = model.deck, 0.0
    first, elapsed = (restart.n_steps, restart.wall_time) if restart else (0, 0.0)
    n_steps = first
    start = time.perf_counter() - elapsed
    status, reason = "completed", ""
    probe = MechanismProbe(model.mesh, deck.analysis.gauss)  # issue 20 §1, history columns
    try:
        steps = (run_nonlinear(model, restart.checkpoint, restart.file) if restart
                 else run_nonlinear(model))
        for n_steps, report in enumerate(steps, start=first + 1):
            tic = time.perf_counter()
            inc, ev = report.increment, report.increment.evaluation
            due = _fields_due(deck, n_steps)
            gauss = {name: getattr(ev, name) for name in ("stress", "strain")
                     if due and name in fields}
            if due and "state" in fields:
                gauss.update(report.state_fields())
            load = inc.load_factor * model.measure_factor
            groups, shape = report.structure.groups, ev.stress.shape[:2]
            mechanism = probe.scalars(ev.stress, crushed_points(groups, ev.states, shape),
                                      yielded_points(groups, ev.states, shape))
            writer.write_step(StepRecord(
                step=n_steps, control_displacement=inc.control_displacement, load=load,
                load_factor=inc.load_factor, iterations=inc.iterations,
                displacement_norm=min(inc.displacement_norm, 1e300), load_norm=inc.load_norm,
                wall_time=time.perf_counter() - start, gauss=gauss,
                displacement=report.displacement if due and "displacement" in fields else None,
                scalars={**report.counts, **report.energy, "step_cuts": inc.cuts,
                         "snap_back": int(inc.snap_back), "jumped": int(inc.jumped),
                         "preload_stage": int(inc.kind == "preload"),
                         "preload_factor": inc.preload_factor, **mechanism,
                         **_drop_columns(inc, report.energy)},
                arrays=report.arrays if due and "state" in fields else {},
                forensics={k: np.asarray(v, dtype=np.int64) for k, v in inc.forensics.items()}))
            writer.write_checkpoint(report.checkpoint())
            write_time += time.perf_counter() - tic
            drop = (f", dynamic drop: {inc.forensics['time_steps'][0]} time steps"
                    if "time_steps" in inc.forensics else "")
            say(f"  step {n_steps:3d} {inc.kind:8s} deflection {inc.control_displacement:7.3f} mm"
                f"  {model.measure_name} = {load:.5g} {model.measure_unit}  "
                f"({inc.iterations} it{', cut ' + str(inc.cuts) if inc.cuts else ''}{drop})")
    except ConvergenceError as exc:
        status, reason = "stopped", f"{exc.reason}: {exc}"
        say(f"stopped after {n_steps} converged steps: {reason}")
    timings["solve"] = time.perf_counter() - start - elapsed - write_time
    timings["write"] = write_time
    return n_steps, status, reason
