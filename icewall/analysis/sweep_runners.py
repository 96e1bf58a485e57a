"""Where the runs of a sweep run (`icewall.analysis.sweep`): one job in a worker (`run_job`,
never raises), a local process pool whose workers die with the sweep and stop cleanly on
SIGTERM (`run_local`), or an existing Dask cluster (`run_dask`)."""

from __future__ import annotations

import json
import os
import time
from collections.abc import Callable
from dataclasses import dataclass

from icewall.deck.load import load_deck
from icewall.errors import IcewallError, Interrupted
from icewall.pipeline import run_deck


@dataclass(frozen=True)
class Job:
    """One run of a sweep: deck, its overrides (fixed, then varied), name and result file."""

    name: str
    deck: str
    overrides: tuple[str, ...]
    varied: tuple[str, ...]
    output: str
    profile: str | None = None  # the profile file applied under the overrides (deck.profile)


_RUN_IN_PROGRESS = False  # in a worker: whether run_job is running (SIGTERM interrupts it)
_STOPPING = False  # in a worker: SIGTERM came; the worker ends once its run is closed


def run_job(job: Job) -> dict:
    """Run one job (in a worker); never raises: a failure is a result with status failed."""
    global _RUN_IN_PROGRESS
    start = time.perf_counter()
    out = {"name": job.name, "path": job.output, "status": "failed", "reason": "",
           "run_time_s": 0.0, "n_steps": 0}
    _RUN_IN_PROGRESS = True
    try:
        loaded = load_deck(job.deck, job.overrides, job.profile)
        report = run_deck(loaded, job.output, progress=None, replace=True,
                          attrs={"sweep_overrides": json.dumps(list(job.overrides))})
        out.update(path=report.path, status=report.status, reason=report.reason,
                   n_steps=report.n_steps)
    except IcewallError as exc:
        out["reason"] = str(exc)
    except Exception as exc:  # noqa: BLE001 - any failure is this job's, the sweep goes on
        out["reason"] = f"{type(exc).__name__}: {exc}"
    finally:
        _RUN_IN_PROGRESS = False
        if _STOPPING:  # the sweep is stopping: its table lists only finished runs
            os._exit(143)
    out["run_time_s"] = time.perf_counter() - start
    return out


def _failed(job: Job, reason: str) -> dict:
    return {"name": job.name, "path": job.output, "status": "failed", "reason": reason,
            "run_time_s": 0.0, "n_steps": 0}


def _die_with(sweep_pid: int) -> None:
    """Worker initializer: the worker dies with the sweep, however the sweep ends, and SIGTERM
    interrupts its run as in `icewall run` (the writer records why and keeps the steps)."""
    import signal
    import sys
    import threading

    def interrupted(signum, frame) -> None:
        global _STOPPING
        if not _RUN_IN_PROGRESS:  # an idle worker just ends
            os._exit(128 + signum)
        if _STOPPING:  # a repeated signal: let the run close its file first
            return
        _STOPPING = True
        raise Interrupted(signal.Signals(signum).name, 128 + signum)

    signal.signal(signal.SIGTERM, interrupted)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the sweep's to handle
    parent = os.getppid()
    if sys.platform.startswith("linux"):  # the parent (the sweep or its forkserver) dies
        import ctypes

        pr_set_pdeathsig = 1
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(pr_set_pdeathsig, signal.SIGKILL, 0, 0, 0)

    def watch() -> None:  # also where prctl is missing, or the parent died before it
        while True:
            if not (_alive(sweep_pid) and os.getppid() == parent):
                os.kill(os.getpid(), signal.SIGKILL)
            time.sleep(0.5)

    threading.Thread(target=watch, name="icewall-sweep-watch", daemon=True).start()


def _pool(workers: int):
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    methods = multiprocessing.get_all_start_methods()
    ctx = multiprocessing.get_context("forkserver" if "forkserver" in methods else "spawn")
    if ctx.get_start_method() == "forkserver":
        ctx.set_forkserver_preload(["icewall.pipeline"])
    return ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=_die_with,
                               initargs=(os.getpid(),))


def _stop_workers(workers) -> None:
    """SIGTERM a pool's workers: each run records the interruption and keeps its steps."""
    for process in workers:
        if process.is_alive():
            process.terminate()


def run_local(jobs: list[Job], workers: int, done: Callable[[dict], None],
              runner: Callable[[Job], dict] = run_job) -> None:
    """Run `jobs` in a process pool; `done(result)` as each finishes. A worker that dies breaks
    the pool and fails every job not yet done; each of those is rerun in a pool of its own (as
    many at a time as `workers`), so that only the culprit fails."""
    from concurrent.futures import as_completed
    from concurrent.futures.process import BrokenProcessPool

    suspects: list[Job] = []
    with _pool(max(1, min(workers, len(jobs)))) as pool:
        futures = {pool.submit(runner, job): job for job in jobs}
        try:
            for future in as_completed(futures):
                try:
                    done(future.result())
                except BrokenProcessPool:
                    suspects.append(futures[future])
                except Exception as exc:  # noqa: BLE001
                    done(_failed(futures[future], f"{type(exc).__name__}: {exc}"))
        except BaseException:  # Ctrl-C, SIGTERM: start no more runs, stop the running ones
            workers = list((getattr(pool, "_processes", None) or {}).values())
            pool.shutdown(wait=False, cancel_futures=True)
            _stop_workers(workers)
            raise
    if suspects:
        from concurrent.futures import ThreadPoolExecutor

        def alone(job: Job) -> dict:
            with _pool(1) as pool:
                try:
                    return pool.submit(runner, job).result()
                except BrokenProcessPool:
                    return _failed(job, "the worker process died (crash or out of memory)")

        with ThreadPoolExecutor(max(1, min(workers, len(suspects)))) as threads:
            for future in as_completed([threads.submit(alone, job) for job in suspects]):
                done(future.result())


def run_dask(jobs: list[Job], address: str, done: Callable[[dict], None],
             runner: Callable[[Job], dict] = run_job) -> None:
    """Submit `jobs` to the Dask scheduler at `address`; `done(result)` as each finishes."""
    try:
        from dask.distributed import Client, as_completed
    except ImportError:
        raise IcewallError("--scheduler needs Dask: pip install 'icewall[cluster]'") from None
    absolute = [Job(j.name, os.path.abspath(j.deck), j.overrides, j.varied,
                    os.path.abspath(j.output),
                    None if j.profile is None else os.path.abspath(j.profile)) for j in jobs]
    try:
        client = Client(address, timeout="20s")
    except (OSError, TimeoutError, ValueError) as exc:
        raise IcewallError(f"cannot connect to the Dask scheduler {address}: {exc}") from None
    with client:
        futures = {client.submit(runner, job, key=f"icewall-sweep-{job.name}-{time.time_ns()}",
                                 pure=False): job for job in absolute}
        try:
            for future in as_completed(futures):
                try:
                    done(future.result())
                except Exception as exc:  # noqa: BLE001 - KilledWorker, lost worker, ...
                    done(_failed(futures[future], f"{type(exc).__name__}: {exc}"))
        except BaseException:  # Ctrl-C: withdraw what has not run
            client.cancel(list(futures))
            raise


def _alive(pid: int) -> bool:
    """Whether process `pid` runs: it exists and, on Linux, is not a zombie (a SIGKILLed
    sweep stays a zombie until its parent reaps it, and os.kill(pid, 0) still succeeds)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    try:
        with open(f"/proc/{pid}/stat", "rb") as stat:
            return stat.read().rsplit(b")", 1)[1].split()[0] not in (b"Z", b"X")
    except OSError:
        return True  # no /proc: existence is all that can be told
