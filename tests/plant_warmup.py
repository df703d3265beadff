"""Compile every shipped house once per test run, on every core, before the tests start (#27).

A plant is compiled by numba when it is first loaded: house 1 takes ~50 s of CPU (with the
component kernels every house shares), each other house 10-20 s; afterwards it loads from the
on-disk plant cache (plant/__init__.py) in ~1 s. Left to the tests, the two pytest-xdist workers
can compile the same house at the same time (twice the CPU for one result), and the test that
happens to load a house first pays for it inside its own 300 s timeout, which a district's
federates or a `twin` subprocess compiling on a loaded machine can overrun. Here each house is
compiled once, in a pool of processes, while the workers collect the tests
(tests/conftest.py: whole-suite runs with workers only); a house already in the cache costs a
load of ~1 s.
"""
from __future__ import annotations

import multiprocessing
import re
import time
from concurrent.futures import Future, ProcessPoolExecutor
from pathlib import Path

HOUSES = Path(__file__).resolve().parents[1] / "plant" / "houses"


def house_files() -> list[Path]:
    """The shipped house files (those with a [house] table), house1.toml first: it compiles the
    kernels the others share, so the other processes find them in the cache sooner."""
    files = [p for p in sorted(HOUSES.glob("*.toml")) if re.search(r"^\[house\]", p.read_text(), re.M)]
    return sorted(files, key=lambda p: p.name != "house1.toml")


def compile_house(path: str) -> tuple[str, float, str | None]:
    """Load (and so compile, or find in the cache) one house: (file name, seconds, error)."""
    t = time.monotonic()
    try:
        from plant.house import load_house

        load_house(path).close()
    except Exception as e:  # noqa: BLE001 - a broken house fails its own tests, not the warm-up
        return Path(path).name, time.monotonic() - t, f"{type(e).__name__}: {e}"
    return Path(path).name, time.monotonic() - t, None


class Warmup:
    """Compile the shipped houses in `jobs` fresh processes; wait() for the result."""

    def __init__(self, jobs: int):
        self.t0 = time.monotonic()
        self.pool = ProcessPoolExecutor(jobs, mp_context=multiprocessing.get_context("spawn"))
        self.futures: list[Future] = [self.pool.submit(compile_house, str(p)) for p in house_files()]
        self.jobs = jobs

    def wait(self) -> str:
        """Block until every house is compiled; one line saying what it took."""
        try:
            results = [f.result() for f in self.futures]
        except Exception as e:  # noqa: BLE001 - a lost process: the tests compile what is missing
            self.pool.shutdown(cancel_futures=True)
            return f"plant warm-up stopped ({type(e).__name__}: {e}); the tests compile what is missing"
        self.pool.shutdown()
        failed = [f"{name} ({error.splitlines()[0][:120]})" for name, _, error in results if error]
        slowest = max(results, key=lambda r: r[1])
        line = (f"plant warm-up: {len(results)} shipped houses compiled or found in the plant cache in "
                f"{time.monotonic() - self.t0:.0f} s by {self.jobs} processes (slowest {slowest[0]} "
                f"{slowest[1]:.0f} s)")
        return line + (f"; failed, left to their tests: {', '.join(failed)}" if failed else "")
