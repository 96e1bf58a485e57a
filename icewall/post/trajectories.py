"""Principal stress trajectories in the concrete (thesis Figs. 5.18-5.23): at every concrete
Gauss point two crossed lines along the in-plane principal directions, each as long as its
principal stress is large (relative to the largest), compression blue, tension red."""

from __future__ import annotations

import numpy as np

from icewall.mesh.gauss import gauss_points_xy
from icewall.post.common import cells_of_kind, gauss_order, gauss_spacing, require_fields
from icewall.post.figures import draw_wall, legend_above, step_title, wall_figure


def principal_stresses(stress: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """In-plane principal stresses s1 >= s2 and the angle theta of s1 from x (rad, in
    (-pi/2, pi/2]) of stresses [..., (xx, yy, zz, xy)] (Mohr's circle)."""
    sx, sy, txy = stress[..., 0], stress[..., 1], stress[..., 3]
    centre, radius = 0.5 * (sx + sy), np.hypot(0.5 * (sx - sy), txy)
    return centre + radius, centre - radius, 0.5 * np.arctan2(2.0 * txy, sx - sy)


def trajectory_lines(xy: np.ndarray, stress: np.ndarray, length: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Segments (2m, 2, 2) along both principal directions at the points xy (m, 2) with
    stresses (m, 4) and full lengths `length` (m,) for the largest |stress|; and the signed
    principal stress of each segment (2m,)."""
    s1, s2, theta = principal_stresses(stress)
    values = np.concatenate([s1, s2])
    angles = np.concatenate([theta, theta + 0.5 * np.pi])
    peak = float(np.abs(values).max(initial=0.0)) or 1.0
    half = 0.5 * (np.tile(length, 2) * np.abs(values) / peak)[:, None] \
        * np.column_stack([np.cos(angles), np.sin(angles)])
    centres = np.tile(xy, (2, 1))
    return np.stack([centres - half, centres + half], axis=1), values


def plot_trajectories(result, step: int):
    """Figure of the principal stress trajectories of the concrete at a stored `step`."""
    from matplotlib.collections import LineCollection

    require_fields(result, step, ("stress",), "the stress trajectories")
    stress, mesh = result.gauss(step, "stress"), result.mesh
    n = gauss_order(result, stress)
    concrete = cells_of_kind(mesh, "concrete")
    xy = gauss_points_xy(mesh, n)[concrete].reshape(-1, 2)
    length = np.repeat(0.9 * gauss_spacing(mesh, n)[concrete], stress.shape[1])
    lines, values = trajectory_lines(xy, stress[concrete].reshape(-1, 4), length)
    fig, (ax,) = wall_figure(mesh)
    draw_wall(ax, mesh, alpha=0.6)
    peak = float(np.abs(values).max(initial=0.0))
    for mask, colour, what in ((values < 0, "tab:blue", "compression"),
                               (values > 0, "tab:red", "tension")):
        extreme = f", max |s| {np.abs(values[mask]).max():.3g} MPa" if mask.any() else ""
        ax.add_collection(LineCollection(lines[mask], colors=colour, linewidths=1.0, zorder=3,
                                         label=f"{what}{extreme}"))
    ax.set_title(step_title(result, step, f"principal stresses (longest line {peak:.3g} MPa)"),
                 loc="left", pad=22)
    legend_above(ax, ncol=2)
    return fig
