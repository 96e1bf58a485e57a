"""What the pipeline checks of a run before its solver starts, the same for every scheme (issue
38, item 4), and how it keeps NumPy's floating-point warnings from the user.

* ``check_initial_system``: the deck's initial elastic system (the initial moduli, interface
  pairs tied: the linear solver's model) is factorised and loaded once with the patch loads,
  through the linear solver's own checks (solve.linear: pivots against their diagonals, a
  finite solution; solve.linear_static: the loads move the control point). A singular or
  zero-stiffness system stops every scheme (linear, secant, newton) here with the same
  ConvergenceError (reason "singular system"), before any file is written. Tying the pairs
  only adds stiffness, so a deck this refuses has no equilibrium under gap elements either.
* ``floating_point_guard``: NumPy's overflow / invalid / divide warnings of the run are
  counted instead of printed (np.errstate "call"; no value is changed) and reported as one
  line by the caller.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import replace

import numpy as np

from icewall.deck.schema import Deck
from icewall.errors import ConvergenceError
from icewall.mesh.mesh import Mesh
from icewall.model.build import Model, build_model
from icewall.solve.linear_static import run_linear


def check_initial_system(deck: Deck, mesh: Mesh, materials: dict[str, str],
                         model: Model | None = None) -> None:
    """ConvergenceError(reason="singular system") when the deck's initial elastic system
    (interface pairs tied) is singular or its patch loads do not move the control point.
    `model`: the run's own, reused where it is the linear one."""
    if model is None or deck.analysis.solver != "linear":
        tied = replace(deck, analysis=replace(deck.analysis, solver="linear"))
        model = build_model(tied, mesh, materials)
    try:
        with np.errstate(all="ignore"):
            first = next(run_linear(model, want_fields=False), None)
    except ConvergenceError as exc:
        raise ConvergenceError(f"the deck's initial elastic system (initial moduli, interface "
                               f"pairs tied) has no solution: {exc}; is a modulus or a "
                               "thickness far outside its physical range?",
                               reason="singular system") from None
    if first is not None and not (np.isfinite(first.load_factor) and first.load_factor != 0):
        raise ConvergenceError("the deck's initial elastic system carries no load at the first "
                               f"increment (jack load {first.load_factor:g} N): no stiffness",
                               reason="singular system")


@contextmanager
def floating_point_guard() -> Iterator[dict[str, int]]:
    """Count NumPy's floating-point errors ("overflow", "invalid value", "divide by zero")
    in the block instead of warning about each; yields the counts (filled as it runs)."""
    counts: dict[str, int] = {}

    def count(kind: str, flag: int) -> None:
        counts[kind] = counts.get(kind, 0) + 1

    with np.errstate(over="call", invalid="call", divide="call", under="ignore", call=count):
        yield counts


def floating_point_note(counts: dict[str, int]) -> str:
    """One line for the counts of floating_point_guard ("" where there were none)."""
    if not counts:
        return ""
    what = ", ".join(f"{n} {kind}" for kind, n in sorted(counts.items()))
    return (f"NumPy floating-point errors during the analysis ({what}); values that large or "
            "undefined mean a modulus, a size or a load far outside its range, so check the "
            "result")
