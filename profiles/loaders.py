"""Loaders for the shipped profiles, resampled to uniform series on one local-time axis.

Time axis: seconds since 2021-01-01 00:00 local standard time (CET, UTC+1, no daylight saving).
Choices about the original data's quirks (written down here and in plant/houses/house1.md):
  * weather (Munich 2021, 15 min): the file's axis is UTC (solar noon near 11:10), so it is
    shifted by +1 h onto local standard time; column 4 ("direct") is treated as horizontal beam
    irradiance, column 5 as horizontal diffuse; temperature is hourly data repeated, used as is
    with linear interpolation;
  * household electricity: the 15-min standard load profile (1000 kWh/a), scaled to the house's
    annual consumption;
  * presence: hourly fraction of residents at home, one year;
  * hot water: the DHWcalc whole-year minute series of house SF1 (l/h per minute, daylight saving
    applied by DHWcalc; we read it as local standard time, so summer draws are 1 h early —
    irrelevant for heating-season studies);
  * the default DHW profile of the original library (time in minutes read as seconds) is not used.
All series wrap around at the end of the year.
"""
from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime
from functools import cache
from pathlib import Path

import numpy as np
from numba import njit

from plant.errors import ConfigError, DataError
from plant.tables import read_tables

HERE = Path(__file__).parent
YEAR_S = 365 * 86400.0
YEAR_START = datetime(2021, 1, 1)


@dataclass(frozen=True)
class Series:
    """A uniform series: values[k] at k*step seconds after the year start; linear or step-wise."""

    values: np.ndarray
    step: float
    linear: bool

    def at(self, tau: np.ndarray) -> np.ndarray:
        """The values at local times tau [s] (an array), wrapping at the series' end, as `sample`
        gives them one at a time."""
        tau = np.asarray(tau, dtype=float) % (self.values.size * self.step)
        if not self.linear:
            return self.values[np.minimum((tau // self.step).astype(int), self.values.size - 1)]
        grid = np.arange(self.values.size + 1) * self.step
        return np.interp(tau, grid, np.append(self.values, self.values[0]))


@njit(cache=True)
def sample(values, step, linear, tau):
    """Value of a uniform year series at local time tau [s], wrapping at the year end."""
    n = values.shape[0]
    period = n * step
    tau = tau % period
    pos = tau / step
    k = int(pos)
    if k >= n:
        k = n - 1
    if not linear:
        return values[k]
    w = pos - k
    k1 = k + 1 if k + 1 < n else 0
    return values[k] * (1.0 - w) + values[k1] * w


def start_offset(start: str) -> float:
    """Seconds from the profile year start to an ISO date or datetime (year ignored beyond 2021)."""
    try:
        when = datetime.fromisoformat(str(start))
    except ValueError:
        raise ConfigError(f"start = {start!r}: not a date; use YYYY-MM-DD or YYYY-MM-DDTHH:MM") from None
    when = when.replace(year=2021)
    return (when - YEAR_START).total_seconds()


@cache
def weather() -> dict[str, Series]:
    """Munich 2021, 15 min: air temperature [degC], beam and diffuse horizontal irradiance [W/m2]."""
    table = read_tables(HERE / "weather" / "Weather_2021_Munich_15min.txt")["Weather"]
    if table.shape[0] < 35040:
        raise DataError("profiles/weather: expected 35041 rows of 15-min data")
    shift = 4  # UTC -> CET: the value at local 01:00 is the file's 00:00 value
    cols = {"T_air": 1, "E_dir": 3, "E_dif": 4}
    return {
        name: Series(np.roll(table[:35040, c].copy(), shift), 900.0, True) for name, c in cols.items()
    }


@cache
def presence() -> Series:
    table = read_tables(HERE / "occupancy" / "presenceResidential.txt")["presence"]
    return Series(table[:8760, 1].copy(), 3600.0, True)


@cache
def _electricity_1mwh() -> np.ndarray:
    table = read_tables(HERE / "electricity" / "elPower.txt")["Pel"]
    return table[:35040, 1].copy()


def electricity(annual_kwh: float) -> Series:
    """Household electric power [W], the standard profile scaled to annual_kwh."""
    base = _electricity_1mwh()
    annual = base.sum() * 900.0 / 3.6e6
    return Series(base * (annual_kwh / annual), 900.0, False)


DHW_SERIES = {"SF1": "SF1_wholeyear_Vdot.txt", "SF2": "SF2_wholeyear_Vdot.txt",
              "SF3": "SF3_wholeyear_Vdot.txt", "SF4": "SF4_Vdot.txt", "MF5": "MF5_Vdot.txt"}


@cache
def _dhw_minutes(series: str = "SF1") -> np.ndarray:
    if series not in DHW_SERIES:
        raise ConfigError(f"hot-water series {series!r}: unknown; shipped: {', '.join(DHW_SERIES)}")
    path = HERE / "dhw" / DHW_SERIES[series]
    flows = np.zeros(525600)
    for lineno, line in enumerate(path.read_text().split(), 1):
        try:
            flow, minute = line.split(";")
            flows[int(minute) - 1] = float(flow)
        except (ValueError, IndexError):
            raise DataError(f"{path}:{lineno}: expected 'flow;minute', got {line!r}") from None
    return flows


def hot_water(daily_litres: float, series: str = "SF1") -> Series:
    """Hot-water draw [m3/s] per minute, a house's DHWcalc series (SF1 ... MF5) scaled to
    daily_litres per day."""
    lph = _dhw_minutes(series)
    mean_daily = lph.sum() / 60.0 / 365.0
    return Series(lph * (daily_litres / mean_daily) / 3.6e6, 60.0, False)


# --- type days ----------------------------------------------------------------------------
# The SF1 type-day file holds 11 three-day weather blocks (15 min) and 39 days of presence,
# electricity and hot water. Block k (1-based) covers file days 3k-3 ... 3k-1; its middle day is
# the "type day". Their 2021 dates (found by matching the year file; the last block is a cold
# spell not in 2021): the mapping to the 13 type-day codes upstream is unclear, so blocks are
# addressed by number and date only.
TYPEDAY_BLOCKS = {
    1: "2021-01-24", 2: "2021-01-21", 3: "2021-12-14", 4: "2021-10-17", 5: "2021-10-06",
    6: "2021-04-11", 7: "2021-08-03", 8: "2021-07-04", 9: "2021-08-10", 10: "2021-08-15",
    11: "cold spell (daily means about -8 degC, not in 2021)",
}


@cache
def _typeday_tables() -> dict[str, np.ndarray]:
    return read_tables(HERE / "typedays" / "SF1_Typeday.txt")


def typeday(block: int, household_kwh_per_year: float, dhw_litres_per_day: float) -> dict[str, Series]:
    """Profiles of one type-day block, on an axis where 0 s = file start (block k starts at
    (3k-3) days). Electricity and hot water are rescaled to the house's annual and daily totals."""
    if block not in TYPEDAY_BLOCKS:
        raise ConfigError(f"[profiles] typeday = {block}: no such block; allowed 1 … {len(TYPEDAY_BLOCKS)}")
    t = _typeday_tables()
    w = t["Weather"]
    shift = 4  # UTC -> CET, as for the year file
    out = {name: Series(np.roll(w[:-1, c].copy(), shift), 900.0, True)
           for name, c in (("T_air", 1), ("E_dir", 3), ("E_dif", 4))}
    pres = t["presence"]
    grid = np.arange(0.0, pres[-1, 0] + 1.0, 3600.0)
    out["presence"] = Series(np.interp(grid, pres[:, 0], pres[:, 1]), 3600.0, True)
    pel = t["Pel"][:-1, 1]
    scale = household_kwh_per_year / (pel.mean() * 8760.0 / 1000.0)
    out["P_el"] = Series(pel * scale, 60.0, False)
    dhw = t["V_DHW"]
    minutes = np.zeros(int(dhw[-1, 0] // 60) + 1)
    idx = (dhw[:, 0] // 60).astype(int)
    minutes[idx] = dhw[:, 1]  # change points: a draw at minute k is written as 0 / value / 0
    mean_daily = minutes.sum() / 60.0 / (len(minutes) / 1440.0)
    out["draw"] = Series(minutes * (dhw_litres_per_day / mean_daily) / 3.6e6, 60.0, False)
    return out


def typeday_offset(block: int) -> float:
    """Seconds from the type-day file start to the start of block `block` (midnight)."""
    return (3 * block - 3) * 86400.0
