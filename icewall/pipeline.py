"""deck -> mesh -> model -> solve -> HDF5, as one function the CLI and the sweep call."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from icewall import __version__
from icewall.deck.load import LoadedDeck
from icewall.errors import ResultError
from icewall.mesh.build import build_mesh, region_materials
from icewall.model.build import build_model
from icewall.results.writer import ResultWriter, StepRecord, check_writable
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


def result_path(loaded: LoadedDeck, output: str | Path | None = None) -> Path:
    """Where a deck's result goes: `output` (file or directory) or outputs.directory."""
    name = loaded.deck.specimen.name.replace("/", "_").replace(" ", "_").lower()
    if output is None:
        return Path(loaded.deck.outputs.directory) / f"{name}.h5"
    output = Path(output)
    return output / f"{name}.h5" if output.suffix != ".h5" else output


def run_deck(loaded: LoadedDeck, output: str | Path | None = None,
             progress: Callable[[str], None] | None = None) -> RunReport:
    """Run one deck and write its HDF5 result; returns where and how long."""
    deck = loaded.deck
    say = progress or (lambda message: None)
    path = result_path(loaded, output)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ResultError(f"cannot create the output directory {path.parent}: {exc}") from None
    check_writable(path)  # before any computing
    timings: dict[str, float] = {}
    start = time.perf_counter()
    mesh = build_mesh(deck)
    timings["mesh"] = time.perf_counter() - start
    tic = time.perf_counter()
    model = build_model(deck, mesh, region_materials(deck))
    timings["model"] = time.perf_counter() - tic
    say(f"{deck.specimen.name}: {mesh.n_nodes} nodes, {mesh.n_cells} {mesh.cell_type} "
        f"elements, {model.dof_map.n_equations} equations")
    fields = set(deck.outputs.fields)
    attrs = {"specimen": deck.specimen.name, "formulation": deck.analysis.formulation,
             "gauss_order": deck.analysis.gauss, "solver": deck.analysis.solver,
             "load_measure": model.measure_name, "load_unit": model.measure_unit,
             "icewall_version": __version__}
    solve_times: dict[str, float] = {}
    n_steps, write_time = 0, 0.0
    with ResultWriter(path, deck_text=loaded.text, deck_path=loaded.path, mesh=mesh,
                      attrs=attrs) as writer:
        want_fields = bool(fields & {"stress", "strain"})
        for step in run_linear(model, want_fields=want_fields, timings=solve_times):
            tic = time.perf_counter()
            write_fields = step.step % deck.outputs.every == 0
            gauss = {}
            if write_fields:
                gauss = {name: getattr(step, name) for name in ("stress", "strain")
                         if name in fields}
            writer.write_step(StepRecord(
                step=step.step, control_displacement=step.control_displacement,
                load=step.load, load_factor=step.load_factor, iterations=1,
                displacement_norm=0.0, load_norm=0.0, wall_time=step.wall_time,
                displacement=step.displacement if write_fields and "displacement" in fields
                else None, gauss=gauss))
            write_time += time.perf_counter() - tic
            n_steps = step.step
            say(f"  step {step.step:3d}  deflection {step.control_displacement:7.3f} mm  "
                f"{model.measure_name} = {step.load:.5g} {model.measure_unit}")
        timings.update(solve_times)
        timings["write"] = write_time
        timings["total"] = time.perf_counter() - start
        final = writer.finish(status="completed")
    return RunReport(path=str(final), status="completed", n_steps=n_steps,
                     n_nodes=mesh.n_nodes, n_elements=mesh.n_cells,
                     n_equations=model.dof_map.n_equations, timings=timings)
