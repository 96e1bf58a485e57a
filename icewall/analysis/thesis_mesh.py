"""The mesh size at which a wall has the thesis' Gauss-point spacing h_c (Table 4.4).

Table 4.4's h_c is the thesis' "effective sampling point spacing", eq. 4.3's h_c = sqrt(h1 h2)
of the Gauss points (thesis 4.3.1, Fig. 4.13): element length over the Gauss order (CF-4:
36.6 / 24.5 / 18.2 mm for 2x2 / 3x3 / 4x4, elements of about 73 mm; its Fig. 4.15 is lost).
icewall meshes every grid interval (plates, diaphragms, bearing plates, legs, load patches) with
ceil(length / element_size) elements, so its elements are not all of one size; the rule here
takes eq. 4.3's "area average" literally: the element size (in 1 mm steps) at which the
area-weighted mean h_c of the wall's concrete is nearest Table 4.4's. It reads the geometry
only, never a result. `python -m icewall.analysis.thesis_mesh [--profile thesis]` prints it
for the eight analysed walls (decks/profiles/thesis.yaml carries the sizes).
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass

import numpy as np

from icewall.deck.load import load_deck
from icewall.fem.kinematics import gauss_point_spacing
from icewall.mesh.build import build_mesh

TABLE_4_4_H_C = {"CF-4": 24.5, "CF-5": 24.5, "CF-8": 21.4, "CF-13": 24.5, "TF-1": 23.1,
                 "TF-2": 23.1, "TF-4": 23.1, "VTT3": 18.0}
"""Table 4.4's h_c (mm, 3x3 Gauss points) of the eight analysed walls (specimen names)."""
ANALYSED = {"CF-4": "cf4", "CF-5": "cf5", "CF-8": "cf8", "CF-13": "cf13", "TF-1": "tf1",
            "TF-2": "tf2", "TF-4": "tf4", "VTT3": "vtt3"}
SIZES = tuple(float(s) for s in range(50, 131))


@dataclass(frozen=True)
class MeshSpacing:
    """h_c of a wall's concrete at one element size: area-weighted mean, median, range."""

    element_size: float
    area_mean: float
    median: float
    low: float
    high: float
    n_elements: int


def concrete_spacing(deck_path: str, overrides: list[str], profile: str | None = None
                     ) -> MeshSpacing:
    """eq. 4.3 h_c over the concrete elements of a deck (with overrides and profile)."""
    deck = load_deck(deck_path, overrides, profile).deck
    mesh = build_mesh(deck)
    h = gauss_point_spacing(mesh.points, mesh.cells, deck.analysis.gauss)
    tags = [r.tag for r in mesh.regions if r.kind == "concrete"]
    hc = h[np.isin(mesh.cell_region, tags)]
    area = (deck.analysis.gauss * hc) ** 2  # an element's area is about (n h_c)^2
    return MeshSpacing(deck.analysis.element_size, float((hc * area).sum() / area.sum()),
                       float(np.median(hc)), float(hc.min()), float(hc.max()), int(hc.size))


def nearest_element_size(deck_path: str, target: float, profile: str | None = None,
                         sizes=SIZES) -> MeshSpacing:
    """The element size of `sizes` whose area-weighted mean h_c is nearest `target` (the
    smallest such size where several give the same mesh)."""
    best: MeshSpacing | None = None
    for size in sizes:
        spacing = concrete_spacing(deck_path, [f"analysis.element_size={size}"], profile)
        if best is None or abs(spacing.area_mean - target) < abs(best.area_mean - target):
            best = spacing
    assert best is not None
    return best


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default=None, help="profile applied first (e.g. thesis)")
    parser.add_argument("--decks", default="decks", help="directory of the shipped decks")
    args = parser.parse_args(argv)
    print(f"{'wall':<7}{'Table 4.4':>10}{'size':>7}{'area mean':>11}{'median':>8}"
          f"{'range':>14}{'elements':>10}")
    for name, stem in ANALYSED.items():
        s = nearest_element_size(f"{args.decks}/{stem}.yaml", TABLE_4_4_H_C[name],
                                 args.profile)
        print(f"{name:<7}{TABLE_4_4_H_C[name]:>10.1f}{s.element_size:>7.0f}{s.area_mean:>11.2f}"
              f"{s.median:>8.2f}{f'{s.low:.1f}-{s.high:.1f}':>14}{s.n_elements:>10d}")


if __name__ == "__main__":
    main()
