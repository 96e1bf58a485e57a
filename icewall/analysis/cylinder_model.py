"""The standard concrete cylinder of the thesis' Appendix A, axisymmetric, under platen control.

Quarter model (the thesis gives no size; specimens.md: take the standard 150 x 300 mm
cylinder): 0 <= r <= 75 (x), 0 <= z <= 150 (y), mid-height plane at z = 0. Supports: u_r = 0
on the axis, u_z = 0 on the mid-height plane. The loaded end is the rigid loading head of
Fig. A.4: all its nodes share one u_z equation (the control equation, "constrained to move as a
straight line"); with ``platen="fixed"`` u_r = 0 there too ("fixed to reflect no slip"),
``"frictionless"`` leaves u_r free (the uniform-stress verification case).

The model goes the walls' path: a `ModelDescription` (the deck's own `Concrete`, `Analysis`
and `Control` sections) and a `Model`, whose problem `build_problem` makes as for every wall,
solved by `icewall.solve.path.follow_path` (displacement control, eqs. 3.44-3.50). Its result is
the average stress P / (pi R^2) against the average strain delta / (H / 2), compression > 0.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from icewall.deck.analysis_options import Analysis
from icewall.deck.schema import Concrete, Control
from icewall.errors import ConvergenceError
from icewall.fem.assembly import Assembler
from icewall.fem.dofs import DofMap
from icewall.fem.kinematics import element_kinematics, gauss_point_spacing
from icewall.fem.quadrature import gauss_rule
from icewall.mesh.mesh import CONCRETE, Mesh
from icewall.mesh.structured import rectangle_mesh
from icewall.model.build import Model
from icewall.model.description import ModelDescription
from icewall.solve.path import follow_path
from icewall.solve.problem import Problem, build_problem
from icewall.solve.settings import solver_settings
from icewall.solve.state import PathState

DIAMETER = 150.0  # mm, standard cylinder (specimens.md; the thesis gives no size)
HEIGHT = 300.0  # mm
GAUSS = 3  # 3 x 3 Gauss rule of quad8, as in the wall analyses


@dataclass(frozen=True)
class CylinderCase:
    """One analysis: f'c (MPa), nx x ny quad8 over the quarter, input descending area A_cd
    (MPa; k_c = f'c / A_cd, eq. 3.27 corrected; None keeps eq. 3.34), platen condition and
    further `Concrete` deck fields (e.g. {"model": "elastic"})."""

    fc: float
    nx: int
    ny: int
    input_area: float | None = None
    platen: str = "fixed"  # fixed (no slip, Fig. A.4) | frictionless
    concrete: dict[str, Any] = field(default_factory=dict)

    @property
    def axial_spacing(self) -> float:
        """Gauss-point spacing along the axis, (H/2) / (3 ny), mm."""
        return 0.5 * HEIGHT / (GAUSS * self.ny)


@dataclass(frozen=True)
class CylinderModel:
    """The quarter cylinder as a model (the walls' `Model`, with the study's own description
    and mesh) and the problem `follow_path` solves (`build_problem`, as for the walls)."""

    case: CylinderCase
    model: Model
    problem: Problem

    @property
    def mesh(self) -> Mesh:
        return self.model.mesh

    @property
    def gauss_spacing(self) -> np.ndarray:
        """(n_el,) h_c of eq. 4.3."""
        return self.model.gauss_spacing

    @property
    def area(self) -> float:
        return math.pi * (0.5 * DIAMETER) ** 2


def cylinder_description(case: CylinderCase, increment: float = 0.01, target: float = 1.0,
                         **analysis: Any) -> ModelDescription:
    """Concrete, analysis (axisymmetric quad8, 3x3; `analysis` overrides) and control."""
    concrete = dict(case.concrete)
    if case.input_area is not None:
        concrete["k_c"] = case.fc / case.input_area  # A_cd = sigma_c / k_c (3.27, errata)
    return ModelDescription(
        {"concrete": Concrete(fc=case.fc, **concrete)},
        Analysis(formulation="axisymmetric", element="quad8", gauss=GAUSS, **analysis),
        Control(increment=increment, target=target))


def build_cylinder(case: CylinderCase, **analysis: Any) -> CylinderModel:
    """Mesh, equations (the head's u_z one equation), supports and the control equation."""
    if case.platen not in ("fixed", "frictionless"):
        raise ValueError(f"platen must be 'fixed' or 'frictionless', got {case.platen!r}")
    description = cylinder_description(case, **analysis)
    mesh = rectangle_mesh(0.0, 0.5 * DIAMETER, 0.0, 0.5 * HEIGHT, case.nx, case.ny, "quad8",
                          region_name="concrete", kind=CONCRETE)
    head = mesh.node_sets["top"]
    dof_map = DofMap(mesh.n_nodes, shared=((head, 1),))  # "moves as a straight line"
    kin = element_kinematics(mesh.points, mesh.cells, "quad8", gauss_rule(GAUSS),
                             "axisymmetric", 1.0, dof_map)
    fixed = [dof_map.equations(mesh.node_sets["left"], 0),  # axis: u_r = 0
             dof_map.equations(mesh.node_sets["bottom"], 1)]  # mid-height: u_z = 0
    if case.platen == "fixed":
        fixed.append(dof_map.equations(head, 0))  # no slip under the loading head
    platen = int(dof_map.equations(head[:1], 1)[0])
    reference = np.zeros(dof_map.n_equations)
    reference[platen] = -1.0  # unit downward head force: the load factor is the force P (N)
    model = Model(
        deck=None, description=description, mesh=mesh, dof_map=dof_map, kinematics=kin,
        assembler=Assembler(kin.dofs, dof_map.n_equations),
        cell_material=np.full(mesh.n_cells, "concrete"),
        gauss_spacing=gauss_point_spacing(mesh.points, mesh.cells, GAUSS),
        fixed=np.unique(np.concatenate(fixed)), reference_load=reference, preload=None,
        control_equation=platen, measure_name="P", measure_unit="N", measure_factor=1.0)
    return CylinderModel(case, model, build_problem(model))


@dataclass(frozen=True)
class CylinderCurve:
    """Average stress-strain response of one analysis (compression positive)."""

    strain: np.ndarray  # (m,) head displacement / (H/2), row 0 the origin
    stress: np.ndarray  # (m,) head force / (pi R^2), MPa
    iterations: np.ndarray  # (m,) per increment
    snap_throughs: int  # load drops accepted at the smallest step (analysis.on_snap_back)
    jumps: int  # non-converged increments stepped over (analysis.max_jumps)
    stopped: str  # "" or why the solver stopped early
    run_time: float  # s
    gauss_stress: np.ndarray  # (n_el, nq, 4) at the last step
    displacement: np.ndarray  # (n_nodes, 2) at the last step
    gauss_spacing: np.ndarray = field(default_factory=lambda: np.zeros(0))  # (n_el,) eq. 4.3

    @property
    def peak_index(self) -> int:
        return int(np.argmax(self.stress))

    @property
    def peak_stress(self) -> float:
        return float(self.stress[self.peak_index])

    @property
    def strain_at_peak(self) -> float:
        return float(self.strain[self.peak_index])

    def descending_area(self) -> float:
        """A_c to the last point: trapezoids under the curve from the peak (MPa)."""
        k = self.peak_index
        s, e = self.stress[k:], self.strain[k:]
        return float(np.sum(0.5 * (s[1:] + s[:-1]) * np.diff(e)))

    def tail_area(self, fraction: float = 0.2) -> float:
        """Area beyond the last point for an exponential tail sigma_end / lambda, lambda the
        log-slope of the last `fraction` of the descending strain range (MPa; 0 if the curve
        does not decay there)."""
        k = self.peak_index
        e, s = self.strain[k:], self.stress[k:]
        tail = (e >= e[-1] - fraction * (e[-1] - e[0])) & (s > 0.0)
        if e.size < 3 or tail.sum() < 2 or s[-1] <= 0.0:
            return 0.0
        slope = -np.polyfit(e[tail], np.log(s[tail]), 1)[0]
        return float(s[-1] / slope) if slope > 0.0 else 0.0


def run_cylinder(case: CylinderCase, stages: tuple[tuple[float, float], ...] = ((0.003, 1e-4),),
                 end_stress_ratio: float = 0.0, **analysis: Any) -> CylinderCurve:
    """Drive the head through `stages` of (average strain reached, strain increment), each a
    displacement-control stage of the solver (steps over a stall: `analysis` max_jumps and
    jump_increments, as for the walls). Stops after the peak once the average stress falls
    below `end_stress_ratio` times the peak, at the end of the last stage, or when the solver
    stops (`stopped` says why)."""
    half = 0.5 * HEIGHT
    model = build_cylinder(case, **analysis)
    state = PathState(np.zeros(model.model.dof_map.n_equations), 0.0,
                      model.problem.structure.initial_states())
    strain, stress, iterations, snaps, jumped = [0.0], [0.0], [0], 0, 0
    stopped, tic, done = "", time.perf_counter(), False
    for target, step in stages:
        settings = replace(solver_settings(model.model.description), increment=step * half,
                           target=target * half)
        try:
            for inc, reached in follow_path(model.problem, settings, state):
                state = reached
                strain.append(inc.control_displacement / half)
                stress.append(inc.load_factor / model.area)
                iterations.append(inc.iterations)
                snaps += int(inc.snap_back)
                jumped += int(inc.jumped)
                done = stress[-1] < end_stress_ratio * max(stress)
                if done:
                    break
        except ConvergenceError as exc:
            stopped = f"{exc.reason}: {exc}"
        if stopped or done:
            break
    last = state.evaluation
    return CylinderCurve(
        np.array(strain), np.array(stress), np.array(iterations), snaps, jumped, stopped,
        time.perf_counter() - tic,
        gauss_stress=np.zeros((0, 0, 4)) if last is None else last.stress,
        displacement=model.model.dof_map.expand(state.u),
        gauss_spacing=model.gauss_spacing)
