"""Boundary conditions of the rig on a one-minute grid: weather, hot-water draws, occupancy,
household electricity.

Clock: the simulation runs in local standard time (CET, no daylight saving), as the lab's logger.
The weather file's time axis is taken as UTC (its irradiance centroid lies near 11:00), so the
weather at local time t is read at t - 3600 s. The DHWcalc minute series and the occupancy and
electricity profiles are read as local time.
"""
from __future__ import annotations

import datetime as _dt
from functools import lru_cache

import numpy as np

from .tables import dhwcalc_minutes, table

YEAR_S = 365 * 86400
T_COLD = 10.0              # cold water [degC] (rig description)
DHW_SET = 45.0             # draw temperature at the tap [degC]
HOUSEHOLD_KWH_A = 5000.0   # household electricity, own choice for 300 m2 and ~5 residents
PERSONS = 5
W_PER_PERSON = 80.0        # sensible heat per person at home [W]


def seconds_of_year(date: str) -> int:
    d = _dt.date.fromisoformat(date)
    return (d - _dt.date(d.year, 1, 1)).days * 86400


@lru_cache(maxsize=1)
def _raw():
    w = table("Weather_2021_Munich_15min.txt", "Weather")
    pres = table("presenceResidential.txt", "presence")
    el = table("elPower.txt", "Pel")
    dhw = dhwcalc_minutes()
    return w, pres, el, dhw


def _periodic_interp(t, x, y, period=YEAR_S):
    return np.interp(np.mod(t, period), x, y)


def minute_inputs(t0_abs: float, n_minutes: int) -> dict[str, np.ndarray]:
    """Arrays with one value per minute starting at t0_abs (seconds since 1 Jan 00:00 CET).

    Keys: T_out [degC], solar [W/m2 horizontal global], presence [-], P_house [W],
    q_dhw [kg/s at 45 degC, mean of the minute], T_ground [degC].
    """
    w, pres, el, dhw = _raw()
    t = t0_abs + 60.0 * np.arange(n_minutes)
    t_utc = t - 3600.0
    T_out = _periodic_interp(t_utc, w[:, 0], w[:, 1])
    solar = np.maximum(_periodic_interp(t_utc, w[:, 0], w[:, 3] + w[:, 4]), 0.0)
    presence = np.clip(_periodic_interp(t, pres[:, 0], pres[:, 1]), 0.0, 1.0)
    el_scale = HOUSEHOLD_KWH_A / (np.sum(el[:, 1]) * 900.0 / 3.6e6)
    P_house = np.interp(np.mod(t, YEAR_S), el[:, 0], el[:, 1]) * el_scale
    minute = (np.floor(t / 60.0).astype(np.int64)) % dhw.size
    q_dhw = dhw[minute] / 3600.0  # l/h -> kg/s (1 kg/l)
    # ground below the slab: annual sine around 10 degC, minimum in early March
    doy = np.mod(t, YEAR_S) / 86400.0
    T_ground = 10.0 + 3.0 * np.cos(2 * np.pi * (doy - 240.0) / 365.0)
    return dict(T_out=T_out, solar=solar, presence=presence, P_house=P_house, q_dhw=q_dhw,
                T_ground=T_ground)
