"""Candidate fits in parallel processes.

Each simulate-kind candidate replays the recording a few dozen times, independently of the
others, so they are spread over the CPUs (2 on the reference machine: the 7-day diagnosis takes
about half the wall time). The workers are forked, so they inherit the recording, the replayer
and any user candidates registered at run time (`--effects`) without pickling them; a result
comes back without its effect object, which the parent re-attaches. Where fork is unavailable
or jobs = 1, or other threads run in this process (they would not exist in a forked child while
their locks might), the fits run in this process, in order; results are the same either way.
"""
from __future__ import annotations

import dataclasses
import multiprocessing
import os
import threading
from concurrent.futures import ProcessPoolExecutor

from ..errors import ConfigError
from . import fit, station_fit

_JOB: dict = {}


def _call(i: int):
    return _JOB["fn"](i)


def default_jobs() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def map_forked(fn, n: int, jobs: int | None = None) -> list:
    """[fn(0), ..., fn(n - 1)], in up to `jobs` forked processes (fn and what it reads are
    inherited, not pickled; what it returns is pickled back)."""
    jobs = min(default_jobs() if jobs is None else max(1, int(jobs)), n)
    # fork copies only the calling thread: with other threads alive (a gateway in the same
    # process) a lock they hold could never be released in the child, so run here instead
    if jobs <= 1 or "fork" not in multiprocessing.get_all_start_methods() or threading.active_count() > 1:
        return [fn(i) for i in range(n)]
    _JOB.update(fn=fn)
    try:
        with ProcessPoolExecutor(jobs, mp_context=multiprocessing.get_context("fork")) as pool:
            return list(pool.map(_call, range(n)))
    finally:
        _JOB.clear()


def fit_all(effects: list, ctx, rp, J0t: float, nominal, jobs: int | None = None) -> list:
    """fit.fit_simulate for each effect (station_fit.fit for one on the mixing station alone), in
    up to `jobs` forked processes. A candidate whose values the replayed house refuses (a plume
    beyond half of a smaller tank) comes back unfitted with the house's reason; the others go on."""
    def one(i):
        e = effects[i]
        try:
            r = station_fit.fit(e, ctx, rp) if station_fit.applies(e, rp) else fit.fit_simulate(e, ctx, rp, J0t, nominal)
            return dataclasses.replace(r, effect=None)
        except ConfigError as exc:
            return fit.Result(e.id, e.component, e.kind, False, f"the replayed house refuses its values: {exc}")

    out = map_forked(one, len(effects), jobs)
    return [dataclasses.replace(r, effect=e) for e, r in zip(effects, out)]
