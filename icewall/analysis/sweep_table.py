"""The summary table of a sweep: one row per run, with test/predicted ratios.

A ratio is reference / ours (test/predicted, as in the thesis' Table 5.1), against the test and
against the thesis' FEA, for the ultimate (peak) load and the residual load at 40 mm, both as
icewall.analysis.extract defines them (`peaked` is "no" where the load had not dropped by the
end of the run: the peak is then a lower bound). A run that never peaked (still rising at its
end, or a linear-elastic run) gets no ratio and stays out of the mean and CoV: its largest load
is no prediction of the ultimate load, nor its load at 40 mm of the residual. Reference values
come from icewall.analysis.reference where it knows the specimen, else from the deck's
`specimen.reference`. Ductility per CSA S474 clause 8.4.4 (icewall.analysis.ductility): the
ratio mu reached, pass / fail / undecided, and the energy absorbed (area under the total jack
load - control deflection curve, N mm). Mechanism checks (issue 20 §1,
icewall.analysis.mechanism): the bottom (tension) plate's mean stress at the peak over f_y, at
midspan and its largest along the span; whether it had yielded by the peak and whether that
agrees with thesis 4.2.1 (CF walls); where the first crushing occurred; the residual mechanism
in a line (CSV only). Below the rows: the mean and the coefficient of
variation (sample standard deviation / mean) of each ratio column over the rows that have a value.
"""

from __future__ import annotations

import csv
import math
import os

import numpy as np

from icewall.analysis.ductility import result_ductility
from icewall.analysis.extract import extract
from icewall.analysis.mechanism import mechanism_check
from icewall.analysis.reference import find_reference
from icewall.analysis.summary import finite_figures
from icewall.deck.load import load_deck
from icewall.results.reader import open_result
from icewall.safe_write import csv_kind, open_for_write

RESIDUAL_AT = 40.0  # mm
RATIOS = {  # column -> (reference field, our measure)
    "ult_test/pred": ("ultimate_test", "peak"),
    "ult_thesis/pred": ("ultimate_thesis", "peak"),
    "res_test/pred": ("residual_test", "residual_40"),
    "res_thesis/pred": ("residual_thesis", "residual_40"),
}
DUCTILITY = ("ductility_ratio", "ductility", "energy_Nmm")  # CSA S474 8.4.4 (icewall.post)
MECHANISM = ("plate_mid/fy", "plate_max/fy", "plate_yield@peak", "vs_4.2.1", "first_crush",
             "residual_mechanism")
COLUMNS = ("name", "specimen", "overrides", "status", "peak", "peak_deflection", "peaked",
           "residual_40", "unit", "n_steps", "run_time_s", *RATIOS, *DUCTILITY, *MECHANISM,
           "reason")
_CSV_ONLY = ("reason", "residual_mechanism")
_HEADERS = {"peak_deflection": "defl@peak", "residual_40": "res@40mm", "run_time_s": "time_s",
            "n_steps": "steps", "ductility_ratio": "mu", "energy_Nmm": "energy_Nmm"}
_SCALE = {"N": 1.0, "kN": 1e3, "MN": 1e6, "MPa": 1.0, "N/mm2": 1.0}
TABLE = csv_kind("sweep table", COLUMNS)  # sweep_summary.csv and sweep_realizations.csv
TABLES = ("sweep_summary.csv", "sweep_realizations.csv")


def _measures(path: str) -> dict:
    """Peak load, its deflection and the residual load at 40 mm of one result file, as the
    shared extractor (icewall.analysis.extract) defines them."""
    with open_result(path) as res:
        attrs = res.attrs
        ductility = result_ductility(res) if attrs.get("n_steps") else {}
    fig = extract(path, residual_deflection=RESIDUAL_AT)
    return finite_figures({"specimen": attrs.get("specimen"), "status": attrs.get("status"),
            "reason": attrs.get("stop_reason", ""), "unit": attrs.get("load_unit"),
            "n_steps": attrs.get("n_steps"), "run_time_s": attrs.get("run_time_s"),
            "peak": fig.get("peak_load"), "peak_deflection": fig.get("deflection_at_peak"),
            "peaked": {True: "yes", False: "no"}.get(fig.get("peaked")),
            "residual_40": fig.get("residual_load_40"),
            "ductility_ratio": ductility.get("ductility_ratio"),
            "ductility": _verdict(ductility), "energy_Nmm": ductility.get("energy_Nmm"),
            **_mechanism(path)})  # an undefined figure (non-finite) is no figure


def _mechanism(path: str) -> dict:
    """The MECHANISM columns of one result (icewall.analysis.mechanism)."""
    try:
        check = mechanism_check(path)
    except Exception as exc:  # noqa: BLE001 - the row keeps its loads; the check says why
        return {"residual_mechanism": f"mechanism check failed: {exc}"}
    first = check.get("first_crushing")
    where = None
    if first is not None:
        span = (f"x {first['x_min']:.0f}-{first['x_max']:.0f}" if "x_min" in first
                else "")
        where = " ".join(filter(None, [first["region"], span, f"@{first['deflection']:.4g}mm"]))
    return {"plate_mid/fy": check.get("mid_over_fy"), "plate_max/fy": check.get("max_over_fy"),
            "plate_yield@peak": {True: "yes", False: "no"}.get(check.get("plate_yielded_at_peak")),
            "vs_4.2.1": check.get("plate_vs_thesis"),
            "first_crush": where, "residual_mechanism": check.get("residual_mechanism")}


def _verdict(ductility: dict) -> str | None:
    """pass / fail / undecided, with '>=' noted where the ratio reached is a lower bound."""
    verdict = ductility.get("verdict")
    if verdict and ductility.get("ratio_is_lower_bound") and verdict != "fail":
        return f"{verdict} (mu>=)"
    return verdict


def _references(job, specimen: str | None) -> tuple[dict, str | None]:
    """Reference values of a job's specimen and their unit (None: the deck's load unit)."""
    ref = find_reference(specimen) if specimen else None
    if ref is not None:
        return {k: getattr(ref, k) for k, _ in RATIOS.values()}, ref.unit
    try:
        ref = load_deck(job.deck, job.overrides).deck.specimen.reference
    except Exception:  # noqa: BLE001 - a broken deck has no reference values
        return {}, None
    return {k: getattr(ref, k) for k, _ in RATIOS.values()}, None


def _ratio(reference, ours, ref_unit, our_unit) -> float | None:
    if reference is None or ours is None or ours <= 0.0:
        return None
    if ref_unit and our_unit and ref_unit != our_unit:
        if ref_unit not in _SCALE or our_unit not in _SCALE or \
                (ref_unit == "MPa") != (our_unit == "MPa"):
            return None
        reference = reference * _SCALE[ref_unit] / _SCALE[our_unit]
    return float(reference) / ours


def build_rows(jobs, results: dict[str, dict]) -> list[dict]:
    """One row per job; `results[name]` is the run's result dict (or the skipped run's)."""
    rows = []
    for job in jobs:
        result = results.get(job.name, {})
        row = dict.fromkeys(COLUMNS)
        row.update(name=job.name, overrides=" ".join(job.varied), status=result.get("status"),
                   reason=result.get("reason"), run_time_s=result.get("run_time_s"),
                   n_steps=result.get("n_steps"))
        path = result.get("path") or job.output
        if os.path.exists(path):
            try:
                measures = _measures(path)
            except Exception as exc:  # noqa: BLE001 - named in the row, never a figure
                measures = {"reason": f"unreadable result: {exc}"}
                row["status"] = "unreadable"
            row.update({k: v for k, v in measures.items() if row.get(k) is None})
        refs, ref_unit = _references(job, row["specimen"])
        for column, (field, measure) in RATIOS.items():  # a ratio needs a peak (module doc)
            row[column] = (_ratio(refs.get(field), row[measure], ref_unit, row["unit"])
                           if row["peaked"] == "yes" else None)
        rows.append(row)
    return rows


def ratio_stats(rows: list[dict]) -> dict[str, tuple[float | None, float | None, int]]:
    """Per ratio column: (mean, coefficient of variation, number of rows with a value)."""
    stats = {}
    for column in RATIOS:
        values = np.array([r[column] for r in rows if r[column] is not None], dtype=float)
        mean = float(values.mean()) if len(values) else None
        cov = float(values.std(ddof=1) / mean) if len(values) > 1 and mean else None
        stats[column] = (mean, cov, len(values))
    return stats


def _text(value, column: str) -> str:
    if value is None and column not in RATIOS:
        return ""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    if isinstance(value, float):
        return (f"{value:.3f}" if column in RATIOS or column == "run_time_s" else
                f"{value:.2f}" if column in ("ductility_ratio", *MECHANISM[:2]) else
                f"{value:.5g}")
    return str(value)


def _stat_rows(stats) -> list[dict]:
    mean = {"name": "mean", **{c: s[0] for c, s in stats.items()}}
    cov = {"name": "cov", **{c: s[1] for c, s in stats.items()}}
    return [mean, cov]


def write_csv(path: str | os.PathLike, rows: list[dict], stats,
              columns: tuple[str, ...] = COLUMNS) -> None:
    """Rows, then a `mean` and a `cov` row (ratio columns only); empty cells for no value.
    Written through icewall.safe_write: never through a link, never over another file."""
    with open_for_write(path, TABLE) as f:
        writer = csv.DictWriter(f, fieldnames=columns)
        writer.writeheader()
        for row in rows + _stat_rows(stats):
            writer.writerow({c: "" if row.get(c) is None else row.get(c) for c in columns})


def format_table(rows: list[dict], stats) -> str:
    """Aligned text table (without the reason column; failures are listed under it)."""
    columns = [c for c in COLUMNS if c not in _CSV_ONLY]
    body = [[_text(r.get(c), c) or ("-" if r in rows else "") for c in columns]
            for r in rows + _stat_rows(stats)]
    head = [_HEADERS.get(c, c) for c in columns]
    widths = [max(len(x) for x in col) for col in zip(head, *body, strict=True)]
    numeric = {"peak", "peak_deflection", "residual_40", "n_steps", "run_time_s", *RATIOS,
               "ductility_ratio", "energy_Nmm", *MECHANISM[:2]}

    def line(cells):
        return "  ".join(x.rjust(w) if c in numeric else x.ljust(w)
                         for x, w, c in zip(cells, widths, columns, strict=True)).rstrip()

    out = [line(head), line(["-" * w for w in widths])]
    out += [line(cells) for cells in body[:len(rows)]]
    out += [line(["-" * w for w in widths])] + [line(cells) for cells in body[len(rows):]]
    out += [f"{r['name']}: {r['status']}: {r['reason']}" for r in rows
            if r.get("status") != "completed" and r.get("reason")]
    return "\n".join(out)


# -- round-off realizations (icewall sweep --realizations K) -----------------------------------
BAND_COLUMNS = ("name", "specimen", "realizations", "statuses", "peak", "peak_min", "peak_max",
                "residual_40", "residual_40_min", "residual_40_max", "unit", *RATIOS)


def band_rows(rows: list[dict], base_name) -> list[dict]:
    """One row per run over its round-off realizations (`base_name(name)` groups them): the
    statuses they ended with, the median and the [min, max] of the peak and of the residual at
    40 mm (over those with a value), and each test/predicted ratio as the median over them."""
    groups: dict[str, list[dict]] = {}
    for row in rows:
        groups.setdefault(base_name(row["name"]), []).append(row)
    out = []
    for name, group in groups.items():
        counts: dict[str, int] = {}
        for r in group:
            counts[str(r.get("status"))] = counts.get(str(r.get("status")), 0) + 1
        band = {"name": name, "specimen": group[0].get("specimen"), "unit": group[0].get("unit"),
                "realizations": len(group),
                "statuses": ", ".join(f"{n} {s}" for s, n in sorted(counts.items()))}
        for key in ("peak", "residual_40", *RATIOS):
            values = [float(r[key]) for r in group if r.get(key) is not None]
            band[key] = float(np.median(values)) if values else None
            if key in ("peak", "residual_40"):
                band[f"{key}_min"] = min(values) if values else None
                band[f"{key}_max"] = max(values) if values else None
        out.append(band)
    return out


def format_bands(bands: list[dict], stats) -> str:
    """Text table: per run the median [min-max] of the peak and of the residual at 40 mm over
    its realizations, the statuses, and the median ratios with their mean and CoV."""
    def span(row, key) -> str:
        if row.get(key) is None:
            return "-"
        return (f"{row[key]:.4g} [{row[f'{key}_min']:.4g}-{row[f'{key}_max']:.4g}]")

    head = ["run", "specimen", "statuses", "peak [band]", "res@40mm [band]", "unit",
            *RATIOS]
    body = [[b["name"], str(b.get("specimen") or "-"), b["statuses"], span(b, "peak"),
             span(b, "residual_40"), str(b.get("unit") or "-"),
             *(_text(b.get(c), c) for c in RATIOS)] for b in bands]
    body += [[s["name"], "", "", "", "", "", *(_text(s.get(c), c) for c in RATIOS)]
             for s in _stat_rows(stats)]
    widths = [max(len(x) for x in col) for col in zip(head, *body, strict=True)]

    def line(cells) -> str:
        return "  ".join(x.ljust(w) for x, w in zip(cells, widths, strict=True)).rstrip()

    title = (f"over {max(b['realizations'] for b in bands)} round-off realizations per run "
             "(median [min-max]; ratios: median, then their mean and CoV)")
    return "\n".join([title, line(head), line(["-" * w for w in widths]),
                      *(line(c) for c in body)])
