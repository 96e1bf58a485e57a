"""Interface state map: every steel-concrete pair at its position, stick / slip / open."""

from __future__ import annotations

import numpy as np

from icewall.errors import ResultError
from icewall.post.figures import draw_wall, legend_above, step_title, wall_figure
from icewall.results.reader import FieldMissing

# gap-element states as stored in /steps/N/interface/state (icewall.interface.gap)
STATES = {0: ("stick", "tab:green", "s"), 1: ("slip", "tab:orange", ">"),
          2: ("open", "tab:red", "o")}


def interface_states(result, step: int) -> tuple[np.ndarray, np.ndarray]:
    """(positions (n_pairs, 2) of the pairs' concrete nodes, states (n_pairs,)) at `step`."""
    mesh = result.mesh
    if not len(mesh.interface_pairs):
        raise ResultError(f"{result.path}: the model has no interface pairs (bonded interface)")
    try:
        state = result.array(step, "interface/state")
    except FieldMissing:
        raise ResultError(f"{result.path}: no interface state stored at step {step} (the "
                          "nonlinear solver stores it with the fields of a step)") from None
    return mesh.points[mesh.interface_pairs[:, 1]], np.asarray(state)


def plot_interface_map(result, step: int):
    """Figure of the interface state of every pair at a stored `step`."""
    xy, state = interface_states(result, step)
    mesh = result.mesh
    fig, (ax,) = wall_figure(mesh)
    draw_wall(ax, mesh, alpha=0.5)
    for code, (name, colour, marker) in STATES.items():
        at = xy[state == code]
        ax.plot(at[:, 0], at[:, 1], marker, ls="none", color=colour, ms=4, zorder=3,
                label=f"{name} ({len(at)})")
    ax.set_title(step_title(result, step, "interface state"), loc="left", pad=22)
    legend_above(ax, ncol=3)
    return fig
