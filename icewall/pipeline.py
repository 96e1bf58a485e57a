"""deck -> mesh -> model -> solve -> HDF5, as one function the CLI and the sweep call."""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from icewall import __version__
from icewall.deck.load import LoadedDeck
from icewall.errors import ResultError
from icewall.mesh.build import build_mesh, region_materials
from icewall.model.build import build_model
from icewall.results.checkpoint import checkpoint_path, read_checkpoint
from icewall.results.writer import PARTIAL_SUFFIX, ResultWriter, StepRecord, check_writable
from icewall.solve.linear_static import run_linear


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


def result_path(loaded: LoadedDeck, output: str | Path | None = None) -> Path:
    """Where a deck's result goes: `output` (file or directory) or outputs.directory."""
    name = loaded.deck.specimen.name.replace("/", "_").replace(" ", "_").lower()
    if output is None:
        return Path(loaded.deck.outputs.directory) / f"{name}.h5"
    output = Path(output)
    return output / f"{name}.h5" if output.suffix != ".h5" else output


@dataclass(frozen=True)
class ResumePoint:
    """Where an interrupted run goes on: its checkpoint (None: from the start), the number of
    steps kept in its result file and the wall time they took."""

    checkpoint: dict[str, np.ndarray] | None
    n_steps: int
    wall_time: float


def resume_point(loaded: LoadedDeck, path: Path) -> ResumePoint:
    """Check that `path`.partial is an interrupted run of `loaded` (same deck text and --set)
    and find the last step its checkpoint can go on from; ResultError otherwise."""
    from icewall.results.reader import open_result

    partial = Path(str(path) + PARTIAL_SUFFIX)
    if not partial.exists():
        done = f" ({path} exists: the run finished)" if path.exists() else ""
        raise ResultError(f"nothing to resume: no interrupted run {partial}{done}")
    with open_result(partial) as res:
        overrides = json.loads(res.attrs.get("deck_overrides", "[]"))
        if res.deck_text != loaded.text or overrides != list(loaded.overrides):
            raise ResultError(f"cannot resume {partial}: it was run with another deck text or "
                              f"other --set overrides ({overrides}); resume with the same")
        n_stored = len(res.history["step"])
        wall = res.history["wall_time"]
    ckpt_file = checkpoint_path(path)
    if not Path(ckpt_file).exists():
        if n_stored and loaded.deck.analysis.solver != "linear":
            raise ResultError(f"cannot resume {partial}: its checkpoint {ckpt_file} is missing")
        return ResumePoint(None, 0, 0.0)
    checkpoint = read_checkpoint(ckpt_file)
    n_steps = int(checkpoint["step"])  # == n_stored, or one less if killed in between
    if n_steps > n_stored:
        raise ResultError(f"cannot resume {partial}: its checkpoint {ckpt_file} is of step "
                          f"{n_steps}, the file holds {n_stored} steps")
    return ResumePoint(checkpoint, n_steps, float(wall[n_steps - 1]) if n_steps else 0.0)


def run_deck(loaded: LoadedDeck, output: str | Path | None = None,
             progress: Callable[[str], None] | None = None, resume: bool = False) -> RunReport:
    """Run one deck and write its HDF5 result; returns where and how long. `resume` goes on
    with the interrupted run of the same deck at the same path from its last checkpoint."""
    deck = loaded.deck
    say = progress or (lambda message: None)
    path = result_path(loaded, output)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ResultError(f"cannot create the output directory {path.parent}: {exc}") from None
    check_writable(path)  # before any computing
    restart = resume_point(loaded, path) if resume else None
    timings: dict[str, float] = {}
    start = time.perf_counter()
    mesh = build_mesh(deck)
    timings["mesh"] = time.perf_counter() - start
    tic = time.perf_counter()
    model = build_model(deck, mesh, region_materials(deck))
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
             "warnings": json.dumps(warnings)}
    if restart is None or restart.checkpoint is None:
        writer = ResultWriter(path, deck_text=loaded.text, deck_path=loaded.path, mesh=mesh,
                              attrs=attrs)
    else:
        writer = ResultWriter.reopen(path, restart.n_steps)
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
    from icewall.model.params_report import concrete_parameter_rows

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
    from icewall.analysis.mechanism import MechanismProbe, crushed_points, yielded_points
    from icewall.errors import ConvergenceError
    from icewall.solve.nonlinear import run_nonlinear

    restart = restart if restart is not None and restart.checkpoint is not None else None
    deck, write_time = model.deck, 0.0
    first, elapsed = (restart.n_steps, restart.wall_time) if restart else (0, 0.0)
    n_steps = first
    start = time.perf_counter() - elapsed
    status, reason = "completed", ""
    probe = MechanismProbe(model.mesh, deck.analysis.gauss)  # issue 20 §1, history columns
    try:
        steps = run_nonlinear(model, restart.checkpoint if restart else None)
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
                         "preload_factor": inc.preload_factor, **mechanism},
                arrays=report.arrays if due and "state" in fields else {},
                forensics={k: np.asarray(v, dtype=np.int64) for k, v in inc.forensics.items()}))
            writer.write_checkpoint(report.checkpoint())
            write_time += time.perf_counter() - tic
            say(f"  step {n_steps:3d} {inc.kind:8s} deflection {inc.control_displacement:7.3f} mm"
                f"  {model.measure_name} = {load:.5g} {model.measure_unit}  "
                f"({inc.iterations} it{', cut ' + str(inc.cuts) if inc.cuts else ''})")
    except ConvergenceError as exc:
        status, reason = "stopped", f"{exc.reason}: {exc}"
        say(f"stopped after {n_steps} converged steps: {reason}")
    timings["solve"] = time.perf_counter() - start - elapsed - write_time
    timings["write"] = write_time
    return n_steps, status, reason
