"""`icewall convergence`: studies that run one deck many times.

Registered on icewall.cli.main, which also wraps the callbacks in its error handling (one-line
errors, exit codes); this module does not import icewall.cli (`python -m icewall.cli` would
import it twice, the second time in a circle). The command imports the library in its body, so
`icewall --help` stays fast.
"""

from __future__ import annotations

import sys

import click

SET_HELP = "Override a deck value for every run, e.g. --set analysis.gauss=2 (repeatable)."


@click.command()
@click.argument("deck", type=click.Path(dir_okay=False))
@click.option("-l", "--ladder", type=click.Path(dir_okay=False), default=None,
              help="Ladder file (YAML: families: {name: {keys, values|factors, h}}) "
                   "[default: element size 150/100/75/50/37.5, Gauss 2/3/4, increment x2/x1/"
                   "x0.5, tolerances 0.1/0.05/0.02/0.01].")
@click.option("--quick", is_flag=True,
              help="A small ladder (element size 150/75, increment x2/x1): a smoke test.")
@click.option("--set", "overrides", multiple=True, help=SET_HELP)
@click.option("-o", "--out", "outdir", default=None, type=click.Path(file_okay=False),
              help="Directory for the runs and tables [default: results/convergence/<deck>].")
@click.option("-j", "--workers", type=click.IntRange(1), default=2, show_default=True,
              help="Local worker processes.")
@click.option("--force", is_flag=True, help="Rerun finished runs too.")
@click.option("--tables-only", is_flag=True,
              help="Run nothing: rebuild the tables and the report from the result files in "
                   "the output directory, saying which were made by other code, deck text or "
                   "overrides.")
@click.option("--no-plot", is_flag=True, help="Do not draw convergence.png.")
@click.option("-q", "--quiet", is_flag=True, help="No progress lines.")
def convergence(deck: str, ladder: str | None, quick: bool, overrides: tuple[str, ...],
                outdir: str | None, workers: int, force: bool, tables_only: bool,
                no_plot: bool, quiet: bool) -> None:
    """Run DECK over a ladder of discretisations; tabulate run time, iterations, peak, first
    maximum and residual loads and their errors (against each family's finest run, by
    Richardson extrapolation, against the test), plot error against CPU time and print the
    cheapest settings within 10, 5 and 2 % error."""
    from icewall.analysis.convergence import convergence_command

    if ladder and quick:
        raise click.UsageError("give --ladder or --quick, not both")
    if force and tables_only:
        raise click.UsageError("give --force or --tables-only, not both")
    sys.exit(convergence_command(deck, ladder=ladder, quick=quick, overrides=overrides,
                                 outdir=outdir, workers=workers, force=force,
                                 make_plot=not no_plot, quiet=quiet,
                                 tables_only=tables_only))
