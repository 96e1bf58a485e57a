"""Solver settings taken from a deck, with the thesis' choices as the reference: the limits
every scheme reads, and the scheme itself (icewall.solve.schemes), which owns its own."""

from __future__ import annotations

from dataclasses import dataclass, field

from icewall.deck.schema import Deck
from icewall.model.description import ModelDescription
from icewall.solve.schemes import Dynamic, Newton, Secant, scheme_of


@dataclass(frozen=True)
class SolverSettings:
    tolerance_displacement: float  # eq. 4.4
    tolerance_load: float  # eq. 4.5
    max_iterations: int
    max_step_cuts: int  # halvings of a failed increment before the run stops (or drops)
    increment: float  # control displacement increment, mm
    target: float  # final control displacement, mm
    preload_increments: int  # load-control increments of the in-plane preload
    reset_slip_each_step: bool  # thesis 3.3.4: slipped pairs start each step fixed
    on_snap_back: str = "continue"  # stop | continue (accept the drop, recorded per step)
    # the iteration scheme with its own settings: Secant | Newton | Dynamic
    scheme: Secant | Newton | Dynamic = field(default_factory=Secant)


def solver_settings(description: ModelDescription) -> SolverSettings:
    """The settings of the description's analysis and control sections."""
    a, c = description.analysis, description.control
    return SolverSettings(
        tolerance_displacement=a.tolerance_displacement, tolerance_load=a.tolerance_load,
        max_iterations=a.max_iterations, max_step_cuts=a.max_step_cuts,
        increment=c.increment, target=c.target, preload_increments=a.preload_increments,
        reset_slip_each_step=description.interface.reset_slip_each_step,
        on_snap_back=a.on_snap_back, scheme=scheme_of(a, c))


def scheme_warnings(deck: Deck) -> list[str]:
    """One line each: deck settings under which the chosen scheme is known not to converge."""
    if deck.analysis.solver == "linear":
        return []
    return scheme_of(deck.analysis, deck.loads.control).warnings(deck)
