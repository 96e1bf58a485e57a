"""Run the numerical folders of the default test suite under each OpenBLAS kernel this CPU
can run, with one BLAS thread, and without the compiled concrete kernel: one line per run.

    python tools/test_platforms.py [--kernels Prescott,Haswell] [--folders tests/solve]

A kernel is probed first in a child process (a matrix product and threadpoolctl's report of
the architecture OpenBLAS chose): a kernel the CPU lacks the instructions for (SkylakeX and
Cooperlake need AVX-512) dies of SIGILL there and is reported "not supported", not run. The
environment variables are set here, on the pytest child, never inside the tests. Exit status 1
if any supported run failed. `make test-platforms` runs it (not part of `make test`).
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
KERNELS = ("Prescott", "Nehalem", "Sandybridge", "Haswell", "Zen", "SkylakeX", "Cooperlake")
NUMERICAL = ("tests/fem", "tests/materials", "tests/interface", "tests/model", "tests/solve",
             "tests/verification", "tests/compare", "tests/analysis", "tests/pipeline",
             "tests/stability")
PROBE = ("import numpy as np; from threadpoolctl import threadpool_info; "
         "a = np.arange(4e4).reshape(200, 200) / 4e4; (a @ a).sum(); "
         "print(','.join(sorted({i.get('architecture') or '?' for i in threadpool_info() "
         "if i.get('internal_api') == 'openblas'})))")


def probe(env: dict[str, str]) -> str | None:
    """The architecture OpenBLAS runs under `env`, or None where the CPU cannot run it."""
    done = subprocess.run([sys.executable, "-c", PROBE], env=env, capture_output=True,
                          text=True, check=False)
    return done.stdout.strip() or "?" if done.returncode == 0 else None


def run_pytest(env: dict[str, str], folders: list[str], workers: int = 0
               ) -> tuple[str, float]:
    """(pytest's summary line, seconds) of the folders under `env` (`workers` > 0: that many
    pytest-xdist processes, each test file on one, as `make test` runs them)."""
    tic = time.perf_counter()
    parallel = ["-n", str(workers), "--dist", "loadfile"] if workers > 0 else []
    done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-m", "not slow", "-p",
                           "no:cacheprovider", *parallel, *folders], env=env, cwd=ROOT,
                          capture_output=True, text=True, check=False)
    lines = [line for line in done.stdout.splitlines() if re.search(r"\d+ (passed|failed)",
                                                                     line)]
    summary = lines[-1].strip("= ") if lines else f"pytest exit {done.returncode}"
    if done.returncode != 0:
        failed = [line for line in done.stdout.splitlines() if line.startswith("FAILED")]
        summary += "".join(f"\n    {line}" for line in failed)
    return summary, time.perf_counter() - tic


def runs(kernels: list[str]) -> list[tuple[str, dict[str, str]]]:
    """(label, environment changes) of every run: each kernel, then the machine's own kernel
    with one BLAS thread, and with the NumPy concrete kernel."""
    out = [(k, {"OPENBLAS_CORETYPE": k}) for k in kernels]
    out.append(("default, 1 BLAS thread", {"OPENBLAS_NUM_THREADS": "1",
                                            "OMP_NUM_THREADS": "1"}))
    out.append(("default, NumPy concrete kernel", {"ICEWALL_CONCRETE_KERNEL": "numpy"}))
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--kernels", default=",".join(KERNELS))
    parser.add_argument("--folders", default=",".join(NUMERICAL))
    parser.add_argument("--workers", type=int, default=2,
                        help="pytest-xdist processes per run (0: in-process)")
    args = parser.parse_args()
    folders = [f for f in args.folders.split(",") if f]
    base = {k: v for k, v in os.environ.items()
            if k not in ("OPENBLAS_CORETYPE", "OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS",
                         "ICEWALL_CONCRETE_KERNEL")}
    print(f"{'run':32s} {'architecture (threadpoolctl)':30s} result")
    failed = False
    for label, change in runs([k for k in args.kernels.split(",") if k]):
        env = {**base, **change}
        architecture = probe(env)
        if architecture is None:
            print(f"{label:32s} {'-':30s} not supported by this CPU (SIGILL)", flush=True)
            continue
        summary, seconds = run_pytest(env, folders, args.workers)
        failed |= "failed" in summary or "error" in summary or "exit" in summary
        print(f"{label:32s} {architecture:30s} {summary} ({seconds:.0f} s)", flush=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
