"""Stresses along the top and bottom plates and in the diaphragms (thesis Figs. 5.57-5.60): the
mean normal stress over the plate thickness (axial force / area) at each Gauss-point station,
sigma_xx along x in the plates, sigma_yy along y in the diaphragms."""

from __future__ import annotations

import numpy as np

from icewall.mesh.gauss import gauss_points_xy, gauss_volumes
from icewall.post.common import cells_of_region, gauss_order, require_fields
from icewall.post.figures import legend_above, pyplot, step_title

PLATES = ("top_plate", "bottom_plate")
COMPONENT = {0: 0, 1: 1}  # axis along the member -> stress component (xx, yy)


def section_means(position: np.ndarray, values: np.ndarray, weights: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Weighted mean of `values` over the points that share a `position` (rounded to 1e-6 mm):
    (sorted stations, means). With Gauss weights x |det J| this is the through-thickness
    integral / thickness at each station."""
    stations, where = np.unique(np.round(position, 6), return_inverse=True)
    total = np.bincount(where, weights=weights)
    return stations, np.bincount(where, weights=weights * values) / total


def member_stresses(mesh, stress: np.ndarray, order: int) -> dict[str, tuple]:
    """Region name -> (axis, stations (mm), mean normal stress (MPa)) of the plates (axis 0:
    sigma_xx along x) and diaphragms (axis 1: sigma_yy along y)."""
    xy, dv = gauss_points_xy(mesh, order), gauss_volumes(mesh, order)
    members = {name: (0, mask) for name, mask in cells_of_region(mesh, "").items()
               if name in PLATES}
    members.update({name: (1, mask) for name, mask in cells_of_region(mesh, "diaphragm").items()})
    out = {}
    for name, (axis, mask) in members.items():
        if mask.any():
            out[name] = (axis, *section_means(xy[mask][..., axis].ravel(),
                                              stress[mask][..., COMPONENT[axis]].ravel(),
                                              dv[mask].ravel()))
    return out


def plot_plate_stresses(result, step: int):
    """Two panels: sigma_xx along the plates, sigma_yy up the diaphragms, at a stored step."""
    require_fields(result, step, ("stress",), "the plate stresses")
    stress = result.gauss(step, "stress")
    members = member_stresses(result.mesh, stress, gauss_order(result, stress))
    fig, (top, side) = pyplot().subplots(1, 2, figsize=(11.0, 4.5),
                                         gridspec_kw={"width_ratios": [2, 1]})
    for name, (axis, stations, mean) in sorted(members.items()):
        if axis == 0:
            top.plot(stations, mean, "-", marker=".", label=name.replace("_", " "))
        else:
            side.plot(mean, stations, "-", marker=".", label=name.replace("_", " "))
    top.set_xlabel("x from midspan (mm)")
    top.set_ylabel("mean plate stress sigma_xx (MPa)")
    side.set_xlabel("mean diaphragm stress sigma_yy (MPa)")
    side.set_ylabel("y (mm)")
    top.axhline(0.0, color="0.6", lw=0.5)
    side.axvline(0.0, color="0.6", lw=0.5)
    for ax in (top, side):
        ax.grid(True, lw=0.3)
        legend_above(ax, ncol=2)
    fig.suptitle(step_title(result, step, "plate and diaphragm stresses"), x=0.02, ha="left")
    fig.tight_layout()
    return fig
