"""End-to-end harness: the real gateway in lock-step, a firmware example scanning every SCAN s.

The plant and the controller alternate deterministically: one controller scan (it reads the
registers = the plant at time t and writes its commands), then SCAN plant steps of 1 s. The
built-in controller does the same with `controller.period = SCAN`: it scans at t = 0, SCAN, ...
on the sensor values at t and holds its outputs for the period, so both runs see the same
alignment and differ only by what the bus adds (0.1 K register resolution).
"""
from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

from gateway.clock import LockStepClock
from gateway.kpi import kpis, load_series
from gateway.runtime import Runtime
from plant.house import load_house

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "firmware-examples"
START = "2021-01-15"        # a winter day (-7.7 ... -1.2 degC outdoors)
DAY = 86400
SCAN = 10                   # controller scan period = plant steps between scans [s]


def load_example(folder: str, name: str = "controller"):
    """Import firmware-examples/<folder>/controller.py (the folders are not packages)."""
    path = EXAMPLES / folder / f"{name}.py"
    spec = importlib.util.spec_from_file_location(f"fw_{folder.replace('-', '_')}_{name}", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def make_runtime(record: Path, modbus: bool = True, can: str | None = None) -> Runtime:
    rt = Runtime(load_house("house1", start=START, controller="external"), clock=LockStepClock(1.0),
                 record=record, record_interval=1.0)
    if modbus:
        rt.add_modbus_tcp("127.0.0.1", 0)
    if can:
        rt.add_canopen(can)
    return rt


def modbus_port(rt: Runtime) -> int:
    return next(tr.port for tr in rt.transports if tr.name == "modbus-tcp")


@pytest.fixture(scope="session")
def offline_kpis():
    """The built-in rules on the same day, scan period and step: the reference."""
    house = load_house("house1", start=START, controller="rule_based",
                       overrides={"controller.period": float(SCAN)})
    times, rows = house.run(DAY, dt=1.0, out_interval=1.0)
    return kpis(times, house.catalogue.names, rows)


def recorded_kpis(directory: Path):
    return kpis(*load_series(directory))


def heat_difference_pct(run, ref) -> dict[str, float]:
    return {g: 100.0 * (getattr(run, f"heat_{g}_kWh") - getattr(ref, f"heat_{g}_kWh"))
            / getattr(ref, f"heat_{g}_kWh") for g in ("chp", "boiler")}
