"""Regression cases of house 1: 7-day runs whose hourly signals are kept as references.

The references in tests/regression/reference/ are our own earlier output. They are written only
by `python3 -m tests.regression.cases --write` and the diff is reviewed; a test never writes them.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

REFERENCE = Path(__file__).parent / "reference"
DAYS = 7
# name -> (start, overrides): the default rule set with the constant-60 degC thermostat, the
# heating-curve thermostat, and the effect knobs of the ideal switch switched on.
CASES = {
    "house1_rule_based": ("2021-01-10", {}),
    "house1_heating_curve": ("2021-03-01", {"thermostat.curve": True}),
    "house1_knobs": ("2021-01-10", {"switch.idle_flow.chp": 0.3,
                                    "switch.pump_coupling.chp": 0.1,
                                    "switch.storage_inlet_mixing": 0.05,
                                    "mixer.leak": 0.05}),
}


def simulate(name: str):
    """(signal names, times [s], rows, ledger) of one case at a 1 s step, recorded hourly."""
    from plant.house import load_house

    start, overrides = CASES[name]
    house = load_house("house1", start=start, overrides=overrides)
    t, rows = house.run(DAYS * 86400, dt=1.0, out_interval=3600.0)
    return list(house.catalogue.names), t, rows, house.ledger()


def write(name: str) -> Path:
    names, t, rows, _ = simulate(name)
    path = REFERENCE / f"{name}.csv"
    with path.open("w") as f:
        f.write(",".join(["time"] + names) + "\n")
        for ti, row in zip(t, rows):
            f.write(",".join([repr(float(ti))] + [repr(float(v)) for v in row]) + "\n")
    return path


def read(name: str) -> tuple[list[str], np.ndarray]:
    path = REFERENCE / f"{name}.csv"
    with path.open() as f:
        header = f.readline().strip().split(",")
    return header, np.loadtxt(path, delimiter=",", skiprows=1)


if __name__ == "__main__":
    if sys.argv[1:] != ["--write"]:
        sys.exit("usage: python3 -m tests.regression.cases --write   (review the diff afterwards)")
    for case in CASES:
        print("wrote", write(case))
