"""The nonlinear solver's iteration schemes as every layer names them: each one's name, the
defaults of the limits a deck leaves out (tolerances, iteration limit, step cuts) and the
analysis options only it reads. The deck takes its choices and defaults from here (it sits
below the solver); the scheme objects of `icewall.solve.schemes` each carry their declaration,
with their own settings and the path they follow."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType


@dataclass(frozen=True)
class SchemeDeclaration:
    name: str
    defaults: Mapping[str, float | int]  # the limits a deck leaves out (analysis.<key>)
    options: tuple[str, ...]  # the analysis.* options that only this scheme reads


SECANT = SchemeDeclaration(
    "secant", MappingProxyType({"tolerance_displacement": 0.05, "tolerance_load": 0.05,
                                "max_iterations": 200, "max_step_cuts": 4}),
    # the thesis' 5 % (4.2.3); a secant step may crawl
    ("stiffness_update", "acceleration", "max_flag_changes", "max_relaxation", "max_jumps",
     "jump_increments"))
NEWTON = SchemeDeclaration(
    "newton", MappingProxyType({"tolerance_displacement": 1e-4, "tolerance_load": 1e-4,
                                "max_iterations": 40, "max_step_cuts": 6}),
    # docs/solver.md: the runs of items 17-25
    ("trace_snap_backs", "drops", "damping_ratio", "spectral_radius", "time_step_scale"))
SCHEMES = {scheme.name: scheme for scheme in (SECANT, NEWTON)}


def declared(name: str) -> SchemeDeclaration:
    """The declaration of the scheme `name` (an unknown name: the secant's, as the deck's
    validation reports it)."""
    return SCHEMES.get(name, SECANT)
