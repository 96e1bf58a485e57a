"""Linear-elastic analysis of a deck, yielded as displacement-controlled steps.

A linear response scales: u = u_pre + P u_ref, where u_pre is the response to the held
preload (if any) and u_ref to a unit jack load on every patch. Step k sets the control
deflection to k * increment and solves for P; one factorisation serves every step.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from icewall.errors import ConvergenceError
from icewall.fem.kinematics import stiffness_blocks, strain
from icewall.materials.elastic import plane_stress_strain_zz
from icewall.model.build import Model, elastic_moduli_per_point, initial_elastic_constants
from icewall.solve.linear import solve_linear


@dataclass(frozen=True)
class LinearStep:
    step: int
    control_displacement: float  # mm, downward positive
    load_factor: float  # jack load P, N
    load: float  # reported measure
    displacement: np.ndarray  # (n_nodes, 2)
    strain: np.ndarray  # (n_el, nq, 4)
    stress: np.ndarray  # (n_el, nq, 4)
    wall_time: float


def run_linear(model: Model, want_fields: bool = True,
               timings: dict[str, float] | None = None) -> Iterator[LinearStep]:
    """Yield the steps of a linear analysis up to the control target.

    `timings`, if given, receives the seconds spent in assembly, solve and field recovery.
    """
    timings = {} if timings is None else timings
    start = time.perf_counter()
    moduli = elastic_moduli_per_point(model)
    poisson = initial_elastic_constants(model.description, model.cell_material,
                                        model.gauss_spacing)[1]
    K = model.assembler.matrix(stiffness_blocks(model.kinematics, moduli))
    timings["assembly"] = time.perf_counter() - start
    rhs = np.column_stack([model.reference_load] +
                          ([model.preload] if model.preload is not None else []))
    u = np.column_stack([solve_linear(K, rhs[:, j], model.fixed) for j in range(rhs.shape[1])])
    u_ref = u[:, 0]
    u_pre = u[:, 1] if u.shape[1] > 1 else np.zeros_like(u_ref)
    timings["solve"] = time.perf_counter() - start - timings["assembly"]
    timings["fields"] = 0.0
    deflection_ref = -u_ref[model.control_equation]
    if not abs(deflection_ref) > 0:
        raise ConvergenceError("the patch loads do not move the control point",
                               reason="singular system")
    control = model.description.control
    n_steps = int(round(control.target / control.increment))
    targets = control.increment * np.arange(1, n_steps + 1)
    targets[-1] = control.target
    for k, target in enumerate(targets, start=1):
        P = (target + u_pre[model.control_equation]) / deflection_ref
        u_eq = u_pre + P * u_ref
        tic = time.perf_counter()
        if want_fields:
            eps = strain(model.kinematics, u_eq)
            sig = np.einsum("eqij,eqj->eqi", moduli, eps)
            if model.description.analysis.formulation == "plane_stress":
                nu = np.broadcast_to(poisson[:, None], eps.shape[:2])
                eps[..., 2] = plane_stress_strain_zz(eps, nu)
            timings["fields"] += time.perf_counter() - tic
        else:
            eps = sig = np.zeros((0, 0, 4))
        yield LinearStep(step=k, control_displacement=float(target), load_factor=float(P),
                         load=float(P * model.measure_factor),
                         displacement=model.dof_map.expand(u_eq), strain=eps, stress=sig,
                         wall_time=time.perf_counter() - start)
