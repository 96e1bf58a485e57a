"""`icewall point`: drive one concrete material point along a strain path (no mesh).

Registered on icewall.cli.main, which also wraps the callback in its error handling (one-line
errors, exit codes); this module does not import icewall.cli. The library is imported in the
command's body, so `icewall --help` stays fast."""

from __future__ import annotations

import json
import math
import sys

import click


@click.command()
@click.option("--fc", type=click.FloatRange(0.0, 1000.0, min_open=True), required=True,
              help="Uniaxial compressive strength f'c (MPa).")
@click.option("--h-c", "h_c", type=click.FloatRange(0.0, 1e5, min_open=True), default=100.0,
              show_default=True,
              help="Crack-band width h_c (mm) for k_t, k_c (eqs. 3.29, 3.34).")
@click.option("--path", "path", default="uniaxial-compression", show_default=True,
              help="uniaxial-compression | uniaxial-tension | biaxial:R | biaxial-tension:R | "
                   "biaxial-strain:R | pure-shear | rotating")
@click.option("--formulation", default="plane_stress", show_default=True,
              type=click.Choice(["plane_stress", "plane_strain", "axisymmetric"]))
@click.option("--steps", type=click.IntRange(1, 1_000_000), default=400, show_default=True)
@click.option("--max-strain", type=click.FloatRange(0.0, 1.0, min_open=True), default=0.006,
              show_default=True,
              help="Final control strain magnitude.")
@click.option("--unload-at", type=float, multiple=True,
              help="Control strain at which to unload to zero and reload (repeatable).")
@click.option("--csv", "csv_path", type=click.Path(dir_okay=False), default=None,
              help="Write the stress-strain path to this CSV file ('-' for stdout).")
@click.option("--json", "as_json", is_flag=True, help="Print the summary as JSON.")
@click.option("--trial-stress", default="corotational", show_default=True,
              type=click.Choice(["corotational", "incremental", "total"]),
              help="Fig. 3.12 step-3 trial stress (the deck's materials.concrete.trial_stress).")
def point(fc: float, h_c: float, path: str, formulation: str, steps: int, max_strain: float,
          unload_at: tuple[float, ...], csv_path: str | None, as_json: bool,
          trial_stress: str) -> None:
    """Drive one concrete material point along a strain path (no mesh)."""
    from icewall.materials.parameters import derive_concrete_parameters
    from icewall.materials.point import run_path
    from icewall.preflight import floating_point_guard, floating_point_note

    _check_point_options(path, unload_at, max_strain)
    try:
        with floating_point_guard() as counts:  # NumPy's warnings: one line at most
            params = derive_concrete_parameters(fc, h_c)
            result = run_path(path, params, formulation, n_steps=steps, max_strain=max_strain,
                              unload_at=unload_at, trial_stress=trial_stress)
    except (ValueError, ArithmeticError) as exc:
        raise click.BadParameter(str(exc) or type(exc).__name__) from None
    if note := floating_point_note(counts):
        click.echo(f"warning: {note}", err=True)
    if csv_path == "-":
        result.to_csv(sys.stdout)
    elif csv_path:  # through icewall.safe_write: no link followed, no other file replaced
        result.to_csv(csv_path)
    summary = result.summary()
    if as_json:
        click.echo(json.dumps(summary, indent=2, default=float))
    elif csv_path != "-":
        for key, value in summary.items():
            click.echo(f"{key:>28}: {value}")


def _check_point_options(path: str, unload_at: tuple[float, ...], max_strain: float) -> None:
    """A path's stress ratio must be a finite number of sensible size and every --unload-at a
    strain on the path (it was silently ignored otherwise; a NaN ratio gave zero stresses)."""
    _, sep, argument = path.partition(":")
    if sep:
        try:
            ratio = float(argument)
        except ValueError:
            ratio = math.nan
        if not (math.isfinite(ratio) and abs(ratio) <= 1e3):
            raise click.BadParameter(f"the ratio of {path!r} must be a number within "
                                     "[-1000, 1000]", param_hint="--path")
    for value in unload_at:
        if not (math.isfinite(value) and 0.0 < abs(value) < max_strain):
            raise click.BadParameter(f"{value!r} is not a strain on the path (0 < |strain| < "
                                     f"--max-strain {max_strain:g})", param_hint="--unload-at")
