"""The Mesh data class: nodes, cells, named sets and steel-concrete interface node pairs.

Coordinates: x along the span (x = 0 at midspan), y upward (y = 0 at the underside of the
bottom plate); for axisymmetric models x is the radius r and y the axis z. Units: mm.
Cells use the icewall node order (= gmsh's): corners counter-clockwise 0-3, then for quad8 the
mid-side nodes 4 (edge 0-1), 5 (1-2), 6 (2-3), 7 (3-0). Edges are stored as
(start corner, end corner[, mid-side node]), gmsh's line/line3 order.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

# Region kinds. Interfaces (double nodes) exist wherever a "concrete" region meets any other.
CONCRETE, STEEL, ELASTIC = "concrete", "steel", "elastic"


@dataclass(frozen=True)
class Region:
    """A named material region of the section (one gmsh physical surface)."""

    name: str
    kind: str  # CONCRETE | STEEL | ELASTIC
    tag: int  # value stored in Mesh.cell_region


@dataclass(frozen=True)
class Mesh:
    """A 2D mesh of quadrilaterals with named node/edge sets and interface node pairs."""

    points: np.ndarray  # (n_nodes, 2) float, mm
    cells: np.ndarray  # (n_el, 4 | 8) int, icewall node order
    cell_type: str  # "quad4" | "quad8"
    cell_region: np.ndarray  # (n_el,) int, Region.tag of each cell
    regions: tuple[Region, ...]
    node_sets: dict[str, np.ndarray] = field(default_factory=dict)  # name -> (k,) node ids
    edge_sets: dict[str, np.ndarray] = field(default_factory=dict)  # name -> (k, 2 | 3) nodes
    # Steel-concrete interface: (n_pairs, 2) = (non-concrete node, concrete node), coincident.
    interface_pairs: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), dtype=int))
    # (n_pairs, 2) unit normal pointing from the steel side into the concrete; at a core corner
    # the normalised sum of the two face normals (interface_corner marks those pairs).
    interface_normals: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    interface_corner: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))

    @property
    def n_nodes(self) -> int:
        return int(self.points.shape[0])

    @property
    def n_cells(self) -> int:
        return int(self.cells.shape[0])

    @property
    def nodes_per_cell(self) -> int:
        return int(self.cells.shape[1])

    def region(self, name: str) -> Region:
        for reg in self.regions:
            if reg.name == name:
                return reg
        raise KeyError(name)

    def cells_of_kind(self, kind: str) -> np.ndarray:
        """Boolean mask (n_el,) of the cells whose region is of `kind`."""
        tags = [r.tag for r in self.regions if r.kind == kind]
        return np.isin(self.cell_region, tags)
