"""The rotating-crack concrete law (thesis ch. 3) as the solver calls it: the sub-stepped stress
update (NumPy or compiled), its iteration moduli or consistent tangent, and what the solver and
the writer read from a concrete state."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from icewall.materials import concrete_formulas as formulas
from icewall.materials.concrete import matrix_secant
from icewall.materials.concrete_compiled import compiled_floored_moduli, compiled_substepped
from icewall.materials.concrete_state import ConcreteState
from icewall.materials.concrete_tangent import tangent_of_update, update_with_tangent
from icewall.materials.law import MaterialLaw, Update
from icewall.materials.orthotropic import (
    condense_plane_stress,
    global_moduli,
    local_normal_components,
    orthotropic_normal_stiffness,
)
from icewall.materials.substep import update_concrete_substepped


@dataclass(frozen=True)
class ConcreteLaw(MaterialLaw):
    """Rotating-crack concrete; its points may be frozen (they then only unload or reload)."""

    freezable = True
    secant_moduli = True

    params: Any  # ConcreteParameters, or per-point ConcretePointParameters
    formulation: str
    max_step: float  # sub-step size of the update (a fraction of the cracking strain)
    trial_stress: str
    floor: float  # iteration moduli: E_i, G12 at least floor times their initial values
    coaxial: bool  # iteration moduli: the co-axial shear modulus (coaxial_shear_modulus)
    own_moduli: bool  # iteration moduli built here from the trial state (floored_moduli)
    kernel: str = "numpy"  # the update: numpy, or numba (concrete_compiled)

    def initial_state(self, n: int) -> ConcreteState:
        return ConcreteState.initial(n, self.params)

    def update(self, strain: np.ndarray, state: ConcreteState, frozen: np.ndarray | None = None,
               returned_secant: bool = False, tangent: bool = False) -> Update:
        """`returned_secant`: E_i no stiffer than the secant of the returned stress (a
        fallback of the solver, solve.recovery.fallbacks)."""
        p, formulation = self.params, self.formulation
        if tangent:
            if frozen is not None:
                raise ValueError("the consistent concrete tangent is not defined for frozen "
                                 "points")
            return update_with_tangent(strain, state, p, formulation, self.trial_stress,
                                       self._substepped)
        if self.kernel == "numba":
            stress, trial = compiled_substepped(strain, state, p, formulation, self.max_step,
                                                trial_stress=self.trial_stress, frozen=frozen)
            return stress, compiled_floored_moduli(trial, p, formulation, self.floor,
                                                   self.coaxial, returned_secant), trial
        stress, moduli, trial = update_concrete_substepped(
            strain, state, p, formulation, self.max_step, trial_stress=self.trial_stress,
            frozen=frozen, with_moduli=not self.own_moduli)
        if self.own_moduli:
            moduli = floored_moduli(trial, p, formulation, self.floor, self.coaxial,
                                    returned_secant)
        return stress, moduli, trial

    def _substepped(self, strain, state, p, formulation, trial_stress, with_moduli=False):
        """The update without moduli, as `concrete_tangent` differentiates it."""
        if self.kernel == "numba":
            stress, trial = compiled_substepped(strain, state, p, formulation, self.max_step,
                                                trial_stress=trial_stress)
            return stress, None, trial
        return update_concrete_substepped(strain, state, p, formulation, self.max_step,
                                          trial_stress=trial_stress, with_moduli=with_moduli)

    def tangent_of(self, strain: np.ndarray, stress: np.ndarray, trial: ConcreteState,
                   state: ConcreteState) -> np.ndarray:
        """The consistent tangent at an update already made (concrete_tangent)."""
        return tangent_of_update(strain, stress, trial, state, self.params, self.formulation,
                                 self.trial_stress, self._substepped)

    def flags(self, state: ConcreteState) -> np.ndarray:
        """(n, 10): cracked (3), crushed (3), loading on a descending branch (3; per
        direction: the loading/unloading decision beyond the peak, the classic limit cycle of
        a secant iteration on softening), and which labelling of the principal axes it took
        (the one nearest the committed axes swaps where the axes rotate by 45 degrees)."""
        magnitude = np.abs(state.equivalent_uniaxial_strain)
        softening = ((magnitude >= state.max_equivalent_uniaxial_strain)
                     & (magnitude > np.abs(state.uniaxial_peak_strain)))
        local_strain = local_normal_components(state.strain, state.angle, 1.0)
        major_on_1 = (local_strain[:, 0] >= local_strain[:, 1])[:, None]
        return np.concatenate([state.cracked, state.crushed, softening, major_on_1], axis=1)

    def counts(self, state: ConcreteState) -> dict[str, int]:
        """Points cracked in plane, out of plane, and crushed (softening)."""
        return {"cracked_in_plane": int(np.count_nonzero(state.cracked_in_plane)),
                "cracked_out_of_plane": int(np.count_nonzero(state.cracked_out_of_plane)),
                "crushed": int(np.count_nonzero(state.crushed_any))}

    def state_fields(self, state: ConcreteState) -> dict[str, np.ndarray]:
        """concrete_flags (n, 6) int8: cracked 1-3, crushed 1-3; orthotropy_angle (n, 1), rad."""
        flags = np.concatenate([state.cracked, state.crushed], axis=1).astype(np.int8)
        return {"concrete_flags": flags, "orthotropy_angle": state.angle.reshape(-1, 1)}

    def cracking(self, state: ConcreteState) -> tuple[np.ndarray, np.ndarray]:
        eps_t = np.broadcast_to(np.asarray(self.params.eps_t, float), (state.strain.shape[0],))
        return eps_t, state.cracked.any(axis=1)

    def crushed(self, state: ConcreteState) -> np.ndarray:
        return state.crushed_any


def coaxial_shear_modulus(state: Any) -> np.ndarray:
    """G = (sigma_1 - sigma_2) / (2 (eps_1 - eps_2)) (errata §3): the shear stiffness that keeps
    stress and strain co-axial, i.e. the one the rotating-crack stress update really has."""
    s, e = state.stress, state.strain
    with np.errstate(divide="ignore", invalid="ignore"):
        return formulas.coaxial_shear_modulus(s[:, 0], s[:, 1], s[:, 3], e[:, 0], e[:, 1],
                                              e[:, 3], state.shear_modulus)


def floored_moduli(state: Any, params: Any, formulation: str, floor: float,
                   coaxial: bool = False, returned_secant: bool = False) -> np.ndarray:
    """Secant moduli of `state` with E_i and G12 held above `floor` times their initial values.

    Only the iteration matrix changes, never the stresses: a fully cracked point (E_i, and by
    eq. 3.21 G12, near zero) would otherwise leave the secant stiffness matrix nearly singular
    and the iteration wandering through near-mechanisms. `returned_secant`: E_i no stiffer than
    the secant of the stress the update returned (concrete.matrix_secant; a fallback of the
    solver, solve.recovery.fallbacks).
    """
    E0, nu0 = float(params.E0), float(params.nu0)
    secant = matrix_secant(state) if returned_secant else state.secant_modulus
    normal = orthotropic_normal_stiffness(np.maximum(secant, floor * E0), state.poisson_ratio,
                                          tuple(getattr(params, "printed_forms", ())))
    if formulation == "plane_stress":
        normal = condense_plane_stress(normal)
    G0 = E0 / (2.0 * (1.0 + nu0))
    shear = coaxial_shear_modulus(state) if coaxial else state.shear_modulus
    shear = np.clip(shear, floor * G0, G0)
    return global_moduli(normal, shear, state.angle)
