"""Load-deflection curves of one or more runs, with the test's peak and residual marked."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from icewall.analysis.extract import control_curve
from icewall.analysis.reference import find_reference
from icewall.errors import ResultError
from icewall.post.common import load_axis
from icewall.post.figures import legend_above, pyplot
from icewall.results.reader import open_result

RESIDUAL_AT = 40.0  # mm, where the residual is compared (icewall.analysis.sweep_table)
RESIDUAL_FROM = 20.0  # mm, start of the residual marker (the plateau of the extractor)


def reference_loads(attrs: dict, stored) -> dict:
    """Test ultimate and residual loads of the run's specimen in the run's load unit (reference
    data of icewall.analysis.reference, else the specimen.reference of the stored deck, a
    LoadedDeck or None where it does not load); {} if unknown."""
    unit = attrs.get("load_unit")
    ref = find_reference(str(attrs.get("specimen") or ""))
    if ref is not None and ref.unit == unit:
        return {k: getattr(ref, k) for k in ("ultimate_test", "residual_test")}
    if stored is None:
        return {}
    deck_ref = stored.deck.specimen.reference
    return {k: getattr(deck_ref, k, None) for k in ("ultimate_test", "residual_test")}


def read_curve(path: str | Path, label: str | None = None) -> dict:
    """The control curve (from its origin) of a result file, its labels and test values."""
    with open_result(path) as r:
        d, p, origin = control_curve(r.history)
        attrs, stored = dict(r.attrs), r.stored_deck()
    if not p.size:
        raise ResultError(f"{path}: no displacement-control steps to plot")
    return {"label": label or Path(path).name.removesuffix(".partial").removesuffix(".h5"),
            "specimen": attrs.get("specimen"), "attrs": attrs,
            "deflection": np.append(origin, d), "load": np.append(0.0, p),
            "reference": reference_loads(attrs, stored)}


def plot_curves(paths: list[str | Path], labels: list[str] | None = None):
    """Figure with the curves of `paths` overlaid, each run's peak marked, and per specimen the
    test's peak (dashed level) and residual (dotted level over 20-40 mm) in the run's colour."""
    plt = pyplot()
    curves = [read_curve(p, (labels or [None] * len(paths))[i]) for i, p in enumerate(paths)]
    axis = {load_axis(c["attrs"]) for c in curves}
    if len(axis) > 1:
        raise ResultError("cannot overlay runs with different load measures: "
                          + ", ".join(sorted(a[0] for a in axis)))
    ylabel, scale = axis.pop()
    fig, ax = plt.subplots(figsize=(8.0, 5.0))
    marked: set[str] = set()
    for c in curves:
        (line,) = ax.plot(c["deflection"], scale * c["load"], lw=1.6, label=c["label"])
        k = int(np.argmax(c["load"]))
        ax.plot(c["deflection"][k], scale * c["load"][k], "o", color=line.get_color(), ms=5)
        ax.annotate(f"peak {scale * c['load'][k]:.3g}", (c["deflection"][k], scale * c["load"][k]),
                    textcoords="offset points", xytext=(4, 6), fontsize="small",
                    color=line.get_color())
        name, ref = c["specimen"] or c["label"], c["reference"]
        if name in marked:
            continue
        marked.add(name)
        if ref.get("ultimate_test") is not None:
            level = scale * ref["ultimate_test"]
            ax.axhline(level, ls="--", lw=1.0, color=line.get_color())
            ax.annotate(f"{name} test peak {level:.3g}", (0.0, level), xycoords=("axes fraction",
                        "data"), xytext=(4, 3), textcoords="offset points", fontsize="small")
        if ref.get("residual_test") is not None:
            level = scale * ref["residual_test"]
            ax.plot([RESIDUAL_FROM, RESIDUAL_AT], [level, level], ls=":", lw=2.0,
                    color=line.get_color())
            ax.annotate(f"{name} test residual {level:.3g}", (RESIDUAL_FROM, level),
                        xytext=(0, -12), textcoords="offset points", fontsize="small")
    ax.set_xlabel("control deflection d (mm)")
    ax.set_ylabel(ylabel)
    ax.set_xlim(left=0.0)
    ax.set_ylim(bottom=0.0)
    ax.grid(True, lw=0.3)
    legend_above(ax, ncol=min(4, len(curves)))
    return fig
