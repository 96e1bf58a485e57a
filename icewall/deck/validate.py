"""Geometric and cross-field checks of a built deck (types and limits are checked earlier)."""

from __future__ import annotations

from collections.abc import Callable

from icewall.deck.physical import check_physical
from icewall.deck.resources import refusals
from icewall.deck.schema import FIXED_POINT_PLACEMENTS, Deck, Geometry

ErrorFactory = Callable[[str, str], Exception]


def _spans_overlap(items: list[tuple[float, float, str]], what: str, fail: ErrorFactory) -> None:
    """items: (start, end, key) along x, mirrored already; touching is allowed."""
    ordered = sorted(items)
    for (a0, a1, ka), (b0, b1, kb) in zip(ordered, ordered[1:], strict=False):
        if b0 < a1 - 1e-9:
            other = f" (overlaps {ka})" if ka != kb else " (overlaps its mirror image)"
            raise fail(f"{what} overlap: [{b0:g}, {b1:g}] mm and [{a0:g}, {a1:g}] mm{other}", kb)


def _mirrored(x: float, half_width: float, key: str) -> list[tuple[float, float, str]]:
    spans = [(x - half_width, x + half_width, key)]
    if x > 0:
        spans.append((-x - half_width, -x + half_width, key))
    return spans


def validate(deck: Deck, fail: ErrorFactory) -> None:
    """Raise fail(message, key_path) for the first impossible combination found."""
    geo, loads, analysis = deck.geometry, deck.loads, deck.analysis
    _check_name(deck.specimen.name, fail)
    _check_section(geo, fail)
    _check_diaphragms(geo, fail)
    _check_supports(geo, fail)
    _check_patches(deck, fail)
    if loads.control.x > geo.half_length:
        raise fail(f"control point x = {loads.control.x:g} mm is off the wall", "loads.control.x")
    if loads.control.increment > loads.control.target:
        raise fail("increment is larger than the target", "loads.control.increment")
    _check_preload(deck, fail)
    if loads.measure.kind == "intensity" and loads.measure.tributary_length is None:
        raise fail("kind 'intensity' needs tributary_length (the jack spacing)",
                   "loads.measure.tributary_length")
    if analysis.formulation == "axisymmetric" and geo.model == "full":
        raise fail("an axisymmetric model is a half model (x = radius >= 0)", "geometry.model")
    # (in a plane-stress analysis plane-stress plates are what "same" gives: consistent)
    if (deck.materials.steel.formulation == "plane_stress"
            and analysis.formulation == "axisymmetric"):
        raise fail("plane-stress plates are an option of plane-strain (or plane-stress) "
                   "analyses only", "materials.steel.formulation")
    _check_fixed_points(deck, fail)
    check_physical(deck, fail)  # (before the cost estimate: 1e308 is a slip, not a big run)
    _check_mesh_size(deck, fail)
    if len(set(deck.outputs.fields)) != len(deck.outputs.fields):
        raise fail("a field is listed twice", "outputs.fields")
    if not deck.outputs.directory.strip():  # as -o '': it wrote into the working directory
        raise fail("is empty: write '.' for the working directory", "outputs.directory")


def _check_section(geo: Geometry, fail: ErrorFactory) -> None:
    """The plates leave a core, the end plate is shorter than the half wall."""
    if geo.top_plate + geo.bottom_plate >= geo.depth:
        raise fail(f"plates ({geo.top_plate:g} + {geo.bottom_plate:g} mm) are as thick as or "
                   f"thicker than the depth {geo.depth:g} mm", "geometry.top_plate")
    if geo.end_plate >= geo.half_length:
        raise fail(f"end plate {geo.end_plate:g} mm is as long as the half wall "
                   f"{geo.half_length:g} mm", "geometry.end_plate")


def _check_diaphragms(geo: Geometry, fail: ErrorFactory) -> None:
    """Diaphragms lie inside the end plates and do not overlap (nor their mirror images)."""
    if geo.diaphragms is None:
        return
    inner = geo.half_length - geo.end_plate
    spans = []
    t = geo.diaphragms.thickness
    for i, x in enumerate(geo.diaphragms.positions):
        key = f"geometry.diaphragms.positions[{i}]"
        if x + 0.5 * t > inner + 1e-9:
            raise fail(f"diaphragm at x = {x:g} mm lies outside the wall (its outer face "
                       f"{x + 0.5 * t:g} mm > {inner:g} mm, the inside of the end)", key)
        spans += _mirrored(x, 0.5 * t, key)
    _spans_overlap(spans, "diaphragms", fail)


def _check_supports(geo: Geometry, fail: ErrorFactory) -> None:
    """Supports and their bearing plates, and legs, on the wall and apart; a full model pinned."""
    half = geo.half_length
    if not geo.supports:
        raise fail("at least one support is required", "geometry.supports")
    plates = []
    for i, sup in enumerate(geo.supports):
        key = f"geometry.supports[{i}]"
        if sup.x > half + 1e-9:
            raise fail(f"support at x = {sup.x:g} mm is off the wall (half length {half:g} mm)",
                       key + ".x")
        if sup.bearing_plate_width > 0:
            if sup.x + 0.5 * sup.bearing_plate_width > half + 1e-9:
                raise fail(f"bearing plate at x = {sup.x:g} mm sticks out beyond the wall end "
                           f"{half:g} mm", key + ".bearing_plate_width")
            plates += _mirrored(sup.x, 0.5 * sup.bearing_plate_width, key)
    _spans_overlap(plates, "bearing plates", fail)
    legs = []
    for i, leg in enumerate(geo.legs):
        key = f"geometry.legs[{i}]"
        if leg.x + 0.5 * leg.length > half + 1e-9:
            raise fail(f"leg at x = {leg.x:g} mm reaches beyond the wall end {half:g} mm", key)
        legs += _mirrored(leg.x, 0.5 * leg.length, key)
    _spans_overlap(legs, "legs", fail)
    for a0, a1, key in plates:
        for b0, b1, _ in legs:
            if a0 < b1 and b0 < a1:
                raise fail("a bearing plate overlaps a leg; support the leg instead", key)
    if geo.model == "full" and not any(s.restraint == "pin" for s in geo.supports):
        raise fail("a full model needs at least one 'pin' support to stop horizontal "
                   "rigid-body motion", "geometry.supports")


def _check_patches(deck: Deck, fail: ErrorFactory) -> None:
    """At least one load patch, each on the top plate, none overlapping another."""
    half, patches = deck.geometry.half_length, []
    width = deck.loads.patches.width
    if not deck.loads.patches.positions:
        raise fail("at least one load patch is required", "loads.patches.positions")
    for i, x in enumerate(deck.loads.patches.positions):
        key = f"loads.patches.positions[{i}]"
        # (a patch flush with the wall end stays valid when a round-off realization widens
        # it by k 1e-8: the mesh clips it to the end, icewall.mesh.layout)
        if x + 0.5 * width > half + 1e-6 * width:
            raise fail(f"load patch at x = {x:g} mm (width {width:g}) runs off the top plate "
                       f"(half length {half:g} mm)", key)
        patches += _mirrored(x, 0.5 * width, key)
    _spans_overlap(patches, "load patches", fail)


def _check_mesh_size(deck: Deck, fail: ErrorFactory) -> None:
    geo, size = deck.geometry, deck.analysis.element_size
    if size > geo.depth:
        raise fail(f"element size {size:g} mm exceeds the wall depth {geo.depth:g} mm; "
                   "the core would have no interior", "analysis.element_size")
    if not deck.analysis.allow_large:  # icewall.deck.resources: cannot finish here
        for message, key in refusals(deck):
            raise fail(f"{message} (analysis.allow_large: true runs it anyway)", key)


MAX_NAME = 200
"""Longest specimen name (it names the result file, at most 255 bytes on most filesystems)."""


def _check_name(name: str, fail: ErrorFactory) -> None:
    """The specimen name also names the result file: no control characters, not too long."""
    if len(name) > MAX_NAME:
        raise fail(f"{len(name)} characters, longer than {MAX_NAME} (it names the result "
                   "file)", "specimen.name")
    bad = sorted({c for c in name if ord(c) < 32 or ord(c) == 127})
    if bad:
        raise fail(f"control character(s) {', '.join(repr(c) for c in bad)} in the name "
                   "(it names the result file)", "specimen.name")


def _check_preload(deck: Deck, fail: ErrorFactory) -> None:
    """A preload the section cannot hold: beyond its squash load f'c A_c + f_y A_s in
    compression, or its yield load f_y A_s + f't A_c in tension (plates and core over the
    width b). No equilibrium exists there, so the preload stage could never converge; a value
    beyond them is a unit slip (kN for N) or a typo, not an analysis."""
    if deck.loads.preload is None:
        return
    geo, concrete, steel = deck.geometry, deck.materials.concrete, deck.materials.steel
    area_steel = geo.width * (geo.top_plate + geo.bottom_plate)
    area_core = geo.width * (geo.depth - geo.top_plate - geo.bottom_plate)
    f_t = concrete.ft if concrete.ft is not None else 0.33 * concrete.fc ** 0.5  # eq. 4.2
    force = deck.loads.preload.axial_force
    if force < 0:
        limit, what = concrete.fc * area_core + steel.fy * area_steel, "squash load"
    else:
        limit, what = steel.fy * area_steel + f_t * area_core, "tensile yield load"
    if abs(force) > limit:
        raise fail(f"{force:.4g} N is beyond the section's {what} {limit:.4g} N "
                   f"(f'c = {concrete.fc:g}, f_y = {steel.fy:g} MPa, b = {geo.width:g} mm); "
                   "is the unit N?", "loads.preload.axial_force")


def _check_fixed_points(deck: Deck, fail: ErrorFactory) -> None:
    key = "materials.interface.fixed_point_placement"
    for i, where in enumerate(deck.materials.interface.fixed_point_placement):
        if where not in FIXED_POINT_PLACEMENTS:
            raise fail(f"unknown fixed-point placement {where!r} (one of "
                       f"{', '.join(FIXED_POINT_PLACEMENTS)})", f"{key}[{i}]")
