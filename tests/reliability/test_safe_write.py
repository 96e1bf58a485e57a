"""Issue 38, item 1: every file icewall writes goes through icewall.safe_write, so none is ever
written through a link icewall did not create, and none replaces a file icewall did not write.
Each writer of the command line, three ways: a planted link (its target untouched), a file of
someone else's at the name (untouched), and icewall's own earlier output (replaced: reruns
work). And a scan of the package: no writer around safe_write."""

from __future__ import annotations

import os
import re
import shutil
from pathlib import Path

import pytest
from reliability_helpers import CF4, digest, icewall, one_error_line

ICEWALL = Path(__file__).resolve().parents[2] / "icewall"
QUICK = ["--set", "analysis.solver=linear", "--set", "loads.control.target=1"]


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> Path:
    """A sweep output of one tiny linear run (its .h5 is the result the readers read)."""
    out = tmp_path_factory.mktemp("runs")
    done = icewall("run", CF4, *QUICK, "--set", "outputs.fields=[displacement, stress]", "-q",
                   "-o", str(out / "cf4.h5"))
    assert done.returncode == 0, done.stderr
    return out


# case -> (argv(work dir, runs dir), the output path it writes, relative to the work dir)
CASES = {
    "sweep-table": (lambda d, r: ["sweep", CF4, *QUICK, "-j", "1", "-q", "-o", str(d)],
                    "sweep_summary.csv"),
    "sweep-result": (lambda d, r: ["sweep", CF4, *QUICK, "-j", "1", "-q", "-o", str(d)],
                     "cf4.h5"),
    "report": (lambda d, r: ["report", str(r / "cf4.h5"), "-o", str(d / "report.html")],
               "report.html"),
    "plot-png": (lambda d, r: ["plot", str(r / "cf4.h5"), "-o", str(d), "--format", "png"],
                 "curves.png"),
    "plot-svg": (lambda d, r: ["plot", str(r / "cf4.h5"), "-o", str(d), "--format", "svg"],
                 "curves.svg"),
    "export-pvd": (lambda d, r: ["export", str(r / "cf4.h5"), "-o", str(d / "x.pvd")],
                   "x.pvd"),
    "export-vtu": (lambda d, r: ["export", str(r / "cf4.h5"), "-o", str(d / "x.pvd")],
                   "x/step_00001.vtu"),
    "schema": (lambda d, r: ["schema", "-o", str(d / "s.json")], "s.json"),
    "point-csv": (lambda d, r: ["point", "--fc", "40", "--steps", "5", "--csv",
                                str(d / "p.csv")], "p.csv"),
    "mesh-msh": (lambda d, r: ["mesh", CF4, "--out", str(d), "--format", "msh"], "cf4.msh"),
    "mesh-xdmf-data": (lambda d, r: ["mesh", CF4, "--out", str(d), "--format", "xdmf"],
                       "cf4.h5"),
    "compare-update": (lambda d, r: ["compare", str(r), "--baseline", str(d / "b.yaml"),
                                     "--update"], "b.yaml"),
    "run-result": (lambda d, r: ["run", CF4, *QUICK, "-q", "-o", str(d / "x.h5")], "x.h5"),
    "run-lock": (lambda d, r: ["run", CF4, *QUICK, "-q", "-o", str(d / "x.h5")], "x.h5.lock"),
    "convergence-table": (lambda d, r: ["convergence", CF4, "--quick", "--tables-only", "-q",
                                        "-o", str(d)], "convergence_runs.csv"),
}


def _work(tmp_path: Path, target: str) -> tuple[Path, Path]:
    work = tmp_path / "work"
    (work / target).parent.mkdir(parents=True, exist_ok=True)
    return work, work / target


@pytest.mark.parametrize("case", list(CASES))
def test_a_planted_link_is_never_written_through(case, runs, tmp_path):
    argv, target = CASES[case]
    work, path = _work(tmp_path, target)
    victim = tmp_path / "victim.txt"
    victim.write_text("precious\n")
    os.symlink(victim, path)
    done = icewall(*argv(work, runs))
    assert done.returncode == 2, (done.stdout, done.stderr)
    assert "symbolic link" in one_error_line(done.stderr)
    assert victim.read_text() == "precious\n" and path.is_symlink()


@pytest.mark.parametrize("case", list(CASES))
def test_a_file_icewall_did_not_write_is_never_replaced(case, runs, tmp_path):
    argv, target = CASES[case]
    work, path = _work(tmp_path, target)
    path.write_bytes(b"someone else's data, not icewall's\n")
    before = digest(path)
    done = icewall(*argv(work, runs))
    assert done.returncode == 2, (done.stdout, done.stderr)
    assert "icewall wrote" in one_error_line(done.stderr)
    assert digest(path) == before


@pytest.mark.parametrize("case", [c for c in CASES if c not in ("run-lock",
                                                                 "convergence-table")])
def test_icewall_replaces_its_own_earlier_output(case, runs, tmp_path):
    argv, target = CASES[case]
    work, path = _work(tmp_path, target)
    extra = ["--force"] if case == "sweep-table" else []
    for _ in range(2):
        done = icewall(*argv(work, runs), *extra)
        assert done.returncode == 0, (done.stdout, done.stderr)
        assert path.is_file() and not path.is_symlink()
    leftovers = [p.name for p in work.rglob("*") if p.name.endswith(".tmp")]
    assert leftovers == []


def test_a_read_only_earlier_output_is_refused(runs, tmp_path):
    out = tmp_path / "s.json"
    assert icewall("schema", "-o", str(out)).returncode == 0
    out.chmod(0o444)
    if os.access(out, os.W_OK):
        pytest.skip("root ignores permissions")
    before = digest(out)
    done = icewall("schema", "-o", str(out))
    assert done.returncode == 2 and "read-only" in one_error_line(done.stderr)
    assert digest(out) == before


def test_the_sweep_refuses_its_table_before_running(tmp_path):
    """The issue's case: the table's planted link is refused before any run, not after."""
    out = tmp_path / "d"
    out.mkdir()
    (out / "v.txt").write_text("precious\n")
    os.symlink(out / "v.txt", out / "sweep_summary.csv")
    done = icewall("sweep", CF4, "--set", "analysis.solver=linear", "--set",
                   "loads.control.target=3", "-j", "1", "-o", str(out))
    assert done.returncode == 2 and "symbolic link" in one_error_line(done.stderr)
    assert (out / "v.txt").read_text() == "precious\n"
    assert sorted(p.name for p in out.iterdir()) == ["sweep_summary.csv", "v.txt"]


def test_a_foreign_partial_is_not_removed(tmp_path):
    """A dead run's .partial (HDF5) is removed by the next run; another file is refused."""
    out = tmp_path / "x.h5"
    partial = tmp_path / "x.h5.partial"
    partial.write_bytes(b"not a result\n")
    done = icewall("run", CF4, *QUICK, "-q", "-o", str(out))
    assert done.returncode == 2 and "partial result icewall wrote" in one_error_line(done.stderr)
    assert partial.read_bytes() == b"not a result\n" and not out.exists()
    shutil.copy(CF4, partial)  # still not HDF5
    assert icewall("run", CF4, *QUICK, "-q", "-o", str(out)).returncode == 2
    partial.write_bytes(b"")  # a run killed while creating it
    assert icewall("run", CF4, *QUICK, "-q", "-o", str(out)).returncode == 0


# -- one place: no writer of the package around icewall.safe_write ------------------------------
_WRITERS = re.compile("|".join([
    r"""open\([^)]*["'][wax]b?\+?["']""", r"\.write_text\(", r"\.write_bytes\(", r"os\.replace\(",
    r"os\.rename\(", r"shutil\.(copy|move)", r"np\.save\(", r"savefig\((?!buffer)",
    r"(meshio|gmsh)\.write\((?!name)",  # `name`: the path safe_write.library_output gives
    r"""h5py\.File\((?!handle)[^)]*["'][wax]""",  # `handle`: safe_write.open_existing's
]))
_ALLOWED = {  # file -> what it may write itself, and why that is safe
    "safe_write.py": "the one place",
    "results/writer.py": "h5py.File(partial, 'x'/'a'): the run's .partial, created exclusively "
                         "under the output's lock, links refused (output_safety)",
}


def test_every_writer_goes_through_safe_write():
    offending = []
    for path in sorted(ICEWALL.rglob("*.py")):
        rel = path.relative_to(ICEWALL).as_posix()
        if rel in _ALLOWED or rel.startswith("solve/"):  # the solver writes no file
            continue
        for number, line in enumerate(path.read_text().splitlines(), start=1):
            if _WRITERS.search(line) and not line.lstrip().startswith("#"):
                offending.append(f"{rel}:{number}: {line.strip()}")
    assert offending == []


def test_the_solver_writes_no_file():
    text = "\n".join(p.read_text() for p in sorted((ICEWALL / "solve").rglob("*.py")))
    assert not _WRITERS.search(text)
