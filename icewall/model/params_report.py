"""Derived concrete parameters per concrete region (thesis 4.3.1, Table 4.4), for checking a
deck before running it."""

from __future__ import annotations

import numpy as np

from icewall.deck.schema import Deck
from icewall.fem.kinematics import gauss_point_spacing
from icewall.mesh.mesh import CONCRETE, Mesh
from icewall.model.materials import concrete_parameters

COLUMNS = (("E0", "E", "MPa", ".0f"), ("ft", "f't", "MPa", ".3f"), ("eps_c", "eps_c", "", ".4f"),
           ("Gf", "G_f", "N/mm", ".3f"), ("G_cr", "G_cr", "N/mm", ".2f"),
           ("alpha", "alpha", "", ".3f"), ("h_c", "h_c", "mm", ".2f"), ("k_t", "k_t", "", ".1f"),
           ("k_c", "k_c", "", ".2f"))


def concrete_parameter_rows(deck: Deck, mesh: Mesh) -> list[dict]:
    """One row per concrete region at its mean Gauss-point spacing, with snap-back warnings
    judged at the region's largest spacing (the crack band cannot represent the branch)."""
    spacing = gauss_point_spacing(mesh.points, mesh.cells, deck.analysis.gauss)
    rows = []
    for region in sorted(mesh.regions, key=lambda r: r.tag):
        if region.kind != CONCRETE:
            continue
        h = spacing[mesh.cell_region == region.tag]
        p = concrete_parameters(deck.materials.concrete, float(np.mean(h)))
        worst = concrete_parameters(deck.materials.concrete, float(np.max(h)))
        row = {"region": region.name, **{key: float(getattr(p, key)) for key, *_ in COLUMNS},
               "h_c_min": float(h.min()), "h_c_max": float(h.max()), "warnings": []}
        if worst.snap_back_tension:
            row["warnings"].append(
                f"h_c up to {h.max():.1f} mm exceeds E G_f / f't^2 = "
                f"{p.E0 * p.Gf / p.ft ** 2:.1f} mm: the tensile softening branch snaps back")
        if worst.snap_back_compression:
            row["warnings"].append(
                f"k_c up to {worst.k_c:.1f} exceeds E / f'c = {p.E0 / p.fc:.1f}: the "
                "compressive softening branch snaps back")
        rows.append(row)
    return rows


def format_parameter_rows(rows: list[dict]) -> str:
    head = f"{'region':<10}" + "".join(f"{label + (' ' + unit if unit else ''):>13}"
                                       for _, label, unit, _ in COLUMNS)
    lines = [head]
    for row in rows:
        lines.append(f"{row['region']:<10}" + "".join(
            f"{row[key]:>13{fmt}}" for key, _, _, fmt in COLUMNS))
        lines += [f"  warning: {w}" for w in row["warnings"]]
    return "\n".join(lines)
