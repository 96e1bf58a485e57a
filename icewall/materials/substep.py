"""Sub-stepping of the hypoelastic concrete update (thesis Fig. 3.12).

The update integrates the trial stress with the committed moduli over the whole strain
increment (forward Euler). Over a large increment that is inaccurate: a crack that opens
within the increment keeps coupling into the other directions with its uncracked Poisson ratio
until the end, which builds spurious out-of-plane stress (and spurious out-of-plane cracks)
in plane strain. Splitting the increment into sub-steps of at most `max_strain_step`
(measured as the largest strain-increment component of the point) bounds that error; only the
points with large increments pay for it.
"""

from __future__ import annotations

from dataclasses import fields
from typing import Any

import numpy as np

from icewall.materials.concrete import take_parameters, update_concrete
from icewall.materials.concrete_state import ConcreteState


def update_concrete_substepped(strain: np.ndarray, state: ConcreteState, params: Any,
                               formulation: str, max_strain_step: float,
                               max_substeps: int = 32, trial_stress: str = "incremental",
                               frozen: np.ndarray | None = None
                               ) -> tuple[np.ndarray, np.ndarray, ConcreteState]:
    """`update_concrete` over sub-steps of at most `max_strain_step` per point (pure)."""
    if trial_stress == "total" or frozen is not None:  # no sub-steps needed / allowed
        return update_concrete(strain, state, params, formulation, trial_stress, frozen)
    strain = np.asarray(strain, dtype=float).reshape(-1, 4)
    n = strain.shape[0]
    increment = strain - state.strain
    if formulation != "axisymmetric":
        increment[:, 2] = 0.0  # zz is not an input in plane strain / plane stress
    size = np.abs(increment).max(axis=1)
    n_sub = np.clip(np.ceil(size / max_strain_step), 1, max_substeps).astype(int)
    if n_sub.max() == 1:
        return update_concrete(strain, state, params, formulation)
    stress, moduli, trial = update_concrete(strain, state, params, formulation)
    many = np.flatnonzero(n_sub > 1)
    current = state.take(many)
    sub_params = take_parameters(params, many, n)
    start = state.strain[many] + 0.0
    steps = n_sub[many]
    for j in range(1, int(steps.max()) + 1):
        fraction = np.minimum(j / steps, 1.0)[:, None]
        target = start + fraction * (strain[many] - start)
        if formulation == "plane_stress":
            target[:, 2] = current.strain[:, 2]
        sig, D, new = update_concrete(target, current, sub_params, formulation)
        done = j > steps  # finished points keep their state
        current = new.select(~done, current) if done.any() else new
        if j == int(steps.max()):
            stress[many], moduli[many] = sig, D
    merged = {f.name: getattr(trial, f.name).copy() for f in fields(ConcreteState)}
    for name, value in merged.items():
        value[many] = getattr(current, name)
    return stress, moduli, ConcreteState(**merged)
