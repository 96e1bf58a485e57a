"""Error estimates of a convergence study: against the finest run of a family, by Richardson
extrapolation, summed over families, the cheapest runs within an error (Pareto); the text
report.

A *row* is one run of one family (dict): ``family``, ``run``, ``h`` (the family's refinement
measure, smaller = finer), ``usable`` (completed: stopped or failed runs get no error, except
in the first maximum where ``usable_first_peak`` says the run stopped after it), ``cost``
(CPU s) and the quantities ``peak``, ``defl_peak``, ``first_peak`` (the largest load before
the curve first softens by 5 %, icewall.analysis.extract.first_maximum), ``defl_first_peak``,
``residual`` and ``curve`` ((d, P) arrays).
Errors are relative, signed for the scalars ((ours - reference) / |reference|); the curve
error is the RMS load difference over the common deflection range divided by the reference
peak. The deck's own setting (the *base* run) is a level of every family; the error of a run
against the finest run of every family is estimated as its own family's error plus the base
run's error in each other family (first order: the parameters are taken to act independently).
"""

from __future__ import annotations

import math

import numpy as np

SCALARS = ("peak", "defl_peak", "first_peak", "defl_first_peak", "residual")
QUANTITIES = ("peak", "first_peak", "residual", "curve")  # what the estimates and Pareto use
RICHARDSON_QUANTITIES = ("peak", "first_peak", "residual")
FIRST_PEAK_QUANTITIES = ("first_peak", "defl_first_peak")
ORDER_RANGE = (0.5, 5.0)  # a sensible observed order of convergence
MIN_RATIO = 1.2  # smallest refinement ratio h_coarse / h_fine between Richardson runs
THRESHOLDS = (0.10, 0.05, 0.02)
CURVE_POINTS = 801


def relative_error(value: float | None, reference: float | None) -> float | None:
    """(value - reference) / |reference|; None where either is missing or reference is 0."""
    if value is None or reference is None or reference == 0:
        return None
    return (value - reference) / abs(reference)


def curve_error(curve, reference) -> float | None:
    """RMS of P - P_ref over the common deflection range (piecewise linear curves sampled at
    CURVE_POINTS points), divided by |max P_ref|."""
    if curve is None or reference is None:
        return None
    (d, p), (dr, pr) = curve, reference
    lo, hi = max(d[0], dr[0]), min(d[-1], dr[-1])
    scale = float(np.max(np.abs(pr)))
    if hi <= lo or scale == 0:
        return None
    x = np.linspace(lo, hi, CURVE_POINTS)
    diff = np.interp(x, d, p) - np.interp(x, dr, pr)
    return float(np.sqrt(np.mean(diff**2)) / scale)


def _ratio_model(p: float, r21: float, r32: float) -> float:
    """(f3 - f2) / (f2 - f1) of f = f_ext + C h^p at h1, h2 = r21 h1, h3 = r32 h2."""
    return r21**p * (r32**p - 1.0) / (r21**p - 1.0)


def richardson(h, f) -> dict:
    """Richardson extrapolation from three runs (h ascending: f[0] is the finest), for
    unequal refinement ratios too (f = f_ext + C h^p; Celik et al. 2008). Returns
    {order, extrapolated, note}; order and extrapolated are None ("n/a") unless the ratios are
    at least MIN_RATIO, the convergence is monotone and the order lies in ORDER_RANGE."""
    from scipy.optimize import brentq

    na = {"order": None, "extrapolated": None}
    if len(h) != 3 or any(v is None for v in (*h, *f)):
        return {**na, "note": "n/a: needs three usable runs"}
    r21, r32 = h[1] / h[0], h[2] / h[1]
    if min(r21, r32) < MIN_RATIO:
        return {**na, "note": f"n/a: refinement ratio {min(r21, r32):.2f} < {MIN_RATIO}"}
    e21, e32 = f[1] - f[0], f[2] - f[1]
    if e21 == 0 or e32 == 0:
        return {**na, "note": "n/a: no change between two runs"}
    if e32 / e21 < 0:
        return {**na, "note": "n/a: oscillatory (not monotone)"}
    lo, hi = ORDER_RANGE
    target = math.log(e32 / e21)
    g_lo, g_hi = (math.log(_ratio_model(p, r21, r32)) - target for p in (lo, hi))
    if g_lo * g_hi > 0:
        side = f"< {lo}" if g_lo > 0 else f"> {hi}"
        return {**na, "note": f"n/a: observed order {side}"}
    p = brentq(lambda q: math.log(_ratio_model(q, r21, r32)) - target, lo, hi, xtol=1e-12)
    return {"order": p, "extrapolated": f[0] - e21 / (r21**p - 1.0), "note": ""}


def usable_for(row: dict, quantity: str) -> bool:
    """Whether `row` has `quantity`: a completed run has every one; a run that stopped after
    its curve fell 5 % below its first maximum (``usable_first_peak``) has the first maximum
    and its deflection too, whatever stopped it later."""
    if quantity in FIRST_PEAK_QUANTITIES:
        return bool(row.get("usable_first_peak", row["usable"]))
    return bool(row["usable"])


def _finest(members: list[dict], quantity: str) -> list[dict]:
    return sorted((r for r in members if usable_for(r, quantity) and r["h"] is not None),
                  key=lambda r: r["h"])


def family_errors(rows: list[dict]) -> dict:
    """Fill each row's errors against its family's finest usable run (``err_*``, ``reference``;
    for the first maximum, the finest run that has it: ``usable_for``) and its Richardson
    extrapolation (``rich_err_*``). Returns per family: {reference, first_peak_reference,
    finer_unusable (finer runs that did not complete: the reference is then not the finest
    level), richardson: {quantity: richardson dict with the runs used}}."""
    out = {}
    for family in dict.fromkeys(r["family"] for r in rows):
        members = [r for r in rows if r["family"] == family]
        usable = {q: _finest(members, q) for q in SCALARS}
        ref = usable["peak"][0] if usable["peak"] else None
        for row in members:
            row["reference"] = ref["run"] if ref else None
            for q in SCALARS:
                own = usable[q][0] if usable[q] else None
                row[f"err_{q}"] = (relative_error(row[q], own[q])
                                   if own is not None and usable_for(row, q) else None)
            ok = ref is not None and row["usable"]
            row["err_curve"] = curve_error(row["curve"], ref["curve"]) if ok else None
        finer = [r["run"] for r in members if not r["usable"] and
                 (ref is None or r["h"] is None or r["h"] < ref["h"])]
        first = usable["first_peak"][0]["run"] if usable["first_peak"] else None
        out[family] = {"reference": ref["run"] if ref else None, "finer_unusable": finer,
                       "first_peak_reference": first, "richardson": {}}
        for q in RICHARDSON_QUANTITIES:
            three = usable[q][:3]
            rich = richardson([r["h"] for r in three], [r[q] for r in three])
            out[family]["richardson"][q] = {**rich, "runs": [r["run"] for r in three]}
            for row in members:
                row[f"rich_err_{q}"] = (relative_error(row[q], rich["extrapolated"])
                                        if usable_for(row, q) else None)
    return out


def total_errors(rows: list[dict], base: str) -> None:
    """``total_err_<q>``: |own family error| + the base run's |error| in every other family
    (None where a family has no error of the base run)."""
    base_err = {(r["family"], q): r[f"err_{q}"] for r in rows if r["run"] == base
                for q in QUANTITIES}
    families = list(dict.fromkeys(r["family"] for r in rows))
    for row in rows:
        for q in QUANTITIES:
            parts = [row[f"err_{q}"]] + [base_err.get((f, q)) for f in families
                                         if f != row["family"]]
            row[f"total_err_{q}"] = (None if any(v is None for v in parts)
                                     else float(sum(abs(v) for v in parts)))


def pareto_front(points: list[tuple[float, float, str]]) -> list[tuple[float, float, str]]:
    """The (cost, error, name) points no other point beats in both cost and error, by cost."""
    front: list[tuple[float, float, str]] = []
    for point in sorted(points, key=lambda p: (p[0], p[1])):
        if not front or point[1] < front[-1][1]:
            front.append(point)
    return front


def cheapest_within(points: list[tuple[float, float, str]], threshold: float):
    """The cheapest (cost, error, name) point with error <= threshold (on the front), else
    None."""
    return next((p for p in pareto_front(points) if p[1] <= threshold), None)


def _error_of(values: dict, quantity: str) -> float | None:
    parts = [values.get(q) for q in (QUANTITIES if quantity == "all" else (quantity,))]
    return None if any(v is None for v in parts) else max(parts)


def measured_points(rows: list[dict], quantity: str) -> list[tuple[float, float, str]]:
    """(cost, total error, run) of every distinct usable run; quantity "all" takes the largest
    of the QUANTITIES' errors."""
    seen: dict[str, tuple[float, float, str]] = {}
    for row in rows:
        err = _error_of({q: row[f"total_err_{q}"] for q in QUANTITIES}, quantity)
        has = row["usable"] if quantity == "all" else usable_for(row, quantity)
        if has and row["cost"] is not None and err is not None:
            seen[row["run"]] = (float(row["cost"]), err, row["run"])
    return list(seen.values())


def pareto_rows(rows: list[dict]) -> list[dict]:
    """Per threshold and quantity (QUANTITIES and "all"): the cheapest measured run whose
    estimated error (``total_err_*``) is within the threshold."""
    out = []
    for quantity in (*QUANTITIES, "all"):
        points = measured_points(rows, quantity)
        for t in THRESHOLDS:
            best = cheapest_within(points, t)
            out.append({"threshold": t, "quantity": quantity, "run": best[2] if best else None,
                        "cost_s": best[0] if best else None,
                        "error": best[1] if best else None})
    return out


def format_report(rows: list[dict], families: dict, pareto: list[dict]) -> str:
    """Text report: the run table, each family's reference and Richardson estimates, the
    cheapest runs within each error."""
    def pct(v):
        return "-" if v is None else f"{100 * v:+.1f}%"

    out = [f"{'family':<13}{'value':>8}  {'status':<9}{'cpu_s':>7}{'iter':>6}{'peak':>10}"
           f"{'first_pk':>10}{'residual':>10}{'e_peak':>8}{'e_first':>8}{'e_res':>8}"
           f"{'e_curve':>8}{'test_pk':>8}{'test_res':>9}"]
    for r in rows:
        num = [f"{r[c]:.4g}" if r[c] is not None else "-"
               for c in ("peak", "first_peak", "residual")]
        out.append(f"{r['family']:<13}{r['value']:>8}  {r['status']:<9}"
                   f"{r['cost'] or 0:>7.1f}{r['iterations'] or 0:>6}{num[0]:>10}{num[1]:>10}"
                   f"{num[2]:>10}{pct(r['err_peak']):>8}{pct(r['err_first_peak']):>8}"
                   f"{pct(r['err_residual']):>8}"
                   f"{pct(r['err_curve']).lstrip('+'):>8}{pct(r['test_err_peak']):>8}"
                   f"{pct(r['test_err_residual']):>9}")
    out += [f"{r['run']}: {r['status']}: {r['stop_reason']}" for r in rows
            if r["status"] != "completed" and r["stop_reason"]]
    out.append("Reference (finest completed run) and Richardson extrapolation (its three "
               "finest completed runs) per family:")
    for name, f in families.items():
        note = f"; finer, not completed: {', '.join(f['finer_unusable'])}" \
            if f["finer_unusable"] else ""
        out.append(f"  {name:<13}reference {f['reference']}{note}")
        if f.get("first_peak_reference") not in (None, f["reference"]):
            out.append(f"  {'':<13}first maximum: reference {f['first_peak_reference']} "
                       "(stopped after it)")
        for q, r in f["richardson"].items():
            what = r["note"] or f"order {r['order']:.2f}, extrapolated {r['extrapolated']:.5g}"
            out.append(f"  {'':<13}{q:<11}{what}")
    out.append("Cheapest run within an error, estimated against the finest run of every family "
               "(CPU s, estimated error):")
    for p in pareto:
        got = (f"{p['run']} ({p['cost_s']:.1f} s, {100 * p['error']:.1f} %)" if p["run"]
               else "none")
        within = f"{100 * p['threshold']:.0f} %"
        out.append(f"  {within:<6}{p['quantity']:<10}{got}")
    return "\n".join(out)
