"""Load vectors and the reported load measure of a wall deck."""

from __future__ import annotations

import numpy as np

from icewall.deck.schema import Deck
from icewall.fem.loads import edge_traction_loads
from icewall.mesh.mesh import Mesh


def patch_load_vector(deck: Deck, mesh: Mesh) -> np.ndarray:
    """Nodal forces (2 n_nodes,) of a unit jack load P = 1 N on every patch (downward).

    Each patch spreads P uniformly over its width x b; a patch cut by the symmetry line of a
    half model carries the half that lies in the model.
    """
    patches = deck.loads.patches
    pressure = 1.0 / (patches.width * deck.geometry.width)
    edges = np.concatenate([e for name, e in mesh.edge_sets.items() if name.startswith("patch_")])
    return edge_traction_loads(mesh.points, edges, (0.0, -pressure),
                               deck.analysis.formulation, deck.geometry.width)


def preload_vector(deck: Deck, mesh: Mesh) -> np.ndarray | None:
    """Nodal forces of the in-plane axial force N on the wall ends, or None without preload."""
    if deck.loads.preload is None:
        return None
    stress = deck.loads.preload.axial_force / (deck.geometry.depth * deck.geometry.width)
    f = edge_traction_loads(mesh.points, mesh.edge_sets["end_right"], (stress, 0.0),
                            deck.analysis.formulation, deck.geometry.width)
    if "end_left" in mesh.edge_sets:
        f += edge_traction_loads(mesh.points, mesh.edge_sets["end_left"], (-stress, 0.0),
                                 deck.analysis.formulation, deck.geometry.width)
    return f


def jack_count(deck: Deck) -> int:
    """Number of jacks on the whole (mirrored) specimen."""
    return sum(1 if x == 0 else 2 for x in deck.loads.patches.positions)


def load_measure(deck: Deck) -> tuple[str, str, float]:
    """(name, unit, factor) with reported load = factor * P (P = one jack load in N)."""
    measure = deck.loads.measure
    if measure.kind == "intensity":
        return "w", "MPa", 1.0 / (deck.geometry.width * measure.tributary_length)
    return "total load", "N", float(jack_count(deck))
