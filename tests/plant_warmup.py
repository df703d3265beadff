"""Compile every shipped house once per test run, on every core, before the tests start (#27).

A plant is compiled by numba when it is first loaded: house 1 takes ~30 s of CPU (with the
component kernels every house shares), each other house 10-15 s; afterwards it loads from the
on-disk plant cache (plant/__init__.py) in ~1 s. Left to the tests, the pytest-xdist workers
can compile the same house at the same time (twice the CPU for one result), and the test that
happens to load a house first pays for it inside its own 300 s timeout, which a district's
federates or a `twin` subprocess compiling on a loaded machine can overrun. Here each house is
compiled once, in a pool of processes, while the workers collect the tests
(tests/conftest.py: whole-suite runs with workers only); a house already in the cache costs a
load of ~1 s.

After the shipped houses, the same pool compiles the variants the diagnoses of house-1 and house-2
recordings replay (DIAGNOSIS_VARIANTS: the derived circuit cut, with and without the re-fit's port
mixing, at whatever sensor heights a columns file gives, and house 1 whole with it), with the
replay's `drive`: a dozen diagnosis tests need them, and both workers would otherwise compile the
same ones side by side when the diagnosis files start.
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


# (label, house, cut, overrides that change the generated plant): what a diagnosis loads besides the
# file's plant (cut: the house's derived circuit cut, plant/diagnose/derive.py). An inflow spread
# beyond its port layer (calibration.NOMINAL_REFIT's switch.storage_inlet_mixing, house 2's heating
# branch too) compiles another plant; sensor heights (a columns file's) are parameters of the step
# and compile none, so a plant read at the lab's or the rig's sensors is the one listed here.
# House 2's are those its rig recording replays (tests/diagnose/test_any_house.py), found by
# loading every plant a diagnosis of it replays.
# A cut may also put the boiler at its measured outlet (pipeline.outlets: where the recording runs it
# otherwise than the twin's model; most of the house-1 lab and rig recordings the tests diagnose).
_MIXING = {"switch.storage_inlet_mixing": 0.025}
_BOILER = ("boiler",)
DIAGNOSIS_VARIANTS = (
    ("house1 (driven)", "house1", False, {}),
    ("house1 + port mixing", "house1", False, _MIXING),
    ("house1 cut", "house1", True, {}),
    ("house1 cut + port mixing", "house1", True, _MIXING),
    ("house1 cut, boiler at its outlet", "house1", _BOILER, {}),
    ("house1 cut, boiler at its outlet + port mixing", "house1", _BOILER, _MIXING),
    ("house2 cut", "house2", True, {}),
    ("house2 cut + port mixing", "house2", True, _MIXING),
    ("house2 cut + heating port mixing", "house2", True, {"heating.storage_inlet_mixing": 0.025}),
    ("house2 cut + both port mixings", "house2", True, {**_MIXING, "heating.storage_inlet_mixing": 0.025}),
)


def compile_variant(label: str, house: str, cut, overrides: dict) -> tuple[str, float, str | None]:
    """Load one variant as a replay does (external controller) and drive it for two samples, so
    that its advance is compiled (or found in the cache): (label, seconds, error). cut: False (the
    house), True (its circuit cut) or the generators the cut puts at their measured outlets."""
    t = time.monotonic()
    try:
        import numpy as np

        from plant.house import load_house

        path = house
        if cut:
            from plant.diagnose.derive import derive

            path = str(derive(house, "circuit", () if cut is True else tuple(cut)).path())
        h = load_house(path, start="2021-01-10", controller="external", overrides=overrides or None)
        h.drive(np.array([0.0, 60.0]), [], np.zeros((2, 0)))
        h.close()
    except Exception as e:  # noqa: BLE001 - a broken variant fails its own tests, not the warm-up
        return label, time.monotonic() - t, f"{type(e).__name__}: {e}"
    return label, time.monotonic() - t, None


class Warmup:
    """Compile the shipped houses in `jobs` fresh processes; wait() for the result."""

    def __init__(self, jobs: int):
        self.t0 = time.monotonic()
        self.pool = ProcessPoolExecutor(jobs, mp_context=multiprocessing.get_context("spawn"))
        self.futures: list[Future] = [self.pool.submit(compile_house, str(p)) for p in house_files()]
        self.variants: list[Future] = [self.pool.submit(compile_variant, *v) for v in DIAGNOSIS_VARIANTS]
        self.jobs = jobs

    def wait(self) -> str:
        """Block until every house is compiled; one line saying what it took."""
        try:
            results = [f.result() for f in self.futures]
            variants = [f.result() for f in self.variants]
        except Exception as e:  # noqa: BLE001 - a lost process: the tests compile what is missing
            self.pool.shutdown(cancel_futures=True)
            return f"plant warm-up stopped ({type(e).__name__}: {e}); the tests compile what is missing"
        self.pool.shutdown()
        failed = [f"{name} ({error.splitlines()[0][:120]})" for name, _, error in results if error]
        slowest = max(results, key=lambda r: r[1])
        line = (f"plant warm-up: {len(results)} shipped houses compiled or found in the plant cache in "
                f"{time.monotonic() - self.t0:.0f} s by {self.jobs} processes (slowest {slowest[0]} "
                f"{slowest[1]:.0f} s)")
        failed += [f"{name} ({error.splitlines()[0][:120]})" for name, _, error in variants if error]
        line += f", and {len(variants)} variants a diagnosis replays"
        return line + (f"; failed, left to their tests: {', '.join(failed)}" if failed else "")
