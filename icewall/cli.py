"""The `icewall` command: a thin shell over the library (parse, call, map errors to exit codes).

The commands import the library inside their bodies, so `icewall --help` loads neither NumPy
nor SciPy nor h5py, and `icewall check` no NumPy."""

from __future__ import annotations

import errno
import functools
import json
import os
import sys
from pathlib import Path

import click

from icewall import __version__
from icewall.environment import check_environment
from icewall.errors import DeckError, IcewallError, Interrupted

SET_HELP = "Override a deck value, e.g. --set materials.concrete.fc=40 (repeatable)."
PROFILE_HELP = ("Apply a deck profile under --set: a NAME in decks/profiles/ (e.g. thesis) or a "
                "path to a profile file.")


def _raise_interrupted(signum, frame) -> None:
    import signal

    name = signal.Signals(signum).name
    raise Interrupted(name, 128 + signum)


def _handle_errors(func):
    """Report IcewallError as one line on stderr with its exit code; no traceback. SIGINT and
    SIGTERM become Interrupted, so a run's writer records the reason and keeps its steps."""

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        import signal

        for signum in (signal.SIGINT, signal.SIGTERM):
            signal.signal(signum, _raise_interrupted)
        try:
            check_environment()
            return func(*args, **kwargs)
        except IcewallError as exc:
            _fail(str(exc), exc.exit_code)
        except KeyboardInterrupt:
            _fail("interrupted", 130, prefix="")
        except OSError as exc:  # a file or folder that cannot be read or written
            where = f"{exc.filename}: " if exc.filename else ""
            _fail(f"{where}{exc.strerror or exc}", 2 if exc.errno in _BAD_PATH_ERRNOS else 1)
        except (click.exceptions.ClickException, click.exceptions.Exit, click.Abort):
            raise  # click's own usage errors and exits
        except Exception as exc:  # noqa: BLE001 - the promise: no traceback, ever
            if os.environ.get("ICEWALL_TRACEBACK", "") == "1":
                raise
            text = " ".join(str(exc).split())[:200]
            _fail(f"internal error ({type(exc).__name__}: {text}); please report it "
                  "(ICEWALL_TRACEBACK=1 shows where)", 1)

    return wrapper


_BAD_PATH_ERRNOS = {errno.ENOENT, errno.ENOTDIR, errno.EISDIR, errno.EACCES, errno.EPERM,
                    errno.EEXIST, errno.EROFS, errno.ENAMETOOLONG, errno.ELOOP, errno.EINVAL}


def _fail(message: str, exit_code: int, prefix: str = "error: ") -> None:
    """One line on stderr, then exit."""
    click.echo(prefix + " ".join(message.split()), err=True)
    sys.exit(exit_code)


def _warn_resources(loaded, output_dir: str | None = None) -> None:
    """Warn (stderr) about a long run and a scheme that the deck's settings keep from
    converging; refuse (exit 2) a result larger than the free disk of `output_dir` [default
    outputs.directory] unless analysis.allow_large."""
    from icewall.deck.resources import estimate, output_refusal, warnings_for
    from icewall.solve.settings import scheme_warnings

    deck = loaded.deck
    est = estimate(deck)
    for warning in [*warnings_for(deck, est), *scheme_warnings(deck)]:
        click.echo(f"warning: {loaded.path}: {warning}", err=True)
    problem = output_refusal(deck, output_dir or deck.outputs.directory, est)
    if problem and deck.analysis.allow_large:
        click.echo(f"warning: {loaded.path}: {problem} (allowed by analysis.allow_large)",
                   err=True)
    elif problem:
        raise DeckError(f"{problem} (analysis.allow_large: true runs it anyway)", loaded.path,
                        loaded.line_of("outputs.fields"), "outputs.fields")


class _OneLineErrors(click.Group):
    """click's usage errors as one line (`error: ...`, exit 2), like every other error."""

    def main(self, *args, **kwargs):
        kwargs["standalone_mode"] = False
        try:
            return super().main(*args, **kwargs)
        except click.exceptions.UsageError as exc:
            hint = f" (icewall {exc.ctx.info_name} --help)" if exc.ctx else ""
            _fail(f"{exc.format_message()}{hint}", exc.exit_code)
        except click.ClickException as exc:
            _fail(exc.format_message(), exc.exit_code)
        except click.Abort:
            _fail("aborted", 1)


@click.group(cls=_OneLineErrors)
@click.version_option(__version__, prog_name="icewall")
@click.option("-v", "--verbose", count=True, help="-v: solver messages; -vv: every iteration.")
def main(verbose: int) -> None:
    """Nonlinear FE analysis of steel-concrete-steel composite ice-resisting walls.

    Units: N, mm, MPa.
    """
    if verbose:
        import logging

        logging.basicConfig(format="%(message)s", stream=sys.stderr)
        logging.getLogger("icewall").setLevel(logging.DEBUG if verbose > 1 else logging.INFO)


@main.command()
@click.argument("deck", type=click.Path(dir_okay=False))
@click.option("--set", "overrides", multiple=True, help=SET_HELP)
@click.option("--profile", default=None, metavar="NAME", help=PROFILE_HELP)
@click.option("--json", "as_json", is_flag=True, help="Print the validated deck as JSON.")
@_handle_errors
def check(deck: str, overrides: tuple[str, ...], profile: str | None, as_json: bool) -> None:
    """Validate DECK without running it (exit code 2 on any problem)."""
    from dataclasses import asdict

    from icewall.deck.load import load_deck

    loaded = load_deck(deck, overrides, profile)
    _warn_resources(loaded)
    if as_json:
        click.echo(json.dumps(asdict(loaded.deck), indent=2))
    else:
        click.echo(f"{deck}: ok ({loaded.deck.specimen.name})")


@main.command()
@click.argument("deck", type=click.Path(dir_okay=False))
@click.option("--set", "overrides", multiple=True, help=SET_HELP)
@click.option("--out", "out_dir", default="meshes", show_default=True,
              type=click.Path(file_okay=False), help="Directory for the mesh files.")
@click.option("--format", "formats", default="msh,vtu,xdmf", show_default=True,
              help="Comma-separated: msh, vtu, xdmf.")
@click.option("--profile", default=None, metavar="NAME", help=PROFILE_HELP)
@_handle_errors
def mesh(deck: str, overrides: tuple[str, ...], out_dir: str, formats: str,
         profile: str | None) -> None:
    """Mesh DECK, write the mesh files and print counts and Gauss-point spacing h_c."""
    from icewall.deck.load import load_deck
    from icewall.mesh.build import build_mesh
    from icewall.mesh.io import FORMATS, mesh_report, write_mesh

    chosen = [f.strip() for f in formats.split(",") if f.strip()]
    if unknown := [f for f in chosen if f not in FORMATS] or ([] if chosen else ["(none)"]):
        raise click.BadParameter(f"unknown mesh format(s) {', '.join(unknown)}; choose from "
                                 f"{', '.join(FORMATS)}", param_hint="--format")
    loaded = load_deck(deck, overrides, profile)
    the_mesh = build_mesh(loaded.deck)
    stem = Path(out_dir) / Path(deck).stem
    for path in write_mesh(the_mesh, stem, chosen):
        click.echo(f"wrote {path}")
    click.echo(mesh_report(the_mesh, loaded.deck.analysis.gauss))


@main.command()
@click.argument("deck", type=click.Path(dir_okay=False))
@click.option("--set", "overrides", multiple=True, help=SET_HELP)
@click.option("-o", "--output", type=click.Path(), default=None,
              help="Result file (.h5, .hdf5, .he5, .hdf, any case) or directory [default: "
                   "outputs.directory of the deck].")
@click.option("-q", "--quiet", is_flag=True, help="No progress output.")
@click.option("--resume", is_flag=True,
              help="Go on with the interrupted run of DECK (same deck, --set and output) from "
                   "its last converged step, in the same result file.")
@click.option("--profile", default=None, metavar="NAME", help=PROFILE_HELP)
@_handle_errors
def run(deck: str, overrides: tuple[str, ...], output: str | None, quiet: bool,
        resume: bool, profile: str | None) -> None:
    """Run the analysis of DECK and write an HDF5 result."""
    from icewall.deck.load import load_deck
    from icewall.pipeline import run_deck

    if output is not None and not output.strip():
        raise click.BadParameter("is empty: give a result file or a directory",
                                 param_hint="-o/--output")
    loaded = load_deck(deck, overrides, profile)
    _warn_resources(loaded, None if output is None else
                    str(Path(output).parent if output.endswith(".h5") else output))
    report = run_deck(loaded, output, progress=None if quiet else click.echo, resume=resume)
    for warning in report.warnings:
        click.echo(f"warning: {warning}", err=True)
    if not quiet:
        t = report.timings
        shares = ", ".join(f"{k} {v:.3f} s" for k, v in t.items() if k != "total")
        click.echo(f"{report.status}: {report.n_steps} steps -> {report.path}")
        click.echo(f"time {t.get('total', 0.0):.3f} s ({shares})")
    if report.status != "completed":
        click.echo(f"error: the analysis stopped ({report.reason}); the {report.n_steps} "
                   f"converged steps are in {report.path}", err=True)
        sys.exit(1)


@main.command()
@click.argument("decks", nargs=-1, type=click.Path(dir_okay=False))
@click.option("-f", "--file", "sweep_file", type=click.Path(dir_okay=False), default=None,
              help="Sweep file (YAML: decks, vary, fixed).")
@click.option("--set", "overrides", multiple=True,
              help="key.path=v1,v2,... varies a deck value (cartesian product over several "
                   "--set; a comma inside [..], {..} or quotes does not split); one value "
                   "applies to every run.")
@click.option("-o", "--out", "outdir", default="results/sweep", show_default=True,
              type=click.Path(file_okay=False), help="Directory for the results and the table.")
@click.option("-j", "--workers", type=click.IntRange(1), default=None,
              help="Local worker processes [default: number of CPUs].")
@click.option("--scheduler", default=None, metavar="ADDRESS",
              help="Run on this Dask distributed scheduler (e.g. tcp://host:8786).")
@click.option("--force", is_flag=True, help="Rerun finished runs too.")
@click.option("--dry-run", is_flag=True, help="List the runs, run nothing.")
@click.option("-q", "--quiet", is_flag=True, help="No progress lines.")
@click.option("--realizations", type=click.IntRange(1), default=1, show_default=True,
              help="Runs of each job: the job and K-1 round-off realizations (load patches "
                   "widened by k 1e-8); OUT/sweep_realizations.csv gives the band of each "
                   "figure over them.")
@click.option("--profile", default=None, metavar="NAME", help=PROFILE_HELP)
@_handle_errors
def sweep(decks: tuple[str, ...], sweep_file: str | None, overrides: tuple[str, ...],
          outdir: str, workers: int | None, scheduler: str | None, force: bool, dry_run: bool,
          quiet: bool, realizations: int, profile: str | None) -> None:
    """Run DECKS (and/or a sweep file) over parameter variations, in parallel and resumably;
    writes one HDF5 per run and OUT/sweep_summary.csv with test/predicted ratios."""
    from icewall.analysis.sweep import sweep_command

    sys.exit(sweep_command(decks, sweep_file=sweep_file, overrides=overrides, outdir=outdir,
                           workers=workers, scheduler=scheduler, force=force, quiet=quiet,
                           dry_run=dry_run, realizations=realizations, profile=profile))


@main.command()
@click.argument("results_dir", type=click.Path(file_okay=False))
@click.option("--baseline", "baseline_path", required=True, type=click.Path(dir_okay=False),
              help="Baseline file (YAML): per run peak and residual loads, and the tolerances.")
@click.option("--update", is_flag=True, help="Rewrite the baseline from the results.")
@click.option("--peak-tol", type=click.FloatRange(min=0.0), default=None,
              help="Relative tolerance on each peak load [baseline's, else 0.03].")
@click.option("--residual-tol", type=click.FloatRange(min=0.0), default=None,
              help="Relative tolerance on each residual load [baseline's, else 0.10].")
@click.option("--band", type=(float, float), default=None, metavar="LO HI",
              help="Band of the mean test/predicted ultimate-load ratio [baseline's, else "
                   "0.93 1.07].")
@_handle_errors
def compare(results_dir: str, baseline_path: str, update: bool, peak_tol: float | None,
            residual_tol: float | None, band: tuple[float, float] | None) -> None:
    """Compare the results in RESULTS_DIR (an icewall sweep output) with a stored baseline of
    peak and residual loads; exit 1 when a check fails. --update rewrites the baseline."""
    from icewall.analysis.compare import FROM_HEADER, compare_command

    sys.exit(compare_command(results_dir, baseline_path, update=update, peak_tol=peak_tol,
                             residual_tol=FROM_HEADER if residual_tol is None else residual_tol,
                             band=band))


@main.command()
@click.argument("result", type=click.Path(dir_okay=False))
@click.option("--json", "as_json", is_flag=True, help="Print the summary as JSON.")
@_handle_errors
def summary(result: str, as_json: bool) -> None:
    """Key figures of a RESULT file: peak load and its deflection, final load, steps, time."""
    from icewall.analysis.summary import format_summary, summarize
    from icewall.results.reader import damaged_result

    with damaged_result(result):
        data = summarize(result)
        text = (json.dumps(data, indent=2, allow_nan=False) if as_json  # valid JSON only
                else format_summary(data))
    click.echo(text)


@main.command()
@click.argument("deck", type=click.Path(dir_okay=False))
@click.option("--set", "overrides", multiple=True, help=SET_HELP)
@click.option("--profile", default=None, metavar="NAME", help=PROFILE_HELP)
@click.option("--json", "as_json", is_flag=True, help="Print the rows as JSON.")
@_handle_errors
def params(deck: str, overrides: tuple[str, ...], profile: str | None, as_json: bool) -> None:
    """Derived concrete parameters per region (E, f't, eps_c, G_f, G_cr, alpha, h_c, k_t, k_c),
    to check against the thesis' Table 4.4 before running; warns where h_c is too large for
    the crack band (snap-back of the softening branch)."""
    from icewall.deck.load import load_deck
    from icewall.mesh.build import build_mesh
    from icewall.model.params_report import concrete_parameter_rows, format_parameter_rows

    loaded = load_deck(deck, overrides, profile)
    rows = concrete_parameter_rows(loaded.deck, build_mesh(loaded.deck))
    if as_json:
        click.echo(json.dumps(rows, indent=2))
    else:
        click.echo(format_parameter_rows(rows))
    for row in rows:
        for warning in row["warnings"]:
            click.echo(f"warning: {row['region']}: {warning}", err=True)


@main.command()
@click.option("-o", "--output", type=click.Path(dir_okay=False), default=None,
              help="Write to a file instead of standard output.")
@_handle_errors
def schema(output: str | None) -> None:
    """Print the JSON Schema of the deck format (for editors)."""
    from icewall.deck.jsonschema import deck_json_schema
    from icewall.safe_write import SCHEMA, write_text

    text = json.dumps(deck_json_schema(), indent=2) + "\n"
    if output:
        write_text(output, text, SCHEMA)
    else:
        click.echo(text, nl=False)


# commands in their own modules (registered after main and _handle_errors are defined)
from icewall.cli_point import point  # noqa: E402
from icewall.cli_post import export, plot, report  # noqa: E402
from icewall.cli_study import convergence  # noqa: E402

for _command in (point, plot, export, report, convergence):
    _command.callback = _handle_errors(_command.callback)
    main.add_command(_command)

if __name__ == "__main__":  # pragma: no cover
    main()
