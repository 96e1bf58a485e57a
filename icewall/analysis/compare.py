"""`icewall compare`: check a set of results against a stored baseline (issue 5 §4).

A *baseline* is a YAML file (format: :mod:`icewall.analysis.baseline`) with one entry per run.

The residual is the load at the run's own target deflection, not at 40 mm: the CI variants
stop a little past their peaks. Every value is as :func:`icewall.analysis.extract.extract`
defines it.

**Round-off realizations.** Past the first softening the path of these walls is chaotic in
round-off: the secant iteration stops at the first iterate within the tolerances (0.05, the
thesis'), and which iterate that is, with it where the softening localises, changes with the
last bits of the arithmetic -- another NumPy or BLAS build, another CPU. Measured on the CI
variants with the load patches widened by 1e-8 of their width: peaks move by up to 2 % (CF-8),
the load a few millimetres past the peak by up to 2x, and whether a run needs a fallback or
stops changes too. A baseline written with ``realizations: K`` therefore runs every variant
K times (the run itself and K - 1 such perturbations) and stores the band [min, max] that each
figure spans and the statuses the realizations ended with.

:func:`compare` fails a run when a pre-peak load (the loads at `baseline.CURVE_DEFLECTIONS`,
where the secant iteration is not yet chaotic in round-off) lies outside its band widened by
``curve_tol``, when its peak load lies outside its band widened by ``peak_tol`` (relative; a
band of one value where the baseline has none), when its residual load lies outside its band
widened by ``residual_tol`` (None: the residual is reported, never gated), when it ends with a
status none of the baseline's realizations ended with (a run that completed now stops, or the
reverse: either way the baseline no longer describes the code), when its overrides differ from
the baseline's, or when it is missing. A figure whose own band spans more than GATE_FRACTION of
its tolerance is reported, not gated: no tolerance we would want on it holds across platforms
(issue 18). Over
the runs whose specimen has a test value, the mean test/predicted ratio of the ultimate load
must lie in ``ratio_band``. Runs absent from the baseline are reported ("new") but do not fail.
The CI baseline's bands also span the variants run on other platforms (:mod:`icewall.analysis.
ci_gate`, ``--platform DIR``:
other OPENBLAS_CORETYPE kernels, the other concrete kernel, one thread).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

from icewall.analysis.baseline import (  # noqa: F401  (re-exported: the public names)
    CURVE_TOL,
    DECKS_DIR,
    NOTE,
    PEAK_TOL,
    RATIO_BAND,
    RATIO_NAME,
    RESIDUAL_TOL,
    make_baseline,
    mean_ratio,
    measure,
    measure_results,
    read_baseline,
    write_baseline,
)
from icewall.errors import IcewallError, ResultError
from icewall.safe_write import BASELINE, check_replaceable

# A figure is gated only where its band spans at most this fraction of its tolerance: a band
# of ten realizations that already spans nearly the tolerance does not bound the next platform.
GATE_FRACTION = 0.5
FROM_HEADER = "from the baseline's header"  # compare_command: a tolerance the header gives

@dataclass
class Row:
    run: str
    quantity: str
    baseline: object
    now: object
    change: float | None = None  # relative
    verdict: str = "ok"  # ok | FAIL | new | info
    note: str = ""


@dataclass
class CompareReport:
    rows: list[Row] = field(default_factory=list)
    peak_tol: float = PEAK_TOL
    residual_tol: float | None = RESIDUAL_TOL  # None: the residual is reported, not gated
    curve_tol: float = CURVE_TOL
    ratio_band: tuple[float, float] = RATIO_BAND
    ratio_now: float | None = None
    ratio_baseline: float | None = None
    ratio_n: int = 0

    @property
    def failures(self) -> list[Row]:
        return [r for r in self.rows if r.verdict == "FAIL"]

    @property
    def passed(self) -> bool:
        return not self.failures


def _relative(base, now) -> float | None:
    if base is None or now is None:
        return None
    if base == 0:
        return 0.0 if now == 0 else math.inf
    return (now - base) / abs(base)


def _value_row(run: str, quantity: str, base, now, tol: float, band=None,
               may_be_missing: bool = False) -> Row:
    """Check `now` against the baseline value `base`, or against the band [lo, hi] that the
    baseline's realizations span, widened by `tol` (relative). `may_be_missing`: a realization
    of the baseline had no value either (it stopped short), so none now is no change."""
    if band is None and base is not None:
        band = [base, base]
    if now is None:
        if base is None or may_be_missing:
            return Row(run, quantity, base, None, None, "ok", "no value (stopped short)")
        return Row(run, quantity, base, None, None, "FAIL", "no value now")
    if band is None:
        return Row(run, quantity, None, now, None, "FAIL", "no baseline value")
    lo, hi = float(min(band)), float(max(band))
    below, above = _relative(lo, now), _relative(hi, now)
    change = below if below < 0 else above if above > 0 else 0.0  # from the nearer band edge
    where = f"band [{lo:.5g}, {hi:.5g}]" if hi > lo else ""
    if tol is None:
        return Row(run, quantity, base, now, change, "info",
                   "reported, not gated" + (f" ({where})" if where else ""))
    spread = _relative(lo, hi) if lo > 0 else 0.0
    if spread > GATE_FRACTION * tol:  # its own round-off/platform band is too wide to gate
        return Row(run, quantity, base, now, change, "info",
                   f"reported, not gated: its realizations span {spread:.1%} > "
                   f"{GATE_FRACTION:g} x {tol:.1%}")
    if abs(change) > tol:
        return Row(run, quantity, base, now, change, "FAIL",
                   f"moved more than {100 * tol:g}%" + (f" outside its {where}" if where else ""))
    return Row(run, quantity, base, now, change, "ok", f"in {where}" if where else "")


def compare(results, baseline, peak_tol: float = PEAK_TOL,
            residual_tol: float | None = RESIDUAL_TOL,
            ratio_band: tuple[float, float] = RATIO_BAND,
            curve_tol: float = CURVE_TOL) -> CompareReport:
    """Compare `results` (a sweep output directory, a list of .h5 files, or measured records
    {name: record}) with `baseline` (a file path or its data). Rules: module docstring."""
    base = baseline if isinstance(baseline, Mapping) else read_baseline(baseline)
    base_runs: dict = base.get("runs") or {}
    now_runs = measure_results(results)
    lo, hi = float(ratio_band[0]), float(ratio_band[1])
    report = CompareReport(peak_tol=peak_tol, residual_tol=residual_tol, curve_tol=curve_tol,
                           ratio_band=(lo, hi))
    for name in sorted(set(base_runs) | set(now_runs)):
        b, n = base_runs.get(name), now_runs.get(name)
        if n is None:
            report.rows.append(Row(name, "run", b.get("status"), None, None, "FAIL",
                                   "missing from the results"))
            continue
        if b is None:
            report.rows.append(Row(name, "run", None, n.get("status"), None, "new",
                                   "not in the baseline"))
            continue
        b_over, n_over = list(b.get("overrides") or []), list(n.get("overrides") or [])
        if b_over != n_over:  # shown: the assignments that differ
            report.rows.append(Row(name, "overrides",
                                   " ".join(o for o in b_over if o not in n_over) or "-",
                                   " ".join(o for o in n_over if o not in b_over) or "-",
                                   None, "FAIL", "made with other overrides than the baseline"))
        bs, ns = b.get("status"), n.get("status")
        statuses = set(b.get("statuses") or [bs])
        if ns not in statuses:
            why = {("completed", "stopped"): f"now stops: {n.get('stop_reason', '')}",
                   ("stopped", "completed"): "now completes: update the baseline if intended"}
            report.rows.append(Row(name, "status", bs, ns, None, "FAIL",
                                   why.get((bs, ns), f"status {bs} -> {ns}")))
        else:
            report.rows.append(Row(name, "status", bs, ns, None, "ok"))
        report.rows.extend(_curve_rows(name, b, n, curve_tol))
        report.rows.append(_value_row(name, "peak", b.get("peak_load"), n.get("peak_load"),
                                      peak_tol, b.get("peak_band")))
        report.rows.append(Row(name, "defl@peak", b.get("deflection_at_peak"),
                               n.get("deflection_at_peak"),
                               _relative(b.get("deflection_at_peak"),
                                         n.get("deflection_at_peak")), "info"))
        at = n.get("residual_deflection") or b.get("residual_deflection")
        label = f"res@{at:g}mm" if isinstance(at, int | float) else "residual"
        report.rows.append(_value_row(name, label, b.get("residual_load"),
                                      n.get("residual_load"), residual_tol,
                                      b.get("residual_band"), "stopped" in statuses))
        if "stopped" in statuses or ns == "stopped":
            report.rows.append(Row(name, "end defl", b.get("final_deflection"),
                                   n.get("final_deflection"),
                                   _relative(b.get("final_deflection"),
                                             n.get("final_deflection")), "info"))
    mean, count = mean_ratio({k: v for k, v in now_runs.items() if k in base_runs}
                             if base_runs else now_runs)
    report.ratio_now, report.ratio_n = mean, count
    report.ratio_baseline = (base.get("ratio") or {}).get("mean")
    if mean is None:
        report.rows.append(Row("(all)", f"mean {RATIO_NAME}", report.ratio_baseline, None, None,
                               "FAIL" if report.ratio_baseline is not None else "info",
                               "no run with a test value"))
    else:
        inside = lo <= mean <= hi
        report.rows.append(Row("(all)", f"mean {RATIO_NAME} (n={count})", report.ratio_baseline,
                               mean, _relative(report.ratio_baseline, mean),
                               "ok" if inside else "FAIL", f"band [{lo:g}, {hi:g}]"
                               + ("" if inside else ": outside")))
    return report


def _curve_rows(name: str, base: dict, now: dict, tol: float) -> list[Row]:
    """One row per pre-peak deflection of the baseline: the load there against its band."""
    rows = []
    points = base.get("curve_deflections") or []
    loads, bands = base.get("curve_loads") or [], base.get("curve_bands") or []
    now_points = now.get("curve_deflections") or []
    now_loads = now.get("curve_loads") or []
    for k, x in enumerate(points):
        value = (now_loads[now_points.index(x)]
                 if x in now_points and now_points.index(x) < len(now_loads) else None)
        rows.append(_value_row(name, f"load@{x:g}mm", loads[k] if k < len(loads) else None,
                               value, tol, bands[k] if k < len(bands) else None))
    return rows


def _cell(value) -> str:
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        return f"{value:.5g}"
    return str(value)


def format_report(report: CompareReport) -> str:
    """Aligned table: run, quantity, baseline, now, change, verdict, note; then the verdict."""
    head = ("run", "quantity", "baseline", "now", "change", "verdict", "note")
    body = [(r.run, r.quantity, _cell(r.baseline), _cell(r.now),
             "-" if r.change is None else "inf" if math.isinf(r.change) else f"{r.change:+.1%}",
             r.verdict, r.note if len(r.note) <= 90 else r.note[:87] + "...")
            for r in report.rows]
    widths = [max(len(x) for x in col) for col in zip(head, *body, strict=True)]
    right = {2, 3, 4}

    def line(cells) -> str:
        return "  ".join(c.rjust(w) if i in right else c.ljust(w)
                         for i, (c, w) in enumerate(zip(cells, widths, strict=True))).rstrip()

    out = [line(head), line(["-" * w for w in widths]), *(line(c) for c in body)]
    n_fail = len(report.failures)
    residual = ("reported only" if report.residual_tol is None
                else f"{report.residual_tol:.0%}")
    out.append(f"tolerances: pre-peak loads {report.curve_tol:.1%}, peak {report.peak_tol:.1%}, "
               f"residual {residual} (relative, beyond the bands); mean {RATIO_NAME} band "
               f"[{report.ratio_band[0]:g}, "
               f"{report.ratio_band[1]:g}]")
    out.append("PASS" if not n_fail else f"FAIL: {n_fail} check(s) failed")
    return "\n".join(out)


# -- the command -------------------------------------------------------------------------------
def refuse_failing_baseline(records: Mapping[str, dict], new: dict, path) -> None:
    """ResultError (nothing written) unless the baseline `new`, made from `records`, passes
    against those same records: one that fails at once (the mean test/predicted ratio outside
    the band it records) describes nothing."""
    tol = new["tolerances"]
    report = compare(records, new, tol["peak"], tol["residual"], tuple(tol["ratio_band"]),
                     tol["curve"])
    if not report.passed:
        why = "; ".join(f"{r.run} {r.quantity}: {_cell(r.now)} ({r.note})"
                        for r in report.failures)
        raise ResultError(f"not writing {path}: it would fail against the results it is made "
                          f"from ({why}); give the band or tolerances that hold them "
                          "(--band LO HI, --peak-tol, --residual-tol)")


def compare_command(results_dir: str | os.PathLike, baseline_path: str | os.PathLike,
                    update: bool = False, peak_tol: float | None = None,
                    residual_tol: float | str | None = FROM_HEADER,
                    band: tuple[float, float] | None = None, command: str | None = None,
                    curve_tol: float | None = None,
                    echo: Callable[[str], None] | None = None,
                    realizations: Mapping[str, list[dict]] | None = None) -> int:
    """Body of `icewall compare RESULTS_DIR --baseline FILE [--update] [--peak-tol F]
    [--residual-tol F] [--band LO HI]`; returns the exit status (0: pass, 1: a check failed).

    A tolerance not given comes from the baseline's header, else the defaults (3 %, 10 %,
    0.93-1.07). `update` rewrites the baseline from the results (after printing the comparison
    with the old one where there is one) and returns 0; the header records `command`, the
    tolerances in force and the date. Missing or unreadable inputs raise ResultError (exit 2).
    """
    if echo is None:
        import click

        echo = click.echo
    records = measure_results(results_dir)
    if not records:
        raise ResultError(f"no result files (*.h5) in {results_dir}")
    old = None
    if update:  # refused before anything is read or written: a link, a file not a baseline
        check_replaceable(baseline_path, BASELINE)
    if not update or Path(baseline_path).exists():
        old = read_baseline(baseline_path)
    stated = (old or {}).get("tolerances") or {}
    peak_tol = float(peak_tol if peak_tol is not None else stated.get("peak", PEAK_TOL))
    curve_tol = float(curve_tol if curve_tol is not None else stated.get("curve", CURVE_TOL))
    if residual_tol == FROM_HEADER:  # the header's null: the residual is reported, not gated
        residual_tol = stated["residual"] if "residual" in stated else RESIDUAL_TOL
    residual_tol = None if residual_tol is None else float(residual_tol)
    band = tuple(band if band is not None else stated.get("ratio_band", RATIO_BAND))
    if not (peak_tol >= 0 and curve_tol >= 0 and (residual_tol is None or residual_tol >= 0)
            and band[0] <= band[1]):
        raise IcewallError("tolerances must be >= 0 and the band LO <= HI")
    status = 0
    if old is not None:
        report = compare(records, old, peak_tol, residual_tol, band, curve_tol)
        echo(format_report(report))
        status = 0 if report.passed else 1
    if update:
        if command is None:
            import shlex
            import sys

            command = "icewall " + " ".join(shlex.quote(a) for a in sys.argv[1:])
        new = make_baseline(records, command=command, peak_tol=peak_tol,
                            residual_tol=residual_tol, ratio_band=band, curve_tol=curve_tol,
                            realizations=realizations)
        refuse_failing_baseline(records, new, baseline_path)
        write_baseline(baseline_path, new)
        echo(f"baseline {baseline_path} written: {len(records)} run(s)")
        return 0
    return status
