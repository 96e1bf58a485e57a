"""The iteration schemes of the nonlinear solver, each an object chosen once from the deck
(`scheme_of`) that owns its settings, its declaration (its name and the defaults of the limits
a deck leaves out: `icewall.schemes`), how the problem is set up for it and the stages of
the path it gives the one path-following loop (solve/path.py):

- `Secant`: the thesis' secant iteration (control.py) with its relaxation and chatter damping,
  and where a smallest step fails, its fallback iterations and steps over a stall;
- `Newton`: Newton-Raphson on the consistent tangent (newton.py), the step size from the
  iteration count, limit points located, and drops at a fixed deflection taken through viscous
  sub-steps (drop.py) or, traced first, under the opening control;
- `Dynamic`: the Newton scheme whose drops are the wall's motion with its own mass, its states
  stable with the stroke held (dynamic.py, stability.py).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from icewall.deck.analysis_options import CONVERGED_TOLERANCE
from icewall.schemes import NEWTON, SECANT, SchemeDeclaration
from icewall.solve.control import SecantStage
from icewall.solve.newton_stages import NewtonControl, NewtonPreload
from icewall.solve.problem import newton_constraints, wall_mass


class _Declared:
    """A scheme's name and defaults, from its declaration (icewall.schemes), and its stages."""

    declaration: ClassVar[SchemeDeclaration]
    inertia: ClassVar[bool] = False  # its drops move the wall's mass (Problem.mass)

    @property
    def name(self) -> str:
        return self.declaration.name

    @property
    def defaults(self):
        """The limits a deck leaves out (analysis.tolerance_*, max_iterations, max_step_cuts)."""
        return self.declaration.defaults

    def stages(self, problem) -> tuple[str, ...]:
        """The stages of the path (solve.path): the preload where there is one, the control."""
        return ("preload", "control") if problem.preload is not None else ("control",)


@dataclass(frozen=True)
class Secant(_Declared):
    """The thesis' secant iteration and its settings (the analysis options of the same names;
    `iteration_secant` is the fallbacks' own, `max_jumps` 0 unless a deck asks for jumps)."""

    declaration: ClassVar[SchemeDeclaration] = SECANT
    stiffness_update: str = "every_iteration"  # every_iteration | every_step
    acceleration: str = "halving"  # relaxation of the corrections: halving | aitken | none
    max_flag_changes: int = 4  # flag changes of a Gauss point in an increment before freezing
    max_relaxation: float = 1.0  # largest relaxation factor of the halving scheme
    max_jumps: int = 0  # failed smallest control steps retried as one step of ...
    jump_increments: float = 2.0  # ... this many increments
    # concrete E_i of the iteration matrix: committed (the trial state's secants) | returned
    # (never stiffer than the stress the update returned: a fallback, recovery.fallbacks)
    iteration_secant: str = "committed"

    @classmethod
    def of(cls, analysis, control_section) -> Secant:
        return cls(stiffness_update=analysis.stiffness_update,
                   acceleration=analysis.acceleration,
                   max_flag_changes=analysis.max_flag_changes,
                   max_relaxation=analysis.max_relaxation, max_jumps=analysis.max_jumps,
                   jump_increments=analysis.jump_increments)

    def prepare(self, constraints) -> None:
        """Set the constraint set up for the scheme (the secant's as they are built)."""

    def mass(self, model) -> np.ndarray | None:
        """The wall's mass where the scheme's drops need it (None)."""
        return None

    def warnings(self, deck) -> list[str]:
        """Deck settings under which the scheme is known not to converge (one line each)."""
        return []

    def stage(self, name: str, problem, settings, state, cursor=None) -> SecantStage:
        """The stage `name` from `state` (or from where `cursor` says)."""
        return SecantStage(name, problem, settings, state, cursor)


@dataclass(frozen=True)
class Newton(_Declared):
    """The converged Newton scheme and its settings, its drops viscous."""

    declaration: ClassVar[SchemeDeclaration] = NEWTON
    target_iterations: int = 6  # iterations per step the step-size controller aims at
    trace_snap_backs: bool = False  # trace a snap-back (opening control) before a drop
    drop_held: str = "deflection"  # a drop holds the deflection | the stroke

    @classmethod
    def of(cls, analysis, control_section) -> Newton:
        chosen = Dynamic if analysis.drops == "dynamic" else Newton
        options = dict(trace_snap_backs=analysis.trace_snap_backs,
                       drop_held=control_section.drop_held)
        if chosen is Dynamic:
            options.update(damping_ratio=analysis.damping_ratio,
                           spectral_radius=analysis.spectral_radius,
                           time_step_scale=analysis.time_step_scale)
        return chosen(**options)

    def prepare(self, constraints) -> None:
        newton_constraints(constraints)

    def mass(self, model) -> np.ndarray | None:
        return wall_mass(model) if self.inertia else None

    def warnings(self, deck) -> list[str]:
        return newton_warnings(deck)

    def stage(self, name: str, problem, settings, state, cursor=None
              ) -> NewtonPreload | NewtonControl:
        """The stage `name` from `state` (or from where `cursor` says)."""
        kind = NewtonPreload if name == "preload" else NewtonControl
        return kind(problem, settings, state, cursor)


@dataclass(frozen=True)
class Dynamic(Newton):
    """The Newton scheme whose drops are the wall's motion with its own mass (HRZ-lumped
    densities, Rayleigh damping `damping_ratio` at the first mode, generalized-alpha with
    `spectral_radius`, every time step scaled by `time_step_scale`)."""

    inertia: ClassVar[bool] = True
    damping_ratio: float = 0.05
    spectral_radius: float = 0.5
    time_step_scale: float = 1.0


SCHEMES = {scheme.declaration.name: scheme for scheme in (Secant, Newton)}


def scheme_of(analysis, control_section) -> Secant | Newton:
    """The scheme of a deck's analysis section (and its loads.control: what a drop holds)."""
    return SCHEMES[analysis.scheme].of(analysis, control_section)


def newton_warnings(deck) -> list[str]:
    """One line each: deck settings under which the Newton scheme is known not to converge."""
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
