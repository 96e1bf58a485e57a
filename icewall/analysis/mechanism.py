"""Mechanism checks of one run (issue 20 §1): what a reading must be held to.

* **Tension plate at the peak against f_y.** The plate checked is ``bottom_plate``: the plate
  opposite the loaded face, in flexural tension at midspan. Thesis 5.3 calls this the "bottom
  steel plate" that "had yielded significantly" in the CF-8 analysis, 5.5 gives it the "tensile
  loads" of the strut-and-tie model, and 4.3.2 loads the model "on the top steel plate"; 4.2.1's
  "before the bottom steel plate yielded" is read the same way (decks/README.md, "CF loading
  stations"). Its stress is sigma_xx averaged over the plate thickness (Gauss weights x
  |det J|, as icewall.post.plate_stresses) at each Gauss station along the span: at the station
  nearest midspan and the largest along the span (with its x). Compared with the deck's f_y
  (after ``fy_reduction``); in plane strain the plate's sigma_xx at first yield is about
  1.12 f_y (sigma_zz = nu sigma_xx), so a ratio >= 1 is a mean stress at or past f_y, not
  necessarily plastic flow.
* **Whether the tension plate yielded by the peak**: a section of it yielded through its whole
  thickness (every Gauss point at one station along x, ``tension_plate_sections_yielded``; the
  plate as a tension chord, not one face bent locally at a diaphragm, which
  ``tension_plate_yielded``, the count of its yielded points, also catches), next to what the
  thesis says of the wall: 4.2.1, "The ultimate
  load for all walls except Specimen CF-8 was reached before the bottom steel plate yielded"
  (and 5.3 for CF-8's analysis: the bottom plate "had yielded significantly").
* **Where the first crushing occurs**: the crushed (compressive softening) Gauss points at the
  first step with any: their x range, mean y and the region holding most of them.
* **Residual mechanism**: the same at the last step (or at 40 mm), with the load as a fraction
  of the peak, in one line.

The figures come from history columns that every nonlinear run records
(icewall.results.probe.MechanismProbe, called by icewall.pipeline at each step), so the check
works with ``outputs.fields=[]`` (``make validate``). For result files written before those
columns existed, the plate stress falls back to the stored ``stress`` field at the peak step
(exactly that step: fields stored only every k steps give no plate figure) and the crushing to
icewall.analysis.extract's ``concrete_flags`` location; without either the entries are None
and ``source`` says why.
"""

from __future__ import annotations

import os

import numpy as np

from icewall.analysis.extract import control_curve, extract
from icewall.results.probe import (
    PLATE_COLUMNS,
    SECTION_COLUMN,
    SECTION_X_COLUMN,
    TENSION_PLATE,
    YIELD_COLUMN,
    MechanismProbe,
)
from icewall.results.reader import open_result

RESIDUAL_DEFLECTION = 40.0  # mm


def thesis_plate_statement(specimen: str | None) -> bool | None:
    """Whether the thesis says the wall's bottom plate had yielded by the ultimate: 4.2.1 for
    the CF series (all walls but CF-8 had not); None where the text says nothing."""
    name = (specimen or "").upper().replace(" ", "")
    if not name.startswith("CF-"):
        return None
    return name == "CF-8"


# -- the check of a result file -----------------------------------------------------------------
def _yield_stress(result) -> float | None:
    """f_y of the plates from the stored deck (None where it no longer loads: the reader's
    rule, results.reader.ResultFile.stored_deck)."""
    loaded = result.stored_deck()
    if loaded is None:
        return None
    steel = loaded.deck.materials.steel
    return steel.fy * (1.0 - steel.fy_reduction)


def _plate_from_field(result, step: int) -> dict:
    if step not in result.steps or "stress" not in result.gauss_fields(step):
        return {}
    stress = result.gauss(step, "stress")
    order = int(result.attrs.get("gauss_order") or round(np.sqrt(stress.shape[1])))
    return MechanismProbe(result.mesh, order).plate_stress(stress)


def _value(hist: dict, column: str, i: int) -> float | None:
    if column not in hist:
        return None
    v = float(hist[column][i])
    return None if np.isnan(v) or (column == "crushed_region" and v < 0) else v


def _crush_at(hist: dict, i: int | None, names: dict[int, str]) -> dict | None:
    if i is None or _value(hist, "crushed_x_min", i) is None:
        return None
    return {"step": int(hist["step"][i]), "deflection": float(hist["control_displacement"][i]),
            "x_min": _value(hist, "crushed_x_min", i), "x_max": _value(hist, "crushed_x_max", i),
            "y_mean": _value(hist, "crushed_y_mean", i),
            "region": names.get(int(hist["crushed_region"][i]), "?")}


def _plate_at(hist: dict, i: int) -> dict:
    return {c: _value(hist, c, i) for c in PLATE_COLUMNS if _value(hist, c, i) is not None}


def _peak_plate(result, hist: dict, i_peak: int, peak_step: int) -> tuple[dict, str]:
    """Plate stresses at the peak from the history, else from the stress field; and whence."""
    plate = _plate_at(hist, i_peak)
    if plate:
        return plate, "history"
    plate = _plate_from_field(result, peak_step)
    if plate:
        return plate, f"stress field at step {peak_step}"
    return {}, ("no plate stress: neither the history columns nor the stress field at the peak "
                "step (run with outputs.fields including stress)")


def _first_crush_row(hist: dict, rows: np.ndarray) -> int | None:
    if "crushed_x_min" not in hist:
        return None
    hit = np.flatnonzero(np.isfinite(np.asarray(hist["crushed_x_min"], float)[rows]))
    return int(rows[hit[0]]) if hit.size else None


def mechanism_check(path: str | os.PathLike) -> dict:
    """The §1 checks of one result file (module docstring), as a JSON-ready dict."""
    with open_result(path) as r:
        hist, f_y, specimen = r.history, _yield_stress(r), r.attrs.get("specimen")
        names = {reg.tag: reg.name for reg in r.mesh.regions}
        control = np.ones(len(hist["step"]), bool)
        if "preload_stage" in hist:
            control = np.asarray(hist["preload_stage"]) != 1
        out: dict = {"plate": TENSION_PLATE, "f_y": f_y, "source": None, "peak_step": None}
        if not control.any():
            return out
        d, p, _ = control_curve(hist)
        rows = np.flatnonzero(control)
        i_peak = int(rows[int(np.argmax(p))])
        peak_step = int(hist["step"][i_peak])
        out.update(peak_step=peak_step, peak_deflection=float(d[int(np.argmax(p))]))
        plate, out["source"] = _peak_plate(r, hist, i_peak, peak_step)
        first = _crush_at(hist, _first_crush_row(hist, rows), names)
        end = _end_row(d, rows)
        residual = _crush_at(hist, end, names)
        end_plate = _plate_at(hist, end)
        load_end, peak = float(hist["load"][end]), float(np.max(p))
    out.update(_ratios(plate, f_y))
    out["plate_reached_fy_before_peak"] = _reached_fy(hist, rows, i_peak, f_y)
    out.update(_plate_yield(hist, rows, i_peak, specimen))
    if first is None and "crushed_x_min" not in hist:
        first = _crush_from_fields(path)
    out["first_crushing"] = first
    if first is not None and "x_min" in first:
        out["first_crushing"]["relative_to_peak"] = (
            "before_peak" if first["step"] < peak_step else
            "at_peak" if first["step"] == peak_step else "after_peak")
    out["residual"] = {"deflection": float(hist["control_displacement"][end]),
                       "load_over_peak": load_end / peak if peak > 0 else None,
                       "crushing": residual, **_ratios(end_plate, f_y)}
    out["residual_mechanism"] = residual_line(out["residual"])
    return out


def _crush_from_fields(path) -> dict | None:
    """First crushing of a file without the history columns: icewall.analysis.extract's
    event, with its element centroid where concrete_flags was stored."""
    event = extract(path).get("first_crushing")
    if event is None:
        return None
    where = event.get("location") or {}
    return {"step": event["step"], "deflection": event["deflection"],
            "relative_to_peak": event["relative_to_peak"], "region": where.get("region", "?"),
            "x": where.get("x"), "y": where.get("y"),
            "source": "crushed count; element centroid from concrete_flags" if where else
            "crushed count only (no location stored)"}


def _end_row(d: np.ndarray, rows: np.ndarray) -> int:
    """History row at 40 mm (the first step at or past it), else the last control step."""
    hit = np.flatnonzero(d >= RESIDUAL_DEFLECTION - 1e-9)
    return int(rows[hit[0]] if hit.size else rows[-1])


def _ratios(plate: dict, f_y: float | None) -> dict:
    out: dict = {"stress_mid": plate.get("tension_plate_stress_mid"),
                 "stress_max": plate.get("tension_plate_stress_max"),
                 "stress_max_x": plate.get("tension_plate_stress_max_x")}
    for key in ("mid", "max"):
        s = out[f"stress_{key}"]
        out[f"{key}_over_fy"] = s / f_y if s is not None and f_y else None
    return out


def _reached_fy(hist: dict, rows: np.ndarray, i_peak: int, f_y: float | None) -> bool | None:
    """Whether the plate's mean stress reached f_y anywhere along the span at or before the
    peak (history columns only; None without them)."""
    if "tension_plate_stress_max" not in hist or not f_y:
        return None
    s = np.asarray(hist["tension_plate_stress_max"], float)[rows[rows <= i_peak]]
    return bool(np.nanmax(s) >= f_y) if np.isfinite(s).any() else None


def _plate_yield(hist: dict, rows: np.ndarray, i_peak: int, specimen: str | None) -> dict:
    """Whether a section of the tension plate had yielded through its thickness at the peak
    step, its first such yield (and the first yield of any point), and the thesis' statement
    (thesis_plate_statement) with agreement; None without the columns."""
    thesis = thesis_plate_statement(specimen)
    out: dict = {"plate_yielded_at_peak": None, "plate_first_yield": None,
                 "plate_first_point_yield": None,
                 "thesis_plate_yielded": thesis, "plate_vs_thesis": None}
    if SECTION_COLUMN not in hist:
        return out
    at_peak = bool(np.asarray(hist[SECTION_COLUMN])[i_peak] > 0)
    out["plate_yielded_at_peak"] = at_peak
    for key, column in (("plate_first_yield", SECTION_COLUMN),
                        ("plate_first_point_yield", YIELD_COLUMN)):
        hit = np.flatnonzero(np.asarray(hist[column])[rows] > 0)
        if hit.size:
            i = int(rows[hit[0]])
            out[key] = {"step": int(hist["step"][i]),
                        "deflection": float(hist["control_displacement"][i])}
            if key == "plate_first_yield":
                out[key]["x"] = _value(hist, SECTION_X_COLUMN, i)
    if thesis is not None:
        out["plate_vs_thesis"] = "agrees" if at_peak == thesis else "contradicts"
    return out


def residual_line(residual: dict) -> str:
    """One line: where the crushed points lie at the end, the plate, the load left."""
    parts = [f"at {residual['deflection']:.4g} mm"]
    c = residual.get("crushing")
    if c is not None:
        parts.append(f"crushed x {c['x_min']:.0f}-{c['x_max']:.0f} mm (mostly {c['region']}, "
                     f"mean y {c['y_mean']:.0f})")
    else:
        parts.append("no crushing recorded")
    if residual.get("mid_over_fy") is not None:
        parts.append(f"bottom plate {residual['mid_over_fy']:.2f} f_y at midspan, "
                     f"{residual['max_over_fy']:.2f} f_y max at x {residual['stress_max_x']:.0f}")
    if residual.get("load_over_peak") is not None:
        parts.append(f"load {residual['load_over_peak']:.0%} of the peak")
    return "; ".join(parts)


def format_mechanism(check: dict) -> list[tuple[str, str]]:
    """(label, text) lines for icewall summary."""
    def ratio(key: str) -> str:
        v = check.get(key)
        return "-" if v is None else f"{v:.2f}"

    lines = []
    if check.get("stress_mid") is not None:
        lines.append(("bottom plate at peak", (
            f"{check['stress_mid']:.4g} MPa = {ratio('mid_over_fy')} f_y at midspan, max "
            f"{check['stress_max']:.4g} MPa = {ratio('max_over_fy')} f_y at x "
            f"{check['stress_max_x']:.0f} mm ({_f_y(check)}; {check['source']})")))
    else:
        lines.append(("bottom plate at peak", str(check.get("source") or "-")))
    lines.append(("bottom plate yielded", _yield_text(check)))
    lines.append(("first crushing", _first_crushing_text(check.get("first_crushing"))))
    lines.append(("residual mechanism", check.get("residual_mechanism") or "-"))
    return lines


def _f_y(check: dict) -> str:
    f_y = check.get("f_y")
    return "f_y unknown: the stored deck does not load" if f_y is None else f"f_y {f_y:.4g}"


def _first_crushing_text(first: dict | None) -> str:
    if first is None:
        return "-"
    head = f"step {first['step']} ({first['deflection']:.4g} mm, {first['relative_to_peak']})"
    if "x_min" not in first:  # an old file: extract's event
        return f"{head}: {first['region']} ({first['source']})"
    return (f"{head}: x {first['x_min']:.0f}-{first['x_max']:.0f} mm, mostly {first['region']}, "
            f"mean y {first['y_mean']:.0f}")


def _yield_text(check: dict) -> str:
    at_peak = check.get("plate_yielded_at_peak")
    if at_peak is None:
        return f"- (no {SECTION_COLUMN} history column)"
    first = check.get("plate_first_yield")
    where = (f"first at step {first['step']}, {first['deflection']:.4g} mm, x {first['x']:.0f}"
             if first else "")
    text = "through the thickness " + (f"by the peak ({where})" if at_peak else
                                       "not by the peak" + (f" ({where})" if first else
                                                            ", nor later"))
    point = check.get("plate_first_point_yield")
    if point is not None:
        text += f"; first yielded point at step {point['step']}"
    thesis = check.get("thesis_plate_yielded")
    if thesis is not None:
        text += (f"; thesis 4.2.1: {'yielded' if thesis else 'not yielded'} at the ultimate: "
                 f"{check['plate_vs_thesis']}")
    return text
