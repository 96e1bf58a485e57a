"""History columns every nonlinear run records for the mechanism check (issue 20 §1;
icewall.analysis.mechanism reads them): the tension plate's mean stress and yielded sections,
and where the concrete crushes, per step, from the live material states."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from icewall.materials.law import MaterialLaw
from icewall.mesh.gauss import gauss_points_xy, gauss_volumes

TENSION_PLATE = "bottom_plate"
PLATE_COLUMNS = ("tension_plate_stress_mid", "tension_plate_stress_max",
                 "tension_plate_stress_max_x")
YIELD_COLUMN = "tension_plate_yielded"  # yielded Gauss points of the plate
SECTION_COLUMN = "tension_plate_sections_yielded"  # stations yielded through the thickness
SECTION_X_COLUMN = "tension_plate_section_yield_x"  # the one of them nearest midspan
CRUSH_COLUMNS = ("crushed_x_min", "crushed_x_max", "crushed_y_mean", "crushed_region")


class MechanismProbe:
    """Per-step history scalars of the tension plate's mean stress and of the crushed points,
    for one mesh and Gauss rule (stations and weights computed once)."""

    def __init__(self, mesh, gauss_order: int) -> None:
        self.xy = gauss_points_xy(mesh, gauss_order)
        self.cell_region = mesh.cell_region
        tags = {r.name: r.tag for r in mesh.regions}
        self.plate = mesh.cell_region == tags.get(TENSION_PLATE, -1)
        if self.plate.any():
            x = self.xy[self.plate][..., 0].ravel()
            self.stations, self.where = np.unique(np.round(x, 6), return_inverse=True)
            self.weights = gauss_volumes(mesh, gauss_order)[self.plate].ravel()
            self.totals = np.bincount(self.where, weights=self.weights)
            self.mid = int(np.argmin(np.abs(self.stations)))

    def plate_stress(self, stress: np.ndarray) -> dict[str, float]:
        """Mean sigma_xx over the thickness at midspan and its maximum along the span (MPa)."""
        if not self.plate.any():
            return {}
        sxx = stress[self.plate][..., 0].ravel()
        means = np.bincount(self.where, weights=self.weights * sxx) / self.totals
        k = int(np.argmax(means))
        return {"tension_plate_stress_mid": float(means[self.mid]),
                "tension_plate_stress_max": float(means[k]),
                "tension_plate_stress_max_x": float(self.stations[k])}

    def crushing(self, crushed: np.ndarray) -> dict[str, float | int]:
        """x range, mean y and region (tag with most points) of the crushed Gauss points
        `crushed` (n_el, n_qp) bool; empty without any (the history column then holds its
        fill value)."""
        if not crushed.any():
            return {}
        xy = self.xy[crushed]
        regions = np.broadcast_to(self.cell_region[:, None], crushed.shape)[crushed]
        values, counts = np.unique(regions, return_counts=True)
        return {"crushed_x_min": float(xy[:, 0].min()), "crushed_x_max": float(xy[:, 0].max()),
                "crushed_y_mean": float(xy[:, 1].mean()),
                "crushed_region": int(values[np.argmax(counts)])}

    def scalars(self, stress: np.ndarray, crushed: np.ndarray | None,
                yielded: np.ndarray | None = None) -> dict:
        """History columns of one step; `crushed`, `yielded`: (n_el, n_qp) bool or None."""
        out: dict = dict(self.plate_stress(stress))
        if crushed is not None:
            out.update(self.crushing(crushed))
        if yielded is not None and self.plate.any():
            out.update(self.plate_yield(yielded))
        return out

    def plate_yield(self, yielded: np.ndarray) -> dict:
        """Yielded points of the plate, the stations yielded through the whole thickness and
        the x of the one nearest midspan (absent without any)."""
        points = yielded[self.plate].ravel()
        full = np.bincount(self.where, weights=points) == np.bincount(self.where)
        out: dict = {YIELD_COLUMN: int(np.count_nonzero(points)),
                     SECTION_COLUMN: int(np.count_nonzero(full))}
        if full.any():
            out[SECTION_X_COLUMN] = float(self.stations[full][np.argmin(np.abs(
                self.stations[full]))])
        return out


def _points(groups, states, shape: tuple[int, int], points: Callable[[MaterialLaw, Any], Any]
            ) -> np.ndarray | None:
    """(n_el, n_qp) bool of `points(law, state)` over the groups whose law has them."""
    mask, found = np.zeros(shape, dtype=bool), False
    for group, state in zip(groups, states, strict=True):
        chosen = points(group.law, state)
        if chosen is not None:
            mask[group.cells] = np.asarray(chosen).reshape(len(group.cells), -1)
            found = True
    return mask if found else None


def crushed_points(groups, states, shape: tuple[int, int]) -> np.ndarray | None:
    """(n_el, n_qp) bool of the concrete points in compressive softening, from the material
    groups and their states (None without a law that crushes)."""
    return _points(groups, states, shape, lambda law, state: law.crushed(state))


def yielded_points(groups, states, shape: tuple[int, int]) -> np.ndarray | None:
    """(n_el, n_qp) bool of the steel points that have yielded (None without a law that
    yields)."""
    return _points(groups, states, shape, lambda law, state: law.yielded(state))
