"""`icewall convergence DECK`: one deck over a ladder of discretisations, error against cost.

A *ladder* is a set of refinement families; each family varies one setting (one or more keys
set to the same value, e.g. both convergence tolerances) with every other at the deck's value.
A ladder file (YAML)::

    families:
      element_size: {keys: analysis.element_size, values: [150, 100, 75, 50, 37.5], h: mesh}
      gauss: {keys: analysis.gauss, values: [2, 3, 4], h: inverse}
      increment: {keys: loads.control.increment, factors: [2, 1, 0.5]}   # x the deck's value
      tolerance: {keys: [analysis.tolerance_displacement, analysis.tolerance_load],
                  values: [0.1, 0.05, 0.02, 0.01]}

``h`` is the family's refinement measure (smaller = finer): ``value`` (the default), ``inverse``
(1 / value: a higher Gauss order is finer) or ``mesh`` (the measured size of the concrete
elements, sqrt(core area / elements): the tensor-grid mesher does not scale the element size
exactly). A level equal to the deck's own setting is the *base* run, made once and shared.
Runs go through the sweep machinery (icewall.analysis.sweep: process pool, resumable, one HDF5
per run in OUT) with ``outputs.fields=[]`` (history only) before any --set. Each run's CPU time
is stamped in its file (``cpu_time_s``); cost is CPU time (wall time on a shared machine says
more about the neighbours). Quantities (icewall.analysis.extract): peak load, its deflection, the
first maximum (the largest load before the curve first softens by 5 %) and its deflection,
residual load (at 40 mm, the thesis' residual, or at the deck's target if that is shorter) and
the whole curve; error estimates: icewall.analysis.convergence_table.

Writes OUT/convergence_runs.csv (one row per family level), convergence_families.csv (each
family's reference run and Richardson estimates), convergence_pareto.csv (the cheapest run
within 10, 5 and 2 % estimated error), convergence_curves.csv (every run's load-deflection
curve) and, with matplotlib, convergence.png (error against CPU time, log-log, one line per family).
"""

from __future__ import annotations

import csv
import io
import math
import os
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from icewall.analysis import convergence_table as ct
from icewall.analysis.extract import RESIDUAL_DEFLECTION, extract
from icewall.analysis.reference import find_reference
from icewall.analysis.sweep import FINISHED, finished_status, make_output_directory, reuse_verdict
from icewall.analysis.sweep_runners import Job, run_job, run_local
from icewall.deck.load import load_deck
from icewall.deck.yamlsrc import read_yaml
from icewall.errors import DeckError, ResultError
from icewall.results.reader import open_result
from icewall.results.writer import RESULT
from icewall.safe_write import MARK, PNG, csv_kind, open_existing, open_for_write, write_bytes

DEFAULT_LADDER = {"families": {
    "element_size": {"keys": "analysis.element_size", "values": [150, 100, 75, 50, 37.5],
                     "h": "mesh"},
    "gauss": {"keys": "analysis.gauss", "values": [2, 3, 4], "h": "inverse"},
    "increment": {"keys": "loads.control.increment", "factors": [2, 1, 0.5]},
    "tolerance": {"keys": ["analysis.tolerance_displacement", "analysis.tolerance_load"],
                  "values": [0.1, 0.05, 0.02, 0.01]}}}
QUICK_LADDER = {"families": {
    "element_size": {"keys": "analysis.element_size", "values": [150, 75], "h": "mesh"},
    "increment": {"keys": "loads.control.increment", "factors": [2, 1]}}}
FIXED = ("outputs.fields=[]",)
H_KINDS = ("value", "inverse", "mesh")
COLUMNS = ("family", "value", "h", "run", "status", "stop_reason", "cpu_s", "wall_s",
           "iterations", "steps", "elements", "peak", "defl_peak", "first_peak",
           "defl_first_peak", "first_peak_settled", "residual", "residual_at", "unit",
           "reference",
           "err_peak", "err_defl_peak", "err_first_peak", "err_defl_first_peak",
           "err_residual", "err_curve", "rich_err_peak", "rich_err_first_peak",
           "rich_err_residual", "test_err_peak", "test_err_first_peak", "test_err_residual",
           "total_err_peak", "total_err_first_peak", "total_err_residual", "total_err_curve")
OUTPUTS = {  # what the study writes into its directory, and how an earlier one is recognised
    "convergence_runs.csv": csv_kind("convergence table", COLUMNS),
    "convergence_families.csv": csv_kind("convergence table", ("family", "reference")),
    "convergence_pareto.csv": csv_kind("convergence table", ("threshold", "quantity")),
    "convergence_curves.csv": csv_kind("convergence table", ("run", "deflection")),
    "convergence.png": PNG}


@dataclass(frozen=True)
class Family:
    """One refinement family: `keys` all set to each of `values` (or `factors` x the deck's)."""

    name: str
    keys: tuple[str, ...]
    values: tuple[float, ...]
    relative: bool = False
    h: str = "value"


def parse_ladder(data, where: str = "ladder") -> list[Family]:
    """Families of a ladder mapping (as read from YAML); DeckError naming the entry if bad."""
    if not isinstance(data, dict) or set(data) != {"families"} or \
            not isinstance(data["families"], dict) or not data["families"]:
        raise DeckError("a ladder is a mapping with one key, families: {name: {...}}", where)
    families = []
    line_of = getattr(data["families"], "line_of", lambda key: None)  # a LineDict knows lines
    for name, spec in data["families"].items():
        at = line_of(name)
        if not isinstance(spec, dict) or set(spec) - {"keys", "values", "factors", "h"} or \
                ("values" in spec) == ("factors" in spec) or "keys" not in spec:
            raise DeckError("a family has keys, values or factors, and optionally h", where,
                            at, f"families.{name}")
        keys = spec["keys"] if isinstance(spec["keys"], list) else [spec["keys"]]
        values = spec.get("values", spec.get("factors"))
        if not values or not isinstance(values, list) or not all(
                isinstance(v, int | float) and not isinstance(v, bool) and v > 0
                for v in values) or not all(isinstance(k, str) and k for k in keys):
            raise DeckError("keys are key paths, values/factors a list of positive numbers",
                            where, at, f"families.{name}")
        if spec.get("h", "value") not in H_KINDS:
            raise DeckError(f"h is one of {', '.join(H_KINDS)}", where, at, f"families.{name}")
        families.append(Family(str(name), tuple(keys), tuple(float(v) for v in values),
                               "factors" in spec, spec.get("h", "value")))
    return families


def read_ladder(path: str | os.PathLike) -> list[Family]:
    """Families of a ladder file (YAML)."""
    return parse_ladder(read_yaml(path)[1], str(path))


def _label(value: float) -> str:
    return f"{value:.10g}"


def _deck_value(deck, key: str, where: str) -> float:
    node = deck
    for part in key.split("."):
        if not hasattr(node, part):
            raise DeckError(f"ladder key {key}: no such deck option", where)
        node = getattr(node, part)
    if not isinstance(node, int | float) or isinstance(node, bool):
        raise DeckError(f"ladder key {key}: the deck's value {node!r} is not a number", where)
    return float(node)


def build_jobs(deck_path: str, families: list[Family], sets: Iterable[str] = (),
               outdir: str | os.PathLike = "results/convergence"
               ) -> tuple[list[dict], Job, float]:
    """One level per (family, value): dicts {family, value, job, nominal, h_kind}; the base
    job; the residual deflection. Every job's deck is loaded (validated) here, before any run."""
    fixed = (*FIXED, *sets)
    deck = load_deck(deck_path, fixed).deck
    stem = Path(deck_path).stem
    base = Job(f"{stem}__base", deck_path, fixed, (), str(Path(outdir) / f"{stem}__base.h5"))
    levels = []
    for fam in families:
        own = [_deck_value(deck, k, deck_path) for k in fam.keys]
        for raw in fam.values:
            values = [raw * v for v in own] if fam.relative else [raw] * len(fam.keys)
            if len(set(values)) != 1:
                raise DeckError(f"family {fam.name}: the keys' deck values differ", deck_path)
            value = values[0]
            varied = tuple(f"{k}={_label(value)}" for k in fam.keys)
            if all(math.isclose(v, value, rel_tol=1e-12) for v in own):
                job = base
            else:
                name = f"{stem}__{fam.name}={_label(value)}"
                job = Job(name, deck_path, fixed + varied, varied,
                          str(Path(outdir) / f"{name}.h5"))
                load_deck(deck_path, job.overrides)
            nominal = 1.0 / value if fam.h == "inverse" else value
            levels.append({"family": fam.name, "value": _label(value), "job": job,
                           "nominal": nominal, "h_kind": fam.h})
    return levels, base, min(RESIDUAL_DEFLECTION, deck.loads.control.target)


def run_timed(job: Job) -> dict:
    """run_job plus the worker's CPU time, also stamped in the result file (cpu_time_s)."""
    start = time.process_time()
    out = run_job(job)
    out["cpu_time_s"] = time.process_time() - start
    if out["status"] in FINISHED:  # in place, never through a link (safe_write)
        import h5py

        with open_existing(out["path"], RESULT) as handle, h5py.File(handle, "a") as f:
            f.attrs["cpu_time_s"] = out["cpu_time_s"]
    return out


def measure_run(path: str, residual_at: float = RESIDUAL_DEFLECTION) -> dict:
    """Quantities and costs of one result file: peak, its deflection, residual at
    `residual_at` mm, the curve (the extractor's: start point then the control steps),
    iterations, elements, h (sqrt of the mean concrete element area)."""
    with open_result(path) as res:
        hist, attrs, mesh = res.history, res.attrs, res.mesh
    fig = extract(hist, residual_deflection=residual_at)  # the history read once, here
    d, p = hist["control_displacement"], hist["load"]
    control = hist["preload_stage"] != 1 if "preload_stage" in hist else np.ones(d.size, bool)
    d0 = fig["start_deflection"]
    curve = (np.concatenate([[d0], d[control]]), np.concatenate([[0.0], p[control]]))
    core = mesh.cells_of_kind("concrete")
    xy = mesh.points[mesh.cells[core]]
    area = np.sum(np.ptp(xy[..., 0], axis=1) * np.ptp(xy[..., 1], axis=1))  # rectangles
    return {"status": attrs.get("status"), "stop_reason": attrs.get("stop_reason", ""),
            "specimen": attrs.get("specimen"), "unit": attrs.get("load_unit"),
            "wall_s": attrs.get("run_time_s"), "cpu_s": attrs.get("cpu_time_s"),
            "iterations": int(hist["iterations"].sum()), "steps": int(d.size),
            "elements": int(mesh.n_cells), "h_mesh": float(math.sqrt(area / core.sum())),
            "peak": fig.get("peak_load"), "defl_peak": fig.get("deflection_at_peak"),
            "first_peak": fig.get("first_peak_load"),
            "defl_first_peak": fig.get("deflection_at_first_peak"),
            "first_peak_settled": fig.get("first_peak_settled"),
            "residual": fig.get("residual_load_40"), "residual_at": residual_at,
            "curve": curve if control.any() else None}


def _test_values(specimen: str | None, deck_path: str) -> dict:
    ref = find_reference(specimen) if specimen else None
    if ref is None:
        ref = load_deck(deck_path).deck.specimen.reference
    return {"peak": ref.ultimate_test, "residual": ref.residual_test}


def build_rows(levels: list[dict], results: dict[str, dict], deck_path: str, base: str,
               residual_at: float = RESIDUAL_DEFLECTION) -> tuple[list[dict], dict]:
    """One row per level with the run's measures and every error estimate; and per family its
    reference and Richardson estimates (convergence_table.family_errors)."""
    rows = []
    for level in levels:
        job = level["job"]
        result = results.get(job.name, {})
        row = dict.fromkeys(COLUMNS)
        row.update(family=level["family"], value=level["value"], run=job.name,
                   status=result.get("status", "failed"), stop_reason=result.get("reason"),
                   cpu_s=result.get("cpu_time_s"), wall_s=result.get("run_time_s"),
                   curve=None, specimen=None)
        if os.path.exists(job.output):
            try:
                measures = measure_run(job.output, residual_at)
                row.update({k: v for k, v in measures.items() if v is not None})
            except (ResultError, OSError, KeyError, ValueError) as exc:
                row["stop_reason"] = f"unreadable result: {exc}"
        row["usable"] = row["status"] == "completed" and row["peak"] is not None
        row["usable_first_peak"] = row["usable"] or (
            row["status"] == "stopped" and bool(row.get("first_peak_settled")))
        row["h"] = row.get("h_mesh") if level["h_kind"] == "mesh" else level["nominal"]
        row["cost"] = row["cpu_s"] if row["cpu_s"] is not None else row["wall_s"]
        rows.append(row)
    families = ct.family_errors(rows)
    ct.total_errors(rows, base)
    tests = _test_values(next((r["specimen"] for r in rows if r["specimen"]), None), deck_path)
    for row in rows:
        for q, test in (("peak", "peak"), ("first_peak", "peak"), ("residual", "residual")):
            row[f"test_err_{q}"] = (ct.relative_error(row[q], tests[test])
                                    if ct.usable_for(row, q) else None)
    return rows, families


def _cell(value) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return f"{value:.8g}"
    return str(value)


def write_tables(outdir: str, rows: list[dict], families: dict, pareto: list[dict]) -> None:
    """The four CSV tables (module docstring); empty cells for no value; through safe_write
    (never through a link, never over a file that is not that table)."""
    def write(name: str, fields, records) -> None:
        with open_for_write(os.path.join(outdir, name), OUTPUTS[name]) as f:
            writer = csv.writer(f)
            writer.writerow(fields)
            writer.writerows([_cell(r.get(c)) for c in fields] for r in records)

    write("convergence_runs.csv", COLUMNS, rows)
    fam = [{"family": name, "reference": (f["first_peak_reference"] if q == "first_peak"
                                          else f["reference"]),
            "finer_unusable": " ".join(f["finer_unusable"]), "quantity": q,
            "richardson_runs": " ".join(r["runs"]), "order": r["order"],
            "extrapolated": r["extrapolated"], "note": r["note"]}
           for name, f in families.items() for q, r in f["richardson"].items()]
    write("convergence_families.csv", ("family", "reference", "finer_unusable", "quantity",
                                       "richardson_runs", "order", "extrapolated", "note"), fam)
    write("convergence_pareto.csv", ("threshold", "quantity", "run", "cost_s", "error"), pareto)
    curves = {r["run"]: r["curve"] for r in rows if r["curve"] is not None}
    write("convergence_curves.csv", ("run", "deflection", "load"),
          [{"run": run, "deflection": float(x), "load": float(y)}
           for run, (d, p) in curves.items() for x, y in zip(d, p, strict=True)])


def plot(path: str, rows: list[dict], title: str) -> bool:
    """Error (against the family's finest run) against CPU time, log-log, one line per family
    (coarse to fine; the reference, with no error, is left out) and one panel per quantity;
    False (nothing written) without matplotlib."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return False
    fig, axes = plt.subplots(1, len(ct.QUANTITIES), figsize=(13, 3.4), layout="constrained")
    labels = {"peak": "peak load", "first_peak": "first maximum", "residual": "residual load",
              "curve": "whole curve"}
    families = list(dict.fromkeys(r["family"] for r in rows))
    for ax, q in zip(axes, ct.QUANTITIES, strict=True):
        for i, family in enumerate(families):
            pts = [(r["cost"], abs(r[f"err_{q}"])) for r in sorted(
                (r for r in rows if r["family"] == family and r["h"] is not None),
                key=lambda r: -r["h"]) if r["cost"] and r[f"err_{q}"]]  # coarse to fine
            if pts:
                ax.loglog(*zip(*pts, strict=True), "o-", color=f"C{i}")
        ax.set(title=labels[q], xlabel="CPU time (s)", ylabel="relative error")
        ax.grid(True, which="both", alpha=0.3)
    handles = [plt.Line2D([], [], color=f"C{i}", marker="o") for i in range(len(families))]
    fig.legend(handles, families, loc="outside right center", fontsize="small")
    fig.suptitle(title)
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=80, metadata={"Software": MARK})
    plt.close(fig)
    write_bytes(path, buffer.getvalue(), PNG)
    return True


def _stored(job: Job, say: Callable[[str], None]) -> dict:
    """The result of `job` as its file in the output directory holds it (--tables-only)."""
    if not os.path.exists(job.output):
        say(f"{job.name}: no result file: not tabled")
        return {"status": "missing"}
    try:
        with open_result(job.output) as res:
            status = res.status
    except ResultError as exc:
        say(f"{job.name}: unreadable result: {exc}")
        return {"status": "failed", "reason": str(exc)}
    why = reuse_verdict(job)[1]
    say(f"{job.name}: tabled from its file ({why or 'this run'})")
    return {"status": status}


def convergence_command(deck: str, ladder: str | None = None, quick: bool = False,
                        overrides: Iterable[str] = (), outdir: str | None = None,
                        workers: int = 2, force: bool = False, make_plot: bool = True,
                        quiet: bool = False, echo: Callable[[str], None] | None = None,
                        tables_only: bool = False) -> int:
    """Body of `icewall convergence`; returns 0, or 1 when a run failed with an error (a run
    the solver stopped, e.g. at a snap-back, is a result: tabled, not used in the errors).
    `tables_only`: run nothing; table the result files in `outdir` as they are, saying which
    were made by other code, another deck text or other overrides, and which are missing."""
    if echo is None:
        import click

        echo = click.echo
    say = (lambda text: None) if quiet else echo
    families = read_ladder(ladder) if ladder else parse_ladder(
        QUICK_LADDER if quick else DEFAULT_LADDER, "built-in ladder")
    outdir = outdir or os.path.join("results", "convergence", Path(deck).stem)
    levels, base, residual_at = build_jobs(deck, families, overrides, outdir)
    jobs = list({lv["job"].name: lv["job"] for lv in levels}.values())
    make_output_directory(outdir, OUTPUTS)
    results: dict[str, dict] = {}
    todo = []
    for job in jobs:
        if tables_only:
            results[job.name] = _stored(job, say)
            continue
        status = None if force else finished_status(job)
        if status is None:
            todo.append(job)
        else:
            results[job.name] = {"status": status}
            say(f"{job.name}: skipped ({status} earlier)")

    def done(result: dict) -> None:
        results[result["name"]] = result
        say(f"[{len(results)}/{len(jobs)}] {result['name']}: {result['status']} "
            f"{result.get('cpu_time_s', 0.0):.1f} s CPU, {result['run_time_s']:.1f} s wall")

    if todo:
        run_local(todo, workers, done, runner=run_timed)
    rows, families = build_rows(levels, results, deck, base.name, residual_at)
    pareto = ct.pareto_rows(rows)
    write_tables(outdir, rows, families, pareto)
    echo(ct.format_report(rows, families, pareto))
    png = os.path.join(outdir, "convergence.png")
    if make_plot and plot(png, rows, f"{Path(deck).name}: error against CPU time"):
        say(f"plot: {png}")
    elif make_plot:
        say("plot skipped: matplotlib is not installed (pip install 'icewall[plot]')")
    say(f"tables: {outdir}/convergence_*.csv")
    return 1 if any(r["status"] == "failed" for r in results.values()) else 0
