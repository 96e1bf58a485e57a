"""Helpers shared by the post-processors: Gauss-point positions, cell outlines, the stored step
nearest a deflection, the load axis label. No matplotlib here."""

from __future__ import annotations

import numpy as np

from icewall.analysis.extract import control_curve
from icewall.errors import ResultError
from icewall.mesh.mesh import Mesh

# boundary order of the nodes of a cell (quad8: corner, mid-side, corner, ...)
_OUTLINE = {"quad4": [0, 1, 2, 3], "quad8": [0, 4, 1, 5, 2, 6, 3, 7]}
STATE_FIELDS_HINT = ("run the deck with the state fields stored, e.g. "
                     "--set 'outputs.fields=[displacement, stress, strain, state]'")


def gauss_spacing(mesh, n_gauss: int) -> np.ndarray:
    """Gauss-point spacing (n_el,) of each cell: sqrt(bounding-box area) / n_gauss."""
    pts = mesh.points[mesh.cells]
    extent = pts.max(axis=1) - pts.min(axis=1)
    return np.sqrt(extent[:, 0] * extent[:, 1]) / n_gauss


def gauss_order(result, field: np.ndarray) -> int:
    """Gauss rule order of the run (attribute, else from the number of points)."""
    return int(result.attrs.get("gauss_order") or round(np.sqrt(field.shape[1])))


def cell_outlines(points: np.ndarray, mesh: Mesh) -> np.ndarray:
    """Closed-boundary node coordinates (n_el, m, 2) of every cell, from `points`."""
    return points[mesh.cells[:, _OUTLINE[mesh.cell_type]]]


def cells_of_kind(mesh: Mesh, kind: str) -> np.ndarray:
    """Boolean mask (n_el,) of the cells whose region is of `kind` (concrete, steel, elastic)."""
    tags = [r.tag for r in mesh.regions if r.kind == kind]
    return np.isin(mesh.cell_region, tags)


def cells_of_region(mesh: Mesh, prefix: str) -> dict[str, np.ndarray]:
    """Region name -> cell mask, for the regions whose name starts with `prefix`."""
    return {r.name: mesh.cell_region == r.tag for r in mesh.regions
            if r.name.startswith(prefix)}


def step_at(result, at: float | str) -> int:
    """The stored step nearest to deflection `at` (mm), or "peak" / "final".

    ResultError if no step stores fields, or `at` lies outside the stored range by more than
    half the largest spacing of the stored steps (at least 0.5 mm).
    """
    steps = result.steps
    if not steps:
        raise ResultError(f"{result.path}: no step stores fields (outputs.fields / every)")
    h = result.history
    index = {int(s): i for i, s in enumerate(h["step"])}
    defl = np.array([h["control_displacement"][index[s]] for s in steps])
    if at == "final":
        return steps[-1]
    if at == "peak":
        d, p, _ = control_curve(h)
        at = float(d[int(np.argmax(p))]) if p.size else float(defl[-1])
    at = float(at)
    i = int(np.argmin(np.abs(defl - at)))
    slack = max(0.5, 0.5 * float(np.max(np.diff(defl), initial=0.0)))
    if abs(defl[i] - at) > slack:
        raise ResultError(f"{result.path}: no stored step near {at:g} mm (stored steps span "
                          f"{defl.min():g}..{defl.max():g} mm)")
    return steps[i]


def load_axis(attrs: dict) -> tuple[str, float]:
    """(axis label with unit, factor from the stored load to the plotted one)."""
    measure, unit = attrs.get("load_measure") or "load", attrs.get("load_unit") or ""
    if unit == "N":
        return f"{measure} (kN)", 1e-3
    return (f"{measure} ({unit})" if unit else measure), 1.0


def require_fields(result, step: int, names: tuple[str, ...], what: str) -> None:
    """ResultError (exit 2) naming the option to set when a Gauss field is missing."""
    have = result.gauss_fields(step)
    missing = [n for n in names if n not in have]
    if missing:
        hint = STATE_FIELDS_HINT if {"concrete_flags", "orthotropy_angle"} & set(missing) \
            else "store them with outputs.fields"
        raise ResultError(f"{result.path}: {what} needs the Gauss field(s) "
                          f"{', '.join(missing)}, not stored at step {step}: {hint}")
