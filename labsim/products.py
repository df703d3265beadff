"""Measured product tables for labsim: the neoTower 2 CHP and the Wolf CGB-14 boiler.

The tables are the ones shipped in plant/data (MSL text tables, read with plant.tables.read_tables
only); the look-up here is labsim's own: linear in 1-D and bilinear in 2-D, clamped at the grid
edges (reference 0.2). Temperatures in the tables' row abscissae are kelvin; they are converted
to degC once here.
"""
from __future__ import annotations

from functools import cache
from pathlib import Path

import numpy as np

import plant.tables
from plant.tables import read_tables

# the twin's product tables (plant/data), found through the plant package wherever it is installed
DATA = Path(plant.tables.__file__).resolve().parent / "data"


class Table1D:
    """Columns of a 1-D table against its first column; clamped linear interpolation."""

    def __init__(self, table: np.ndarray):
        self.x = np.ascontiguousarray(table[:, 0])
        self.cols = [np.ascontiguousarray(table[:, j]) for j in range(table.shape[1])]

    def __call__(self, x: float, col: int) -> float:
        return float(np.interp(x, self.x, self.cols[col]))


class Table2D:
    """A 2-D table (top-left dummy, first row = column abscissa u2, first column = row abscissa u1)."""

    def __init__(self, table: np.ndarray, row_offset: float = 0.0):
        self.u1 = table[1:, 0] + row_offset
        self.u2 = table[0, 1:]
        self.v = table[1:, 1:]

    def __call__(self, u1: float, u2: float) -> float:
        u1 = min(max(u1, self.u1[0]), self.u1[-1])
        u2 = min(max(u2, self.u2[0]), self.u2[-1])
        i = int(np.searchsorted(self.u1, u1, side="right")) - 1
        i = min(max(i, 0), len(self.u1) - 2)
        j = int(np.searchsorted(self.u2, u2, side="right")) - 1
        j = min(max(j, 0), len(self.u2) - 2)
        a = (u1 - self.u1[i]) / (self.u1[i + 1] - self.u1[i])
        b = (u2 - self.u2[j]) / (self.u2[j + 1] - self.u2[j])
        v = self.v
        return float((1 - a) * (1 - b) * v[i, j] + a * (1 - b) * v[i + 1, j]
                     + (1 - a) * b * v[i, j + 1] + a * b * v[i + 1, j + 1])


@cache
def chp_tables() -> dict:
    """neoTower 2: total efficiency (T_ret degC, modulation), start-up and cool-down tables."""
    d = DATA / "chp_neotower2"
    return {
        "efficiency": Table2D(read_tables(d / "neoTower2_Efficiency.txt")["Efficiency"], -273.15),
        "startup": Table1D(read_tables(d / "neoTower2_StartUp.txt")["StartUp"]),
        "cooldown": Table1D(read_tables(d / "neoTower2_CoolDown.txt")["CoolDown"]),
    }


@cache
def boiler_tables() -> dict:
    """CGB-14: normalised heat, spread and efficiency (T_ret degC, modulation); start-up, cool-down."""
    d = DATA / "boiler_wolf_cgb"
    ss = read_tables(d / "WolfCGB14_SteadyState.txt")
    return {
        "heat": Table2D(ss["PHeat"], -273.15),
        "spread": Table2D(ss["DeltaT"], -273.15),
        "efficiency": Table2D(ss["EffHeat"], -273.15),
        "startup": Table1D(read_tables(d / "WolfCGB14_StartUp.txt")["StartUp"]),
        "cooldown": Table1D(read_tables(d / "WolfCGB14_CoolDown.txt")["CoolDown"]),
    }
