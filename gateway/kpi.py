"""Controller KPIs of a run of any house: comfort, hot-water service, fuel, heat per generator, cycling.

    from gateway.kpi import kpis, load_series
    k = kpis(*load_series("runs/today"))      # a `twin serve --record` directory ...
    k = kpis(*load_series("run.csv"))         # ... or a `twin simulate --out` CSV
    k = kpis(times, names, rows)              # or arrays straight from House.run

Every row of a recording holds the values of the plant step that ends at its time, so each row
stands for the interval back to the previous row (the first row for one median row interval).
Integrals are sums of value x interval; at a 1 s recording they equal the plant's own step sums.
Units: the signals are SI (W, degC, kg/s); the KPIs are reported in kWh, K·h, h, minutes.

What is reported follows the run's columns: every heat generator (generators_of: <g>.Q_flow with
<g>.starts, run_hours, P_fuel, P_el or E_heat beside it; chp, boiler, heat_pump, solar, heater)
with its heat, fuel, electricity out and in, starts and run hours where recorded; comfort when
zone.T_room and zone.T_set are there; DHW service on dhw.T_tap and dhw.m_flow_demand (house 1's
DHW storage and houses 2-5's draw from the main storage have the same names); cycling on
storage.SOC. House 1's attributes (heat_chp_kWh, boiler_starts, chp_run_h ...) are the
generators' entries by name, for any generator (heat_heat_pump_kWh, heater_starts is None ...).
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

#: a prefix <g> is a heat generator when <g>.Q_flow is recorded with any of these beside it
#: (mixer.Q_flow, radiator.Q_flow, dhw.Q_flow have none; solar and the heating rod have a meter
#: or an electric power but no counters)
GENERATOR_MARKS = ("starts", "run_hours", "P_fuel", "P_el", "E_heat")
ZONE = ("zone.T_room", "zone.T_set")
DHW = ("dhw.T_tap", "dhw.m_flow_demand")
SOC = "storage.SOC"


@dataclass
class GeneratorKpis:
    """One heat generator of a run; None where the run has no such signal for it."""
    heat_kWh: float                 # <g>.Q_flow
    fuel_kWh: float | None          # <g>.P_fuel
    el_out_kWh: float | None        # <g>.P_el where positive (produced)
    el_in_kWh: float | None         # -<g>.P_el where negative (consumed: compressor, rod, fan)
    starts: int | None              # increase of <g>.starts
    run_h: float | None             # increase of <g>.run_hours


#: per-generator attributes of Kpis by name: heat_chp_kWh, chp_starts, chp_run_h, fuel_chp_kWh,
#: el_out_chp_kWh, el_in_chp_kWh (as_dict flattens them the same way)
_FLAT = (("heat_{}_kWh", "heat_kWh"), ("fuel_{}_kWh", "fuel_kWh"), ("el_out_{}_kWh", "el_out_kWh"),
         ("el_in_{}_kWh", "el_in_kWh"), ("{}_starts", "starts"), ("{}_run_h", "run_h"))


@dataclass
class Kpis:
    """KPIs of a run of any house; a group the run has no signals for is None."""
    duration_h: float
    generators: dict[str, GeneratorKpis]  # in the order of the run's columns
    discomfort_Kh: float | None           # integral of max(0, T_set - T_room)
    comfort_occupied_pct: float | None    # % of occupied time with T_room >= T_set - 1 K
    occupied_h: float | None
    occupied_by: str | None               # "occupancy.presence > 0.5" or "day hours 06-22"
    dhw_failures: int | None              # draw events with some time delivered below 45 degC
    dhw_failure_min: float | None         # minutes of drawing below 45 degC
    dhw_draws: int | None                 # draw events in total
    fuel_kWh: float                       # sum of the generators' P_fuel
    el_out_kWh: float                     # electricity the generators produced (CHP)
    el_in_kWh: float                      # electricity the generators consumed (heat pump, rod ...)
    pv_kWh: float | None                  # pv.P_el
    soc_swings: int | None                # storage SOC reversals by more than 0.2

    def __getattr__(self, name: str):
        """heat_<g>_kWh, <g>_starts, <g>_run_h ... of generator <g> (see _FLAT)."""
        generators = self.__dict__.get("generators") or {}
        for pattern, field in _FLAT:
            head, tail = pattern.split("{}")
            if name.startswith(head) and name.endswith(tail) and len(name) > len(head) + len(tail):
                g = name[len(head):len(name) - len(tail)]
                if g in generators:
                    return getattr(generators[g], field)
        raise AttributeError(f"Kpis has no {name!r}; generators of this run: {', '.join(generators) or 'none'}")

    def as_dict(self) -> dict:
        """The KPIs with the generators flattened (heat_chp_kWh, chp_starts ...) and nested."""
        d = asdict(self)
        flat = {pattern.format(g): getattr(k, field)
                for g, k in self.generators.items() for pattern, field in _FLAT}
        return {**{key: v for key, v in d.items() if key != "generators"}, **flat,
                "generators": d["generators"]}


def generators_of(names: list[str]) -> list[str]:
    """Heat generators of a run, in column order: prefixes with <g>.Q_flow and a GENERATOR_MARKS signal."""
    have = set(names)
    out = []
    for n in names:
        g = n[:-len(".Q_flow")] if n.endswith(".Q_flow") else None
        if g and g not in out and any(f"{g}.{m}" in have for m in GENERATOR_MARKS):
            out.append(g)
    return out


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
    """KPIs of the run from whatever it recorded: generators, comfort, DHW, storage cycling."""
    col = {n: i for i, n in enumerate(names)}
    has = lambda *ns: all(n in col for n in ns)  # noqa: E731
    gens = generators_of(list(names))
    if not gens and not has(*ZONE) and not has(*DHW) and not has(SOC):
        raise ConfigError("KPIs need a generator (<g>.Q_flow with <g>.starts, run_hours, P_fuel, P_el or "
                          f"E_heat), {' + '.join(ZONE)}, {' + '.join(DHW)} or {SOC}; the run has none of them")
    g = lambda n: rows[:, col[n]]  # noqa: E731
    t = np.asarray(times, dtype=float)
    dt = _intervals(t)
    integral = lambda v: float((v * dt).sum())  # noqa: E731
    kwh = lambda v: integral(v) / J_PER_KWH  # noqa: E731
    per = {}
    for gen in gens:
        P_el = g(f"{gen}.P_el") if has(f"{gen}.P_el") else None
        per[gen] = GeneratorKpis(
            heat_kWh=kwh(g(f"{gen}.Q_flow")),
            fuel_kWh=kwh(g(f"{gen}.P_fuel")) if has(f"{gen}.P_fuel") else None,
            el_out_kWh=kwh(np.maximum(P_el, 0.0)) if P_el is not None else None,
            el_in_kWh=kwh(np.maximum(-P_el, 0.0)) if P_el is not None else None,
            starts=int(round(_counted(t, dt, g(f"{gen}.starts")))) if has(f"{gen}.starts") else None,
            run_h=_counted(t, dt, g(f"{gen}.run_hours")) if has(f"{gen}.run_hours") else None)
    total = lambda field: sum(getattr(k, field) or 0.0 for k in per.values())  # noqa: E731
    comfort = dict(discomfort_Kh=None, comfort_occupied_pct=None, occupied_h=None, occupied_by=None)
    if has(*ZONE):
        T_room, T_set = g("zone.T_room"), g("zone.T_set")
        if "occupancy.presence" in col:
            occupied, by = g("occupancy.presence") > 0.5, "occupancy.presence > 0.5"
        else:  # a trimmed recording: fall back to the day hours of the set-point schedule
            hour = (t % 86400.0) / 3600.0
            occupied, by = (hour >= DAY_HOURS[0]) & (hour < DAY_HOURS[1]), "day hours 06-22"
        occ_s = float(dt[occupied].sum())
        ok_s = float(dt[occupied & (T_room >= T_set - COMFORT_BAND)].sum())
        comfort = dict(discomfort_Kh=integral(np.maximum(0.0, T_set - T_room)) / 3600.0,
                       comfort_occupied_pct=100.0 * ok_s / occ_s if occ_s > 0 else 100.0,
                       occupied_h=occ_s / 3600.0, occupied_by=by)
    dhw = dict(dhw_failures=None, dhw_failure_min=None, dhw_draws=None)
    if has(*DHW):
        drawing = g("dhw.m_flow_demand") > 0
        cold = drawing & (g("dhw.T_tap") < DHW_MIN_TAP)
        draws = _events(drawing)
        dhw = dict(dhw_failures=sum(1 for a, b in draws if cold[a:b].any()),
                   dhw_failure_min=integral(cold.astype(float)) / 60.0, dhw_draws=len(draws))
    return Kpis(
        duration_h=float(dt.sum()) / 3600.0,
        generators=per,
        **comfort,
        **dhw,
        fuel_kWh=total("fuel_kWh"),
        el_out_kWh=total("el_out_kWh"),
        el_in_kWh=total("el_in_kWh"),
        pv_kWh=kwh(g("pv.P_el")) if has("pv.P_el") else None,
        soc_swings=soc_swings(g(SOC)) if has(SOC) else None,
    )


def _num(v, fmt: str) -> str:
    return "-" if v is None else format(v, fmt)


def table(k: Kpis, title: str = "") -> str:
    """Summary rows, then one row per generator (heat, fuel, electricity, starts, run hours)."""
    rows = [("duration", f"{k.duration_h:.2f}", "h")]
    if k.discomfort_Kh is not None:
        rows += [("thermal discomfort (below set-point)", f"{k.discomfort_Kh:.3f}", "K·h"),
                 (f"occupied time within set-point - {COMFORT_BAND:g} K", f"{k.comfort_occupied_pct:.2f}",
                  f"% of {k.occupied_h:.1f} h ({k.occupied_by})")]
    if k.dhw_draws is not None:
        rows += [(f"DHW draws delivered below {DHW_MIN_TAP:g} °C", f"{k.dhw_failures}", f"of {k.dhw_draws} draws"),
                 ("DHW time below temperature", f"{k.dhw_failure_min:.1f}", "min")]
    fuelled = [g for g, x in k.generators.items() if x.fuel_kWh is not None]
    rows += [(f"fuel ({' + '.join(fuelled) or 'none'})", f"{k.fuel_kWh:.3f}", "kWh"),
             ("electricity out (generators)", f"{k.el_out_kWh:.3f}", "kWh"),
             ("electricity in (generators)", f"{k.el_in_kWh:.3f}", "kWh")]
    if k.pv_kWh is not None:
        rows.append(("electricity PV", f"{k.pv_kWh:.3f}", "kWh"))
    if k.soc_swings is not None:
        rows.append((f"storage SOC swings > {SOC_SWING:g}", f"{k.soc_swings}", ""))
    w = max(len(r[0]) for r in rows)
    v = max(len(r[1]) for r in rows)
    lines = [title] if title else []
    lines += [f"  {a:<{w}}  {b:>{v}}  {c}".rstrip() for a, b, c in rows]
    if k.generators:
        head = ("generator", "heat kWh", "fuel kWh", "el out kWh", "el in kWh", "starts", "run h")
        body = [(g, _num(x.heat_kWh, ".3f"), _num(x.fuel_kWh, ".3f"), _num(x.el_out_kWh, ".3f"),
                 _num(x.el_in_kWh, ".3f"), _num(x.starts, "d"), _num(x.run_h, ".2f"))
                for g, x in k.generators.items()]
        widths = [max(len(r[i]) for r in [head, *body]) for i in range(len(head))]
        lines.append("")
        for r in [head, *body]:
            lines.append("  " + "  ".join([r[0].ljust(widths[0])] + [c.rjust(wi) for c, wi in zip(r[1:], widths[1:])]))
    return "\n".join(lines)


def to_json(k: Kpis) -> str:
    return json.dumps(k.as_dict(), indent=2)
