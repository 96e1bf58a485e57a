"""Path following: the one loop of every iteration scheme, a generator of converged increments
so that the writer keeps every converged step on disk.

The scheme (`settings.scheme`, solve/schemes.py) names the stages of the path - the in-plane
preload by load control where there is one, then the control to the target deflection - and
makes each an object of the `Stage` protocol: it proposes and iterates the next increment
from the committed state, decides what follows a failed one (a cut, another iteration, a
switch of the control, or the end of the run: ConvergenceError) and completes a converged one
(its flags, the size of the next step), and keeps where it stands as a typed cursor that the
state after each step holds whole (solve/state.py; the checkpoint writes it field by field).
The loop rolls a failed step back, commits a converged one and yields it; `resume` goes on
from the stage and cursor of the state given (an interrupted run's last converged step).
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from dataclasses import replace
from typing import TYPE_CHECKING, Protocol

import numpy as np

from icewall.errors import ConvergenceError
from icewall.solve.problem import Problem
from icewall.solve.state import Increment, PathState, StepFailed, next_state

if TYPE_CHECKING:
    from icewall.solve.settings import SolverSettings


class Stage(Protocol):
    """A stage of the path under an iteration scheme."""

    direction: np.ndarray | None  # the last increment's displacements, where it keeps them

    def done(self, state: PathState) -> bool:
        """Whether the stage has reached its end at `state`."""

    def step(self, state: PathState) -> Increment:
        """Propose the next increment from the committed `state` and iterate it to
        convergence; StepFailed or ConvergenceError where it does not converge or is not
        accepted (the loop rolls the constraints back)."""

    def failed(self, exc: StepFailed | ConvergenceError, state: PathState) -> None:
        """The next try after a failed step; ConvergenceError where none is left."""

    def converged(self, state: PathState, inc: Increment) -> Increment:
        """The committed increment complete (its flags), the next step's size and control."""

    def cursor(self):
        """Where the stage goes on from the step just taken (a typed, copied value)."""

    def stop(self) -> None:
        """After a converged step is on disk: ConvergenceError where the stage ends there."""


def follow_path(problem: Problem, settings: SolverSettings, initial: PathState,
                resume: bool = False) -> Iterator[tuple[Increment, PathState]]:
    """Every stage of `settings.scheme` from `initial` to the target deflection; `resume`
    goes on from where `initial.cursor` says."""
    scheme, state = settings.scheme, initial
    cursor = initial.cursor if resume else None
    names = scheme.stages(problem)
    if cursor is not None and cursor.stage not in names:
        raise ValueError(f"no {cursor.stage} stage to resume in this problem ({names})")
    for name in names[0 if cursor is None else names.index(cursor.stage):]:
        stage = scheme.stage(name, problem, settings, state, cursor)
        cursor = None
        for inc, reached in _follow(problem, stage, state):
            state = reached
            yield inc, state


def _follow(problem: Problem, stage: Stage, state: PathState
            ) -> Iterator[tuple[Increment, PathState]]:
    """One stage: try, roll back and retry, or commit and yield, until it is done."""
    c = problem.constraints
    while not stage.done(state):
        tic = time.perf_counter()
        try:
            inc = stage.step(state)
        except (StepFailed, ConvergenceError) as exc:
            c.rollback()
            stage.failed(exc, state)
            continue
        c.commit()
        inc = stage.converged(state, replace(inc, wall_time=time.perf_counter() - tic))
        state = next_state(problem, state, inc, stage.cursor(), stage.direction)
        yield inc, state
        stage.stop()
