"""Reference data: the rows reproduce specimens.md's statements; withheld values stay absent."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest
import yaml

from icewall.analysis.reference import (
    find_reference,
    load_reference,
    ratio_stats,
    stated_ratios,
    thesis_figures,
)

DECKS = Path(__file__).resolve().parents[2] / "decks"
ANALYSED = ["CF-4", "CF-5", "CF-8", "CF-13", "TF-1", "TF-2", "TF-4", "VTT3"]
BLIND = ["CF-6", "CF-7", "CF-14", "TF-3", "TF-5", "TF-6", "TF-7", "VTT1", "VTT2", "VTT4"]


def _stats(kind: str) -> tuple[dict, str]:
    refs = load_reference()
    ratios = {name: ref.ratio(kind) for name, ref in refs.items()}
    worst = min((r, n) for n, r in ratios.items() if r is not None)[1]
    return ratio_stats(ratios.values()), worst


def test_table_rows_and_units():
    refs = load_reference()
    assert sorted(refs) == sorted(ANALYSED)
    cf4, tf1 = refs["CF-4"], refs["TF-1"]
    assert (cf4.unit, cf4.measure, cf4.ultimate_test, cf4.ultimate_thesis) == (
        "MPa", "w", 4.91, 5.16)
    assert (tf1.unit, tf1.ultimate_test, tf1.residual_test) == ("N", 5.6e6, 4.5e6)  # kN -> N
    assert refs["VTT3"].residual_thesis == pytest.approx(800e3)
    assert "Table 5.1" in cf4.source
    with pytest.raises(dataclasses.FrozenInstanceError):
        cf4.ultimate_test = 1.0  # type: ignore[misc]


def test_withheld_values_are_absent():
    refs = load_reference()
    assert refs["CF-8"].residual_test is None and refs["CF-8"].ratio("residual") is None
    for name in BLIND:
        assert find_reference(name) is None


def test_ultimate_ratios_reproduce_specimens_md():
    stats, worst = _stats("ultimate")
    stated = stated_ratios()["ultimate"]
    assert stats["n"] == stated["n"] == 8
    assert round(stats["mean"], 2) == stated["mean"] == 0.93
    assert round(stats["cov"], 2) == stated["cov"] == 0.09
    assert round(stats["min"], 2) == stated["worst"] == 0.75 and worst == "TF-4"


def test_residual_ratios_reproduce_specimens_md():
    stats, _ = _stats("residual")
    stated = stated_ratios()["residual"]
    assert stats["n"] == stated["n"] == 7
    assert round(stats["mean"], 2) == stated["mean"] == 1.24
    assert round(stats["cov"], 2) == stated["cov"] == 0.26
    assert round(stats["max"], 2) == stated["worst"] == 1.80
    worst = max((r.ratio("residual") or 0.0, n) for n, r in load_reference().items())[1]
    assert worst == "TF-1"
    # Table 5.1's printed residual mean does not follow from its own rows
    assert abs(stats["mean"] - stated_ratios()["residual_printed_mean"]) > 0.1


def test_thesis_figures():
    f = thesis_figures()
    assert f["cf4_gauss_study"]["peaks"] == {2: 4.02, 3: 5.16, 4: 5.60}
    assert f["cf4_peak_deflection"]["value"] == 10.0
    assert (f["appendix_a"]["alpha_c"], f["appendix_a"]["n"]) == (0.00478, 0.80)


def test_lookup_by_alias():
    assert find_reference("VTT-3").name == "VTT3"
    assert find_reference("cf4").name == "CF-4"
    assert find_reference("TF-8") is None


def test_ratio_with_a_prediction():
    ref = load_reference()["CF-4"]
    assert ref.ratio("ultimate", predicted=4.91) == pytest.approx(1.0)
    assert ratio_stats([None]) == {"n": 0, "mean": None, "cov": None, "min": None, "max": None}


@pytest.mark.parametrize("name", ANALYSED)
def test_decks_agree_with_the_data_file(name):
    """Each analysed deck carries the same reference values as the data file."""
    ref = load_reference()[name]
    deck = yaml.safe_load((DECKS / f"{name.replace('-', '').lower()}.yaml").read_text())
    got = deck["specimen"]["reference"]
    for key in ("ultimate_test", "residual_test", "ultimate_thesis", "residual_thesis"):
        assert got.get(key) == pytest.approx(getattr(ref, key)), key


@pytest.mark.parametrize("name", BLIND)
def test_blind_decks_carry_no_reference(name):
    deck = yaml.safe_load((DECKS / f"{name.replace('-', '').lower()}.yaml").read_text())
    assert "reference" not in deck["specimen"]
