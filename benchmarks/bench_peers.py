"""(b) Time per global iteration against OpenSees' DisplacementControl on the same mesh, in one
pass (not part of the test run). Uses the peer harness in ../shared/bench-peers (read-only):
its mesh_gen.py writes the S/M/L meshes of the 1500 x 250 mm plane-strain beam, its
peer_opensees.py runs OpenSees (quad8n, UmfPack, Debian OpenBLAS) elastic and with
ASDConcrete3D; then icewall's own path (rotating-crack concrete, E 32 200 MPa, nu 0.2,
f'c 40 MPa, same supports, same load, displacement control of the top midspan node to 0.3 mm
in 10 steps) runs on the identical mesh, its iteration matrices also factorised bare.
OpenSees' model adds 2-node faceplate bars, ours has none (same equations otherwise).

Usage: python benchmarks/bench_peers.py [--sizes S M L] [--peers DIR] [--peers-python PY]
Needs the harness venv (bash ../shared/bench-peers/setup_venv.sh ~/.cache/bench-peers-venv).
Writes benchmarks/out/peers.csv; raw JSON and meshes under benchmarks/out/peers/.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from common import (
    OUT,
    PhaseTimer,
    StopBenchmark,
    environment,
    median,
    peak_memory_mb,
    print_table,
    write_csv,
)

ROOT = Path(__file__).resolve().parent.parent
SIZES = {"S": (48, 8), "M": (96, 16), "L": (216, 36), "XL": (300, 50)}
ASDC = "-tangent -autoRegularization 31.25"


def our_iterations(mesh_path: Path, iterations: int, backends: tuple[str, ...]) -> dict:
    """icewall's displacement-controlled path on the harness mesh; time per iteration."""
    spec = importlib.util.spec_from_file_location("peers_common", PEERS / "common.py")
    peers = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(peers)  # the harness's problem data: supports, load
    from icewall.deck.load import load_deck
    from icewall.fem.assembly import Assembler
    from icewall.fem.dofs import DofMap
    from icewall.fem.kinematics import element_kinematics, gauss_point_spacing
    from icewall.fem.quadrature import gauss_rule
    from icewall.mesh.mesh import CONCRETE, Mesh, Region
    from icewall.model.build import Model
    from icewall.model.description import ModelDescription
    from icewall.solve.path import follow_path
    from icewall.solve.problem import build_problem
    from icewall.solve.settings import solver_settings
    from icewall.solve.state import PathState

    with np.load(mesh_path) as z:
        nodes, cells, length, height = z["nodes"], z["elems"], float(z["L"]), float(z["H"])
    deck = load_deck(ROOT / "decks" / "cf4.yaml", [
        "materials.concrete.fc=40.0", "materials.concrete.E=32200.0",
        "materials.concrete.nu=0.2", "loads.control.increment=0.03",
        "loads.control.target=0.3"]).deck
    dofs = DofMap(len(nodes))
    kin = element_kinematics(nodes, cells, "quad8", gauss_rule(3), "plane_strain", 200.0, dofs)
    sets = peers.node_sets(nodes, length, height)
    mesh = Mesh(nodes, cells, "quad8", np.zeros(len(cells), int),
                (Region("concrete", CONCRETE, 0),))  # one block: no interface pairs
    model = Model(  # the harness's mesh, supports and load with the deck's concrete
        deck=None, description=ModelDescription.of_deck(deck), mesh=mesh, dof_map=dofs,
        kinematics=kin, assembler=Assembler(kin.dofs, dofs.n_equations),
        cell_material=np.full(len(cells), "concrete"),
        gauss_spacing=gauss_point_spacing(nodes, cells, 3), fixed=peers.fixed_dofs(sets),
        reference_load=peers.reference_load(len(nodes), sets), preload=None,
        control_equation=2 * sets["mid"] + 1, measure_name="P", measure_unit="N",
        measure_factor=1.0)
    problem = build_problem(model)
    initial = PathState(np.zeros(dofs.n_equations), 0.0, problem.structure.initial_states())
    timer = PhaseTimer(sample_every=1, backends=backends, stop_after=iterations)
    tic = time.perf_counter()
    steps = 0
    with timer.installed():
        try:
            for _ in follow_path(problem, solver_settings(model.description), initial):
                steps += 1
        except StopBenchmark:
            pass
    wall = time.perf_counter() - tic - timer.sampling_seconds
    totals = timer.iteration_totals()
    row = {"equations": dofs.n_equations, "iterations": timer.factorisations, "steps": steps,
           "iteration_ms": 1e3 * median(totals),
           "iteration_all_in_ms": 1e3 * wall / max(timer.factorisations, 1)}
    for backend, times in timer.bare.items():
        row[f"bare_{backend}_ms"] = 1e3 * median(times)
    row["peak_memory_mb"] = peak_memory_mb()
    return row


def run_peer(python: str, script: str, args: list[str], out: Path, log: Path) -> dict | None:
    """One harness script in its venv, JSON into `out`."""
    command = [python, str(PEERS / script), *args, "--out", str(out)]
    with open(log, "w") as handle:
        code = subprocess.call(command, stdout=subprocess.DEVNULL, stderr=handle, cwd=PEERS)
    if code != 0 or not out.exists():
        print(f"  {script} {' '.join(args[:4])}: failed (rc {code}), see {log}", file=sys.stderr)
        return None
    return json.loads(out.read_text())


def main() -> None:
    global PEERS
    parser = argparse.ArgumentParser()
    parser.add_argument("--sizes", nargs="+", default=["S", "M", "L"], choices=list(SIZES))
    parser.add_argument("--peers", default=str(ROOT.parent / "shared" / "bench-peers"))
    parser.add_argument("--peers-python",
                        default=os.path.expanduser("~/.cache/bench-peers-venv/bin/python"))
    parser.add_argument("--iterations", type=int, default=12)
    parser.add_argument("--asdc-budget", type=float, default=90.0,
                        help="seconds of OpenSees ASDConcrete3D analysis per size")
    parser.add_argument("--backends", nargs="+", default=["superlu"])
    parser.add_argument("--ours", help=argparse.SUPPRESS)  # worker: our run on one mesh
    args = parser.parse_args()
    PEERS = Path(args.peers).resolve()
    if args.ours:
        print(json.dumps(our_iterations(Path(args.ours), args.iterations,
                                        tuple(args.backends))))
        return
    if not Path(args.peers_python).exists():
        sys.exit(f"no harness venv at {args.peers_python}: run "
                 f"bash {PEERS / 'setup_venv.sh'} {Path(args.peers_python).parent.parent}")
    meshes, raw = OUT / "peers" / "meshes", OUT / "peers" / "raw"
    meshes.mkdir(parents=True, exist_ok=True)
    raw.mkdir(parents=True, exist_ok=True)
    rows = []
    for size in args.sizes:
        nx, ny = SIZES[size]
        mesh = meshes / f"q8_{nx}x{ny}.npz"
        if not mesh.exists():
            subprocess.run([args.peers_python, str(PEERS / "mesh_gen.py"), "--nx", str(nx),
                            "--ny", str(ny), "--order", "2", "--out", str(mesh)], check=True,
                           stdout=subprocess.DEVNULL, cwd=PEERS)
        common = ["--mesh", str(mesh), "--system", "UmfPack", "--blas", "system"]
        elastic = run_peer(args.peers_python, "peer_opensees.py",
                           ["--material", "elastic", "--steps", "5", "--repeats", "3", *common],
                           raw / f"{size}__ops_elastic.json", raw / f"{size}__ops_elastic.log")
        asdc = run_peer(args.peers_python, "peer_opensees.py",
                        ["--material", "asdc", "--asdc-opts", ASDC, "--steps", "10", "--target",
                         "0.3", "--tol", "1e-5", "--repeats", "1", "--time-budget",
                         str(args.asdc_budget), *common],
                        raw / f"{size}__ops_asdc.json", raw / f"{size}__ops_asdc.log")
        done = subprocess.run([sys.executable, __file__, "--ours", str(mesh), "--peers",
                               str(PEERS), "--iterations", str(args.iterations), "--backends",
                               *args.backends], capture_output=True, text=True, check=False)
        if done.returncode != 0:
            print(f"{size}: icewall run failed\n{done.stderr[-2000:]}", file=sys.stderr)
            continue
        ours = json.loads(done.stdout.strip().splitlines()[-1])
        row = {"mesh": f"{size} ({nx}x{ny} Q8)", "equations": ours["equations"],
               "icewall_iteration_ms": ours["iteration_ms"],
               "icewall_all_in_ms": ours["iteration_all_in_ms"],
               "icewall_iterations": ours["iterations"]}
        row.update({k: v for k, v in ours.items() if k.startswith("bare_")})
        for name, result in (("ops_elastic", elastic), ("ops_asdc", asdc)):
            per = 1e3 * result["median_t_per_factorization"] if result else float("nan")
            row[f"{name}_per_factorisation_ms"] = per
            row[f"ratio_b_{name}"] = ours["iteration_all_in_ms"] / per
        row["ops_equations"] = elastic["equations"] if elastic else -1
        rows.append(row)
        print(f"{size}: icewall {row['icewall_all_in_ms']:.1f} ms, OpenSees elastic "
              f"{row['ops_elastic_per_factorisation_ms']:.1f} ms, ASDConcrete3D "
              f"{row['ops_asdc_per_factorisation_ms']:.1f} ms per global iteration", flush=True)
    if not rows:
        sys.exit("nothing finished")
    print_table(rows, "(b) time per global iteration, icewall vs OpenSees DisplacementControl "
                      "(same mesh, this pass; ratio < 1: icewall faster)")
    env = environment()
    for row in rows:
        row.update(env)
    write_csv(OUT / "peers.csv", rows)
    print(f"\nwritten: {OUT / 'peers.csv'}")


PEERS = Path()

if __name__ == "__main__":
    main()
