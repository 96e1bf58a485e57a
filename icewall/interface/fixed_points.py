"""Where the permanently fixed interface pairs stand: thesis 4.3.2's "fixed points", used "to
keep the core inside the steel plates" (Fig. 4.15, which showed them, is lost). A deck's
`materials.interface` names the placements (`fixed_point_placement`) and how many pairs per core
(`fixed_points_per_core`); `fixed_point_mask` gives the permanent pairs the gap elements
(`icewall.interface.gap.GapState`) hold FIXED."""

from __future__ import annotations

import numpy as np

from icewall.deck.schema import FIXED_POINT_PLACEMENTS
from icewall.mesh.mesh import CONCRETE, Mesh


def fixed_point_mask(mesh: Mesh, interface) -> np.ndarray | None:
    """Permanent pairs (n_pairs,) bool of a deck's ``materials.interface`` (its
    fixed_points_per_core and fixed_point_placement), or None where it asks for none."""
    placement = tuple(getattr(interface, "fixed_point_placement", ("top",)))
    per_core = interface.fixed_points_per_core
    if per_core == 0 and "corners" not in placement:
        return None
    chosen = np.zeros(len(mesh.interface_pairs), dtype=bool)
    for where in placement:
        chosen |= choose_fixed_points(mesh, per_core=per_core, placement=where)
    return chosen


def _node_cores(mesh: Mesh) -> np.ndarray:
    """Concrete region tag of each node (-1 for a node of no core)."""
    node_region = np.full(mesh.n_nodes, -1)
    concrete = mesh.cells_of_kind(CONCRETE)
    node_region[mesh.cells[concrete]] = mesh.cell_region[concrete][:, None]
    return node_region


def _pair_cores(mesh: Mesh) -> np.ndarray:
    """Concrete region tag of each pair's concrete node (-1 for none)."""
    return _node_cores(mesh)[mesh.interface_pairs[:, 1]]


def _bottom_support_points(mesh: Mesh, per_core: int, tol: float) -> np.ndarray:
    """On the bottom face (normal (0, +1), over the bottom plate; corners excluded), the
    `per_core` pairs nearest each support's x on either side of it (the cores next to the
    support: thesis 5.2, the post-peak stresses "enter the support by means of the diaphragm
    and bottom plates")."""
    pairs, normals = mesh.interface_pairs, mesh.interface_normals
    chosen = np.zeros(len(pairs), dtype=bool)
    bottom = (np.abs(normals[:, 0]) < tol) & (normals[:, 1] > 0) & ~mesh.interface_corner
    bottom &= _pair_cores(mesh) >= 0
    if not bottom.any() or per_core == 0:
        return chosen
    x, y = mesh.points[pairs[:, 1]].T
    bottom &= y <= y[bottom].min() + tol  # the face over the bottom plate, not a leg's top
    supports = [mesh.points[nodes, 0] for name, nodes in mesh.node_sets.items()
                if name.startswith("support")]
    for xs in np.unique(np.concatenate(supports)) if supports else ():
        for side in (x <= xs + tol, x >= xs - tol):  # inward and outward of the support
            candidates = np.flatnonzero(bottom & side)
            order = np.lexsort((x[candidates], np.abs(x[candidates] - xs)))
            chosen[candidates[order[:per_core]]] = True
    return chosen


def choose_fixed_points(mesh: Mesh, per_core: int = 2, tol: float = 1e-6,
                        placement: str = "top") -> np.ndarray:
    """Permanent pairs (n_pairs,) bool, at one `placement` (Fig. 4.15, which showed the
    thesis' fixed points, is lost; 4.3.2 says only "a number of fixed points were used to keep
    the core inside the steel plates"):

    * "top": per concrete region (core), `per_core` top-face pairs. In each core the pairs on
      its TOP interface (normal n = (0, -1), under the loaded top plate; corner pairs excluded)
      nearest the core's mid-length x (for a half-model core cut by the "symmetry" node set,
      the symmetry line, where the full core's mid-length lies). One pair only stops the core
      translating; it can still rotate about that pair when all others are FREE, so the default
      takes the two nearest (adjacent) pairs. A core without a top face falls back to its
      non-corner pairs.
    * "corners": every corner pair, i.e. the core corners at the diaphragm-plate (and end
      plate-plate) junctions; `per_core` does not apply.
    * "bottom_support": `per_core` bottom-face pairs on each side of each support.
    * "station": per core, the `per_core` top-face pairs nearest its mid-length (as "top") and
      as many bottom-face pairs there: the core held at one station across its depth. The
      pins remove its three rigid-body modes (the rotation with the core's depth as lever, not
      the 25 mm between two adjacent top pairs) and, standing at one x, take none of the
      plates' stretch, so an in-plane tension goes through the plates (thesis 4.2.2).
    """
    if placement not in FIXED_POINT_PLACEMENTS:
        raise ValueError(f"unknown fixed-point placement {placement!r} "
                         f"(one of {', '.join(FIXED_POINT_PLACEMENTS)})")
    if placement == "corners":
        return mesh.interface_corner.astype(bool) & (_pair_cores(mesh) >= 0)
    if placement == "bottom_support":
        return _bottom_support_points(mesh, per_core, tol)
    if placement == "station":
        return (_mid_length_points(mesh, per_core, tol, top=True)
                | _mid_length_points(mesh, per_core, tol, top=False))
    return _mid_length_points(mesh, per_core, tol, top=True)


def _mid_length_points(mesh: Mesh, per_core: int, tol: float, top: bool) -> np.ndarray:
    """Per core, the `per_core` pairs of its top face (normal (0, -1), under the top plate; or
    with top=False its bottom face, normal (0, +1)) nearest its mid-length, corner pairs
    excluded; a core without such a face falls back to its non-corner pairs."""
    pairs, normals = mesh.interface_pairs, mesh.interface_normals
    chosen = np.zeros(len(pairs), dtype=bool)
    if len(pairs) == 0:
        return chosen
    node_region = _node_cores(mesh)
    pair_region = node_region[pairs[:, 1]]
    x, y = mesh.points[pairs[:, 1]].T
    side = -1.0 if top else 1.0
    face = (np.abs(normals[:, 0]) < tol) & (side * normals[:, 1] > 0) & ~mesh.interface_corner
    for tag in np.unique(pair_region[pair_region >= 0]):  # loop over cores, not pairs
        core_nodes = np.flatnonzero(node_region == tag)
        on_symmetry = np.intersect1d(core_nodes, mesh.node_sets.get("symmetry", []))
        x_core = mesh.points[on_symmetry if on_symmetry.size else core_nodes, 0]
        x_mid = 0.5 * (x_core.min() + x_core.max())
        in_core = pair_region == tag
        candidates = np.flatnonzero(in_core & face)
        if candidates.size:  # the face at the core's top (bottom), not a step in it
            level = side * y[candidates]
            candidates = candidates[level <= level.min() + tol]
        else:
            candidates = np.flatnonzero(in_core & ~mesh.interface_corner)
        order = np.lexsort((x[candidates], np.abs(x[candidates] - x_mid)))
        chosen[candidates[order[:per_core]]] = True
    return chosen
