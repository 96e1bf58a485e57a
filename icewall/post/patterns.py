"""Crack and crush patterns at the Gauss points, as in thesis Figs. 5.4-5.10: in-plane cracks as
short lines along the crack, out-of-plane cracks as diamonds, compressive softening as octagons.

A crack "in direction i" (concrete_flags[..., i-1]) opened normal to orthotropy axis i (axis 1
at orthotropy_angle beta from x, axis 2 at beta + 90 deg), so its line runs along the other
in-plane axis: beta + 90 deg for direction 1, beta for direction 2.
"""

from __future__ import annotations

import numpy as np

from icewall.mesh.gauss import gauss_points_xy
from icewall.post.common import gauss_order, gauss_spacing, require_fields
from icewall.post.figures import draw_wall, legend_above, step_title, wall_figure

MARK_FRACTION = 0.8  # crack line length / Gauss-point spacing of its cell


def crack_marks(xy: np.ndarray, flags: np.ndarray, angle: np.ndarray,
                spacing: np.ndarray) -> dict[str, np.ndarray]:
    """Marks of one step from Gauss-point positions xy (n_el, nq, 2), concrete_flags
    (n_el, nq, 6), orthotropy_angle (n_el, nq[, 1]) and cell spacing (n_el,):
    line centres (m, 2), line angles from x (m,), line lengths (m,); out_of_plane (k, 2);
    crushed (j, 2) (softening in any direction)."""
    f = np.asarray(flags) != 0
    beta = np.asarray(angle).reshape(f.shape[:2])
    length = np.broadcast_to((MARK_FRACTION * spacing)[:, None], f.shape[:2])
    c1, c2 = f[..., 0], f[..., 1]
    return {
        "centres": np.concatenate([xy[c1], xy[c2]]),
        "angles": np.concatenate([beta[c1] + 0.5 * np.pi, beta[c2]]),
        "lengths": np.concatenate([length[c1], length[c2]]),
        "out_of_plane": xy[f[..., 2]],
        "crushed": xy[f[..., 3:6].any(axis=-1)],
    }


def segments(centres: np.ndarray, angles: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """Line segments (m, 2, 2) centred at `centres` along `angles` with `lengths`."""
    half = 0.5 * lengths[:, None] * np.column_stack([np.cos(angles), np.sin(angles)])
    return np.stack([centres - half, centres + half], axis=1)


def plot_cracks(result, step: int):
    """Figure of the crack and crush pattern of an open ResultFile at a stored `step`."""
    from matplotlib.collections import LineCollection

    require_fields(result, step, ("concrete_flags", "orthotropy_angle"), "the crack pattern")
    flags = result.gauss(step, "concrete_flags")
    mesh, n = result.mesh, gauss_order(result, flags)
    marks = crack_marks(gauss_points_xy(mesh, n), flags, result.gauss(step, "orthotropy_angle"),
                        gauss_spacing(mesh, n))
    fig, (ax,) = wall_figure(mesh)
    draw_wall(ax, mesh)
    lines = segments(marks["centres"], marks["angles"], marks["lengths"])
    ax.add_collection(LineCollection(lines, colors="k", linewidths=0.9, zorder=3,
                                     label=f"in-plane crack ({len(lines)})"))
    out, crushed = marks["out_of_plane"], marks["crushed"]
    ax.plot(out[:, 0], out[:, 1], "D", ls="none", mfc="none", mec="tab:blue", ms=4, zorder=4,
            label=f"out-of-plane crack ({len(out)})")
    ax.plot(crushed[:, 0], crushed[:, 1], "8", ls="none", mfc="tab:red", mec="darkred", ms=5,
            zorder=5, label=f"compressive softening ({len(crushed)})")
    ax.set_title(step_title(result, step, "cracks and crushing"), loc="left", pad=22)
    legend_above(ax, ncol=3)
    return fig
