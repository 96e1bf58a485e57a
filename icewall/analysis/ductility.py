"""Member ductility per CSA S474-M1989 clause 8.4.4 (thesis 2.1, Figure 2.1).

Definitions (deflection d from the curve's origin, load P in any unit):

* Initial tangent stiffness K0: the slope of the least-squares line through the origin fitted to
  the first ``initial_points`` points of the curve (default 1: the secant of the first
  increment, which is the tangent where the first increment is still linear).
* Yield load P_y: the peak (largest) load of the curve.
* Yield deflection d_y = P_y / K0: where the level P_y meets the line from the origin with
  slope K0.
* Adequate (``pass``): the member sustains ``required_ratio`` (6) x d_y while keeping at least
  ``load_fraction`` (50 %) of P_y, i.e. after the peak the load does not fall below
  0.5 P_y before d = 6 d_y, and the analysed range reaches 6 d_y.
* Ductility ratio reached mu = d_f / d_y, d_f = the (interpolated) deflection where the load
  first falls below 0.5 P_y after the peak; where it never does, d_f is the end of the
  analysed range and mu is a lower bound (``ratio_is_lower_bound``).
* ``fail``: the load falls below 0.5 P_y before 6 d_y. ``undecided``: the run ended before
  6 d_y without such a drop, or the load was still rising at its end (P_y not known).
* Energy absorbed: the area under the curve (trapezoidal rule) from the origin to the end of
  the analysed range (``energy``) and to 6 d_y where reached (``energy_to_required``), in load
  unit x mm.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from icewall.analysis.extract import stroke_curve
from icewall.model.loads import jack_count, load_measure

REQUIRED_RATIO = 6.0  # clause 8.4.4: six times the yield deflection
LOAD_FRACTION = 0.5  # ... while keeping 50 % of the yield load
_EPS = 1e-12


@dataclass(frozen=True)
class Ductility:
    """Outcome of the clause 8.4.4 check on one load-deflection curve."""

    verdict: str  # "pass" | "fail" | "undecided"
    message: str
    initial_stiffness: float | None  # load unit / mm
    yield_load: float | None
    yield_deflection: float | None  # mm from the origin
    ductility_ratio: float | None  # mu reached
    ratio_is_lower_bound: bool
    energy: float  # area under the whole curve, load unit x mm
    energy_to_required: float | None  # area up to required_ratio x d_y
    required_ratio: float = REQUIRED_RATIO
    load_fraction: float = LOAD_FRACTION

    def as_dict(self) -> dict:
        return asdict(self)


def _area(d: np.ndarray, p: np.ndarray, upto: float) -> float:
    """Trapezoidal area under (d, p) from d[0] to `upto` (<= d[-1])."""
    inside = d < upto
    xs = np.append(d[inside], upto)
    ys = np.append(p[inside], np.interp(upto, d, p))
    return float(np.sum(0.5 * (ys[1:] + ys[:-1]) * np.diff(xs)))


def _first_drop(d: np.ndarray, p: np.ndarray, peak: int, level: float) -> float | None:
    """Deflection where p first falls below `level` after index `peak` (interpolated)."""
    below = np.nonzero(p[peak:] < level)[0]
    if not below.size:
        return None
    i = peak + int(below[0])
    t = (p[i - 1] - level) / (p[i - 1] - p[i])
    return float(d[i - 1] + t * (d[i] - d[i - 1]))


def csa_ductility(deflection, load, *, origin: float = 0.0, initial_points: int = 1,
                  required_ratio: float = REQUIRED_RATIO,
                  load_fraction: float = LOAD_FRACTION) -> Ductility:
    """Clause 8.4.4 check of the curve (deflection [mm], load) that starts from the unloaded
    state at d = `origin` (prepended as (origin, 0) unless the curve already starts there).
    Definitions: module docstring."""
    d = np.asarray(deflection, dtype=float) - origin
    p = np.asarray(load, dtype=float)
    if d.ndim != 1 or d.shape != p.shape or d.size == 0:
        raise ValueError("deflection and load must be non-empty 1-D arrays of the same length")
    if not (abs(d[0]) <= _EPS and abs(p[0]) <= _EPS):
        d, p = np.append(0.0, d), np.append(0.0, p)
    if np.any(np.diff(d) <= 0):
        raise ValueError("deflections must increase along the curve")
    energy = _area(d, p, d[-1])
    first = d[1:1 + max(initial_points, 1)], p[1:1 + max(initial_points, 1)]
    k0 = float(first[0] @ first[1] / (first[0] @ first[0]))
    peak = int(np.argmax(p))
    py = float(p[peak])
    if k0 <= 0 or py <= 0:
        return Ductility("undecided", "no positive initial stiffness or load", k0 or None,
                         None, None, None, False, energy, None, required_ratio, load_fraction)
    dy = py / k0
    need = required_ratio * dy
    drop = _first_drop(d, p, peak, load_fraction * py)
    reached = (drop if drop is not None else d[-1]) / dy
    to_required = _area(d, p, need) if d[-1] >= need - _EPS else None
    common = dict(initial_stiffness=k0, ductility_ratio=reached,
                  ratio_is_lower_bound=drop is None, energy=energy,
                  energy_to_required=to_required, required_ratio=required_ratio,
                  load_fraction=load_fraction)
    level = f"{load_fraction:.0%} of the yield load"
    if drop is not None and drop < need:
        return Ductility("fail", f"load fell below {level} at mu = {reached:.2f} < "
                         f"{required_ratio:g}", yield_load=py, yield_deflection=dy, **common)
    if peak == d.size - 1:
        return Ductility("undecided", "cannot decide: the load was still rising at the end of "
                         "the analysed range, so the yield (peak) load is not known",
                         yield_load=py, yield_deflection=dy, **common)
    if d[-1] >= need - _EPS:
        return Ductility("pass", f"sustains {required_ratio:g} x d_y = {need:.3g} mm above "
                         f"{level} (mu reached {'>= ' if drop is None else ''}{reached:.2f})",
                         yield_load=py, yield_deflection=dy, **common)
    return Ductility("undecided", f"cannot decide: the analysed range ends at {d[-1]:.3g} mm "
                     f"= {reached:.2f} d_y, short of {required_ratio:g} d_y = {need:.3g} mm; "
                     "run further", yield_load=py, yield_deflection=dy, **common)


def energy_factor(stored) -> float | None:
    """Total jack load (N) per unit of the reported load measure, from the stored deck (a
    LoadedDeck; w: n_jacks b L_trib; total load: 1); None when it does not load (None)."""
    if stored is None:
        return None
    return jack_count(stored.deck) / load_measure(stored.deck)[2]


def result_ductility(result) -> dict:
    """Clause 8.4.4 check of an open ResultFile's curve (the displacement-control steps from
    the end of any preload, as icewall.analysis.extract defines it), as a JSON-ready dict with
    the energy also in N mm of the total jack load where the deck gives the loaded area."""
    h = result.history
    d, p = np.asarray(h["control_displacement"], float), np.asarray(h["load"], float)
    control = np.ones(d.size, bool)
    if "preload_stage" in h:
        control = np.asarray(h["preload_stage"]) != 1
    if not control.any():
        return {"verdict": "undecided", "message": "no displacement-control steps"}
    origin = float(d[~control][-1]) if (~control).any() else 0.0
    try:
        out = csa_ductility(*stroke_curve(d[control], p[control]), origin=origin).as_dict()
    except ValueError as exc:  # e.g. a snap-back: the deflection went back
        return {"verdict": "undecided", "message": f"cannot check this curve: {exc}"}
    unit = result.attrs.get("load_unit") or "load unit"
    out["energy_unit"] = f"{unit} mm"
    factor = energy_factor(result.stored_deck())
    for key in ("energy", "energy_to_required"):
        out[f"{key}_Nmm"] = None if factor is None or out[key] is None else out[key] * factor
    return out
