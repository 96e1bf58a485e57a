"""The deck's analysis section (deck format v1): the idealisation, the mesh and Gauss rule, the
nonlinear solver's scheme and limits, with the scheme-dependent defaults of the limits."""

from __future__ import annotations

from dataclasses import dataclass

from icewall.deck.fields import option
from icewall.formulations import FORMULATIONS
from icewall.schemes import SCHEMES, declared

SCHEME_DEFAULTS: dict[str, dict[str, float | int]] = {
    name: dict(scheme.defaults) for name, scheme in SCHEMES.items()}
"""analysis.tolerance_displacement, tolerance_load, max_iterations and max_step_cuts of a deck
that leaves them out, by analysis.scheme (each scheme's own: icewall.schemes)."""
CONVERGED_TOLERANCE = 1e-4
"""Tolerances at or below this make each step a converged equilibrium (issue 19's acceptance
level; `icewall summary` says so, `icewall check` warns above it under Newton): at 1e-3 TF-1's
peak is still 5.8 % off the 1e-4 one, and at the thesis' 0.05 the peaks move with the
tolerance (docs/solver.md items 14, 22, 25 and 27)."""


@dataclass(frozen=True, kw_only=True)
class Analysis:
    solver: str = option("nonlinear", doc="nonlinear: the thesis model, displacement control "
                         "(preceded by load control of any preload); linear: linear elasticity "
                         "with the initial moduli, interface pairs tied",
                         choices=("nonlinear", "linear"))
    formulation: str = option("plane_strain", doc="2D idealisation", choices=FORMULATIONS)
    element: str = option("quad8", doc="element type", choices=("quad8", "quad4"))
    gauss: int = option(3, doc="Gauss rule n x n", choices=(2, 3, 4))
    element_size: float = option(75.0, doc="target element size", unit="mm",
                                 exclusive_minimum=0.0)
    scheme: str = option("secant", doc="iteration of the nonlinear solver: secant (the thesis' "
                         "secant iteration with relaxation, chatter damping and fallbacks) or "
                         "newton (Newton-Raphson with the consistent tangent, line search and "
                         "automatic step size); the tolerances, max_iterations and "
                         "max_step_cuts a deck leaves out take the scheme's defaults",
                         choices=tuple(SCHEMES))
    tolerance_displacement: float | None = option(
        None, doc="displacement norm tolerance (eq. 4.4); default 0.05 under scheme secant "
        "(the thesis), 1e-4 under newton", exclusive_minimum=0.0, maximum=1.0)
    tolerance_load: float | None = option(
        None, doc="load norm tolerance (eq. 4.5); default 0.05 under scheme secant (the "
        "thesis), 1e-4 under newton", exclusive_minimum=0.0, maximum=1.0)
    max_iterations: int | None = option(
        None, doc="iteration limit per step; default 200 under scheme secant, 40 under newton "
        "(whose iterations converge quadratically or not at all: a failed try costs 5x less)",
        minimum=1)
    concrete_stiffness: str = option("secant-coaxial", doc="concrete moduli of the iteration "
                                     "matrix: secant-coaxial (secant E_i, nu_i with the G12 that "
                                     "keeps stress and strain co-axial, errata §3), secant (the "
                                     "thesis, G12 of eq. 3.21: 150+ iterations per step on "
                                     "CF-4) or tangent (algorithmic, by differences)",
                                     choices=("secant", "secant-coaxial", "tangent"))
    iteration_stiffness_floor: float = option(0.02, doc="concrete moduli in the iteration "
                                              "matrix are kept above this fraction of their "
                                              "initial values (stresses unaffected; 0 = pure "
                                              "secant, the thesis)", minimum=0.0, maximum=1.0)
    acceleration: str = option("halving", doc="relaxation of the iteration's corrections: "
                               "aitken (dynamic relaxation from successive corrections), "
                               "halving (halve when the load norm grows, grow back by 1.5 "
                               "while it falls, to a limit that halves every third rise in "
                               "the increment) or none (the thesis)",
                               choices=("aitken", "halving", "none"))
    max_flag_changes: int = option(4, doc="times a concrete Gauss point may change its crack "
                                   "or crush flags within one increment before it may only "
                                   "unload and reload for the rest of it (chatter damping)",
                                   minimum=1)
    on_snap_back: str = option("continue", doc="a load drop that does not shrink with the "
                               "step (the control displacement snaps back): continue, accepting "
                               "the drop as a snap-through at the held control displacement, as "
                               "a stroke-controlled test does (flagged in the history column "
                               "snap_back and counted by icewall summary), or stop the run with "
                               "reason snap-back",
                               choices=("stop", "continue"))
    trace_snap_backs: bool = option(False, doc="scheme newton: where displacement control "
                                    "fails at its smallest step, first trace the snap-back "
                                    "under the opening control of the cracking points (until "
                                    "load and deflection rise together again) and take the "
                                    "drop at a fixed deflection only where that fails; false "
                                    "takes the drop at once, as a stroke-controlled test does "
                                    "(docs/solver.md, item 17)")
    max_jumps: int = option(3, doc="times per run that a control step which does not converge "
                            "even at the smallest size and with every fallback iteration "
                            "scheme is retried once as one step of jump_increments increments "
                            "from the last converged state (stepping over a local instability, as "
                            "a stroke-controlled test does); flagged in the history column "
                            "jumped and listed by icewall summary; 0 stops there instead",
                            minimum=0, maximum=100)
    jump_increments: float = option(2.0, doc="size of a step over a stall (max_jumps), in "
                                    "control increments", minimum=1.0, maximum=100.0)
    max_relaxation: float = option(1.0, doc="largest factor on a correction in the halving "
                                   "scheme: above 1 it over-relaxes the slow drift of the "
                                   "secant iteration after the peak (1.5: CF-4 needs 40 % "
                                   "fewer iterations, but 8 of the 18 specimen decks stop "
                                   "before 40 mm instead of 5)", exclusive_minimum=0.0,
                                   maximum=3.0)
    max_step_cuts: int | None = option(
        None, doc="halvings of a failed increment before the run stops (newton: before a "
        "drop); default 4 under scheme secant, 6 under newton", minimum=0, maximum=20)
    stiffness_update: str = option("every_iteration", doc="re-form the (secant) stiffness every "
                                   "iteration (thesis) or once per step",
                                   choices=("every_iteration", "every_step"))
    preload_increments: int = option(5, doc="load-control increments of the in-plane preload",
                                     minimum=1)
    drops: str = option("viscous", doc="scheme newton: how a drop past a limit point of the "
                        "held stroke is taken: viscous (committed viscous sub-steps without "
                        "mass to a static equilibrium, docs/solver.md item 17) or dynamic (the "
                        "wall's motion with its own mass and damping, generalized-alpha, until "
                        "it comes to rest: item 36; it stops where the concrete law's stress "
                        "jumps, items 21-24, 36)", choices=("viscous", "dynamic"))
    damping_ratio: float = option(0.05, doc="scheme newton: viscous damping of a dynamic drop "
                                  "as a fraction of critical at the wall's first mode "
                                  "(mass-proportional Rayleigh damping, C = 2 xi omega_1 M; 5 "
                                  "%: a cracked reinforced-concrete member), a parameter of "
                                  "the physics (docs/solver.md)", minimum=0.0, maximum=1.0)
    spectral_radius: float = option(0.5, doc="scheme newton: the generalized-alpha "
                                    "integrator's spectral radius at infinite frequency "
                                    "(Chung & Hulbert 1993): 1 keeps every mode, lower values "
                                    "damp the spurious high modes of the mesh and of the "
                                    "interface pairs' impacts (0.8 let CF-4's third drop run "
                                    "away, item 36); the low modes are kept to second order "
                                    "either way", minimum=0.0,
                                    maximum=1.0)
    time_step_scale: float = option(1.0, doc="scheme newton: factor on every time step of a "
                                    "dynamic drop (0.5 halves them all: the time-step "
                                    "convergence check)", exclusive_minimum=0.0, maximum=10.0)
    allow_large: bool = option(False, doc="run a deck that icewall check estimates cannot "
                               "finish on this machine (over 1e5 steps, over 2e5 elements, more "
                               "memory than available, more output than free disk); each limit "
                               "passed is then a warning")
    allow_unphysical: bool = option(False, doc="run a deck with a material or geometric value "
                                    "outside its physical range (icewall.deck.physical: e.g. "
                                    "a steel E outside 1e5-3e5 MPa, a plate outside 0.5-200 "
                                    "mm; usually a unit slip); each value outside is then a "
                                    "warning")

    def __post_init__(self) -> None:
        # the keys a deck leaves out (None) take its scheme's defaults
        for key, value in declared(self.scheme).defaults.items():
            if getattr(self, key) is None:
                object.__setattr__(self, key, value)
