"""What a deck will cost before anything is meshed: steps, elements, equations, memory, output
size and run time, from the geometry and the analysis settings alone (`estimate`).

`icewall check` and `icewall run` (every deck load, through deck.validate) refuse a deck that
cannot finish on this machine; `analysis.allow_large: true` turns each refusal into a warning
for those who mean it. The figures are order-of-magnitude estimates (calibrated on CF-4, quad8,
3x3 Gauss: 199 elements -> 821 nodes, 1642 equations, about 130 kB of output and 0.03-0.07 s
per iteration), not measurements.
"""

from __future__ import annotations

import math
import os
import shutil
from dataclasses import dataclass
from pathlib import Path

from icewall.deck.physical import physical_warnings
from icewall.deck.schema import Deck

MAX_STEPS = 100_000
"""Control plus preload steps above which a run is refused (a day at 1 s per step)."""
MAX_ELEMENTS = 200_000
"""Elements above which a mesh is refused (about 1.2 million equations)."""
MAX_RUNS = 10_000
"""Runs of one sweep above which it is refused (icewall.analysis.sweep.check_run_count)."""
HOURS_WARNING = 1.0
"""Estimated run time (hours) above which check and run warn."""
NONLINEAR_ITERATIONS_PER_STEP = 30
"""Typical equilibrium iterations per step of the nonlinear solver (CF-4 to 40 mm: 10-80)."""
BYTES_PER_FLOAT = 8
PROCESS_BYTES = 3e8
"""The process itself with NumPy, SciPy and numba loaded (peak RSS of the shipped CF-4 run to
40 mm: 294 MB, nearly all of it this)."""
GAUSS_COMPONENTS = {"stress": 4, "strain": 4, "state": 8}  # state: 6 int8 flags + 2 floats
NODES_PER_ELEMENT = {"quad8": 3.0, "quad4": 1.0}  # structured grid, interior share per element
DOFS_PER_ELEMENT = {"quad8": 16, "quad4": 8}


@dataclass(frozen=True)
class Estimate:
    """Order-of-magnitude cost of one run of a deck."""

    n_steps: int | float    # control steps + preload increments, no cuts (float: absurd)
    n_steps_with_cuts: int | float  # every control step cut max_step_cuts times (worst case)
    n_elements: int | float
    n_equations: int | float
    memory_bytes: float     # stiffness, factors, Gauss-point state, per-step arrays
    output_bytes: float     # the HDF5 result: stored fields x stored steps + history
    hours: float            # run time at the typical iteration count


def _grid_elements(deck: Deck) -> float:
    """Elements of a structured grid of element_size over the section (a lower bound: the
    mesh also follows every plate, diaphragm and patch edge)."""
    geo, size = deck.geometry, deck.analysis.element_size
    length = geo.half_length * (1 if geo.model == "half" else 2)
    height = geo.depth + max([leg.height for leg in geo.legs], default=0.0)
    return (length / size + 1) * (height / size + 1)


def estimate(deck: Deck) -> Estimate:
    """Steps, elements, equations, memory, output size and run time of one run of `deck`."""
    analysis, control = deck.analysis, deck.loads.control
    n_control = _count(control.target / control.increment - 1e-9)
    n_preload = analysis.preload_increments if deck.loads.preload is not None else 0
    n_steps = n_control + n_preload
    n_el = _grid_elements(deck)
    n_nodes = NODES_PER_ELEMENT[analysis.element] * n_el * 1.1  # + interface node pairs
    n_eq = 2.0 * n_nodes
    n_qp = n_el * analysis.gauss ** 2
    # stiffness (~40 entries a row) and its assembly triplets; LU factors of a 2D mesh under a
    # fill-reducing ordering grow as n log n (nested dissection, George 1973): 16 n log2 n
    # entries for L and U; values 8 bytes, indices 4
    matrix = 12.0 * 40 * n_eq + 16.0 * DOFS_PER_ELEMENT[analysis.element] ** 2 * n_el
    factors = 12.0 * 16 * n_eq * math.log2(max(n_eq, 2.0))
    gauss_state = BYTES_PER_FLOAT * 60 * n_qp * 3  # committed, trial, iteration copies
    per_step = BYTES_PER_FLOAT * 24 * n_steps      # history columns (the linear path too)
    fields = set(deck.outputs.fields)
    step_bytes = BYTES_PER_FLOAT * (2 * n_nodes * ("displacement" in fields)
                                    + n_qp * sum(GAUSS_COMPONENTS[f] for f in fields
                                                 if f in GAUSS_COMPONENTS))
    memory = (PROCESS_BYTES + matrix + factors + gauss_state + per_step
              + 2 * step_bytes)  # a step's fields in flight
    n_stored = n_steps / deck.outputs.every
    output = step_bytes * n_stored + BYTES_PER_FLOAT * 24 * n_steps + 64.0 * n_nodes
    its = NONLINEAR_ITERATIONS_PER_STEP if analysis.solver == "nonlinear" else 1
    # seconds per iteration: Python overhead, element loops (vectorized), sparse factorization
    per_iteration = 0.02 + 1.5e-4 * n_el + 1e-8 * min(n_eq, 1e100) ** 1.5  # (no overflow)
    hours = n_steps * its * per_iteration / 3600.0
    return Estimate(n_steps=n_steps, n_steps_with_cuts=n_preload + n_control * 2 **
                    analysis.max_step_cuts, n_elements=_count(n_el), n_equations=_count(n_eq),
                    memory_bytes=memory, output_bytes=output, hours=hours)


def _count(value: float) -> int | float:
    """ceil(value), kept a float where it is beyond any int a run could reach (an absurd
    element size or increment gives 1e300 or inf)."""
    return math.ceil(value) if value < 1e18 else float(value)


def available_memory() -> float | None:
    """Bytes of memory available to a new process (Linux MemAvailable), None if unknown."""
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024.0
    except OSError:
        pass
    try:
        return float(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return None


def free_disk(directory: str | os.PathLike) -> float | None:
    """Free bytes on the file system that `directory` (or its nearest existing parent) is on."""
    path = Path(directory).absolute()
    while not path.exists() and path != path.parent:
        path = path.parent
    try:
        return float(shutil.disk_usage(path).free)
    except OSError:
        return None


def _size(n_bytes: float) -> str:
    for unit, scale in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n_bytes >= scale:
            return f"{n_bytes / scale:.3g} {unit}"
    return f"{n_bytes:.0f} B"


def refusals(deck: Deck, est: Estimate | None = None) -> list[tuple[str, str]]:
    """(message, key path) of every limit the deck exceeds on this machine (memory, but not the
    output disk, which depends on where the result goes: output_refusal)."""
    est = est or estimate(deck)
    out = []
    if est.n_steps > MAX_STEPS:
        out.append((f"about {est.n_steps:.3g} steps (target / increment; limit {MAX_STEPS:.0e}): "
                    "the run would not finish", "loads.control.increment"))
    if est.n_elements > MAX_ELEMENTS:
        out.append((f"element size {deck.analysis.element_size:g} mm gives at least "
                    f"{est.n_elements:.3g} elements (limit {MAX_ELEMENTS:.0e}); is the unit mm?",
                    "analysis.element_size"))
    memory = available_memory()
    if memory is not None and est.memory_bytes > memory:
        out.append((f"the run needs about {_size(est.memory_bytes)} of memory, this machine has "
                    f"{_size(memory)} available", "analysis.element_size"))
    return out


def output_refusal(deck: Deck, directory: str | os.PathLike,
                   est: Estimate | None = None) -> str | None:
    """Why the result will not fit on the disk of `directory`, or None."""
    est = est or estimate(deck)
    free = free_disk(directory)
    if free is None or est.output_bytes <= free:
        return None
    return (f"the result needs about {_size(est.output_bytes)} ({len(deck.outputs.fields)} "
            f"fields x {est.n_steps:.3g} steps / outputs.every {deck.outputs.every}), "
            f"{directory} has {_size(free)} free")


def warnings_for(deck: Deck, est: Estimate | None = None) -> list[str]:
    """One line each: a long run, with analysis.allow_large each limit it exceeds, with
    analysis.allow_unphysical each value outside its physical range (deck.physical)."""
    est = est or estimate(deck)
    out = physical_warnings(deck)
    if deck.analysis.allow_large:
        out += [f"{message} (allowed by analysis.allow_large)" for message, _ in refusals(
            deck, est)]
    if est.hours > HOURS_WARNING:
        out.append(f"about {est.n_steps:.3g} steps (up to {est.n_steps_with_cuts:.3g} with "
                   f"step cuts) of about {est.n_equations:.3g} equations: expect about "
                   f"{est.hours:.2g} h")
    return out
