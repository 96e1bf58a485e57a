"""Closed-form statics of the CF walls (issue 20 §1): no FE, only equilibrium.

The CF wall is a simply supported beam with overhangs: statically determinate, so the midspan
moment per station load, M = c P, follows from where the loading stations stand and what each
carries. Thesis 4.2.1: "The ultimate load for all walls except Specimen CF-8 was reached before
the bottom steel plate yielded" (the bottom plate read as the plate in flexural tension at
midspan: decks/README.md, "CF loading stations"). With the concrete cracked at midspan (4.2.1:
"a flexural crack occurred in the midspan region") the tension plate carries at least M / z,
z <= h - t_f the distance between the plate centroids (any concrete compression only shortens
the lever arm). So at the TEST ultimate P_1 (Table 4.1)

    ratio = c P_1 / ((h - t_f) f_y t_f b)

is a lower bound on the bottom plate's force over its yield force: a layout with ratio >= 1 for
a wall other than CF-8 contradicts 4.2.1. The check has a second side: CF-8's plate did yield
(4.2.1; 5.3: "the bottom steel plate had yielded significantly"). The force can exceed M / z
only as far as concrete in compression shortens the lever arm (5.5: the concrete "assists in
carrying the compressive load" at midspan); a lever arm below LEVER_ARM_MIN (h - t_f), a
concrete compression block over most of the core, is read as impossible, so a layout with CF-8
below LEVER_ARM_MIN contradicts 4.2.1 as well.

Run ``python -m icewall.analysis.statics`` for the table over the candidate layouts.
"""

from __future__ import annotations

from dataclasses import dataclass

# Table 4.1 (test values): the four analysed CF walls. P_1 in N, lengths in mm, f_y in MPa.
CF_WALLS = {
    "CF-4": {"P_1": 560e3, "f_y": 371.0, "t_f": 12.6, "h": 250.0, "b": 381.0,
             "L": 1500.0, "S1": 300.0, "S2": 333.0},
    "CF-5": {"P_1": 437e3, "f_y": 371.0, "t_f": 12.4, "h": 250.0, "b": 381.0,
             "L": 1500.0, "S1": 300.0, "S2": 333.0},
    "CF-8": {"P_1": 761e3, "f_y": 371.0, "t_f": 12.4, "h": 250.0, "b": 381.0,
             "L": 1500.0, "S1": 300.0, "S2": 333.0},
    "CF-13": {"P_1": 712e3, "f_y": 398.0, "t_f": 9.5, "h": 250.0, "b": 375.0,
              "L": 1250.0, "S1": 300.0, "S2": 333.0},
}
YIELDED_AT_ULTIMATE = {"CF-8"}  # 4.2.1: the one wall whose bottom plate yielded before the peak
LEVER_ARM_MIN = 0.8  # smallest lever arm / (h - t_f) taken as possible (module docstring)
PATCH_WIDTH = 50.0  # mm, the decks' jack patches (an end station sits flush with the wall end)


@dataclass(frozen=True)
class Station:
    """A loading station at x >= 0 from midspan (mirrored; x = 0 counts once) carrying
    `load` times the station load P."""

    x: float
    load: float = 1.0


@dataclass(frozen=True)
class Layout:
    """One candidate layout of the loading stations of a CF wall (half, mirrored)."""

    name: str
    description: str
    stations: tuple[Station, ...]


def midspan_moment_per_load(span: float, stations: tuple[Station, ...]) -> float:
    """c = M(0) / P of a simply supported beam (supports at +-span/2) under the mirrored
    stations: free body of the right half, R span/2 - sum_{x > 0} P_i x_i with R = half the
    total load (the midspan station's half acts at the cut)."""
    half_total = sum(s.load * (0.5 if s.x == 0.0 else 1.0) for s in stations)
    return half_total * 0.5 * span - sum(s.load * s.x for s in stations if s.x > 0.0)


def fixed_end_moment_per_load(span: float, stations: tuple[Station, ...]) -> float:
    """Support moment / P of the span stations on a beam fixed at both supports: the moment
    that overhang loads must supply to make the supports act as in a continuous beam
    (sum P a b^2 / L^2 over the full, mirrored set of span stations)."""
    total = 0.0
    for s in stations:
        if s.x >= 0.5 * span:
            continue
        for x in ((s.x,) if s.x == 0.0 else (s.x, -s.x)):
            a, b = 0.5 * span + x, 0.5 * span - x
            total += s.load * a * b * b / span**2
    return total


def _span_stations(span: float, s1: float, *, inside_central_cell: bool) -> list[Station]:
    """Stations at 0, +-L/5, +-2L/5 (spacing L/5, Table 4.1's tributary length), optionally
    only those inside the central cell (|x| < L/2 - S1: none in the cell nearest the support)."""
    xs = [k * span / 5.0 for k in range(3)]
    if inside_central_cell:
        xs = [x for x in xs if x < 0.5 * span - s1]
    return [Station(x) for x in xs]


def cf_layouts(span: float, s1: float, s2: float, patch_width: float = PATCH_WIDTH
               ) -> tuple[Layout, ...]:
    """The layouts the text allows (decks/README.md, "CF loading stations", argues each)."""
    mid_overhang = 0.5 * span + 0.5 * s2
    end = 0.5 * span + s2 - 0.5 * patch_width  # patch flush with the wall end
    every = _span_stations(span, s1, inside_central_cell=False)
    central = _span_stations(span, s1, inside_central_cell=True)
    shifted = [Station(x) for x in (0.1 * span, 0.3 * span)]
    layouts = [
        Layout("A", "0, +-L/5, +-2L/5 + mid-overhang, all P (decks today)",
               (*every, Station(mid_overhang))),
        Layout("B", "0, +-L/5, +-2L/5 + wall end, all P", (*every, Station(end))),
        Layout("C", "central cell only (0, +-L/5) + mid-overhang, all P",
               (*central, Station(mid_overhang))),
        Layout("D", "central cell only (0, +-L/5) + wall end, all P",
               (*central, Station(end))),
        Layout("E", "+-L/10, +-3L/10 (no midspan station) + mid-overhang, all P",
               (*shifted, Station(mid_overhang))),
        Layout("A0", "0, +-L/5, +-2L/5, no overhang load", tuple(every)),
    ]
    for name, span_set, label in (("F", every, "0, +-L/5, +-2L/5"),
                                  ("G", central, "central cell only")):
        q = fixed_end_moment_per_load(span, tuple(span_set)) / (end - 0.5 * span)
        layouts.append(Layout(name, f"{label} + wall end carrying q P, q = fixed-end moment / "
                              "arm (full continuity at the supports)",
                              (*span_set, Station(end, q))))
    return tuple(layouts)


def plate_force_ratio(c: float, load: float, *, h: float, t_f: float, f_y: float, b: float
                      ) -> float:
    """Lower bound on the tension plate's force over its yield force: c P / z / (f_y t_f b),
    z = h - t_f between the plate centroids."""
    return c * load / (h - t_f) / (f_y * t_f * b)


def candidate_table(walls: dict[str, dict] = CF_WALLS) -> list[dict]:
    """Per layout: c for each span, the ratio of each wall at its test ultimate, and whether
    4.2.1 rules it out: ratio >= 1 for a wall other than CF-8 (``violates_4_2_1``), or CF-8
    below LEVER_ARM_MIN, its plate unable to yield (``cf8_cannot_yield``)."""
    rows: dict[str, dict] = {}
    for wall, g in walls.items():
        for layout in cf_layouts(g["L"], g["S1"], g["S2"]):
            row = rows.setdefault(layout.name, {"layout": layout.name,
                                                "description": layout.description,
                                                "c": {}, "ratio": {}})
            c = midspan_moment_per_load(g["L"], layout.stations)
            row["c"][g["L"]] = c
            row["ratio"][wall] = plate_force_ratio(c, g["P_1"], h=g["h"], t_f=g["t_f"],
                                                   f_y=g["f_y"], b=g["b"])
    for row in rows.values():
        row["violates_4_2_1"] = [w for w, r in row["ratio"].items()
                                 if r >= 1.0 and w not in YIELDED_AT_ULTIMATE]
        row["cf8_cannot_yield"] = [w for w, r in row["ratio"].items()
                                   if w in YIELDED_AT_ULTIMATE and r < LEVER_ARM_MIN]
    return list(rows.values())


def format_candidate_table(rows: list[dict]) -> str:
    """Markdown table of candidate_table()."""
    walls = list(rows[0]["ratio"])
    spans = sorted(rows[0]["c"], reverse=True)
    head = (["layout", *(f"c (L={s:g})" for s in spans), *walls, "ruled out by 4.2.1"])

    def verdict(r: dict) -> str:
        out = [f"{w} >= 1" for w in r["violates_4_2_1"]]
        out += [f"{w} < {LEVER_ARM_MIN:g}: cannot yield" for w in r["cf8_cannot_yield"]]
        return ", ".join(out) or "no"

    out = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        cells = [f"{r['layout']}: {r['description']}", *(f"{r['c'][s]:.1f}" for s in spans),
                 *(f"{r['ratio'][w]:.3f}" for w in walls),
                 verdict(r)]
        out.append("| " + " | ".join(cells) + " |")
    return "\n".join(out)


if __name__ == "__main__":
    print(format_candidate_table(candidate_table()))
