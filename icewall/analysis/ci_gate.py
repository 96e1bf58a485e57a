"""The CI gate (issue 18): the CI variants of the eight analysed decks, run and compared with
the stored baseline `tests/compare/baseline_ci.yaml` (`make test`, `make compare`), and the
rewriting of that baseline from round-off realizations and other platforms' runs:

    python -m icewall.analysis.ci_gate [-o OUTDIR] [-j N]           # compare
    python -m icewall.analysis.ci_gate --update [--platform DIR]...  # rewrite the baseline

The comparison itself (bands, tolerances, what is gated) is :mod:`icewall.analysis.compare`.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path

from icewall.analysis.baseline import DECKS_DIR, measure_results
from icewall.analysis.compare import compare_command
from icewall.analysis.sweep import expand_jobs, finished_status, realization_name, with_realizations
from icewall.analysis.sweep_runners import run_local
from icewall.analysis.sweep_table import build_rows, format_table, ratio_stats, write_csv
from icewall.errors import IcewallError, ResultError

# The CI tolerances (issue 18), written into the header of a rewritten baseline. The bands
# span the run's round-off realizations and its runs on other platforms (OPENBLAS_CORETYPE
# Haswell, Sandybridge, Prescott and SkylakeX, the NumPy and numba concrete kernels, one BLAS
# thread); a figure is gated at its tolerance beyond its band where the band spans at most
# GATE_FRACTION of it, else reported (compare._value_row). Gated pre-peak loads agree across
# all of those to 0.07 % (23 of 24); a 3 % change of f'c, of the friction
# coefficient or of the TF leg width moves some of them by more than 0.5 % beyond their bands
# (tests/compare/model_changes.yaml): with the readings of issue 20 a 1 % tolerance no longer
# caught the f'c change (its largest gated move was 0.99 %), hence 0.5 %. The secant
# iteration's post-peak path moves by up to 2x with the
# platform, so the residual is reported, never gated, until the solver converges it. The band
# of the mean test/predicted ratio: the variants' mean is 0.82 with the readings of issue 20
# (every wall over-predicted, CF-8 by 4 % and CF-5 by 50 %; docs/validation.md), under the
# acceptance band; the floor sits under that by more than the platforms move it (the variants'
# peaks spread by up to 16 % over their ten runs), so that a change which makes the agreement
# with the tests clearly worse fails even after --update has reset the per-run values; the
# ceiling leaves room for the fix. The acceptance band (baseline.RATIO_BAND) is for
# `make validate`.
CI_TOLERANCES = {"peak_tol": 0.03, "curve_tol": 0.005, "residual_tol": None,
                 "band": (0.75, 1.10)}
BASELINE_CI = Path(__file__).resolve().parents[2] / "tests" / "compare" / "baseline_ci.yaml"
# CI variants of the eight analysed decks: the shipped deck (50 mm elements, 1 mm increments)
# ended a little past its peak on the secant iteration (the CF walls peak at 7-14.5 mm, TF at
# 5-7.5; VTT3 is on its plateau at 10 mm, within 1 % of its peak at 11-31 mm) and with no field
# output (history only): the figures CI checks are those of `make validate`, not of a coarser
# model, at about the cost of the former coarse variants.
CI_VARIANTS: dict[str, tuple[str, ...]] = {
    name: (f"loads.control.target={15 if name[0] == 'c' else 8 if name[0] == 't' else 10}",
           "outputs.fields=[]")
    for name in ("cf4", "cf5", "cf8", "cf13", "tf1", "tf2", "tf4", "vtt3")}
REALIZATIONS = 5  # round-off realizations per variant in a new baseline




def ci_jobs(outdir: str | os.PathLike, variants: Mapping[str, Iterable[str]] | None = None,
            decks_dir: str | os.PathLike = DECKS_DIR, realizations: int = 1) -> list:
    """Sweep jobs of the CI variants (run name = deck stem) with their round-off realizations
    (icewall.analysis.sweep.with_realizations: `<stem>.r<k>`) when realizations > 1."""
    jobs = []
    for name, overrides in (variants or CI_VARIANTS).items():
        jobs += expand_jobs([Path(decks_dir) / f"{name}.yaml"], list(overrides), None, outdir)
    return with_realizations(jobs, realizations)


def run_variants(outdir: str | os.PathLike, workers: int | None = None,
                 variants: Mapping[str, Iterable[str]] | None = None, realizations: int = 1,
                 echo: Callable[[str], None] = print) -> list[dict]:
    """Run the CI variants (and their realizations) in a local process pool (finished runs
    are skipped, as in `icewall sweep`); writes OUTDIR/<name>.h5 and OUTDIR/sweep_summary.csv.
    Returns the per-run results (name, path, status, run_time_s, ...)."""
    os.makedirs(outdir, exist_ok=True)
    jobs = ci_jobs(outdir, variants, realizations=realizations)
    results: dict[str, dict] = {}
    todo = []
    for job in jobs:
        status = finished_status(job)
        if status is None:
            todo.append(job)
        else:
            results[job.name] = {"name": job.name, "path": job.output, "status": status,
                                 "reason": "", "run_time_s": None, "n_steps": None}

    def done(result: dict) -> None:
        results[result["name"]] = result
        echo(f"[{len(results)}/{len(jobs)}] {result['name']}: {result['status']} "
             f"{result['run_time_s']:.1f} s")

    start = time.perf_counter()
    if todo:
        run_local(todo, workers or os.cpu_count() or 1, done)
    rows = build_rows(jobs, results)
    stats = ratio_stats(rows)
    write_csv(os.path.join(outdir, "sweep_summary.csv"), rows, stats)
    echo(format_table(rows, stats))
    echo(f"{len(todo)} run(s) in {time.perf_counter() - start:.1f} s, "
         f"{len(jobs) - len(todo)} skipped")
    return [results[j.name] for j in jobs]


def run_ci_comparison(outdir: str | os.PathLike, baseline: str | os.PathLike = BASELINE_CI,
                      workers: int | None = None, update: bool = False,
                      echo: Callable[[str], None] = print,
                      realizations: int = REALIZATIONS,
                      platform_dirs: Iterable[str | os.PathLike] = (),
                      command: str = "python -m icewall.analysis.ci_gate --update",
                      **tolerances) -> int:
    """Run the CI variants into `outdir` and compare them with `baseline`; with `update`,
    also run `realizations` - 1 round-off realizations of each and rewrite the baseline with
    the bands they span. Returns the exit status of :func:`compare_command`. Only the
    variants' own result files are compared (the run names of CI_VARIANTS). With `update`,
    `platform_dirs` are output directories of the same variants run elsewhere (another
    OPENBLAS_CORETYPE, the other concrete kernel, other thread counts): their runs join the
    realizations, so that the bands span the platforms as well as the round-off."""
    if update:  # a rewritten baseline states the CI's own tolerances (module constants)
        for key, value in CI_TOLERANCES.items():
            tolerances.setdefault(key, value)
    results = run_variants(outdir, workers, realizations=realizations if update else 1,
                           echo=echo)
    paths = {r["name"]: r["path"] for r in results if os.path.exists(r["path"])}
    own = [paths[name] for name in CI_VARIANTS if name in paths]
    if not own:
        raise ResultError(f"no CI run left a result in {outdir}")
    groups, measured = None, own
    if update:  # every realization measured once; the variants' own records are among them
        records = measure_results(list(paths.values()))
        groups = {name: [records[realization_name(name, k)] for k in range(realizations)
                         if realization_name(name, k) in records] for name in CI_VARIANTS}
        for folder in platform_dirs:
            other = measure_results([Path(folder) / f"{name}.h5" for name in CI_VARIANTS
                                     if (Path(folder) / f"{name}.h5").exists()])
            for name, record in other.items():
                groups[name].append(record)
        measured = {name: records[name] for name in CI_VARIANTS if name in records}
    return compare_command(measured, baseline, update=update, echo=echo, command=command,
                           realizations=groups, **tolerances)


def main(argv: list[str] | None = None) -> int:
    """`python -m icewall.analysis.ci_gate [--update] [-o OUTDIR] [--baseline FILE] [-j N]`:
    run the CI variants and compare them with (or rewrite, running every round-off
    realization) the stored baseline."""
    import argparse

    parser = argparse.ArgumentParser(prog="python -m icewall.analysis.ci_gate",
                                     description=main.__doc__)
    parser.add_argument("-o", "--out", default="results/compare")
    parser.add_argument("--baseline", default=str(BASELINE_CI))
    parser.add_argument("-j", "--workers", type=int, default=None)
    parser.add_argument("--update", action="store_true")
    parser.add_argument("--platform", action="append", default=[], metavar="DIR",
                        help="with --update: a directory of the same variants run on other "
                             "BLAS kernels / concrete kernel / threads, added to the bands")
    args = parser.parse_args(argv)
    try:
        import shlex
        import sys

        words = sys.argv[1:] if argv is None else argv
        return run_ci_comparison(args.out, args.baseline, args.workers, args.update,
                                 platform_dirs=args.platform,
                                 command=" ".join(["python -m icewall.analysis.ci_gate",
                                                   *map(shlex.quote, words)]))
    except IcewallError as exc:
        print(f"error: {exc}")
        return getattr(exc, "exit_code", 1)


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
