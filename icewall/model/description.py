"""What the model's laws and the solver read of an input: one description for every study."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from icewall.deck.analysis_options import Analysis
from icewall.deck.schema import Control, Deck, Interface

MATERIAL_KEYS = ("concrete", "steel", "bearing_plates", "legs")
"""The deck's material keys, in the order the model builds their groups."""


@dataclass(frozen=True)
class ModelDescription:
    """The deck sections the material groups, the constraints and the solver settings are
    built from: a wall deck's (`of_deck`) or a study's own, with the deck's own section types
    (the cylinder of thesis Appendix A has concrete only)."""

    materials: Mapping[str, Any]  # material key -> its section (Concrete, Steel, Elastic)
    analysis: Analysis
    control: Control
    interface: Interface = Interface()

    @classmethod
    def of_deck(cls, deck: Deck) -> ModelDescription:
        m = deck.materials
        return cls({key: getattr(m, key) for key in MATERIAL_KEYS}, deck.analysis,
                   deck.loads.control, m.interface)
