"""The solver state: the committed solution the path goes on from (`PathState`), a converged
increment as the writer and the reporting need it (`Increment`), and where a scheme's stage
stands (its cursor: `SecantCursor`, `PreloadCursor`, `solve.mode.Mode`), which the state holds
whole and the checkpoint writes and reads field by field (solve/checkpoint.py)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from icewall.model.structure import Evaluation


@dataclass(frozen=True)
class PathState:
    """Committed solution: displacements, load factor (jack load P, N), material states."""

    u: np.ndarray
    load_factor: float
    states: tuple[Any, ...]
    evaluation: Evaluation | None = None
    preload_factor: float = 0.0  # fraction of the in-plane preload applied
    load_scale: float = 0.0  # largest external-load norm reached: the eq. 4.5 reference
    # where the scheme's stage goes on from here (a typed cursor, None before the first step);
    # follow_path(..., resume=True) continues an interrupted run from it
    cursor: Any = None
    # the displacements of the increment that led here (the Newton predictor's direction)
    last_increment: np.ndarray | None = None


@dataclass(frozen=True)
class Increment:
    """A converged increment as the writer and the reporting need it, built complete (the
    path's stages add their flags with dataclasses.replace)."""

    kind: str  # "preload" | "control"
    control_displacement: float
    load_factor: float
    preload_factor: float
    iterations: int
    displacement_norm: float
    load_norm: float
    evaluation: Evaluation
    u: np.ndarray
    forensics: dict[str, list[int]] = field(default_factory=dict)
    cuts: int = 0
    wall_time: float = 0.0
    snap_back: bool = False  # the load dropped in a jump displacement control cannot follow
    jumped: bool = False  # a step over a stall (the secant scheme's max_jumps, jump_increments)
    # a dynamic drop's work terms summed over its time steps (solve.energy.DropEnergy): the
    # energy account takes them instead of one trapezoid from the drop's start to its end
    path_energy: Any = None


class StepFailed(Exception):
    """An increment did not converge (reason in .reason); the caller may cut the step."""

    def __init__(self, message: str, reason: str) -> None:
        super().__init__(message)
        self.reason = reason


@dataclass(frozen=True)
class SecantCursor:
    """Where a stage of the secant scheme goes on: its stage, the control deflection (or
    preload fraction) reached, the next step size, the largest load factor of the stage (the
    snap-back check) and the steps over a stall made so far (a resumed run makes no more than
    `analysis.max_jumps` in all)."""

    kind: ClassVar[str] = "secant"
    stage: str  # "preload" | "control"
    position: float
    size: float
    peak: float
    jumps: int = 0


@dataclass(frozen=True)
class PreloadCursor:
    """Where the Newton scheme's preload stage goes on: the preload fraction reached and the
    next step size."""

    kind: ClassVar[str] = "preload"
    stage: ClassVar[str] = "preload"
    position: float
    size: float


def _norm(x: np.ndarray) -> float:
    return float(np.sqrt(x @ x))


def external_force_norm(constraints, applied: np.ndarray, internal: np.ndarray) -> float:
    """|| applied loads on the free equations, reactions on the supported ones ||."""
    reactions = internal[constraints.fixed]
    return float(np.sqrt(_norm(applied) ** 2 + reactions @ reactions))


def next_state(problem, state: PathState, inc: Increment, cursor,
               last_increment: np.ndarray | None = None) -> PathState:
    """The committed state after `inc` from `state`: its eq. 4.5 reference never less than
    the external force system reached (applied loads and reactions), `cursor` where the stage
    goes on."""
    c = problem.constraints
    applied = c.restrict(inc.load_factor * problem.reference_load + (
        0.0 if problem.preload is None else inc.preload_factor * problem.preload))
    scale = max(state.load_scale, external_force_norm(c, applied,
                                                      inc.evaluation.internal_force))
    return PathState(inc.u, inc.load_factor, inc.evaluation.states, inc.evaluation,
                     inc.preload_factor, scale, cursor, last_increment)
