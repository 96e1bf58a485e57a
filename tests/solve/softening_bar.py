"""A 1D softening bar built from the FE pieces, for testing path following (not a test)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from icewall.fem.assembly import Assembler
from icewall.fem.dofs import DofMap
from icewall.fem.kinematics import element_kinematics
from icewall.fem.quadrature import gauss_rule
from icewall.materials.law import MaterialLaw
from icewall.mesh.structured import rectangle_mesh
from icewall.model.materials import MaterialGroup
from icewall.model.structure import Structure
from icewall.solve.constraints import SupportConstraints
from icewall.solve.problem import Problem
from icewall.solve.schemes import Secant
from icewall.solve.settings import SolverSettings
from icewall.solve.state import PathState


@dataclass(frozen=True)
class SofteningParams:
    """Linear softening in xx (secant damage), elastic with nu = 0 in the other components."""

    E: float
    strength: np.ndarray  # (n,) per point
    failure_strain: float


def softening_law(strain, kappa, p: SofteningParams):
    eps = strain[:, 0]
    k = np.maximum(kappa, eps)
    peak = p.strength / p.E
    stress_on_envelope = np.where(
        k <= peak, p.E * k,
        np.maximum(p.strength * (p.failure_strain - k) / (p.failure_strain - peak), 1e-9 * p.E * k))
    secant = np.where(k > 0, stress_on_envelope / np.maximum(k, 1e-300), p.E)
    secant = np.minimum(secant, p.E)
    D = np.zeros((len(eps), 4, 4))
    D[:, 0, 0] = secant
    D[:, 1, 1] = D[:, 2, 2] = p.E
    D[:, 3, 3] = 0.5 * p.E
    stress = np.einsum("nij,nj->ni", D, strain)
    return stress, D, k


@dataclass(frozen=True)
class SofteningLaw(MaterialLaw):
    """`softening_law`; the state is the largest strain so far, a point past its peak strain
    is flagged."""

    params: SofteningParams

    def initial_state(self, n: int) -> np.ndarray:
        return np.zeros(n)

    def update(self, strain, state, frozen=None, returned_secant=False, tangent=False):
        return softening_law(strain, state, self.params)

    def flags(self, state: np.ndarray) -> np.ndarray:
        return (state > self.params.strength / self.params.E)[:, None]


def bar_problem(length: float, n_el: int, E=30000.0, strength=3.0, weak=0.9,
                failure_strain=0.002):
    """Bar [0, L] x [0, 10], 1 mm thick, fixed at x = L, pulled at x = 0 in -x."""
    mesh = rectangle_mesh(0.0, length, 0.0, 10.0, n_el, 1, cell_type="quad4")
    dofs = DofMap(mesh.n_nodes)
    kin = element_kinematics(mesh.points, mesh.cells, "quad4", gauss_rule(2), "plane_stress",
                             1.0, dofs)
    strengths = np.full(n_el * 4, strength)
    strengths[:4] = weak * strength  # the element at the loaded end is the weak one
    group = MaterialGroup("bar", np.arange(n_el),
                          SofteningLaw(SofteningParams(E, strengths, failure_strain)))
    structure = Structure(kin, Assembler(kin.dofs, dofs.n_equations), (group,))
    right = mesh.node_sets["right"]
    fixed = np.concatenate([dofs.equations(right, 0), dofs.equations(np.arange(mesh.n_nodes),
                                                                       1)])
    left = mesh.node_sets["left"]
    R = np.zeros(dofs.n_equations)
    R[dofs.equations(left, 0)] = -0.5  # total 1 N pulling in -x
    control = int(dofs.equations(left[:1], 0)[0])
    problem = Problem(structure, SupportConstraints(dofs.n_equations, fixed), R, None, control)
    initial = PathState(np.zeros(dofs.n_equations), 0.0, structure.initial_states())
    return problem, initial


def settings(target: float, increment: float, tolerance: float = 1e-8, iterations: int = 400,
             cuts: int = 4, on_snap_back: str = "stop", **secant) -> SolverSettings:
    """The secant scheme's settings (`secant`: its own, e.g. max_jumps)."""
    return SolverSettings(tolerance_displacement=tolerance, tolerance_load=tolerance,
                          max_iterations=iterations, max_step_cuts=cuts, increment=increment,
                          target=target, preload_increments=1, reset_slip_each_step=True,
                          on_snap_back=on_snap_back, scheme=Secant(**secant))


