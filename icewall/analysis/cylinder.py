"""Appendix A of the thesis: the 24 standard-cylinder analyses of Table A.1 and the fit of
A_c = (alpha_c h_c A_cd)^n (eq. A.3) against the thesis' alpha_c = 0.00478, n = 0.80 (A.7).

`python -m icewall.analysis.cylinder [-o DIR] [-j N] [--fc F] [--mesh NAME]` runs the cases
(model: `icewall.analysis.cylinder_model`), writes DIR/cylinder_study.csv and prints the
table and the fit. docs/cylinder_study.md gives the results and the choices behind them.
"""

from __future__ import annotations

import csv
import math
import sys
from collections.abc import Iterable, Sequence
from dataclasses import asdict, dataclass, fields
from pathlib import Path

import numpy as np

from icewall.analysis.cylinder_model import CylinderCase, run_cylinder
from icewall.errors import ResultError
from icewall.safe_write import check_replaceable, csv_kind, open_for_write

THESIS_ALPHA_C = 0.00478  # 1/mm, eq. A.7a
THESIS_N = 0.80  # eq. A.7b
#: Table A.1: f'c (MPa) -> input areas A_cd (MPa); A_cd / f'c = 0.00625 k and 0.0125 k (errata)
TABLE_A1 = {53.5: (0.334, 0.669, 1.003, 1.338), 30.0: (0.375, 0.750, 1.125, 1.500)}
#: Table A.1 meshes: name -> (nominal h_c mm, nx, ny). The axial Gauss spacing (H/2)/(3 ny)
#: equals the nominal h_c; nx is the nearest whole radial division (Fig. A.3 is lost).
MESHES = {"coarse": (16.67, 2, 3), "intermediate": (10.0, 3, 5), "fine": (5.0, 5, 10)}
#: Solver and law choices of the study (docs/cylinder_study.md): the thesis' tolerance 0.05
#: (deck default), Fig. 3.12's incremental trial stress, no chatter freezing, load drops
#: accepted as snap-throughs; 1e-5 strain steps from 0.002 on, a non-converging increment
#: stepped over by the solver (up to 20 times per stage, 10 steps at once: analysis.max_jumps,
#: jump_increments); stop at 2 % of the peak.
STUDY_CONCRETE = {"trial_stress": "incremental"}
STUDY_ANALYSIS = {"max_flag_changes": 10**9, "on_snap_back": "continue", "max_iterations": 50,
                  "max_jumps": 20, "jump_increments": 10.0}
STAGES = ((0.002, 2.5e-4), (0.04, 1e-5))
END_STRESS_RATIO = 0.02


def thesis_area(h_c: float | np.ndarray, input_area: float | np.ndarray) -> np.ndarray:
    """A_c of the thesis' fit, (alpha_c h_c A_cd)^n (eqs. A.3, A.7)."""
    return (THESIS_ALPHA_C * np.asarray(h_c) * np.asarray(input_area)) ** THESIS_N


def fit_power_law(h_times_area: Sequence[float], output_area: Sequence[float]
                  ) -> tuple[float, float]:
    """(alpha_c, n) of A_c = (alpha_c h_c A_cd)^n by least squares on the logarithms:
    ln A_c = n ln(h_c A_cd) + n ln alpha_c (eq. A.3)."""
    x, y = np.log(np.asarray(h_times_area, float)), np.log(np.asarray(output_area, float))
    if x.size < 2 or np.ptp(x) == 0.0:
        raise ValueError("the fit needs at least two different h_c A_cd")
    n, intercept = np.polyfit(x, y, 1)
    return float(math.exp(intercept / n)), float(n)


def crushing_energy_from_fit(output_area: float, alpha_c: float, n: float) -> float:
    """G_cr = A_c^(1/n) / alpha_c (eq. A.6), N/mm."""
    return output_area ** (1.0 / n) / alpha_c


@dataclass(frozen=True)
class StudyRow:
    """One analysis of Table A.1 and what the thesis extracts from it."""

    fc: float
    mesh: str
    h_c: float  # nominal (Table A.1), mm
    h_c_eq43: float  # mean sqrt(h1 h2) of the mesh, eq. 4.3, mm
    input_area: float  # A_cd, MPa
    k_c: float
    peak_stress: float  # MPa
    peak_ratio: float  # peak / f'c
    strain_at_peak: float
    area_to_end: float  # MPa
    tail: float  # exponential tail beyond the end, MPa
    output_area: float  # A_c = area_to_end + tail, MPa
    thesis_output_area: float  # (alpha_c h_c A_cd)^n with the thesis' constants
    end_strain: float
    end_stress: float
    snap_throughs: int
    jumps: int
    steps: int
    iterations: int
    run_time: float  # s
    stopped: str

    @property
    def completed(self) -> bool:
        return not self.stopped


STUDY_TABLE = csv_kind("cylinder study table", [f.name for f in fields(StudyRow)])


def table_a1_cases(fcs: Iterable[float] | None = None, meshes: Iterable[str] | None = None
                   ) -> list[tuple[str, float, CylinderCase]]:
    """(mesh name, nominal h_c, case) for every Table A.1 cell (24 without filters)."""
    out = []
    for fc in (TABLE_A1 if fcs is None else fcs):
        for name in (MESHES if meshes is None else meshes):
            h_c, nx, ny = MESHES[name]
            for area in TABLE_A1[fc]:
                out.append((name, h_c, CylinderCase(fc, nx, ny, area, "fixed",
                                                    dict(STUDY_CONCRETE))))
    return out


def run_case(spec: tuple[str, float, CylinderCase]) -> StudyRow:
    """Run one Table A.1 cell with the study's settings and extract its figures."""
    name, h_c, case = spec
    curve = run_cylinder(case, STAGES, END_STRESS_RATIO, **STUDY_ANALYSIS)
    spacing = curve.gauss_spacing
    area, tail = curve.descending_area(), curve.tail_area()
    return StudyRow(
        fc=case.fc, mesh=name, h_c=h_c, h_c_eq43=float(spacing.mean()),
        input_area=float(case.input_area), k_c=case.fc / float(case.input_area),
        peak_stress=curve.peak_stress, peak_ratio=curve.peak_stress / case.fc,
        strain_at_peak=curve.strain_at_peak, area_to_end=area, tail=tail,
        output_area=area + tail, thesis_output_area=float(thesis_area(h_c, case.input_area)),
        end_strain=float(curve.strain[-1]), end_stress=float(curve.stress[-1]),
        snap_throughs=curve.snap_throughs, jumps=curve.jumps, steps=len(curve.strain) - 1,
        iterations=int(curve.iterations.sum()), run_time=curve.run_time, stopped=curve.stopped)


def run_study(specs: list[tuple[str, float, CylinderCase]], workers: int = 1,
              progress=print) -> list[StudyRow]:
    """Run the cases (in `workers` processes when > 1), in the order given."""
    if workers <= 1:
        rows = []
        for spec in specs:
            rows.append(run_case(spec))
            progress(_progress_line(rows[-1]))
        return rows
    from concurrent.futures import ProcessPoolExecutor

    with ProcessPoolExecutor(max_workers=workers) as pool:
        rows = []
        for row in pool.map(run_case, specs):
            rows.append(row)
            progress(_progress_line(row))
    return rows


def _progress_line(row: StudyRow) -> str:
    return (f"  f'c {row.fc:4.1f}  {row.mesh:12s} A_cd {row.input_area:.3f}: A_c "
            f"{row.output_area:.4f} MPa, peak {row.peak_stress:.2f} MPa ({row.run_time:.0f} s)"
            + (f"  STOPPED: {row.stopped}" if row.stopped else ""))


def study_fit(rows: Sequence[StudyRow]) -> dict[str, tuple[float, float]]:
    """(alpha_c, n) over the completed rows (all, per strength) and over every row, stopped
    ones with their extrapolated tail: name -> (alpha_c, n)."""
    done = [r for r in rows if r.completed]
    groups = {"completed": done}
    for fc in sorted({r.fc for r in rows}, reverse=True):
        groups[f"completed, f'c = {fc:g}"] = [r for r in done if r.fc == fc]
    if len(done) < len(rows):
        groups["all, stopped ones extrapolated"] = list(rows)
    fits: dict[str, tuple[float, float]] = {}
    for name, sel in groups.items():
        try:
            fits[name] = fit_power_law([r.h_c * r.input_area for r in sel],
                                       [r.output_area for r in sel])
        except ValueError:
            continue
    return fits


def read_csv(path: str | Path) -> list[StudyRow]:
    """Rows written by `write_csv`."""
    kinds = {f.name: f.type for f in fields(StudyRow)}
    convert = {"float": float, "int": int, "str": str}
    with open(path, newline="") as handle:
        return [StudyRow(**{k: convert[kinds[k]](v) for k, v in row.items()})
                for row in csv.DictReader(handle)]


def write_csv(rows: Sequence[StudyRow], path: str | Path) -> None:
    """The study table, through safe_write (never through a link, never over another file)."""
    names = [f.name for f in fields(StudyRow)]
    with open_for_write(path, STUDY_TABLE) as handle:
        writer = csv.DictWriter(handle, fieldnames=names)
        writer.writeheader()
        for row in rows:
            writer.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v)
                             for k, v in asdict(row).items()})


def format_table(rows: Sequence[StudyRow], fits: dict[str, tuple[float, float]]) -> str:
    """Markdown table of the cells (ours beside the thesis' fit) and the fitted constants."""
    lines = ["| f'c | mesh | h_c | h_c (4.3) | A_cd | peak | peak/f'c | eps at peak | A_c | "
             "A_c thesis | ratio | snaps/jumps | run s |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        mark = " (stopped)" if r.stopped else ""
        lines.append(
            f"| {r.fc:g} | {r.mesh} | {r.h_c:g} | {r.h_c_eq43:.2f} | {r.input_area:.3f} | "
            f"{r.peak_stress:.2f} | {r.peak_ratio:.3f} | {r.strain_at_peak:.5f} | "
            f"{r.output_area:.4f}{mark} | {r.thesis_output_area:.4f} | "
            f"{r.output_area / r.thesis_output_area:.2f} | {r.snap_throughs}/{r.jumps} | "
            f"{r.run_time:.0f} |")
    lines += ["", "| fit | alpha_c (1/mm) | n | 1/alpha_c | 1/n |", "|---|---|---|---|---|",
              f"| thesis (A.7) | {THESIS_ALPHA_C:.5f} | {THESIS_N:.3f} | "
              f"{1 / THESIS_ALPHA_C:.1f} | {1 / THESIS_N:.3f} |"]
    for name, (alpha_c, n) in fits.items():
        lines.append(f"| ours, {name} | {alpha_c:.5f} | {n:.3f} | {1 / alpha_c:.1f} | "
                     f"{1 / n:.3f} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """Run the Appendix A cylinder study, write the CSV, print the table and the fit."""
    import argparse

    parser = argparse.ArgumentParser(prog="python -m icewall.analysis.cylinder",
                                     description=main.__doc__)
    parser.add_argument("-o", "--out", default="results/cylinder", help="output directory")
    parser.add_argument("-j", "--workers", type=int, default=1, help="parallel processes")
    parser.add_argument("--fc", type=float, action="append", choices=sorted(TABLE_A1),
                        help="only this strength (repeatable)")
    parser.add_argument("--mesh", action="append", choices=list(MESHES),
                        help="only this mesh (repeatable)")
    parser.add_argument("--table", metavar="CSV", help="print the table and fit of a written "
                        "CSV instead of running")
    args = parser.parse_args(argv)
    if args.table:
        try:
            rows = read_csv(args.table)
        except (OSError, KeyError, TypeError, ValueError) as exc:
            print(f"error: {args.table}: cannot read the study table ({exc})", file=sys.stderr)
            return 2
        print(format_table(rows, study_fit(rows)))
        return 0
    out = Path(args.out)
    try:
        out.mkdir(parents=True, exist_ok=True)
        check_replaceable(out / "cylinder_study.csv", STUDY_TABLE)
    except (OSError, ResultError) as exc:
        print(f"error: cannot create {out}: {exc}", file=sys.stderr)
        return 2
    specs = table_a1_cases(args.fc, args.mesh)
    print(f"Appendix A cylinder study: {len(specs)} analyses")
    rows = run_study(specs, max(args.workers, 1))
    fits = study_fit(rows)
    path = out / "cylinder_study.csv"
    write_csv(rows, path)
    print(format_table(rows, fits))
    print(f"\n{len(rows)} analyses, {sum(r.run_time for r in rows):.0f} s of solver time; "
          f"table in {path}")
    return 0 if all(r.completed for r in rows) else 1


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
