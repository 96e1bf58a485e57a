"""`icewall sweep`: many decks and parameter variations, run in parallel and resumably.

Jobs are decks x the cartesian product of the varied values. `--set key.path=v1,v2,v3` varies a
key (values split at top-level commas: a comma inside [...], {...} or quotes does not split, so
`--set 'geometry.diaphragms.positions=[450, 750],[300, 750]'` gives two lists and
`--set 'specimen.description="a, b"'` one string); a `--set` with one value applies to every job
and is not part of the run name. A sweep file (YAML) holds the same: `decks: [paths relative to
the file]`, `vary: {key.path: [values]}`, `fixed: {key.path: value}`. A run is named
`<deck stem>__<key>=<value>...` (varied keys only) and writes `OUTDIR/<name>.h5`.

A run whose final file exists with status completed or stopped and whose `run_stamp` (deck
text, overrides and code version; every `icewall run` stores it) is this job's is skipped unless
`force`; any other file at its path (another deck, other overrides, other code, no stamp) is
rerun, as is a `.partial` left by a crash. Each run holds its output's lock: a rerun while an
orphaned worker still writes that output fails that job and touches nothing. Workers die with
the sweep (SIGKILL included); SIGTERM or Ctrl-C writes the table of the runs finished so far.
Runs go to a local process pool, or with `scheduler` to an existing Dask distributed cluster
(paths must then be valid on the workers: a shared filesystem).
"""

from __future__ import annotations

import itertools
import json
import math
import os
import re
import time
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path

import yaml

from icewall.analysis.sweep_runners import Job, run_dask, run_local
from icewall.analysis.sweep_table import (
    BAND_COLUMNS,
    TABLE,
    TABLES,
    band_rows,
    build_rows,
    format_bands,
    format_table,
    ratio_stats,
    write_csv,
)
from icewall.deck.load import load_deck
from icewall.deck.profile import find_profile
from icewall.deck.resources import MAX_RUNS
from icewall.deck.yamlsrc import load_yaml
from icewall.errors import DeckError, Interrupted, ResultError
from icewall.pipeline import run_stamp
from icewall.results.reader import open_result
from icewall.results.writer import refuse_output_links
from icewall.safe_write import Kind, check_replaceable

FINISHED = ("completed", "stopped")
_UNSAFE = re.compile(r"[^A-Za-z0-9._+=-]+")
_MAX_NAME = 150


def split_values(raw: str) -> list[str]:
    """Split `v1,v2,...` at commas outside brackets, braces and quotes."""
    values, buf, depth, quote, escape = [], [], 0, "", False
    for ch in raw:
        if quote:
            escape = not escape and ch == "\\" and quote == '"'
            quote = "" if ch == quote and not escape else quote
        elif ch in "'\"":
            quote = ch
        elif ch in "[{":
            depth += 1
        elif ch in "]}":
            depth -= 1
        elif ch == "," and depth == 0:
            values.append("".join(buf).strip())
            buf = []
            continue
        buf.append(ch)
    values.append("".join(buf).strip())
    if any(not v for v in values):
        raise DeckError(f"--set: empty value in {raw!r}", "icewall sweep")
    return values


def _yaml_text(value) -> str:
    """A sweep-file value as the YAML text of a --set override."""
    if isinstance(value, str):
        try:
            same = yaml.safe_load(value) == value
        except yaml.YAMLError:
            same = False
        return value if same and "\n" not in value else json.dumps(value)
    return json.dumps(value)


def _read_sweep_file(path: str | Path) -> tuple[list[str], dict, dict]:
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise DeckError(f"cannot read the sweep file: {exc}", str(path)) from None
    data = load_yaml(text, str(path)) or {}  # the deck reader's YAML: one-line errors
    if not isinstance(data, dict) or set(data) - {"decks", "vary", "fixed"}:
        raise DeckError("a sweep file is a mapping of decks, vary, fixed", str(path))
    base = Path(path).parent
    decks, vary, fixed = data.get("decks") or [], data.get("vary") or {}, data.get("fixed") or {}
    if not isinstance(decks, list) or not isinstance(vary, dict) or not isinstance(fixed, dict):
        raise DeckError("decks is a list, vary and fixed are mappings", str(path))
    vary = {str(k): [_yaml_text(v) for v in (vs if isinstance(vs, list) else [vs])]
            for k, vs in vary.items()}
    fixed = {str(k): _yaml_text(v) for k, v in fixed.items()}
    return [str(base / d) for d in decks], vary, fixed


def _run_name(deck: str, varied: Iterable[tuple[str, str]]) -> str:
    def clean(text: str) -> str:
        return _UNSAFE.sub("_", text).strip("_") or "_"

    name = "__".join([clean(Path(deck).stem)] + [f"{clean(k)}={clean(v)}" for k, v in varied])
    if len(name) > _MAX_NAME:
        import hashlib

        name = name[:_MAX_NAME - 9] + "~" + hashlib.sha1(name.encode()).hexdigest()[:8]
    return name


def expand_jobs(decks: Iterable[str | Path] = (), sets: Iterable[str] = (),
                sweep_file: str | Path | None = None, outdir: str | Path = "results/sweep",
                profile: str | None = None) -> list[Job]:
    """Jobs of a sweep: decks (CLI, then the sweep file's) x cartesian product of varied values;
    `profile` (a name or path, deck.profile) applies to every job, under its overrides."""
    profile_file = None if profile is None else str(find_profile(profile).resolve())
    deck_list, vary, fixed = _read_sweep_file(sweep_file) if sweep_file else ([], {}, {})
    deck_list = [str(d) for d in decks] + deck_list
    where = str(sweep_file) if sweep_file else "icewall sweep"
    if both := set(vary) & set(fixed):
        raise DeckError(f"{', '.join(sorted(both))} both varied and fixed", where)
    given: set[str] = set()
    for assignment in sets:  # a --set replaces the sweep file's entry for its key
        key, sep, raw = assignment.partition("=")
        key = key.strip()
        if not sep or not key:
            raise DeckError(f"--set expects key.path=value[,value...], got {assignment!r}", where)
        if key in given:
            raise DeckError(f"--set: {key} is given twice", where)
        given.add(key)
        vary.pop(key, None)
        fixed.pop(key, None)
        values = split_values(raw)
        if len(values) == 1:
            fixed[key] = values[0]
        else:
            vary[key] = values
    if not deck_list:
        raise DeckError("no decks to run", where)
    check_run_count(len(deck_list) * math.prod(len(vs) for vs in vary.values()), fixed, where)
    fixed_over = tuple(f"{k}={v}" for k, v in fixed.items())
    jobs: dict[str, Job] = {}
    for deck in deck_list:
        for combo in itertools.product(*([(k, v) for v in vs] for k, vs in vary.items())):
            name = _run_name(deck, combo)
            varied = tuple(f"{k}={v}" for k, v in combo)
            job = Job(name, deck, fixed_over + varied, varied, str(Path(outdir) / f"{name}.h5"),
                      profile_file)
            if name in jobs and jobs[name] != job:
                raise DeckError(f"two runs would share the name {name} "
                                f"({jobs[name].deck}, {deck}): rename one deck", where)
            jobs[name] = job
    return list(jobs.values())


def check_run_count(n_runs: int, fixed: dict, where: str) -> None:
    """Refuse more than resources.MAX_RUNS runs up front (before any job is listed) unless
    the sweep fixes analysis.allow_large to true."""
    allowed = str(fixed.get("analysis.allow_large", "false")).strip().lower() == "true"
    if n_runs > MAX_RUNS and not allowed:
        raise DeckError(f"{n_runs:.3g} runs (limit {MAX_RUNS:.0e}): the sweep would not finish; "
                        "--set analysis.allow_large=true runs it anyway", where)


PERTURBATION = 1e-8
"""Relative widening of the load patches per round-off realization (with_realizations)."""


def realization_name(name: str, k: int) -> str:
    """Run name of round-off realization `k` of run `name` (k = 0: the run itself)."""
    return name if k == 0 else f"{name}.r{k}"


def base_name(name: str) -> str:
    """The run a realization's name belongs to (inverse of realization_name)."""
    stem, dot, k = name.rpartition(".r")
    return stem if dot and k.isdigit() else name


def with_realizations(jobs: list[Job], realizations: int) -> list[Job]:
    """Each job and its `realizations` - 1 round-off realizations: realization k widens the
    load patches by k PERTURBATION of their width, which changes the loads in their last bits
    only; where the path is chaotic in round-off (after the first softening) it follows another
    branch, as on another machine or NumPy build. Named `<run>.r<k>`, beside the run."""
    if realizations <= 1:
        return list(jobs)
    fixed = dict(o.split("=", 1) for job in jobs[:1] for o in job.overrides if "=" in o)
    check_run_count(len(jobs) * realizations, fixed, "icewall sweep --realizations")
    out = []
    for job in jobs:
        out.append(job)
        width = load_deck(job.deck, list(job.overrides), job.profile).deck.loads.patches.width
        for k in range(1, realizations):
            wider = f"loads.patches.width={width * (1.0 + k * PERTURBATION)!r}"
            name = realization_name(job.name, k)
            out.append(Job(name, job.deck, job.overrides + (wider,), job.varied + (wider,),
                           str(Path(job.output).with_name(f"{name}.h5")), job.profile))
    return out


def reuse_verdict(job: Job) -> tuple[str | None, str]:
    """(status, "") of an earlier run of `job` that can be skipped (completed/stopped), else
    (None, why it is rerun; "" where there is no result). Same run: same `run_stamp`."""
    if not os.path.lexists(job.output):
        return None, ""
    try:
        with open_result(job.output) as res:
            status, stamp = res.status, res.attrs.get("run_stamp")
        text = Path(job.deck).read_text(encoding="utf-8")
    except (ResultError, OSError, UnicodeDecodeError):
        return None, "the earlier result is unreadable"
    if stamp is None:
        return None, "the earlier result has no run stamp"
    try:
        ours = json.loads(_job_stamp(job, text))
    except DeckError:
        return None, "the deck or its profile does not load"
    try:
        theirs = json.loads(stamp)
    except (TypeError, ValueError):
        return None, "the earlier result's run stamp is damaged"
    differs = [what for key, what in (("deck_sha256", "deck text"), ("profile", "profile"),
                                      ("overrides", "overrides"), ("code", "code version"))
               if not isinstance(theirs, dict) or theirs.get(key) != ours.get(key)]
    if differs:
        return None, f"the earlier result differs in {', '.join(differs)}"
    return (status, "") if status in FINISHED else (None, f"the earlier run {status}")


def _job_stamp(job: Job, text: str) -> str:
    """The run stamp a run of `job` stores (its profile's assignments among the overrides)."""
    if job.profile is None:
        return run_stamp(text, job.overrides)
    loaded = load_deck(job.deck, job.overrides, job.profile)
    return run_stamp(loaded.text, loaded.overrides, loaded.profile)


def finished_status(job: Job) -> str | None:
    """Status of an earlier run of `job` that can be skipped (completed/stopped), else None."""
    return reuse_verdict(job)[0]


def validate_jobs(jobs: Iterable[Job]) -> None:
    """Load and validate the deck of every job with its overrides (`--dry-run`): a bad value
    in one run is a DeckError (exit 2) naming that run. A real sweep does not stop for it:
    that run fails with the same message and the others go on."""
    for job in jobs:
        try:
            load_deck(job.deck, job.overrides, job.profile)
        except DeckError as exc:
            raise DeckError(f"{exc.detail} (in run {job.name})", exc.file, exc.line,
                            exc.key) from None


def sweep_command(decks: Iterable[str] = (), sweep_file: str | None = None,
                  overrides: Iterable[str] = (), outdir: str = "results/sweep",
                  workers: int | None = None, scheduler: str | None = None,
                  force: bool = False, quiet: bool = False, dry_run: bool = False,
                  echo: Callable[[str], None] | None = None, realizations: int = 1,
                  profile: str | None = None) -> int:
    """Body of `icewall sweep`; returns the exit status (0: every run completed, 1: not).

    CLI: `icewall sweep [DECK]... [-f/--file SWEEP.yaml] [--set key.path=v1,v2 ...]
    [-o/--out OUTDIR (results/sweep)] [-j/--workers N (os.cpu_count())] [--scheduler ADDRESS]
    [--force] [--dry-run] [-q/--quiet] [--realizations K] [--profile NAME]`. Deck errors raise
    DeckError (exit 2) before any run. With K > 1 every run has K - 1 round-off realizations
    beside it (with_realizations) and OUTDIR/sweep_realizations.csv gives the band each figure
    spans. `profile` applies to every run (expand_jobs).
    """
    if echo is None:
        import click

        echo = click.echo
    say = (lambda text: None) if quiet else echo
    jobs = with_realizations(expand_jobs(decks, overrides, sweep_file, outdir, profile),
                             realizations)
    if dry_run:  # every run's deck and overrides checked: a listed run is one that can start
        for job in jobs:
            shown = f"--profile {job.profile} " if job.profile else ""
            echo(f"{job.name}  {job.deck}  {shown}{' '.join(job.overrides)}  -> {job.output}")
        validate_jobs(jobs)
        return 0
    make_output_directory(outdir)
    for job in jobs:  # a link or another file at a run's output: refused before any run
        refuse_output_links(job.output)
    width = max(len(job.name) for job in jobs)
    results, todo = _skip_finished(jobs, force, width, say)

    def done(result: dict) -> None:
        results[result["name"]] = result
        why = result["reason"]
        reason = f"  ({why[:77] + '...' if len(why) > 80 else why})" if why else ""
        say(f"[{len(results)}/{len(jobs)}] {result['name']:<{width}}  {result['status']:<9}"
            f"  {result['run_time_s']:.1f} s{reason}")

    start = time.perf_counter()
    try:
        if todo and scheduler:
            run_dask(todo, scheduler, done)
        elif todo:
            run_local(todo, workers or os.cpu_count() or 1, done)
    except (Interrupted, KeyboardInterrupt):  # the table of what finished, then exit 143/130
        finished = [job for job in jobs if job.name in results]
        rows = build_rows(finished, results)
        table = os.path.join(outdir, "sweep_summary.csv")
        write_csv(table, rows, ratio_stats(rows))
        echo(f"interrupted: {len(finished)} of {len(jobs)} runs in the table {table}")
        raise
    rows, table = _write_tables(jobs, results, outdir, realizations, echo)
    say(f"{len(todo)} run(s) in {time.perf_counter() - start:.1f} s, "
        f"{len(jobs) - len(todo)} skipped; table: {table}")
    return 0 if all(r["status"] == "completed" for r in rows) else 1


def _skip_finished(jobs: list[Job], force: bool, width: int, say: Callable[[str], None]
                   ) -> tuple[dict[str, dict], list[Job]]:
    """The results of the jobs an earlier run finished (reuse_verdict; none with `force`),
    each reported as skipped, and the jobs to run (with why, where an earlier result is not
    reused)."""
    results: dict[str, dict] = {}
    todo = []
    for job in jobs:
        status, why = (None, "") if force else reuse_verdict(job)
        if status is None:
            todo.append(job)
            if why:
                say(f"{job.name}: rerun: {why}")
            continue
        results[job.name] = {"name": job.name, "path": job.output, "status": status}
        say(f"[{len(results)}/{len(jobs)}] {job.name:<{width}}  skipped ({status} earlier)")
    return results, todo


def _write_tables(jobs: list[Job], results: dict[str, dict], outdir: str, realizations: int,
                  echo: Callable[[str], None]) -> tuple[list[dict], str]:
    """Write and echo OUTDIR/sweep_summary.csv and, with realizations, the bands of
    OUTDIR/sweep_realizations.csv; return the summary's rows and its path."""
    rows = build_rows(jobs, results)
    stats = ratio_stats(rows)
    table = os.path.join(outdir, "sweep_summary.csv")
    write_csv(table, rows, stats)
    echo(format_table(rows, stats))
    if realizations > 1:
        bands = band_rows(rows, base_name)
        band_stats = ratio_stats(bands)
        write_csv(os.path.join(outdir, "sweep_realizations.csv"), bands, band_stats,
                  BAND_COLUMNS)
        echo(format_bands(bands, band_stats))
    return rows, table


def make_output_directory(outdir: str | os.PathLike,
                          tables: Mapping[str, Kind] | None = None) -> None:
    """Create `outdir` (and parents), or raise ResultError saying why not; a table (file name
    -> Kind, default the sweep's) the study would end by writing over a link or a file icewall
    did not write is refused up front (icewall.safe_write)."""
    try:
        os.makedirs(outdir, exist_ok=True)
    except OSError as exc:
        raise ResultError(f"cannot create the output directory {outdir}: {exc}") from None
    for name, kind in (dict.fromkeys(TABLES, TABLE) if tables is None else tables).items():
        check_replaceable(os.path.join(outdir, name), kind)
