"""Physical ranges of the deck's material and geometric values (issue 38, item 4): a value
outside its range is almost always a unit slip (GPa or Pa for MPa, m for mm) or a typo, and it
can give a silent wrong result (a steel E of 1e-300 MPa ran under Newton to "completed" at zero
load), so `icewall check` and `run` refuse it with one line naming the file, the line and the
key (exit 2). `analysis.allow_unphysical: true` runs such a deck anyway, each value outside its
range then a warning: the same override as analysis.allow_large for a run too large.

The ranges are wide (every steel, concrete and wall the model is meant for lies well inside);
the hard limits of the schema (a thickness > 0, f'c 10-150 MPa, ...) are checked before them
and admit no override. A zero where zero means "none" (an open end, no bearing plate) is
always allowed."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

from icewall.deck.schema import Deck


@dataclass(frozen=True)
class Range:
    low: float | None
    high: float | None
    unit: str
    what: str
    zero_is_none: bool = False  # 0 means "none here" and is allowed


MM, MPA = "mm", "MPa"
ELASTIC_E = Range(1.0e3, 1.0e9, MPA, "an elastic part (1e9: a stiff device)")
RANGES: dict[str, Range] = {
    "geometry.depth": Range(50.0, 2.0e4, MM, "a wall"),
    "geometry.width": Range(10.0, 1.0e5, MM, "a wall"),
    "geometry.top_plate": Range(0.5, 200.0, MM, "a steel plate"),
    "geometry.bottom_plate": Range(0.5, 200.0, MM, "a steel plate"),
    "geometry.span": Range(100.0, 2.0e5, MM, "a wall"),
    "geometry.overhang": Range(None, 1.0e5, MM, "a wall"),
    "geometry.end_plate": Range(0.5, 500.0, MM, "a steel plate", zero_is_none=True),
    "geometry.diaphragms.thickness": Range(0.5, 200.0, MM, "a steel plate"),
    "geometry.supports[*].bearing_plate_width": Range(1.0, 1.0e4, MM, "a bearing plate",
                                                      zero_is_none=True),
    "geometry.supports[*].bearing_plate_thickness": Range(1.0, 1000.0, MM, "a bearing plate"),
    "geometry.legs[*].length": Range(1.0, 1.0e5, MM, "a leg"),
    "geometry.legs[*].height": Range(1.0, 1.0e5, MM, "a leg"),
    "materials.concrete.E": Range(5.0e3, 1.0e5, MPA, "concrete"),
    "materials.concrete.ft": Range(0.1, 20.0, MPA, "concrete"),
    "materials.concrete.Gf": Range(0.005, 2.0, "N/mm", "concrete"),
    "materials.concrete.eps_c": Range(5.0e-4, 0.02, "", "concrete"),
    "materials.concrete.k_t": Range(1.0e-2, 1.0e7, "", "concrete"),
    "materials.concrete.k_c": Range(1.0e-2, 1.0e7, "", "concrete"),
    "materials.concrete.surface.biaxial_ratio": Range(None, 2.0, "", "concrete"),
    "materials.concrete.surface.f1_ratio": Range(0.5, 5.0, "", "concrete"),
    "materials.concrete.surface.f2_ratio": Range(0.5, 5.0, "", "concrete"),
    "materials.steel.E": Range(1.0e5, 3.0e5, MPA, "structural steel"),
    "materials.steel.fy": Range(100.0, 2000.0, MPA, "structural steel"),
    "materials.bearing_plates.E": ELASTIC_E,
    "materials.legs.E": ELASTIC_E,
    "loads.patches.width": Range(1.0, 1.0e4, MM, "a load patch"),
    "loads.measure.tributary_length": Range(10.0, 1.0e5, MM, "a jack spacing"),
}
OVERRIDE = "analysis.allow_unphysical"


def _values(deck: Deck, key: str) -> Iterator[tuple[str, object]]:
    """(concrete key path, value) of every value `key` names ('[*]': each list item)."""
    nodes: list[tuple[str, object]] = [("", deck)]
    for token in key.split("."):
        name, many = token.removesuffix("[*]"), token.endswith("[*]")
        step = []
        for path, node in nodes:
            value = getattr(node, name, None)
            here = f"{path}.{name}" if path else name
            if many:
                step += [(f"{here}[{i}]", item) for i, item in enumerate(value or ())]
            elif value is not None:
                step.append((here, value))
        nodes = step
    yield from nodes


def _shown(value: float, unit: str = "") -> str:
    return f"{value:g} {unit}".rstrip()


def _message(value: float, rng: Range) -> str | None:
    """What is wrong with `value` against `rng` (None: inside it)."""
    low = rng.low is not None and value < rng.low
    high = rng.high is not None and value > rng.high
    if not (low or high):
        return None
    if rng.low is not None and rng.high is not None:
        return (f"{_shown(value, rng.unit)} is outside the physical range "
                f"[{_shown(rng.low)}, {_shown(rng.high, rng.unit)}] of {rng.what}")
    edge, word = (rng.low, "below") if low else (rng.high, "above")
    return (f"{_shown(value, rng.unit)} is {word} {_shown(edge, rng.unit)}, the physical "
            f"{'minimum' if low else 'maximum'} of {rng.what}")


def outside(deck: Deck) -> list[tuple[str, str]]:
    """(key path, message) of every value outside its physical range."""
    found = []
    for key, rng in RANGES.items():
        for path, value in _values(deck, key):
            if not isinstance(value, int | float) or (rng.zero_is_none and value == 0):
                continue
            if (message := _message(float(value), rng)) is not None:
                found.append((path, message))
    return found


def check_physical(deck: Deck, fail) -> None:
    """Raise fail(message, key) for the first value outside its range, unless the deck sets
    analysis.allow_unphysical (then physical_warnings lists them)."""
    if deck.analysis.allow_unphysical:
        return
    for key, message in outside(deck)[:1]:
        raise fail(f"{message} (is the unit right? {OVERRIDE}: true runs it anyway)", key)


def physical_warnings(deck: Deck) -> list[str]:
    """With analysis.allow_unphysical, one line per value outside its range."""
    if not deck.analysis.allow_unphysical:
        return []
    return [f"{key}: {message} (allowed by {OVERRIDE})" for key, message in outside(deck)]
