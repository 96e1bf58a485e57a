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

from collections.abc import Callable
from dataclasses import fields
from typing import Any

import numpy as np

from icewall.materials.concrete import update_concrete
from icewall.materials.concrete_state import ConcreteState
from icewall.materials.parameters import take_parameters


def update_concrete_substepped(strain: np.ndarray, state: ConcreteState, params: Any,
                               formulation: str, max_strain_step: float,
                               max_substeps: int = 32, trial_stress: str = "incremental",
                               frozen: np.ndarray | None = None, with_moduli: bool = True,
                               update: Callable = update_concrete
                               ) -> tuple[np.ndarray, np.ndarray | None, ConcreteState]:
    """`update` (`update_concrete` or its compiled form, same signature) over sub-steps of at
    most `max_strain_step` per point (pure)."""
    if trial_stress != "incremental":  # total / co-rotational trials are not sub-stepped
        return update(strain, state, params, formulation, trial_stress=trial_stress,
                      frozen=frozen, with_moduli=with_moduli)
    strain = np.asarray(strain, dtype=float).reshape(-1, 4)
    n = strain.shape[0]
    increment = strain - state.strain
    if formulation != "axisymmetric":
        increment[:, 2] = 0.0  # zz is not an input in plane strain / plane stress
    size = np.abs(increment).max(axis=1)
    n_sub = np.clip(np.ceil(size / max_strain_step), 1, max_substeps).astype(int)
    # frozen (chatter-damped) points are sub-stepped too: the map must not change form in
    # the middle of an increment when the solver starts to freeze points
    if n_sub.max() == 1:
        return update(strain, state, params, formulation, frozen=frozen,
                      with_moduli=with_moduli)
    stress, moduli, trial = update(strain, state, params, formulation, frozen=frozen,
                                   with_moduli=with_moduli)
    many = np.flatnonzero(n_sub > 1)
    sub_frozen = None if frozen is None else np.asarray(frozen, dtype=bool)[many]
    current = state.take(many)
    sub_params = take_parameters(params, many, n)
    start = state.strain[many] + 0.0
    steps = n_sub[many]
    for j in range(1, int(steps.max()) + 1):
        fraction = np.minimum(j / steps, 1.0)[:, None]
        target = start + fraction * (strain[many] - start)
        if formulation == "plane_stress":
            target[:, 2] = current.strain[:, 2]
        sig, D, new = update(target, current, sub_params, formulation, frozen=sub_frozen,
                             with_moduli=with_moduli)
        done = j > steps  # finished points keep their state
        current = new.select(~done, current) if done.any() else new
        if j == int(steps.max()):
            stress[many] = sig
            if moduli is not None:
                moduli[many] = D
    merged = {f.name: getattr(trial, f.name).copy() for f in fields(ConcreteState)}
    for name, value in merged.items():
        value[many] = getattr(current, name)
    return stress, moduli, ConcreteState(**merged)
