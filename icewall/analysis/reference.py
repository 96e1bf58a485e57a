"""Test and thesis-FEA reference values (Link & Elwi 1992, Table 5.1 via specimens.md).

The numbers live in ``reference_data.yaml`` beside this module, in the units the thesis prints
(MPa for the CF intensity w, kN for the TF and VTT totals). :class:`SpecimenReference` holds them
in icewall's load measure: MPa for w, N for total loads (the HDF5 ``load`` column). Withheld
values (blind cases) are absent from the file and ``None`` here.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from functools import cache
from importlib import resources

import yaml

DATA_FILE = "reference_data.yaml"
_TO_ICEWALL = {"MPa": ("MPa", 1.0), "kN": ("N", 1000.0), "N": ("N", 1.0)}


@dataclass(frozen=True)
class SpecimenReference:
    """Reference values of one specimen in icewall's load measure (``unit``)."""

    name: str
    series: str
    measure: str  # w (CF), F_t (TF), P_f (VTT)
    unit: str  # "MPa" or "N"
    ultimate_test: float | None = None
    ultimate_thesis: float | None = None
    residual_test: float | None = None
    residual_thesis: float | None = None
    source: str = ""
    notes: tuple[str, ...] = ()
    aliases: tuple[str, ...] = ()

    def ratio(self, kind: str, predicted: float | None = None) -> float | None:
        """Test / predicted for ``kind`` "ultimate" or "residual"; predicted defaults to the
        thesis' FEA. None where a value is missing."""
        test = getattr(self, f"{kind}_test")
        pred = getattr(self, f"{kind}_thesis") if predicted is None else predicted
        if test is None or pred is None or pred == 0:
            return None
        return test / pred


def _raw() -> dict:
    text = resources.files("icewall.analysis").joinpath(DATA_FILE).read_text(encoding="utf-8")
    return yaml.safe_load(text)


@cache
def _load() -> tuple[dict[str, SpecimenReference], dict]:
    raw = _raw()
    out: dict[str, SpecimenReference] = {}
    for name, row in raw["specimens"].items():
        unit, factor = _TO_ICEWALL[row["unit"]]
        values = {k: None if row.get(k) is None else float(row[k]) * factor
                  for k in ("ultimate_test", "ultimate_thesis", "residual_test",
                            "residual_thesis")}
        out[name] = SpecimenReference(
            name=name, series=row["series"], measure=row["measure"], unit=unit,
            source=row.get("source", raw["source"]), notes=tuple(row.get("notes", ())),
            aliases=tuple(row.get("aliases", ())), **values)
    return out, raw


def load_reference() -> dict[str, SpecimenReference]:
    """Specimen name (as in the decks, e.g. "CF-4", "VTT3") -> its reference values."""
    return dict(_load()[0])


def thesis_figures() -> dict:
    """The thesis' other figures (Gauss-rule study, Appendix A fit, ...) as stored."""
    return _load()[1]["figures"]


def stated_ratios() -> dict:
    """Mean / CoV / worst test-predicted ratios as specimens.md states them."""
    return _load()[1]["statements"]


def _key(name: str) -> str:
    return name.replace("-", "").replace("_", "").replace(" ", "").upper()


def find_reference(name: str) -> SpecimenReference | None:
    """Look a specimen up by name, ignoring case, hyphens and spaces ("VTT-3" finds VTT3)."""
    for ref in load_reference().values():
        if _key(name) in {_key(ref.name), *(_key(a) for a in ref.aliases)}:
            return ref
    return None


def ratio_stats(ratios: Iterable[float | None]) -> dict:
    """Mean, coefficient of variation (sample standard deviation / mean), min, max and count
    of the ratios that are not None."""
    vals = [float(r) for r in ratios if r is not None]
    n = len(vals)
    if not n:
        return {"n": 0, "mean": None, "cov": None, "min": None, "max": None}
    mean = sum(vals) / n
    sd = math.sqrt(sum((v - mean) ** 2 for v in vals) / (n - 1)) if n > 1 else 0.0
    return {"n": n, "mean": mean, "cov": sd / mean, "min": min(vals), "max": max(vals)}
