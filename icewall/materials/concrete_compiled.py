"""Optional numba kernel of the concrete update and of the iteration moduli (extra `compiled`).

`compiled_update` is `update_concrete` (without moduli) point by point in compiled code,
`compiled_substepped` its sub-stepped form, `compiled_floored_moduli` is
`concrete_law.floored_moduli`: the same arithmetic in the same order and NumPy's own exp and
arctan2, so the same results bit for bit where NumPy's einsum and BLAS sum in the order copied
here (x86-64; checked with AVX-512, NumPy 2.4 and its OpenBLAS), else to round-off (see
concrete_kernels_compiled). The NumPy implementation stays the reference. Plane strain and
axisymmetric, corotational and incremental trial stresses; CF-4 (1125 points): 0.35 ms per
update with moduli against NumPy's 2.5 ms.

`ICEWALL_CONCRETE_KERNEL` = numpy | numba | auto (default) chooses (`choose_kernel`): auto is
numba where it imports and covers the case; numba asked for where it cannot be had falls back
to numpy with a warning. numba is imported on first use only, never by `import icewall`.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import fields
from functools import cache
from types import ModuleType
from typing import Any

import numpy as np

from icewall.materials import concrete, orthotropic, uniaxial
from icewall.materials.concrete import matrix_secant
from icewall.materials.concrete_state import ConcreteState
from icewall.materials.rotation import continuous_axes, resolved_stress
from icewall.materials.substep import update_concrete_substepped

KERNEL_VARIABLE = "ICEWALL_CONCRETE_KERNEL"
KERNELS = ("numpy", "numba")
COMPILED_FORMULATIONS = ("plane_strain", "axisymmetric")
TRIAL_STRESSES = ("corotational", "incremental")


@cache
def numba_installed() -> bool:
    """Whether numba imports here (tried once, only when asked)."""
    try:
        import numba  # noqa: F401
    except Exception:  # a broken optional install counts as absent
        return False
    return True


def supported(formulation: str, trial_stress: str) -> bool:
    """Whether the kernel covers this formulation and trial stress."""
    return formulation in COMPILED_FORMULATIONS and trial_stress in TRIAL_STRESSES


def available(formulation: str = "plane_strain", trial_stress: str = "corotational") -> bool:
    """numba imports and the kernel covers the case."""
    return supported(formulation, trial_stress) and numba_installed()


def choose_kernel(formulation: str, trial_stress: str, requested: str | None = None) -> str:
    """`requested`, else $ICEWALL_CONCRETE_KERNEL, else auto: "numba" or "numpy"."""
    name = (requested or os.environ.get(KERNEL_VARIABLE) or "auto").strip().lower()
    if name == "auto":
        return "numba" if available(formulation, trial_stress) else "numpy"
    if name not in KERNELS:
        raise ValueError(f"unknown concrete kernel {name!r}; expected auto or one of {KERNELS}")
    if name == "numba" and not available(formulation, trial_stress):
        why = (f"it covers {', '.join(COMPILED_FORMULATIONS)} with "
               f"{', '.join(TRIAL_STRESSES)} trial stresses, not {formulation} with "
               f"{trial_stress}" if numba_installed()
               else "numba is not installed (pip install icewall[compiled])")
        warnings.warn(f"concrete kernel 'numba': {why}; using numpy", RuntimeWarning,
                      stacklevel=2)
        return "numpy"
    return name


@cache
def _kernels() -> ModuleType:
    from icewall.materials import concrete_kernels_compiled  # numba: the compiled extra

    return concrete_kernels_compiled


def parameter_tuple(params: Any) -> tuple[float, ...]:
    """The scalar parameters and the NumPy modules' constants in the kernels' order (P_* of
    concrete_kernels_compiled)."""
    surface = params.surface
    values = [params.E0, params.nu0, params.nu_max, params.fc, params.ft, params.eps_c,
              params.eps_t, params.peak_strain_slope,
              params.compression_tension_rule == "equal", *surface.a, *surface.b,
              surface.sigma_limit, concrete.LOADING_TOLERANCE, uniaxial.SECANT_FLOOR,
              orthotropic.PHI_MIN, orthotropic.ANGLE_TOLERANCE,
              params.mode_rule_band * params.ft, params.post_peak_strength == "peak",
              getattr(params, "fallen_strength", "envelope") == "scaled",
              orthotropic.AXIS_PERIODS[getattr(params, "rotating_axes", "nearest")]]
    return tuple(float(v) for v in values)


def _per_point(value: Any, n: int) -> np.ndarray:
    return np.array(np.broadcast_to(np.asarray(value, dtype=float).reshape(-1), (n,)))


def _kernel_array(value: Any, dtype: type) -> np.ndarray:
    """C-contiguous and writable (one compiled signature for every call)."""
    if (isinstance(value, np.ndarray) and value.dtype == dtype and value.flags.c_contiguous
            and value.flags.writeable):
        return value
    return np.require(value, dtype, ("C", "W"))


def _state_arrays(state: ConcreteState) -> tuple[np.ndarray, ...]:
    return tuple(_kernel_array(getattr(state, f.name),
                               bool if f.name in ("cracked", "crushed") else float)
                 for f in fields(ConcreteState))


def compiled_update(strain: np.ndarray, state: ConcreteState, params: Any, formulation: str,
                    trial_stress: str = "incremental", frozen: np.ndarray | None = None
                    ) -> tuple[np.ndarray, ConcreteState]:
    """Stress (n, 4) and trial state of `update_concrete(strain, state, params, formulation,
    trial_stress, frozen)`. Parameters other than h_c, k_t, k_c must be scalars."""
    if not supported(formulation, trial_stress):
        raise ValueError(f"the compiled concrete kernel does not cover {formulation} with "
                         f"{trial_stress} trial stresses")
    kernels = _kernels()
    strain = _kernel_array(np.reshape(strain, (-1, 4)), float)
    n = strain.shape[0]
    S = _state_arrays(state)
    out = tuple(np.empty_like(a) for a in S)
    prm, k_t, k_c = parameter_tuple(params), _per_point(params.k_t, n), _per_point(params.k_c, n)
    mask = np.zeros(n, dtype=bool) if frozen is None else _kernel_array(frozen, bool)
    work, flags = np.empty((n, kernels.N_WORK, 3)), np.empty((n, kernels.N_FLAGS, 3), dtype=bool)
    exponent = np.empty((n, 3))
    scaled = getattr(params, "fallen_strength", "envelope") == "scaled"
    exponent_at_max = np.zeros((n, 3)) if scaled else exponent  # written only when scaled
    lode_x, lode_y = np.empty(n), np.empty(n)
    # NumPy's arctan2 and exp between the passes, as principal_strain_angle, lode_angle and
    # softening_stress call them (SIMD code where NumPy has it: no libm call matches it)
    kernels.trial_pass(strain, orthotropic.major_strain_angle(strain), S, mask, frozen is not None,
                       trial_stress == "corotational", formulation == "plane_strain", prm, k_t,
                       k_c, out, work, flags, exponent)
    kernels.ray_pass(S, prm, work, flags, np.exp(-exponent), lode_x, lode_y)
    kernels.strength_pass(S, prm, k_t, k_c, work, flags, np.arctan2(lode_y, lode_x), exponent,
                          exponent_at_max)
    decayed = np.exp(-exponent)
    kernels.finish_pass(S, mask, frozen is not None, prm, work, flags, decayed,
                        np.exp(-exponent_at_max) if scaled else decayed, out)
    trial = ConcreteState(*out)
    if continuous_axes(params):  # the returned stress; the state keeps the law's
        return resolved_stress(trial, state, params, formulation, _update, trial_stress,
                               frozen), trial
    return out[1], trial


def _update(strain: np.ndarray, state: ConcreteState, params: Any, formulation: str,
            trial_stress: str = "incremental", frozen: np.ndarray | None = None,
            with_moduli: bool = False) -> tuple[np.ndarray, None, ConcreteState]:
    """`compiled_update` with `update_concrete`'s signature and result (no moduli)."""
    stress, trial = compiled_update(strain, state, params, formulation, trial_stress, frozen)
    return stress, None, trial


def compiled_substepped(strain: np.ndarray, state: ConcreteState, params: Any,
                        formulation: str, max_strain_step: float, max_substeps: int = 32,
                        trial_stress: str = "incremental", frozen: np.ndarray | None = None
                        ) -> tuple[np.ndarray, ConcreteState]:
    """`update_concrete_substepped` (without moduli) over `compiled_update`: the same
    sub-steps, targets and merging (substep.py runs them)."""
    stress, _, trial = update_concrete_substepped(
        strain, state, params, formulation, max_strain_step, max_substeps, trial_stress,
        frozen, with_moduli=False, update=_update)
    return stress, trial


def compiled_floored_moduli(state: ConcreteState, params: Any, formulation: str, floor: float,
                            coaxial: bool = False, returned_secant: bool = False) -> np.ndarray:
    """`concrete_law.floored_moduli` (n, 4, 4) for plane strain and axisymmetric."""
    if formulation not in COMPILED_FORMULATIONS:
        raise ValueError(f"the compiled moduli do not cover {formulation}")
    secant = matrix_secant(state) if returned_secant else state.secant_modulus
    arrays = [_kernel_array(secant, float)]  # the E_i of floored_moduli
    arrays += [_kernel_array(getattr(state, name), float) for name in (
        "poisson_ratio", "shear_modulus", "stress", "strain", "angle")]
    return _kernels().floored_moduli_points(*arrays, float(params.E0), float(params.nu0),
                                            float(floor), bool(coaxial),
                                            float(orthotropic.PHI_MIN))
