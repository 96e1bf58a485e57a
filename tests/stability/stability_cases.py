"""The stability matrix of issue 6 §2: stiff and extreme variants of the shipped decks, coarse
and short where the case allows (`make stability` runs them all)."""

from __future__ import annotations

from stability_checks import Case

# CF-4 with 2 elements across the core depth (224.8 mm / 150), to 16 mm (past the peak) in 2 mm
# steps (the CI's coarse compare variants use the same steps)
CF = ("analysis.element_size=150", "loads.control.target=16", "loads.control.increment=2")
TF = ("analysis.element_size=150", "loads.control.target=10", "loads.control.increment=1")
# the shipped CF-4 mesh to 16 mm in 2 mm steps, with a tenth of the fracture energy
BRITTLE = ("materials.concrete.Gf=0.01", "loads.control.target=16", "loads.control.increment=2")
CORE_DEPTH = 250.0 - 2 * 12.6  # CF-4


def _across_core(n: int) -> str:
    """Element size giving n elements across the CF-4 core depth (ceil(depth / size) = n)."""
    return f"analysis.element_size={CORE_DEPTH / n + 1e-3:.4f}"


# the default test run keeps these (a few seconds each)
QUICK = [
    Case("cf4_coarse", "cf4.yaml", CF),
    Case("friction_0.3", "cf4.yaml", CF + ("materials.interface.friction=0.3",)),
]

HEAVY = [
    Case("plates_1mm", "cf4.yaml", CF + ("geometry.top_plate=1", "geometry.bottom_plate=1")),
    Case("plates_50mm", "cf4.yaml", CF + ("geometry.top_plate=50", "geometry.bottom_plate=50")),
    Case("concrete_20MPa", "cf4.yaml", CF + ("materials.concrete.fc=20",)),
    Case("bearing_plates_1000x_stiffer", "cf4.yaml", CF + ("materials.bearing_plates.E=2.0e+8",)),
    Case("friction_0", "cf4.yaml", CF + ("materials.interface.friction=0",)),
    Case("friction_1.0", "cf4.yaml", CF + ("materials.interface.friction=1.0",)),
    Case("brittle_Gf_0.01", "cf4.yaml", BRITTLE),
    Case("brittle_Gf_0.01_continue", "cf4.yaml", BRITTLE + ("analysis.on_snap_back=continue",)),
    Case("brittle_Gf_0.01_1_element", "cf4.yaml", CF + ("materials.concrete.Gf=0.01",
                                                        "analysis.element_size=250")),
    Case("high_strength_100MPa", "cf4.yaml", CF + ("materials.concrete.fc=100",)),
    Case("tf4_confinement", "tf4.yaml", TF),
    Case("tf5_tension", "tf5.yaml", TF),
    Case("tf6_tension", "tf6.yaml", TF),
    Case("tf7_tension", "tf7.yaml", TF),
    Case("steps_0.05mm", "cf4.yaml", CF + ("loads.control.increment=0.05",
                                           "loads.control.target=1")),
    Case("steps_5mm", "cf4.yaml", CF + ("loads.control.increment=5",
                                        "loads.control.target=20")),
    Case("core_1_element", "cf4.yaml", CF + (_across_core(1),)),
    Case("core_4_elements", "cf4.yaml", CF + (_across_core(4), "loads.control.target=6")),
    Case("core_8_elements", "cf4.yaml", CF + (_across_core(8), "loads.control.target=3")),
    Case("core_12_elements", "cf4.yaml", CF + (_across_core(12), "loads.control.target=2")),
]
