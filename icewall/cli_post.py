"""The post-processing commands `icewall plot`, `export` and `report` (registered on the main
group by icewall.cli). The library (NumPy, matplotlib, meshio) is imported inside the commands
only, so `icewall --help` stays fast."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from icewall.errors import ResultError

PLOTS = ("curves", "cracks", "deformed", "trajectories", "plates", "interface")


def _deflections(text: str) -> list[float | str]:
    out: list[float | str] = []
    for item in (t.strip() for t in text.split(",") if t.strip()):
        if item in ("peak", "final"):
            out.append(item)
            continue
        try:
            out.append(float(item))
        except ValueError:
            raise click.BadParameter(f"{item!r} is not a deflection in mm, 'peak' or "
                                     "'final'", param_hint="--at") from None
    return out


def _step_figures(path: str, kinds: list[str], where: float | str, scale: float | None):
    """(stem suffix, figure or the ResultError that kept it from being drawn) of every step
    plot asked for, one result file, one deflection: a kind whose fields are missing does not
    stop the others."""
    from icewall.post.common import step_at
    from icewall.post.deformed import plot_deformed
    from icewall.post.interface_map import plot_interface_map
    from icewall.post.patterns import plot_cracks
    from icewall.post.plate_stresses import plot_plate_stresses
    from icewall.post.trajectories import plot_trajectories
    from icewall.results.reader import open_result

    builders = {"cracks": plot_cracks, "trajectories": plot_trajectories,
                "plates": plot_plate_stresses, "interface": plot_interface_map,
                "deformed": lambda r, s: plot_deformed(r, s, scale)}
    label = where if isinstance(where, str) else f"{where:g}mm"
    with open_result(path) as r:
        step = step_at(r, where)
        for kind in kinds:
            if kind in builders:
                try:
                    yield f"{kind}_{label}", builders[kind](r, step)
                except ResultError as exc:
                    yield f"{kind}_{label}", exc


@click.command()
@click.argument("results", nargs=-1, required=True, type=click.Path(dir_okay=False))
@click.option("-k", "--kind", "kinds", default="curves", show_default=True,
              help=f"Comma-separated plots: {', '.join(PLOTS)} or all.")
@click.option("--at", "at", default="peak", show_default=True,
              help="Deflections (mm) for the step plots, comma-separated; also 'peak', 'final'.")
@click.option("--scale", type=click.FloatRange(min=0.0, min_open=True), default=None,
              help="Magnification of the deformed shape [default: automatic, 1/2/5 x 10^k].")
@click.option("-o", "--out", "outdir", default="plots", show_default=True,
              type=click.Path(file_okay=False), help="Directory for the figures.")
@click.option("--format", "formats", default="png,svg", show_default=True,
              help="Comma-separated: png, svg.")
@click.option("--label", "labels", multiple=True, help="Curve label per result (repeatable).")
def plot(results: tuple[str, ...], kinds: str, at: str, scale: float | None, outdir: str,
         formats: str, labels: tuple[str, ...]) -> None:
    """Plot RESULTS (needs the `plot` extra: matplotlib): load-deflection curves of all of
    them overlaid with the test's peak and residual, and per result at each --at deflection:
    crack patterns (needs outputs.fields with state), deformed shape, principal stress
    trajectories, plate and diaphragm stresses, interface state map."""
    from icewall.post.curves import plot_curves
    from icewall.post.figures import save

    everything = kinds.strip() == "all"
    chosen = list(PLOTS) if everything else [k.strip() for k in kinds.split(",")]
    unknown = [k for k in chosen if k not in PLOTS]
    if unknown or not chosen:
        raise click.BadParameter(f"unknown plot(s) {unknown}; choose from {', '.join(PLOTS)} "
                                 "or all", param_hint="--kind")
    if labels and len(labels) != len(results):
        raise click.BadParameter(f"{len(labels)} labels for {len(results)} results",
                                 param_hint="--label")
    fmts = tuple(f.strip() for f in formats.split(",") if f.strip())
    written = []
    if "curves" in chosen:
        written += save(plot_curves(list(results), list(labels) or None),
                        Path(outdir) / "curves", fmts)
    points, problems, skipped = _deflections(at), [], []
    for path in results:
        stem = Path(path).name.removesuffix(".partial").removesuffix(".h5")
        for where in points:
            try:
                for suffix, fig in _step_figures(path, chosen, where, scale):
                    if isinstance(fig, ResultError):  # -k all: skip what cannot be drawn
                        (skipped if everything else problems).append(f"{suffix}: {fig}")
                    else:
                        written += save(fig, Path(outdir) / f"{stem}_{suffix}", fmts)
            except ResultError as exc:
                problems.append(str(exc))
    for p in written:
        click.echo(f"wrote {p}")
    for message in skipped:
        click.echo(f"skipped {message}", err=True)
    if problems:  # one line each, after what could be drawn
        for message in problems:
            click.echo(f"error: {message}", err=True)
        sys.exit(2)


@click.command()
@click.argument("result", type=click.Path(dir_okay=False))
@click.option("-o", "--output", type=click.Path(dir_okay=False), default=None,
              help="Collection file (.pvd) [default: RESULT_paraview.pvd beside RESULT]; the "
                   ".vtu files go into the folder of the same name.")
def export(result: str, output: str | None) -> None:
    """Export RESULT for ParaView: a time series (.pvd + one .vtu per stored step) of the mesh,
    nodal displacements, interface state and cell means of the Gauss fields."""
    from icewall.post.export import export_vtu_series
    from icewall.results.reader import damaged_result

    with damaged_result(result):
        path, time_axis = export_vtu_series(
            result, output, warn=lambda text: click.echo(f"warning: {text}", err=True))
    click.echo(f"wrote {path} (time = {time_axis}; ParaView opens it directly)")


@click.command()
@click.argument("results", nargs=-1, required=True, type=click.Path(dir_okay=False))
@click.option("-o", "--output", default="report.html", show_default=True,
              type=click.Path(dir_okay=False), help="HTML file to write.")
@click.option("--title", default=None, help="Page title.")
def report(results: tuple[str, ...], output: str, title: str | None) -> None:
    """One self-contained HTML page for RESULTS (needs matplotlib): validation table against
    the tests, CSA S474 ductility, curves against the tests, crack patterns at peak and 40 mm."""
    from icewall.post.html_report import build_report

    click.echo(f"wrote {build_report(list(results), output, title)}")
