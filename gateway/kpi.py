"""Controller KPIs of a run: comfort, hot-water service, fuel, heat per generator, cycling.

    from gateway.kpi import kpis, load_series
    k = kpis(*load_series("runs/today"))      # a `twin serve --record` directory ...
    k = kpis(*load_series("run.csv"))         # ... or a `twin simulate --out` CSV
    k = kpis(times, names, rows)              # or arrays straight from House.run

Every row of a recording holds the values of the plant step that ends at its time, so each row
stands for the interval back to the previous row (the first row for one median row interval).
Integrals are sums of value x interval; at a 1 s recording they equal the plant's own step sums.
Units: the signals are SI (W, degC, kg/s); the KPIs are reported in kWh, K·h, h, minutes.
"""
from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from plant.errors import ConfigError, DataError
from plant.units import UNITS
from profiles.recording import read_recording

J_PER_KWH = UNITS["kWh"].factor  # 3.6e6, from the one unit table
#: a draw is delivered too cold below 45 degC; 0.5 K tolerance for the tap's mixing transient
DHW_MIN_TAP = 44.5
#: the comfort band: room at least set-point - 1 K
COMFORT_BAND = 1.0
#: storage cycling counts swings of the state of charge larger than this
SOC_SWING = 0.2
#: day hours used as "occupied" when a recording has no occupancy signal
DAY_HOURS = (6.0, 22.0)

NEEDED = ("zone.T_room", "zone.T_set", "dhw.T_tap", "dhw.m_flow_demand", "chp.P_fuel", "boiler.P_fuel",
          "chp.P_el", "chp.Q_flow", "boiler.Q_flow", "chp.starts", "boiler.starts", "chp.run_hours",
          "boiler.run_hours", "storage.SOC")


@dataclass
class Kpis:
    duration_h: float
    discomfort_Kh: float            # integral of max(0, T_set - T_room)
    comfort_occupied_pct: float     # % of occupied time with T_room >= T_set - 1 K
    occupied_h: float
    occupied_by: str                # "occupancy.presence > 0.5" or "day hours 06-22"
    dhw_failures: int               # draw events with some time delivered below 45 degC
    dhw_failure_min: float          # minutes of drawing below 45 degC
    dhw_draws: int                  # draw events in total
    fuel_kWh: float                 # chp.P_fuel + boiler.P_fuel
    el_out_kWh: float               # chp.P_el
    heat_chp_kWh: float
    heat_boiler_kWh: float
    chp_starts: int
    boiler_starts: int
    chp_run_h: float
    boiler_run_h: float
    soc_swings: int                 # storage SOC reversals by more than 0.2

    def as_dict(self) -> dict:
        return asdict(self)


def load_series(path: str | Path) -> tuple[np.ndarray, list[str], np.ndarray]:
    """(times [s], names, rows) of a recording directory or a simulate CSV."""
    try:
        rec = read_recording(path)
    except DataError as exc:
        raise ConfigError(f"{exc}; not a house-twin recording: give a `twin serve --record` "
                          "directory or a `twin simulate --out` CSV") from None
    return rec.time, rec.names, rec.values


def _intervals(t: np.ndarray) -> np.ndarray:
    """Length of the interval each row stands for [s]."""
    if t.size == 0:
        return t
    if t.size == 1:
        return np.array([max(t[0], 0.0)])
    d = np.diff(t)
    return np.concatenate([[float(np.median(d))], d])


def _events(mask: np.ndarray) -> list[tuple[int, int]]:
    """[start, end) index runs where mask is True."""
    m = np.concatenate([[False], mask.astype(bool), [False]])
    edges = np.flatnonzero(m[1:] != m[:-1])
    return list(zip(edges[0::2], edges[1::2]))


def soc_swings(soc: np.ndarray, swing: float = SOC_SWING) -> int:
    """Legs of the SOC (rise or fall between turning points) larger than `swing`; a zig-zag
    filter, so wiggles smaller than `swing` neither count nor split a leg."""
    if soc.size == 0:
        return 0
    lo = hi = ext = float(soc[0])
    direction, count = 0, 0
    for v in map(float, soc[1:]):
        if direction == 0:
            lo, hi = min(lo, v), max(hi, v)
            if hi - lo > swing:
                direction, ext, count = (1 if v == hi else -1), v, 1
        elif direction == 1:
            if v > ext:
                ext = v
            elif ext - v > swing:
                direction, ext, count = -1, v, count + 1
        else:
            if v < ext:
                ext = v
            elif v - ext > swing:
                direction, ext, count = 1, v, count + 1
    return count


def _counted(t: np.ndarray, dt: np.ndarray, counter: np.ndarray) -> float:
    """Increase of a plant counter during the run; a run recorded from its beginning (counters
    start at 0) also counts what happened in the step of row 0."""
    if counter.size == 0:
        return 0.0
    from_start = t[0] <= dt[0] + 1e-9
    return float(counter[-1] - (0.0 if from_start else counter[0]))


def kpis(times: np.ndarray, names: list[str], rows: np.ndarray) -> Kpis:
    missing = [n for n in NEEDED if n not in names]
    if missing:
        raise ConfigError(f"KPIs need the signals {', '.join(missing)}; the run does not have them")
    col = {n: i for i, n in enumerate(names)}
    g = lambda n: rows[:, col[n]]  # noqa: E731
    t = np.asarray(times, dtype=float)
    dt = _intervals(t)
    T_room, T_set = g("zone.T_room"), g("zone.T_set")
    if "occupancy.presence" in col:
        occupied, by = g("occupancy.presence") > 0.5, "occupancy.presence > 0.5"
    else:  # a trimmed recording: fall back to the day hours of the set-point schedule
        hour = (t % 86400.0) / 3600.0
        occupied, by = (hour >= DAY_HOURS[0]) & (hour < DAY_HOURS[1]), "day hours 06-22"
    occ_s = float(dt[occupied].sum())
    ok_s = float(dt[occupied & (T_room >= T_set - COMFORT_BAND)].sum())
    drawing = g("dhw.m_flow_demand") > 0
    cold = drawing & (g("dhw.T_tap") < DHW_MIN_TAP)
    draws = _events(drawing)
    failures = sum(1 for a, b in draws if cold[a:b].any())
    integral = lambda v: float((v * dt).sum())  # noqa: E731
    return Kpis(
        duration_h=float(dt.sum()) / 3600.0,
        discomfort_Kh=integral(np.maximum(0.0, T_set - T_room)) / 3600.0,
        comfort_occupied_pct=100.0 * ok_s / occ_s if occ_s > 0 else 100.0,
        occupied_h=occ_s / 3600.0,
        occupied_by=by,
        dhw_failures=int(failures),
        dhw_failure_min=integral(cold.astype(float)) / 60.0,
        dhw_draws=len(draws),
        fuel_kWh=integral(g("chp.P_fuel") + g("boiler.P_fuel")) / J_PER_KWH,
        el_out_kWh=integral(g("chp.P_el")) / J_PER_KWH,
        heat_chp_kWh=integral(g("chp.Q_flow")) / J_PER_KWH,
        heat_boiler_kWh=integral(g("boiler.Q_flow")) / J_PER_KWH,
        chp_starts=int(round(_counted(t, dt, g("chp.starts")))),
        boiler_starts=int(round(_counted(t, dt, g("boiler.starts")))),
        chp_run_h=_counted(t, dt, g("chp.run_hours")),
        boiler_run_h=_counted(t, dt, g("boiler.run_hours")),
        soc_swings=soc_swings(g("storage.SOC")),
    )


def table(k: Kpis, title: str = "") -> str:
    rows = [
        ("duration", f"{k.duration_h:.2f}", "h"),
        ("thermal discomfort (below set-point)", f"{k.discomfort_Kh:.3f}", "K·h"),
        (f"occupied time within set-point - {COMFORT_BAND:g} K", f"{k.comfort_occupied_pct:.2f}",
         f"% of {k.occupied_h:.1f} h ({k.occupied_by})"),
        (f"DHW draws delivered below {DHW_MIN_TAP:g} °C", f"{k.dhw_failures}", f"of {k.dhw_draws} draws"),
        ("DHW time below temperature", f"{k.dhw_failure_min:.1f}", "min"),
        ("fuel (CHP + boiler)", f"{k.fuel_kWh:.3f}", "kWh"),
        ("electricity out (CHP)", f"{k.el_out_kWh:.3f}", "kWh"),
        ("heat CHP", f"{k.heat_chp_kWh:.3f}", "kWh"),
        ("heat boiler", f"{k.heat_boiler_kWh:.3f}", "kWh"),
        ("starts CHP / boiler", f"{k.chp_starts} / {k.boiler_starts}", ""),
        ("run hours CHP / boiler", f"{k.chp_run_h:.2f} / {k.boiler_run_h:.2f}", "h"),
        (f"storage SOC swings > {SOC_SWING:g}", f"{k.soc_swings}", ""),
    ]
    w = max(len(r[0]) for r in rows)
    v = max(len(r[1]) for r in rows)
    lines = [title] if title else []
    lines += [f"  {a:<{w}}  {b:>{v}}  {c}".rstrip() for a, b, c in rows]
    return "\n".join(lines)


def to_json(k: Kpis) -> str:
    return json.dumps(k.as_dict(), indent=2)
