"""Solver settings taken from a deck, with the thesis' choices as the reference."""

from __future__ import annotations

from dataclasses import dataclass

from icewall.deck.analysis_options import CONVERGED_TOLERANCE
from icewall.deck.schema import Deck
from icewall.model.description import ModelDescription


@dataclass(frozen=True)
class SolverSettings:
    tolerance_displacement: float  # eq. 4.4
    tolerance_load: float  # eq. 4.5
    max_iterations: int
    max_step_cuts: int  # halvings of a failed increment before the run stops
    stiffness_update: str  # every_iteration | every_step
    increment: float  # control displacement increment, mm
    target: float  # final control displacement, mm
    preload_increments: int  # load-control increments of the in-plane preload
    reset_slip_each_step: bool  # thesis 3.3.4: slipped pairs start each step fixed
    acceleration: str = "halving"  # relaxation of the corrections: halving | aitken | none
    max_flag_changes: int = 4  # flag changes of a Gauss point in an increment before freezing
    on_snap_back: str = "continue"  # stop | continue (accept the drop, recorded per step)
    max_relaxation: float = 1.0  # largest relaxation factor of the halving scheme
    max_jumps: int = 0  # failed smallest control steps retried as one step of ...
    jump_increments: float = 2.0  # ... this many increments
    # concrete E_i of the iteration matrix: committed (the trial state's secants) | returned
    # (never stiffer than the stress the update returned: a fallback, control._schemes)
    iteration_secant: str = "committed"
    scheme: str = "secant"  # secant (the thesis' iteration) | newton (solve/path.py)
    target_iterations: int = 6  # Newton: iterations per step the step-size controller aims at
    trace_snap_backs: bool = False  # Newton: trace a snap-back (opening control) before a drop
    drop_held: str = "deflection"  # Newton: a drop holds the deflection | the stroke
    drops: str = "viscous"  # Newton: viscous | dynamic (a drop's physics)
    damping_ratio: float = 0.05  # Newton: a dynamic drop's damping at the first mode
    spectral_radius: float = 0.5  # Newton: generalized-alpha rho_inf of the dynamic drops
    time_step_scale: float = 1.0  # Newton: factor on every time step of a dynamic drop


def solver_settings(description: ModelDescription) -> SolverSettings:
    """The settings of the description's analysis and control sections."""
    a, c = description.analysis, description.control
    return SolverSettings(
        tolerance_displacement=a.tolerance_displacement, tolerance_load=a.tolerance_load,
        max_iterations=a.max_iterations, max_step_cuts=a.max_step_cuts,
        stiffness_update=a.stiffness_update, increment=c.increment, target=c.target,
        preload_increments=a.preload_increments,
        reset_slip_each_step=description.interface.reset_slip_each_step,
        acceleration=a.acceleration, max_flag_changes=a.max_flag_changes,
        on_snap_back=a.on_snap_back, max_relaxation=a.max_relaxation, max_jumps=a.max_jumps,
        jump_increments=a.jump_increments,
        scheme=a.scheme, trace_snap_backs=a.trace_snap_backs, drop_held=c.drop_held,
        drops=a.drops, damping_ratio=a.damping_ratio, spectral_radius=a.spectral_radius,
        time_step_scale=a.time_step_scale)


def scheme_warnings(deck: Deck) -> list[str]:
    """One line each: deck settings under which the chosen scheme is known not to converge."""
    if deck.analysis.scheme != "newton" or deck.analysis.solver == "linear":
        return []
    warnings = []
    loosest = max(deck.analysis.tolerance_load, deck.analysis.tolerance_displacement)
    if loosest > CONVERGED_TOLERANCE:
        warnings.append(f"analysis.scheme newton with a tolerance of {loosest:g}: its figures "
                        f"are converged equilibria only at {CONVERGED_TOLERANCE:g} or tighter "
                        "(the scheme's default); at 1e-3 TF-1's peak is 5.8 % off "
                        "(docs/solver.md, items 25 and 27)")
    concrete = deck.materials.concrete
    if concrete.mode_rule_band == 0.0:
        worse = (" (compression_tension_rule equal: also the confined compressive strength)"
                 if concrete.compression_tension_rule == "equal" else "")
        warnings.append("analysis.scheme newton with materials.concrete.mode_rule_band 0: the "
                        "3.2.5 mode rules make the concrete strengths jump where a principal "
                        f"stress changes sign{worse}, and Newton need not converge next to such "
                        "a point (docs/solver.md, items 7, 10 and 18); mode_rule_band 0.1 "
                        "blends them over a band of 0.1 f't")
    if concrete.post_peak_strength == "ray":
        warnings.append("analysis.scheme newton with materials.concrete.post_peak_strength "
                        "ray: the strengths of a direction past its peak move with the other "
                        "stresses, its stress jumps where it turns from unloading to loading "
                        "after they have fallen, and a drop's iteration may stall there "
                        "(docs/solver.md, items 21 and 22); post_peak_strength peak keeps them")
    interface = deck.materials.interface
    preload = deck.loads.preload
    if (preload is not None and preload.axial_force > 0.0 and interface.model == "gap"
            and interface.fixed_points_per_core == 0):
        warnings.append("analysis.scheme newton with an in-plane tension preload and no fixed "
                        "points: every interface pair opens, the cores float and the first "
                        "preload step is singular (docs/solver.md, item 11); the secant scheme "
                        "runs it")
    return warnings
