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


@cache
def _dhw_minutes() -> np.ndarray:
    path = HERE / "dhw" / "SF1_wholeyear_Vdot.txt"
    flows = np.zeros(525600)
    for lineno, line in enumerate(path.read_text().split(), 1):
        try:
            flow, minute = line.split(";")
            flows[int(minute) - 1] = float(flow)
        except (ValueError, IndexError):
            raise DataError(f"{path}:{lineno}: expected 'flow;minute', got {line!r}") from None
    return flows


def hot_water(daily_litres: float) -> Series:
    """Hot-water draw [m3/s] per minute, the SF1 DHWcalc series scaled to daily_litres per day."""
    lph = _dhw_minutes()
    mean_daily = lph.sum() / 60.0 / 365.0
    return Series(lph * (daily_litres / mean_daily) / 3.6e6, 60.0, False)
