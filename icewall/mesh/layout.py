"""The section of a wall deck as a grid of axis-aligned blocks, each owned by one region.

Every plate, diaphragm, core, bearing plate and leg of these walls is a rectangle, so the whole
section is a tensor grid of x and y lines through all their edges (plus load-patch edges, the
support and control points). Each occupied grid cell is one block; gmsh then meshes every block
as a structured (transfinite) patch, so neighbouring blocks share nodes and the same deck always
gives the same mesh.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from icewall.deck.schema import Deck
from icewall.mesh.mesh import CONCRETE, ELASTIC, STEEL

_TOL = 1e-6


@dataclass(frozen=True)
class Block:
    ix: int  # x-interval index
    iy: int  # y-interval index
    region: str


@dataclass(frozen=True)
class Layout:
    """Grid lines, their subdivisions and the occupied blocks."""

    x_lines: np.ndarray
    y_lines: np.ndarray
    x_divisions: np.ndarray  # elements per x-interval
    y_divisions: np.ndarray
    blocks: tuple[Block, ...]
    region_kinds: dict[str, str]  # region name -> CONCRETE | STEEL | ELASTIC
    region_materials: dict[str, str]  # region name -> deck material key


def mirror_positions(xs, model: str) -> list[float]:
    """Positions x >= 0 from midspan and, in a full model, their mirror images (-x after x)."""
    out = []
    for x in xs:
        out.append(x)
        if model == "full" and x > 0:
            out.append(-x)
    return out


def _spans(centres, half_widths, model: str) -> list[tuple[float, float]]:
    """(x0, x1) of mirrored rectangles, clipped to x >= 0 for a half model."""
    return [s[:2] for s in _spans_with_source(centres, half_widths, model)]


def _spans_with_source(centres, half_widths, model: str) -> list[tuple[float, float, int]]:
    """(x0, x1, index of the deck item) of mirrored rectangles, clipped for a half model."""
    spans = []
    for i, (x, w) in enumerate(zip(centres, half_widths, strict=True)):
        spans.append((max(x - w, 0.0) if model == "half" else x - w, x + w, i))
        if x > 0 and model == "full":
            spans.append((-x - w, -x + w, i))
    return spans


def _unique(values) -> np.ndarray:
    values = np.sort(np.asarray(values, dtype=float))
    keep = np.concatenate([[True], np.diff(values) > _TOL])
    return values[keep]


ROUND_OFF = 1e-6
"""An interval longer than a whole number of elements by less than this fraction of one gets
that number of elements: a load patch widened by a round-off realization (k 1e-8 of its width)
keeps the mesh of the run it perturbs (with 1e-9, CF-4's 50 mm patch intervals split in two)."""


def _divisions(lines: np.ndarray, size: float) -> np.ndarray:
    lengths = np.diff(lines)
    return np.maximum(1, np.ceil(lengths / size - ROUND_OFF)).astype(int)


def build_layout(deck: Deck) -> Layout:
    """Blocks of the wall section described by `deck` (x = 0 at midspan, y = 0 underside)."""
    geo, model = deck.geometry, deck.geometry.model
    half = geo.half_length
    x_lo = 0.0 if model == "half" else -half
    depth, t_top, t_bot = geo.depth, geo.top_plate, geo.bottom_plate
    diaphragms = geo.diaphragms
    d_spans = [] if diaphragms is None else _spans(
        diaphragms.positions, [0.5 * diaphragms.thickness] * len(diaphragms.positions), model)
    if geo.end_plate > 0:
        d_spans_end = [(half - geo.end_plate, half)] + ([(-half, -half + geo.end_plate)]
                                                        if model == "full" else [])
    else:
        d_spans_end = []
    sups = [s for s in geo.supports if s.bearing_plate_width > 0]
    bp = _spans_with_source([s.x for s in sups], [0.5 * s.bearing_plate_width for s in sups],
                            model)
    bp_spans = [(a, b) for a, b, _ in bp]
    bp_depth = {(a, b): sups[i].bearing_plate_thickness for a, b, i in bp}
    legs = _spans_with_source([g.x for g in geo.legs], [0.5 * g.length for g in geo.legs], model)
    leg_spans = [(a, b) for a, b, _ in legs]
    leg_height = {(a, b): geo.legs[i].height for a, b, i in legs}
    p = deck.loads.patches
    # clipped to the wall: a patch flush with its end, widened by a round-off realization
    patch_spans = [(max(a, -half), min(b, half))
                   for a, b in _spans(p.positions, [0.5 * p.width] * len(p.positions), model)]

    xs = [x_lo, half]
    for a, b in d_spans + d_spans_end + bp_spans + leg_spans + patch_spans:
        xs += [a, b]
    points = mirror_positions([deck.loads.control.x] + [s.x for s in geo.supports], model)
    x_lines = _add_node_lines(_unique([x for x in xs if x >= x_lo - _TOL]), points,
                              deck.analysis.element_size, deck.analysis.element)
    ys = [0.0, t_bot, depth - t_top, depth]
    ys += [-t for t in bp_depth.values()] + [-h for h in leg_height.values()]
    y_lines = _unique(ys)

    def inside(x: float, spans) -> tuple[float, float] | None:
        return next((s for s in spans if s[0] - _TOL <= x <= s[1] + _TOL), None)

    walls = d_spans + d_spans_end
    blocks, kinds, materials = [], {}, {}

    def add(ix: int, iy: int, name: str, kind: str, material: str) -> None:
        blocks.append(Block(ix, iy, name))
        kinds[name], materials[name] = kind, material

    x_mid = 0.5 * (x_lines[1:] + x_lines[:-1])
    y_mid = 0.5 * (y_lines[1:] + y_lines[:-1])
    for iy, y in enumerate(y_mid):
        for ix, x in enumerate(x_mid):
            if 0 < y < t_bot:
                add(ix, iy, "bottom_plate", STEEL, "steel")
            elif depth - t_top < y < depth:
                add(ix, iy, "top_plate", STEEL, "steel")
            elif t_bot < y < depth - t_top:
                span = inside(x, d_spans_end)
                if span is not None:
                    add(ix, iy, "end_plate", STEEL, "steel")
                    continue
                span = inside(x, d_spans)
                if span is not None:
                    k = sorted(d_spans).index(span) + 1
                    add(ix, iy, f"diaphragm_{k}", STEEL, "steel")
                    continue
                k = 1 + sum(1 for a, b in walls if b <= x)
                add(ix, iy, f"core_{k}", CONCRETE, "concrete")
            elif y < 0:
                span = inside(x, bp_spans)
                if span is not None and y > -bp_depth[span]:
                    k = sorted(bp_spans).index(span) + 1
                    add(ix, iy, f"bearing_plate_{k}", ELASTIC, "bearing_plates")
                    continue
                span = inside(x, leg_spans)
                if span is not None and y > -leg_height[span]:
                    k = sorted(leg_spans).index(span) + 1
                    add(ix, iy, f"leg_{k}", ELASTIC, "legs")
    size = deck.analysis.element_size
    return Layout(x_lines, y_lines, _divisions(x_lines, size), _divisions(y_lines, size),
                  tuple(blocks), kinds, materials)


def _add_node_lines(lines: np.ndarray, points, size: float, element: str) -> np.ndarray:
    """Add grid lines at `points` (supports, control point) that would not fall on a node."""
    per_division = 2 if element == "quad8" else 1
    for x in points:
        divisions = _divisions(lines, size)
        i = int(np.clip(np.searchsorted(lines, x) - 1, 0, len(lines) - 2))
        steps = divisions[i] * per_division
        position = (x - lines[i]) / (lines[i + 1] - lines[i]) * steps
        if abs(position - round(position)) > 1e-6:
            lines = _unique([*lines, x])
    return lines
