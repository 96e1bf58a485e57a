"""matplotlib helpers (the ``plot`` extra): import, wall drawing, titles, saving PNG/SVG."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from icewall.errors import IcewallError
from icewall.post.common import cell_outlines, cells_of_kind
from icewall.safe_write import FIGURES, MARK, write_bytes

FORMATS = ("png", "svg")
STEEL_COLOUR, CONCRETE_COLOUR = "0.35", "0.93"


class PlotError(IcewallError):
    """Plotting is not possible as asked: matplotlib missing, unknown format (exit code 2)."""

    exit_code = 2


def pyplot():
    """matplotlib.pyplot on the non-interactive Agg backend."""
    try:
        import matplotlib
    except ImportError:
        raise PlotError("plotting needs matplotlib: pip install 'icewall[plot]'") from None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def wall_figure(mesh, n_panels: int = 1):
    """A figure sized to the wall's aspect ratio, with `n_panels` stacked axes."""
    plt = pyplot()
    (x0, y0), (x1, y1) = mesh.points.min(axis=0), mesh.points.max(axis=0)
    width = 10.0
    height = n_panels * max(2.0, width * (y1 - y0) / max(x1 - x0, 1e-9)) + 1.2
    fig, axes = plt.subplots(n_panels, 1, figsize=(width, height), squeeze=False)
    for ax in axes[:, 0]:
        ax.set_aspect("equal")
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("y (mm)")
    return fig, list(axes[:, 0])


def draw_wall(ax, mesh, points: np.ndarray | None = None, *, edges: bool = False,
              alpha: float = 1.0) -> None:
    """Cells at `points` (default: undeformed): concrete light, steel dark (the steel outline)."""
    from matplotlib.collections import PolyCollection

    outlines = cell_outlines(mesh.points if points is None else points, mesh)
    concrete = cells_of_kind(mesh, "concrete")
    for mask, face in ((concrete, CONCRETE_COLOUR), (~concrete, STEEL_COLOUR)):
        if mask.any():
            ax.add_collection(PolyCollection(
                outlines[mask], facecolors=face, alpha=alpha, linewidths=0.3 if edges else 0.0,
                edgecolors="0.55" if edges else face, zorder=1))
    ax.autoscale_view()


def step_title(result, step: int, what: str) -> str:
    """'CF-4: what at d = 10 mm (w = 5.39 MPa), step 5'."""
    h = result.history
    i = int(np.nonzero(h["step"] == step)[0][0])
    unit = result.attrs.get("load_unit") or ""
    measure = result.attrs.get("load_measure") or "load"
    name = result.attrs.get("specimen") or Path(result.path).stem
    return (f"{name}: {what} at d = {h['control_displacement'][i]:.3g} mm "
            f"({measure} = {h['load'][i]:.4g} {unit}), step {step}")


def legend_above(ax, ncol: int = 4) -> None:
    """A one-row legend just above the axes, where the eye meets it first."""
    ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.02), ncol=ncol, frameon=False,
              fontsize="small", handlelength=1.5)


def figure_bytes(fig, fmt: str, **savefig_args) -> bytes:
    """The figure as PNG or SVG bytes, marked as icewall's (its metadata: safe_write)."""
    key = "Software" if fmt == "png" else "Creator"
    buffer = io.BytesIO()
    fig.savefig(buffer, format=fmt, metadata={key: MARK}, **savefig_args)
    return buffer.getvalue()


def save(fig, stem: str | Path, formats: tuple[str, ...] = FORMATS) -> list[Path]:
    """Write `stem`.png / .svg (tight bounding box), close the figure, return the paths.
    Written through icewall.safe_write: never through a link, never over another file."""
    plt = pyplot()
    stem = Path(stem)
    paths = []
    try:
        if unknown := [fmt for fmt in formats if fmt not in FORMATS]:
            raise PlotError(f"unknown figure format {unknown[0]!r}; choose from "
                            f"{', '.join(FORMATS)}")
        stem.parent.mkdir(parents=True, exist_ok=True)
        for fmt in formats:
            path = stem.with_name(f"{stem.name}.{fmt}")
            write_bytes(path, figure_bytes(fig, fmt, dpi=150, bbox_inches="tight"),
                        FIGURES[fmt])
            paths.append(path)
    finally:
        plt.close(fig)
    return paths
