"""Assemble the linear model of a deck: dof map, kinematics, moduli, supports and loads."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from icewall.deck.schema import Deck
from icewall.fem.assembly import Assembler
from icewall.fem.dofs import DofMap
from icewall.fem.kinematics import ElementKinematics, element_kinematics, gauss_point_spacing
from icewall.fem.quadrature import gauss_rule
from icewall.materials.elastic import elastic_moduli
from icewall.mesh.mesh import Mesh
from icewall.model.description import MATERIAL_KEYS, ModelDescription
from icewall.model.loads import load_measure, patch_load_vector, preload_vector
from icewall.model.materials import initial_elastic


@dataclass(frozen=True)
class Model:
    """Everything the solvers need, built once per run: from a wall deck (`build_model`) or
    from a study's own description and mesh (the cylinder of thesis Appendix A)."""

    deck: Deck | None  # the wall deck it was built from; None for a study's own model
    description: ModelDescription  # what the laws, constraints and solver settings read
    mesh: Mesh
    dof_map: DofMap
    kinematics: ElementKinematics
    assembler: Assembler
    cell_material: np.ndarray  # (n_el,) deck material key of each cell
    gauss_spacing: np.ndarray  # (n_el,) h_c, eq. 4.3
    fixed: np.ndarray  # constrained equation ids (value 0)
    reference_load: np.ndarray  # (n_eq,) unit jack load on every patch
    preload: np.ndarray | None  # (n_eq,) in-plane load, held during displacement control
    control_equation: int  # u_y of the control node (deflection = -u)
    measure_name: str
    measure_unit: str
    measure_factor: float  # reported load = factor * jack load P

    @property
    def separating_preload(self) -> bool:
        """The first load is an in-plane tension (loads.preload.axial_force > 0): the plates
        stretch away from the cores, and the concrete separates from the steel (thesis
        4.2.2)."""
        preload = None if self.deck is None else self.deck.loads.preload
        return preload is not None and preload.axial_force > 0.0


def cell_materials(deck: Deck, mesh: Mesh, materials_of_region: dict[str, str]) -> np.ndarray:
    names = np.array([materials_of_region[r.name] for r in
                      sorted(mesh.regions, key=lambda r: r.tag)])
    return names[mesh.cell_region]


def initial_elastic_constants(description: ModelDescription, cell_material: np.ndarray,
                              gauss_spacing: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Initial E and nu per cell (model.materials.initial_elastic of each material)."""
    E = np.empty(len(cell_material))
    nu = np.empty(len(cell_material))
    for key in MATERIAL_KEYS:
        sel = cell_material == key
        if sel.any():
            E[sel], nu[sel] = initial_elastic(key, description.materials[key],
                                              float(np.mean(gauss_spacing[sel])))
    return E, nu


def build_model(deck: Deck, mesh: Mesh, materials_of_region: dict[str, str]) -> Model:
    """Build the model. Interface pairs get gap elements in the nonlinear analysis; the linear
    analysis ties them (perfect bond)."""
    analysis = deck.analysis
    ties = mesh.interface_pairs if analysis.solver == "linear" else None
    dof_map = DofMap(mesh.n_nodes, ties=ties)
    kin = element_kinematics(mesh.points, mesh.cells, mesh.cell_type, gauss_rule(analysis.gauss),
                             analysis.formulation, deck.geometry.width, dof_map)
    cell_material = cell_materials(deck, mesh, materials_of_region)
    spacing = gauss_point_spacing(mesh.points, mesh.cells, analysis.gauss)
    fixed = [dof_map.equations(mesh.node_sets.get("symmetry", np.zeros(0, int)), 0)]
    for i, sup in enumerate(deck.geometry.supports, start=1):
        nodes = mesh.node_sets[f"support_{i}"]
        fixed.append(dof_map.equations(nodes, 1))
        if sup.restraint == "pin":
            fixed.append(dof_map.equations(nodes, 0))
    preload = preload_vector(deck, mesh)
    name, unit, factor = load_measure(deck)
    return Model(
        deck=deck, description=ModelDescription.of_deck(deck), mesh=mesh, dof_map=dof_map,
        kinematics=kin,
        assembler=Assembler(kin.dofs, dof_map.n_equations), cell_material=cell_material,
        gauss_spacing=spacing, fixed=np.unique(np.concatenate(fixed)),
        reference_load=dof_map.restrict(patch_load_vector(deck, mesh)),
        preload=None if preload is None else dof_map.restrict(preload),
        control_equation=int(dof_map.equations(mesh.node_sets["control"], 1)[0]),
        measure_name=name, measure_unit=unit, measure_factor=factor)


def elastic_moduli_per_point(model: Model) -> np.ndarray:
    """(n_el, nq, 4, 4) initial elastic moduli."""
    E, nu = initial_elastic_constants(model.description, model.cell_material,
                                      model.gauss_spacing)
    D = elastic_moduli(E, nu, model.description.analysis.formulation)  # (n_el, 4, 4)
    nq = model.kinematics.dV.shape[1]
    return np.broadcast_to(D[:, None], (len(E), nq, 4, 4))
