"""Single material-point driver for the concrete model (strain-controlled paths, no mesh).

Paths (control strain t from 0 to max_strain in n_steps, optionally via unloading cycles):

- ``uniaxial-compression`` / ``uniaxial-tension``: eps_xx = -t / +t, sigma_yy = 0.
- ``biaxial:R``: eps_xx = -t with sigma_yy = R sigma_xx (R = 1 equal biaxial compression,
  R < 0 tension-compression); ``biaxial-tension:R``: eps_xx = +t; ``biaxial-strain:R``:
  eps_xx = -t, eps_yy = -R t (strain ratio; follows softening where a stress ratio bifurcates).
- ``pure-shear``: gamma_xy = t, eps_xx = eps_yy = 0 (principal axes at 45 deg).
- ``rotating``: principal strains (0.25 t, -t) reached along x, y in the first half of the
  steps, then the principal axes rotate by 90 deg at fixed principal values.

Plane stress keeps sigma_zz = 0 inside the model; plane strain keeps eps_zz = 0 (sigma_zz
builds up); axisymmetric adds sigma_zz = 0 (hoop) as a further stress condition. Stress
conditions are met by Newton iterations on the free strains with the secant moduli, then the
finite-difference tangent if the secant stalls.
"""

from __future__ import annotations

import csv
from collections.abc import Sequence
from dataclasses import dataclass, fields
from pathlib import Path
from typing import IO, Any

import numpy as np

from icewall.errors import ConvergenceError
from icewall.materials.concrete import concrete_tangent, update_concrete
from icewall.materials.concrete_state import ConcreteState
from icewall.materials.orthotropic import global_strain

PATHS = ("uniaxial-compression", "uniaxial-tension", "biaxial:R", "biaxial-tension:R",
         "biaxial-strain:R", "pure-shear", "rotating")


@dataclass(frozen=True)
class PointResult:
    """History of one material point, one row per converged increment (row 0: virgin)."""

    path: str
    formulation: str
    control: np.ndarray  # (m,) control parameter t
    strain: np.ndarray  # (m, 4)
    stress: np.ndarray  # (m, 4)
    angle: np.ndarray  # (m,) orthotropy angle beta
    equivalent_uniaxial_strain: np.ndarray  # (m, 3)
    secant_modulus: np.ndarray  # (m, 3)
    poisson_ratio: np.ndarray  # (m, 3)
    cracked_in_plane: np.ndarray  # (m,) bool
    cracked_out_of_plane: np.ndarray  # (m,) bool
    crushed: np.ndarray  # (m,) bool
    iterations: np.ndarray  # (m,) int
    stopped: str = ""  # why the path ended early ("" if it reached max_strain)

    def principal_stresses(self) -> np.ndarray:
        """(m, 3) in-plane principal stresses (major, minor) and sigma_zz."""
        centre = 0.5 * (self.stress[:, 0] + self.stress[:, 1])
        radius = np.hypot(0.5 * (self.stress[:, 0] - self.stress[:, 1]), self.stress[:, 3])
        return np.stack([centre + radius, centre - radius, self.stress[:, 2]], axis=1)

    def summary(self) -> dict[str, Any]:
        """Peak (largest magnitude) sigma_xx and the strain there, and the failure mode."""
        peak = int(np.argmax(np.abs(self.stress[:, 0])))
        principal = self.principal_stresses()
        modes = [name for name, flag in (("cracked in plane", self.cracked_in_plane[-1]),
                                         ("cracked out of plane", self.cracked_out_of_plane[-1]),
                                         ("crushed", self.crushed[-1])) if flag]
        return {
            "path": self.path, "formulation": self.formulation,
            "peak_stress_xx": float(self.stress[peak, 0]),
            "strain_at_peak_xx": float(self.strain[peak, 0]),
            "min_principal_stress": float(principal.min()),
            "max_principal_stress": float(principal.max()),
            "final_stress": [float(v) for v in self.stress[-1]],
            "failure_mode": ", ".join(modes) if modes else "none",
            "increments": int(self.control.shape[0] - 1),
            "max_iterations": int(self.iterations.max()),
            "stopped": self.stopped,
        }

    def to_csv(self, file: str | Path | IO[str]) -> None:
        """Write one row per increment (header: control, eps_*, sig_*, angle, state)."""
        header = (["control"] + [f"eps_{c}" for c in ("xx", "yy", "zz", "xy")]
                  + [f"sig_{c}" for c in ("xx", "yy", "zz", "xy")] + ["angle"]
                  + [f"eps_u{i}" for i in (1, 2, 3)] + [f"E{i}" for i in (1, 2, 3)]
                  + [f"nu{i}" for i in (1, 2, 3)]
                  + ["cracked_in_plane", "cracked_out_of_plane", "crushed", "iterations"])
        table = np.column_stack([self.control, self.strain, self.stress, self.angle,
                                 self.equivalent_uniaxial_strain, self.secant_modulus,
                                 self.poisson_ratio, self.cracked_in_plane,
                                 self.cracked_out_of_plane, self.crushed, self.iterations])
        if isinstance(file, (str, Path)):  # never through a link, never over another file
            from icewall.safe_write import csv_kind, open_for_write

            with open_for_write(file, csv_kind("material-point table", header)) as handle:
                self._write(handle, header, table)
        else:
            self._write(file, header, table)

    @staticmethod
    def _write(handle: IO[str], header: list[str], table: np.ndarray) -> None:
        writer = csv.writer(handle)
        writer.writerow(header)
        writer.writerows([f"{v:.10g}" for v in row] for row in table)


@dataclass(frozen=True)
class _Path:
    """Strain = prescribed(t) + sum of free components; stress conditions rows @ sigma = 0."""

    kind: str
    free: list[int]
    conditions: np.ndarray  # (len(free), 4)
    sign: float = -1.0
    ratio: float = 0.0

    def prescribed(self, t: float, fraction: float) -> np.ndarray:
        strain = np.zeros(4)
        if self.kind == "biaxial-strain":
            strain[:2] = (-t, -self.ratio * t)
        elif self.kind == "pure-shear":
            strain[3] = t
        elif self.kind == "rotating":
            ramp, turn = min(2.0 * fraction, 1.0), max(2.0 * fraction - 1.0, 0.0)
            theta = 0.5 * np.pi * turn
            strain[:] = global_strain(np.array([[0.25 * t * ramp, -t * ramp, 0.0]]),
                                      np.array([theta]))[0]
        else:
            strain[0] = self.sign * t
        return strain


def _parse_path(path: str, formulation: str) -> _Path:
    kind, _, argument = path.partition(":")
    rows: list[np.ndarray] = []
    free: list[int] = []
    sign, ratio = -1.0, 0.0
    if kind in ("uniaxial-compression", "uniaxial-tension", "biaxial", "biaxial-tension"):
        sign = 1.0 if kind.endswith("tension") else -1.0
        ratio = float(argument) if kind.startswith("biaxial") else 0.0
        if kind.startswith("biaxial") and not argument:
            raise ValueError(f"path {path!r}: give the stress ratio, e.g. 'biaxial:0.5'")
        free.append(1)
        rows.append(np.array([-ratio, 1.0, 0.0, 0.0]))  # sigma_yy - R sigma_xx = 0
    elif kind == "biaxial-strain":
        ratio = float(argument)
    elif kind not in ("pure-shear", "rotating"):
        raise ValueError(f"unknown path {path!r}; expected one of {PATHS}")
    if formulation == "axisymmetric":
        free.append(2)
        rows.append(np.array([0.0, 0.0, 1.0, 0.0]))  # hoop stress zero
    return _Path(kind, free, np.array(rows).reshape(len(free), 4), sign, ratio)


def control_schedule(max_strain: float, n_steps: int, unload_at: Sequence[float] = ()
                     ) -> np.ndarray:
    """Control values t: 0 -> u1 -> 0 -> u2 -> 0 ... -> max_strain, step max_strain / n_steps."""
    step = abs(max_strain) / max(int(n_steps), 1)
    targets: list[float] = []
    for u in sorted(abs(v) for v in unload_at if 0.0 < abs(v) < abs(max_strain)):
        targets += [u, 0.0]
    targets.append(abs(max_strain))
    values, current = [0.0], 0.0
    for target in targets:
        count = max(int(round(abs(target - current) / step)), 1)
        values.extend(np.linspace(current, target, count + 1)[1:])
        current = target
    return np.array(values)


def _solve_increment(path: _Path, prescribed: np.ndarray, guess: np.ndarray,
                     state: ConcreteState, params: Any, formulation: str,
                     tolerance: float, max_iterations: int, trial_stress: str = "corotational"
                     ) -> tuple[np.ndarray, np.ndarray, ConcreteState, int]:
    """Free strains meeting the stress conditions; Newton with the secant, then the tangent."""
    strain = prescribed.copy()
    strain[path.free] = guess
    for iteration in range(max_iterations):
        stress, moduli, trial = update_concrete(strain[None], state, params, formulation,
                                                trial_stress)
        if not path.free:
            return strain, stress[0], trial, iteration
        residual = path.conditions @ stress[0]
        if np.abs(residual).max() <= tolerance:
            return strain, stress[0], trial, iteration
        if iteration >= max_iterations // 3:  # secant stalls (e.g. softening): tangent
            moduli = concrete_tangent(strain[None], state, params, formulation,
                                      trial_stress=trial_stress)
        jacobian = path.conditions @ moduli[0][:, path.free]
        try:
            correction = np.linalg.solve(jacobian, residual)
        except np.linalg.LinAlgError:
            break
        if not np.all(np.isfinite(correction)):
            break
        strain[path.free] -= correction
    raise ConvergenceError(f"material point: stress conditions not met after {iteration + 1} "
                           f"iterations (residual {np.abs(residual).max():.3g} MPa)")


def run_path(path: str, params: Any, formulation: str = "plane_stress", n_steps: int = 400,
             max_strain: float = 0.006, unload_at: Sequence[float] = (),
             tolerance: float = 1e-12, max_iterations: int = 60, strict: bool = False,
             trial_stress: str = "corotational") -> PointResult:
    """Drive one point along `path` (see module docstring); returns every converged increment.

    tolerance is relative to f'c on the stress conditions. If an increment finds no state
    meeting them (e.g. a stress-ratio path past a softening bifurcation) the path stops there
    and `stopped` says why; strict=True raises ConvergenceError instead. `trial_stress` is
    the concrete update's Fig. 3.12 step-3 form (the deck's `trial_stress`).
    """
    spec = _parse_path(path, formulation)
    schedule = control_schedule(max_strain, n_steps, () if spec.kind == "rotating" else unload_at)
    state = ConcreteState.initial(1, params)
    records: dict[str, list[Any]] = {f.name: [] for f in fields(PointResult)[2:-1]}

    def record(t: float, stress: np.ndarray, s: ConcreteState, iterations: int) -> None:
        for name, value in (("control", t), ("strain", s.strain[0]), ("stress", stress),
                            ("angle", s.angle[0]),
                            ("equivalent_uniaxial_strain", s.equivalent_uniaxial_strain[0]),
                            ("secant_modulus", s.secant_modulus[0]),
                            ("poisson_ratio", s.poisson_ratio[0]),
                            ("cracked_in_plane", s.cracked_in_plane[0]),
                            ("cracked_out_of_plane", s.cracked_out_of_plane[0]),
                            ("crushed", s.crushed_any[0]), ("iterations", iterations)):
            records[name].append(value)

    record(0.0, np.zeros(4), state, 0)
    stopped = ""
    free = np.zeros(len(spec.free))
    previous_free = free.copy()
    for k, t in enumerate(schedule[1:], start=1):
        guess = 2.0 * free - previous_free  # linear extrapolation of the free strains
        prescribed = spec.prescribed(float(t), k / (len(schedule) - 1))
        try:
            strain, stress, state_new, iterations = _solve_increment(
                spec, prescribed, guess, state, params, formulation,
                tolerance * float(params.fc), max_iterations, trial_stress)
        except ConvergenceError as error:
            if strict:
                raise
            stopped = f"increment {k} (control {t:.6g}): {error}"
            break
        previous_free, free = free, strain[spec.free]
        state = state_new  # commit the converged trial state
        record(float(t), stress, state, iterations)
    arrays = {name: np.array(values) for name, values in records.items()}
    return PointResult(path=path, formulation=formulation, **arrays, stopped=stopped)
