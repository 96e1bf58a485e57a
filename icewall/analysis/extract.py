"""Key figures of one load-deflection analysis: the extractor used everywhere (issue 5 §2).

Definitions (deflection d = the control displacement, mm; load P in the run's load measure):

* Curve: the displacement-control steps (history ``preload_stage != 1``), preceded by the start
  point (d0, 0), d0 = the control displacement at the end of any in-plane preload (else 0).
  Deflections are the recorded control displacements, preload part included (the solver's
  target is on that same scale).
* Peak: the largest load of the curve, its deflection and step (the first step if tied).
  ``peaked`` is False when the largest load is the last step: the run ended before any drop, so
  the peak is only a lower bound.
* First peak: the largest load before the curve first falls FIRST_PEAK_SOFTENING (5 %) below
  its running maximum (``first_peak_load``, ``deflection_at_first_peak``): the ultimate of a
  curve with several humps, whose later humps depend on the path after a drop (docs/solver.md
  item 29); the peak itself where the curve never softens that much. ``first_peak_settled``:
  the curve does fall that far after it (a run stopped later still has this figure).
* ``residual_load_40``: P at d = 40 mm, linearly interpolated between the bracketing steps
  (specimens.md: the load at the end of the analysed range); None if the run stopped short.
* ``residual_plateau``: the deflection-weighted mean load (trapezoidal integral / length) over
  the window [max(d_peak + 10, 20), 40] mm. The thesis' residual is "the load level reached
  after the post-peak drop"; 10 mm past the peak skips the drop (CF-4: peak at ~10 mm, plateau
  from ~20 mm), the 20 mm floor keeps an early peak's drop out, and weighting by deflection makes
  it independent of the step size. None if the run stopped short of 40 mm or the window is
  empty (peak beyond 30 mm).
* ``initial_stiffness``: secant from the start point to where the curve first reaches 30 % of
  the peak load (interpolated along the curve; with a coarse first step this is that step's
  secant). ``first_step_stiffness``: secant of the first control step. Load unit per mm.
* Failure sequence (history counts of Gauss points): first step with ``cracked_in_plane > 0``,
  ``crushed > 0`` (compressive softening: where softening started), ``yielded > 0`` (any steel),
  each with step, deflection, load, stage (preload | control) and position relative to the peak.
  Where the Gauss field ``concrete_flags`` is stored, ``first_crushing`` also names the region
  and element centroid (x, y) with the most crushed points at its first stored crushed step.
* Tension (bottom) plate: from the Gauss field ``equivalent_plastic_strain`` of the
  ``bottom_plate`` cells at the stored steps (first step with eps_p > 0); without that field
  from the history column ``tension_plate_yielded`` (the bottom plate's yielded Gauss points,
  every step: icewall.analysis.mechanism), else from the ``yielded`` count, which counts every
  steel region (plates and diaphragms); ``tension_plate_yield.source`` says which.
  ``tension_plate_yielded``: "before_peak" (at or before the peak step), "after_peak",
  "undetermined" (fields not stored densely enough to tell) or "no" (not within the run); None
  without any yield information.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence

import numpy as np

from icewall.results.probe import TENSION_PLATE
from icewall.results.reader import open_result

RESIDUAL_DEFLECTION = 40.0  # mm
PLATEAU_OFFSET = 10.0  # mm past the peak
PLATEAU_START_MIN = 20.0  # mm
STIFFNESS_FRACTION = 0.30
FIRST_PEAK_SOFTENING = 0.05  # fraction of the running maximum the curve falls by after it
_EPS = 1e-9


def control_curve(history: dict) -> tuple[np.ndarray, np.ndarray, float]:
    """(deflection, load, origin) of the displacement-control steps (after any preload)."""
    d = np.asarray(history["control_displacement"], float)
    p = np.asarray(history["load"], float)
    control = np.ones(d.size, bool)
    if "preload_stage" in history:
        control = np.asarray(history["preload_stage"]) != 1
    origin = float(d[~control][-1]) if (~control).any() else 0.0
    return d[control], p[control], origin


def stroke_curve(d: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The curve a stroke-controlled test records of a traced path: the points where the
    control deflection reaches a new maximum. Where the traced path snaps back (the deflection
    turns back while the load falls, under dissipation control), the machine holds the stroke
    and the load drops vertically to where the path comes back to that deflection; the loop
    itself is never recorded. A path whose deflection never turns back is returned as it is."""
    d, p = np.asarray(d, float), np.asarray(p, float)
    keep = stroke_mask(d)
    return d[keep], p[keep]


def first_fall(p: np.ndarray, softening: float = FIRST_PEAK_SOFTENING) -> int | None:
    """Index where `p` first falls below (1 - softening) times its running maximum; None
    where it never does."""
    p = np.asarray(p, float)
    fallen = np.flatnonzero(p < (1.0 - softening) * np.maximum.accumulate(p))
    return int(fallen[0]) if fallen.size else None


def first_maximum(p: np.ndarray, softening: float = FIRST_PEAK_SOFTENING) -> int:
    """Index of the largest load before `p` first falls below (1 - softening) times its
    running maximum (the first point at that maximum); of the largest load where it never
    does. -1 for an empty curve."""
    p = np.asarray(p, float)
    if p.size == 0:
        return -1
    end = first_fall(p, softening)
    return int(np.argmax(p[:p.size if end is None else end]))


def stroke_mask(d: np.ndarray) -> np.ndarray:
    """(n,) bool: the points of `stroke_curve`."""
    d = np.asarray(d, float)
    return d >= np.maximum.accumulate(d) - _EPS if d.size else np.zeros(0, bool)


def _at(d: np.ndarray, p: np.ndarray, x: float) -> float | None:
    """Load at deflection x, interpolated at the first crossing; None if never reached."""
    hit = np.nonzero(d >= x - _EPS)[0]
    if not hit.size:
        return None
    i = int(hit[0])
    if i == 0 or d[i] - d[i - 1] <= 0:
        return float(p[i])
    t = (x - d[i - 1]) / (d[i] - d[i - 1])
    return float(p[i - 1] + t * (p[i] - p[i - 1]))


def _plateau(d: np.ndarray, p: np.ndarray, a: float, b: float) -> float | None:
    if b - a <= _EPS or d[-1] < b - _EPS:
        return None
    inner = (d > a) & (d < b)
    xs = np.concatenate([[a], d[inner], [b]])
    ys = np.concatenate([[_at(d, p, a)], p[inner], [_at(d, p, b)]])
    return float(np.sum(0.5 * (ys[1:] + ys[:-1]) * np.diff(xs)) / (b - a))


def _secant(d: np.ndarray, p: np.ndarray, target: float) -> float | None:
    """Secant stiffness from (d[0], p[0]) to the first point where p reaches target."""
    hit = np.nonzero(p >= target)[0]
    if target <= 0 or not hit.size or hit[0] == 0:
        return None
    i = int(hit[0])
    t = (target - p[i - 1]) / (p[i] - p[i - 1])
    dx = d[i - 1] + t * (d[i] - d[i - 1]) - d[0]
    return float((target - p[0]) / dx) if dx > _EPS else None


def _relative(step: int, peak_step: int) -> str:
    return "before_peak" if step < peak_step else "at_peak" if step == peak_step else "after_peak"


def _event(hist: dict, column: str, peak_step: int) -> dict | None:
    if column not in hist:
        return None
    idx = np.nonzero(np.asarray(hist[column]) > 0)[0]
    if not idx.size:
        return None
    return _event_at(hist, int(idx[0]), peak_step)


def _event_at(hist: dict, i: int, peak_step: int) -> dict:
    step = int(hist["step"][i])
    pre = "preload_stage" in hist and int(hist["preload_stage"][i]) == 1
    return {"step": step, "deflection": float(hist["deflection"][i]),
            "load": float(hist["load"][i]), "stage": "preload" if pre else "control",
            "relative_to_peak": _relative(step, peak_step)}


def _normalise(source) -> tuple[dict, dict]:
    """(history dict with deflection/load/step/..., file info)."""
    if isinstance(source, str | os.PathLike):
        return _from_file(source)
    if isinstance(source, Mapping):
        hist = {k: np.asarray(v) for k, v in source.items()}
    elif isinstance(source, Sequence) and len(source) == 2:
        hist = {"deflection": np.asarray(source[0]), "load": np.asarray(source[1])}
    else:
        raise TypeError("extract() takes a result path, (deflection, load) or a mapping")
    if "control_displacement" in hist and "deflection" not in hist:
        hist["deflection"] = hist.pop("control_displacement")
    hist["deflection"] = np.asarray(hist["deflection"], float)
    hist["load"] = np.asarray(hist["load"], float)
    if hist["deflection"].shape != hist["load"].shape or hist["load"].ndim != 1:
        raise ValueError("deflection and load must be 1-D arrays of the same length")
    hist.setdefault("step", np.arange(1, hist["load"].size + 1))
    return hist, {"source": "arrays"}


def _from_file(path) -> tuple[dict, dict]:
    with open_result(path) as r:
        hist = dict(r.history)
        hist["deflection"] = hist.pop("control_displacement")
        a = r.attrs
        info = {"source": os.fspath(path), "specimen": a.get("specimen"),
                "status": r.status, "stop_reason": a.get("stop_reason", ""),
                "load_measure": a.get("load_measure"), "load_unit": a.get("load_unit")}
        info["_fields"] = _field_history(r)
    return hist, info


def _field_history(r) -> dict:
    """Per stored step: bottom-plate max eps_p and the most-crushed element, where stored."""
    mesh = r.mesh
    tags = {reg.name: reg.tag for reg in mesh.regions}
    plate = mesh.cell_region == tags.get(TENSION_PLATE, -1)
    names = {reg.tag: reg.name for reg in mesh.regions}
    peeq, crush = {}, {}
    for step in r.steps:
        fields = r.gauss_fields(step)
        if "equivalent_plastic_strain" in fields and plate.any():
            peeq[step] = float(r.gauss(step, "equivalent_plastic_strain")[plate].max())
        if "concrete_flags" in fields:
            n = (r.gauss(step, "concrete_flags")[..., 3:6] != 0).any(axis=2).sum(axis=1)
            if n.max() > 0:
                e = int(np.argmax(n))
                x, y = mesh.points[mesh.cells[e]].mean(axis=0)
                crush[step] = {"step": step, "region": names.get(int(mesh.cell_region[e]), "?"),
                               "element": e, "x": float(x), "y": float(y)}
    return {"peeq": peeq, "crush": crush}


def _tension_plate(hist: dict, fields: dict, peak_step: int) -> tuple[dict | None, str | None]:
    peeq = fields.get("peeq", {})
    if peeq:
        steps = sorted(peeq)
        first = next((s for s in steps if peeq[s] > 0), None)
        if first is None:
            return {"source": "equivalent_plastic_strain"}, "no"
        i = int(np.nonzero(hist["step"] == first)[0][0])
        ev = {**_event_at(hist, i, peak_step), "source": "equivalent_plastic_strain",
              "stored_steps": len(steps)}
        before = [s for s in steps if s < first]
        if first <= peak_step:
            verdict = "before_peak"
        elif before and before[-1] >= peak_step:
            verdict = "after_peak"
        else:
            verdict = "undetermined"
        return ev, verdict
    for column, note in (
            ("tension_plate_yielded", "tension_plate_yielded history column (bottom plate "
             "Gauss points)"),
            ("yielded", "yielded count of all steel regions (no equivalent_plastic_strain "
             "field stored)")):
        if column in hist:
            ev = _event(hist, column, peak_step)
            if ev is None:
                return {"source": note}, "no"
            return ({**ev, "source": note},
                    "before_peak" if ev["step"] <= peak_step else "after_peak")
    return None, None


def extract(source, *, residual_deflection: float = RESIDUAL_DEFLECTION,
            curve_deflections: Sequence[float] = ()) -> dict:
    """Key figures (JSON-ready dict) of a result file path, a (deflection, load) pair, or a
    mapping of history columns (deflection or control_displacement, load, optional step,
    preload_stage, cracked_in_plane, crushed, yielded). Definitions: module docstring.
    `curve_deflections`: also the loads at these control deflections ("curve_loads", None
    where the run did not reach one)."""
    hist, info = _normalise(source)
    fields = info.pop("_fields", {})
    d_all, p_all = hist["deflection"], hist["load"]
    control = np.ones(d_all.size, bool)
    if "preload_stage" in hist:
        control = np.asarray(hist["preload_stage"]) != 1
    d0 = float(d_all[~control][-1]) if (~control).any() else 0.0
    out: dict = {**info, "n_steps": int(control.sum()), "start_deflection": d0}
    if not control.any():
        return {**out, "peak_load": None}
    d = np.concatenate([[d0], d_all[control]])
    keep = stroke_mask(d)  # the curve a stroke-controlled test records (snap-backs dropped)
    d, p = d[keep], np.concatenate([[0.0], p_all[control]])[keep]
    steps = np.asarray(hist["step"])[control][keep[1:]]
    k = int(np.argmax(p[1:])) + 1
    peak, d_peak, peak_step = float(p[k]), float(d[k]), int(steps[k - 1])
    first = first_maximum(p)
    a = max(d_peak + PLATEAU_OFFSET, PLATEAU_START_MIN)
    res40 = _at(d, p, residual_deflection)
    plateau = _plateau(d, p, a, residual_deflection)
    out.update({
        "peak_load": peak, "deflection_at_peak": d_peak, "peak_step": peak_step,
        "peaked": bool(k < d.size - 1 and p[-1] < peak),
        "first_peak_load": float(p[first]), "deflection_at_first_peak": float(d[first]),
        "first_peak_settled": first_fall(p) is not None,
        "final_deflection": float(d[-1]), "final_load": float(p[-1]),
        "residual_load_40": res40, "residual_deflection": residual_deflection,
        "residual_plateau": plateau,
        "plateau_window": [a, residual_deflection] if plateau is not None else None,
        "residual_ratio_40": None if res40 is None or peak <= 0 else res40 / peak,
        "initial_stiffness": _secant(d, p, STIFFNESS_FRACTION * peak),
        "first_step_stiffness": (float(p[1] / (d[1] - d0)) if d[1] - d0 > _EPS else None),
        "curve_loads": [_at(d, p, float(x)) for x in curve_deflections],
        "first_cracking": _event(hist, "cracked_in_plane", peak_step),
        "first_crushing": _event(hist, "crushed", peak_step),
        "first_yield": _event(hist, "yielded", peak_step),
    })
    crush = fields.get("crush", {})
    if out["first_crushing"] is not None and crush:
        out["first_crushing"]["location"] = crush[min(crush)]
    out["tension_plate_yield"], out["tension_plate_yielded"] = _tension_plate(
        hist, fields, peak_step)
    return out
