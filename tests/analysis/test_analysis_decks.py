"""Every shipped specimen deck loads and meshes, and follows specimens.md's reading."""

from __future__ import annotations

from pathlib import Path

import pytest

from icewall.deck.load import load_deck
from icewall.mesh.build import build_mesh

DECKS = Path(__file__).resolve().parents[2] / "decks"
NAMES = ["cf4", "cf5", "cf6", "cf7", "cf8", "cf13", "cf14", "tf1", "tf2", "tf3", "tf4", "tf5",
         "tf6", "tf7", "vtt1", "vtt2", "vtt3", "vtt4"]


def deck(name: str):
    return load_deck(DECKS / f"{name}.yaml").deck


def test_the_deck_set():
    stems = {p.stem for p in DECKS.glob("*.yaml")}
    assert set(NAMES) <= stems and "tf8" not in stems  # TF-8 (headed studs) is out of scope


@pytest.mark.parametrize("name", NAMES)
def test_deck_loads_and_meshes(name):
    d = deck(name)
    mesh = build_mesh(d)
    assert mesh.n_cells > 50
    assert any(r.name == "bottom_plate" for r in mesh.regions)


def test_cf_reading():
    for name in ("cf4", "cf5", "cf6", "cf7"):
        g = deck(name).geometry
        assert (g.span, g.overhang, g.diaphragms.positions) == (1500.0, 333.0, (450.0, 750.0))
        # layout D (decks/README.md §1): midspan, +-L/5 and the wall end, patch flush with it
        assert deck(name).loads.patches.positions == (0.0, 300.0, 750.0 + 333.0 - 25.0)
    assert deck("cf8").geometry.diaphragms.positions == (450.0, 600.0, 750.0)  # S1/2 cells
    for name in ("cf13", "cf14"):
        d = deck(name)
        assert (d.geometry.span, d.geometry.width) == (1250.0, 375.0)
        assert d.geometry.diaphragms.positions == (325.0, 625.0)
        assert d.loads.patches.positions == (0.0, 250.0, 625.0 + 333.0 - 25.0)
        assert d.loads.measure.tributary_length == 250.0


@pytest.mark.parametrize("name", NAMES)
def test_shared_readings(name):
    """decks/README.md §3 and the errata: plane-stress plates with E_h = 200 MPa, no f_y
    reduction, rule (b) read with signed stresses; the same for every deck."""
    d = deck(name)
    s = d.materials.steel
    assert (s.formulation, s.hardening * s.E, s.fy_reduction) == ("plane_stress", 200.0, 0.0)
    assert d.materials.concrete.compression_tension_rule == "floor"


def test_vtt_reading():
    for name in ("vtt1", "vtt2", "vtt3", "vtt4"):
        g = deck(name).geometry
        # V-C (decks/README.md §2): a diaphragm over each support, at L/2 = 455
        assert g.diaphragms.positions == (100.0, 300.0, 455.0)
        assert [s.x for s in g.supports] == [455.0]


def test_tf_reading():
    assert len(deck("tf3").geometry.supports) == 1  # no tie-downs (Table 4.2 note 2)
    assert deck("tf3").loads.preload is None
    for name, n in (("tf5", 1e6), ("tf6", 2e6), ("tf7", 3e6)):
        assert deck(name).loads.preload.axial_force == n  # tension positive
    assert deck("tf6").loads.patches.positions == (450.0,)  # inner loads omitted (note 3)
    assert deck("tf6").geometry.diaphragms.positions == (120.0, 450.0, 625.0)
    assert deck("tf7").loads.patches.positions == (451.0,)
    assert deck("tf4").loads.patches.positions == (99.0, 449.0)
    assert deck("tf4").loads.preload.axial_force == -3145e3
