"""Deformed shape with a magnification factor, with slip and separation at the steel-concrete
interfaces (thesis Figs. 5.12-5.17)."""

from __future__ import annotations

import numpy as np

from icewall.post.common import cell_outlines
from icewall.post.figures import draw_wall, legend_above, step_title, wall_figure

SHOWN_FRACTION = 0.05  # automatic scale: largest displacement drawn as 5 % of the wall length
GAP_TOLERANCE = 0.01  # mm: smaller relative displacements are not marked


def interface_motion(mesh, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(separation, slip) (n_pairs,) in mm: the concrete node's displacement relative to its
    steel node, normal (along the pair normal, steel -> concrete; > 0 opens) and tangential
    (along the normal turned +90 deg)."""
    steel, concrete = mesh.interface_pairs[:, 0], mesh.interface_pairs[:, 1]
    rel = u[concrete] - u[steel]
    n = mesh.interface_normals
    return (np.einsum("ij,ij->i", rel, n),
            np.einsum("ij,ij->i", rel, np.column_stack([-n[:, 1], n[:, 0]])))


def auto_scale(points: np.ndarray, u: np.ndarray) -> float:
    """Magnification 1, 2 or 5 x 10^k (at least 1) drawing the largest displacement as about
    SHOWN_FRACTION of the wall's length."""
    largest = float(np.abs(u).max(initial=0.0))
    if largest <= 0.0:
        return 1.0
    want = SHOWN_FRACTION * float(np.ptp(points[:, 0])) / largest
    if want <= 1.0:
        return 1.0
    decade = 10.0 ** np.floor(np.log10(want))
    return float(max(m for m in (1.0, 2.0, 5.0) if m * decade <= want) * decade)


def plot_deformed(result, step: int, scale: float | None = None,
                  tolerance: float = GAP_TOLERANCE):
    """Figure of the deformed mesh (displacements x `scale`, default auto_scale) over the
    undeformed outline, the interface pairs that opened (red) or slipped (orange) by more than
    `tolerance` joined by a line from the steel node to the concrete node."""
    from matplotlib.collections import LineCollection, PolyCollection

    mesh, u = result.mesh, result.displacement(step)
    scale = auto_scale(mesh.points, u) if scale is None else scale
    moved = mesh.points + scale * u
    fig, (ax,) = wall_figure(mesh)
    ax.add_collection(PolyCollection(cell_outlines(mesh.points, mesh), facecolors="none",
                                     edgecolors="0.75", linewidths=0.4, linestyles=":", zorder=0))
    draw_wall(ax, mesh, moved, edges=True)
    if len(mesh.interface_pairs):
        separation, slip = interface_motion(mesh, u)
        opened = separation > tolerance
        slipped = ~opened & (np.abs(slip) > tolerance)
        pairs = moved[mesh.interface_pairs]  # (n_pairs, 2, 2)
        for mask, colour, what, value in ((opened, "red", "separation", separation),
                                          (slipped, "orange", "slip", np.abs(slip))):
            top = f", max {value[mask].max():.3g} mm" if mask.any() else ""
            ax.add_collection(LineCollection(pairs[mask], colors=colour, linewidths=1.5,
                                             zorder=4, label=f"{what} > {tolerance:g} mm "
                                                             f"({int(mask.sum())}{top})"))
            ax.plot(*pairs[mask, 1].T, ".", color=colour, ms=3, zorder=4)
    ax.autoscale_view()
    ax.set_title(step_title(result, step, f"deformed shape x {scale:g}"), loc="left", pad=22)
    legend_above(ax, ncol=2)
    return fig
