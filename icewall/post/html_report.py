"""One self-contained HTML validation page for a set of results: the validation table (peak and
residual against the tests, CSA S474 ductility), the curves against the tests per specimen and
the crack patterns at the peak and at 40 mm. Figures are embedded as base64 PNG."""

from __future__ import annotations

import base64
import html
import io
from datetime import datetime
from pathlib import Path

from icewall import __version__
from icewall.analysis.ductility import result_ductility
from icewall.analysis.extract import extract
from icewall.analysis.reference import ratio_stats
from icewall.analysis.summary import LINEAR_NOTE, finite_figures, solver_label
from icewall.errors import ResultError
from icewall.post.common import step_at
from icewall.post.curves import plot_curves, reference_loads
from icewall.post.figures import pyplot
from icewall.post.patterns import plot_cracks
from icewall.results.reader import open_result
from icewall.safe_write import MARK, REPORT, write_text

RESIDUAL_AT = 40.0  # mm
PATTERNS_AT = ("peak", RESIDUAL_AT)
CSS = """body{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}
table{border-collapse:collapse;font-size:14px}td,th{border:1px solid #bbb;padding:3px 7px}
td.num{text-align:right}tr.stat td{font-style:italic;background:#f4f4f4}
.pass{color:#060}.fail{color:#b00}.undecided{color:#a60}img{max-width:100%}
figure{margin:1em 0}figcaption{font-size:13px;color:#555}"""
COLUMNS = (("name", "run"), ("specimen", "specimen"), ("solver", "solver"), ("status", "status"),
           ("peak", "peak"), ("ultimate_test", "test peak"), ("ult_ratio", "test/pred peak"),
           ("residual_40", "load at 40 mm"), ("residual_test", "test residual"),
           ("res_ratio", "test/pred residual"), ("mu", "ductility ratio"),
           ("verdict", "CSA S474 8.4.4"), ("energy_Nmm", "energy (N mm)"))


def run_name(path: str | Path) -> str:
    return Path(path).name.removesuffix(".partial").removesuffix(".h5")


def validation_row(path: str | Path) -> dict:
    """One table row: peak and load at 40 mm (icewall.analysis.extract), the test values, the
    test/predicted ratios, and the clause 8.4.4 ductility check."""
    with open_result(path) as r:
        attrs, stored = dict(r.attrs), r.stored_deck()
        linear = attrs.get("solver") == "linear"
        ductility = ({"verdict": None, "message": f"not assessed: {LINEAR_NOTE}"} if linear
                     else result_ductility(r))
    fig = extract(str(path), residual_deflection=RESIDUAL_AT)
    ref = reference_loads(attrs, stored)
    row = {"name": run_name(path), "specimen": attrs.get("specimen"),
           "solver": solver_label(attrs.get("solver")),
           "status": attrs.get("status"), "unit": attrs.get("load_unit") or "",
           "peak": fig.get("peak_load"), "residual_40": fig.get("residual_load_40"),
           "ultimate_test": ref.get("ultimate_test"), "residual_test": ref.get("residual_test"),
           "mu": ductility.get("ductility_ratio"), "verdict": ductility.get("verdict"),
           "energy_Nmm": ductility.get("energy_Nmm"), "ductility": ductility}
    for key, test, ours in (("ult_ratio", "ultimate_test", "peak"),
                            ("res_ratio", "residual_test", "residual_40")):
        # a ratio needs a nonlinear run that peaked (icewall.analysis.sweep_table)
        usable = not linear and fig.get("peaked") and row[test] is not None and row[ours]
        row[key] = row[test] / row[ours] if usable else None
    return finite_figures(row)  # an undefined figure (non-finite) is no figure


def _cell(row: dict, key: str) -> str:
    value = row.get(key)
    if value is None:
        return "<td>-</td>"
    if key == "verdict":
        return f'<td class="{html.escape(value)}">{html.escape(value)}</td>'
    if isinstance(value, float):
        text = f"{value:.3f}" if key.endswith("ratio") else f"{value:.4g}"
        if key == "mu" and row["ductility"].get("ratio_is_lower_bound"):
            text = "&ge; " + text
        if key in ("peak", "residual_40", "ultimate_test", "residual_test"):
            text += f" {html.escape(row['unit'])}"
        return f'<td class="num">{text}</td>'
    return f"<td>{html.escape(str(value))}</td>"


def table_html(rows: list[dict]) -> str:
    """The validation table with a mean and a CoV row of the ratios."""
    head = "".join(f"<th>{html.escape(label)}</th>" for _, label in COLUMNS)
    body = [f'<tr class="run">{"".join(_cell(r, k) for k, _ in COLUMNS)}</tr>' for r in rows]
    stats = {k: ratio_stats(r[k] for r in rows) for k in ("ult_ratio", "res_ratio")}
    for s in stats.values():
        s["cov"] = s["cov"] if s["n"] > 1 else None  # no spread from one value
    for what in ("mean", "cov"):
        cells = [f"<td>{what}</td>"] + [
            f'<td class="num">{stats[k][what]:.3f}</td>' if k in stats and stats[k][what]
            is not None else "<td></td>" for k, _ in COLUMNS[1:]]
        body.append(f'<tr class="stat">{"".join(cells)}</tr>')
    return f'<table id="validation"><tr>{head}</tr>\n' + "\n".join(body) + "</table>"


def png_tag(fig, alt: str) -> str:
    """The figure as an <img> with an embedded base64 PNG (the figure is closed)."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=100, bbox_inches="tight")
    pyplot().close(fig)
    data = base64.b64encode(buffer.getvalue()).decode("ascii")
    return f'<img alt="{html.escape(alt)}" src="data:image/png;base64,{data}">'


def _figure(tag: str, caption: str) -> str:
    return f"<figure>{tag}<figcaption>{html.escape(caption)}</figcaption></figure>"


def _patterns(path: str | Path) -> list[str]:
    parts = []
    with open_result(path) as r:
        for at in PATTERNS_AT:
            label = "the peak" if at == "peak" else f"{at:g} mm"
            try:
                step = step_at(r, at)
                parts.append(_figure(png_tag(plot_cracks(r, step), f"cracks at {label}"),
                                     f"{run_name(path)}: cracks and crushing at {label}"))
            except ResultError as exc:
                parts.append(f'<p class="note">{run_name(path)}: no crack pattern at {label}: '
                             f"{html.escape(str(exc))}</p>")
    return parts


def _ductility_html(rows: list[dict]) -> str:
    items = []
    for r in rows:
        d = r["ductility"]
        detail = ""
        if d.get("yield_load") is not None:
            detail = (f" (P_y = {d['yield_load']:.4g} {r['unit']}, K0 = "
                      f"{d['initial_stiffness']:.4g} {r['unit']}/mm, d_y = "
                      f"{d['yield_deflection']:.3g} mm)")
        verdict = d.get("verdict") or "not assessed"
        items.append(f'<li><b>{html.escape(r["name"])}</b>: <span class="{verdict}">'
                     f'{verdict}</span>: {html.escape(d["message"] + detail)}</li>')
    return "<ul>" + "".join(items) + "</ul>"


def build_report(paths: list[str | Path], out: str | Path, title: str | None = None) -> Path:
    """Write the HTML page for the result files `paths` to `out`; returns `out`."""
    if not paths:
        raise ResultError("no result files given for the report")
    rows = [validation_row(p) for p in paths]
    title = title or f"icewall validation report ({len(rows)} runs)"
    parts = [f"<h1>{html.escape(title)}</h1>",
             f"<p>icewall {__version__}, {datetime.now().astimezone():%Y-%m-%d %H:%M %Z}. "
             "Loads in each run's load measure; ratios are test / predicted; the residual is "
             f"the load at {RESIDUAL_AT:g} mm deflection; ductility per CSA S474 clause 8.4.4 "
             "(six times the yield deflection at 50 % of the yield load). A run gets a ratio "
             f"only if it peaked; a linear-solver result is {LINEAR_NOTE}.</p>",
             "<h2>Validation table</h2>", table_html(rows),
             "<h2>Ductility (CSA S474, 8.4.4)</h2>", _ductility_html(rows),
             "<h2>Load-deflection curves against the tests</h2>"]
    by_specimen: dict[str, list] = {}
    for p, row in zip(paths, rows, strict=True):
        by_specimen.setdefault(row["specimen"] or row["name"], []).append(p)
    for specimen, group in by_specimen.items():
        tag = png_tag(plot_curves(group), f"{specimen} load-deflection")
        parts.append(_figure(tag, f"{specimen}: load-deflection, test peak and residual"))
    parts.append("<h2>Crack patterns at the peak and at 40 mm</h2>")
    for p in paths:
        parts += _patterns(p)
    page = (f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
            f'<meta name="generator" content="{MARK}">'
            f"<title>{html.escape(title)}</title><style>{CSS}</style></head><body>\n"
            + "\n".join(parts) + "\n</body></html>\n")
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    write_text(out, page, REPORT)  # never through a link, never over another file
    return out
