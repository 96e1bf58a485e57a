"""Time the vectorised concrete update for 1e4 and 1e5 points (not part of the test run).

Usage: python benchmarks/bench_concrete.py [--points 10000 100000] [--repeat 5]
Prints microseconds per point per update and a cProfile breakdown by function (cumulative
times, so nested rows are included in the rows above them; calls counts e.g. the Newton
evaluations of the ray function, one per iteration plus one at the cap).
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import time
from pathlib import Path

import numpy as np

from icewall.materials.concrete import update_concrete
from icewall.materials.concrete_state import ConcreteState
from icewall.materials.parameters import derive_concrete_parameters

PHASES = {  # (file, function): label; the file tells same-named helpers apart
    ("concrete.py", "update_concrete"): "total update",
    ("mode_rules.py", "equivalent_uniaxial_strengths"): "step 5: sigma_ic (ultimate surface)",
    ("ultimate_surface.py", "strength_scale"): "  of which s on the ray (Newton)",
    ("ultimate_surface.py", "_ray_function"): "    of which f, df/dt evaluations",
    ("mode_rules.py", "equivalent_uniaxial_peak_strains"): "step 5: eps_ic",
    ("concrete.py", "_envelope"): "step 6: envelopes (eqs. 3.9-3.11)",
    ("uniaxial.py", "_envelope"): "  of which uniaxial curves (all calls)",
    ("orthotropic.py", "orthotropic_normal_stiffness"): "steps 3, 7: C_l (eq. 3.2), two calls",
    ("orthotropic.py", "global_moduli"): "step 8: C_g = T^T C_l T",
    ("orthotropic.py", "principal_strain_angle"): "step 2: beta",
    ("orthotropic.py", "local_normal_components"): "step 2: rotate strain, stress",
}


def _states(n: int, formulation: str):
    params = derive_concrete_parameters(53.5, 100.0)
    rng = np.random.default_rng(0)
    strain = rng.uniform(-3e-3, 1e-3, size=(n, 4))
    state = ConcreteState.initial(n, params)
    for t in (0.3, 0.6):  # a mix of elastic, cracked and crushed points
        _, _, state = update_concrete(t * strain, state, params, formulation)
    return params, strain * 0.8, state


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--points", type=int, nargs="+", default=[10_000, 100_000])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--formulation", default="plane_strain")
    args = parser.parse_args()
    print(f"{'points':>8} {'us/point/update':>16} {'best (s)':>10}")
    for n in args.points:
        params, strain, state = _states(n, args.formulation)
        times = []
        for _ in range(args.repeat):
            start = time.perf_counter()
            update_concrete(strain, state, params, args.formulation)
            times.append(time.perf_counter() - start)
        print(f"{n:>8d} {1e6 * min(times) / n:>16.3f} {min(times):>10.4f}")
    n = args.points[-1]
    params, strain, state = _states(n, args.formulation)
    profile = cProfile.Profile()
    profile.enable()
    update_concrete(strain, state, params, args.formulation)
    profile.disable()
    stats = pstats.Stats(profile)
    total = stats.total_tt
    print(f"\nbreakdown for {n} points ({1e6 * total / n:.3f} us/point under cProfile):")
    print(f"{'phase':<44} {'us/point':>9} {'share':>6} {'calls':>6}")
    rows = {(Path(file).name, name): row
            for (file, _, name), row in stats.stats.items()}  # type: ignore[attr-defined]
    for key, label in PHASES.items():
        if key in rows:
            calls, cumulative = rows[key][1], rows[key][3]
            print(f"{label:<44} {1e6 * cumulative / n:>9.3f} {cumulative / total:>6.0%} "
                  f"{calls:>6d}")
    stats.sort_stats("tottime").print_stats(8)


if __name__ == "__main__":
    main()
