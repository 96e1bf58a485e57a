"""Deck -> Mesh: block layout, gmsh meshing, interface splitting and named sets."""

from __future__ import annotations

import numpy as np

from icewall.deck.schema import Deck
from icewall.mesh.geometry import mesh_layout
from icewall.mesh.interfaces import split_interfaces
from icewall.mesh.layout import build_layout
from icewall.mesh.mesh import CONCRETE, Mesh, Region
from icewall.mesh.sets import build_sets


def build_mesh(deck: Deck) -> Mesh:
    """Mesh the wall of `deck`; steel and concrete get double nodes unless bonded."""
    layout = build_layout(deck)
    cell_type = deck.analysis.element
    points, cells, region_index, names = mesh_layout(layout, cell_type)
    regions = tuple(Region(name, layout.region_kinds[name], tag)
                    for tag, name in enumerate(names))
    kind_of_cell = np.array([layout.region_kinds[names[i]] for i in region_index])
    concrete = kind_of_cell == CONCRETE
    pairs = np.zeros((0, 2), dtype=int)
    normals = np.zeros((0, 2))
    corner = np.zeros(0, dtype=bool)
    if deck.materials.interface.model == "gap" and concrete.any():
        points, cells, pairs, normals, corner = split_interfaces(points, cells, cell_type,
                                                                 concrete)
    node_sets, edge_sets = build_sets(deck, points, cells, cell_type)
    return Mesh(points=points, cells=cells, cell_type=cell_type, cell_region=region_index,
                regions=regions, node_sets=node_sets, edge_sets=edge_sets,
                interface_pairs=pairs, interface_normals=normals, interface_corner=corner)


def region_materials(deck: Deck) -> dict[str, str]:
    """Region name -> deck material key (concrete, steel, bearing_plates, legs)."""
    return dict(build_layout(deck).region_materials)
