"""The 2D idealisations every layer names (deck choices, kinematics, material laws)."""

from __future__ import annotations

FORMULATIONS = ("plane_strain", "plane_stress", "axisymmetric")


def check_formulation(formulation: str) -> None:
    """Raise ValueError unless `formulation` is one of FORMULATIONS."""
    if formulation not in FORMULATIONS:
        raise ValueError(f"unknown formulation {formulation!r}; expected one of {FORMULATIONS}")
