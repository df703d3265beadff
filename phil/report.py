"""Tally and report of a PHIL run: per interface, how well the bench followed, the heat both
sides counted, and what was rejected.

Heat (space heating), the two quantities the reference compares (consumed heat of model and
bench within 0.1 %):
  * bench: the increase of the bench's own heat meter E_HC_kWh between the first and the last
    good reading: the heat its circuit gave between its supply and return sensors, i.e. what its
    exchanger had to remove, integrated by the bench on its own clock from its true states;
  * model: the heat the simulated radiator circuit took from the water the bench delivered,
    sum of m_meas cp (T_sup_meas - T_return_model) dt over the same steps (mixer.Q_flow, the
    ledger's heat in of plant/houses/house1_phil.toml).
Both sides run on their own paced clocks. The twin's stays on the wall clock: slots it missed
while stalled (a loaded machine) go into its next step (gateway/clock.py catch_up; reported as
caught_up_s). When the bench stalls (a busy PLC) and drops time, or the twin's steps are late by
less than it makes up, the meter counted a different span than the model's steps did, and the heat
differs by about the mean power times that drift. The bench's clock (T_PLC_s, read with the meter)
says how long its meter counted: the report gives the drift and the heat error over the same span
(the bench's heat scaled to the twin's span) beside the raw one.
They agree when the bench returns the water at the set return (the radiator model's return) and
delivers the flow and supply it reports: their difference is the flow-weighted return follow
error, plus sensor noise and the exchange's timing, which average out over a run. The heat the
radiators gave the room differs from both by the change of the radiator water's stored heat
(reported too, from the house ledger).
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from phil.wiring import FLOWING


class Tally:
    def __init__(self, channels: dict[str, Any]) -> None:
        self.channels = channels
        self.n_steps = 0
        self.sq = {b: {s: 0.0 for s, _ in ch.wiring.pairs} for b, ch in channels.items()}
        self.n_follow = {b: {s: 0 for s, _ in ch.wiring.pairs} for b, ch in channels.items()}
        self.rejected = {b: {} for b in channels}
        self.failures = {b: 0 for b in channels}
        self.exchange_s = {b: [] for b in channels}
        self.meter = {b: [math.nan, math.nan] for b in channels}   # first and last good reading
        self.spans = {b: [math.nan] * 4 for b in channels}   # twin, bench clock at those readings
        self.model_J = {b: 0.0 for b in channels}
        self.model_J_pending = {b: 0.0 for b in channels}
        self.safe_sent: dict[str, dict[str, float]] = {}
        # what each set-point spanned over the counted run (the grid's differential pressure moves
        # only as the district's substations open and close: its range says by how much)
        self.sent_range = {b: {i.name: [math.inf, -math.inf] for i in ch.map.setpoints()}
                           for b, ch in channels.items()}
        self.step_s: list[float] = []      # wall time of each counted step: exchanges + house step
        self.room: list[tuple[float, float, float]] = []           # t, T_room, T_set
        self.demand = {b: [] for b, ch in channels.items() if ch.wiring.demand}   # t, dt, demand

    def exchange(self, bench: str, sent: dict, measured: dict | None, judged: dict,
                 exchange_s: float, t: float) -> None:
        """One counted exchange at twin time t (before its step)."""
        ch = self.channels[bench]
        self.exchange_s[bench].append(exchange_s)
        for name, value in sent.items():
            span = self.sent_range[bench].get(name)
            if span is not None and not math.isnan(value):
                span[0], span[1] = min(span[0], value), max(span[1], value)
        if measured is None:
            self.failures[bench] += 1
        for name, j in judged.items():
            if not j.ok:
                kind = j.reason.split(" ")[0].rstrip(":")
                self.rejected[bench].setdefault(name, {}).setdefault(kind, 0)
                self.rejected[bench][name][kind] += 1
        flowing = not ch.wiring.flow or judged[ch.wiring.flow].value > FLOWING
        for s, m in ch.wiring.pairs:
            temperature = ch.map.dmap.point(s).unit == "°C"
            if judged[m].ok and (flowing or not temperature):
                self.sq[bench][s] += (sent[s] - judged[m].value) ** 2
                self.n_follow[bench][s] += 1
        heat = judged.get(ch.wiring.heat)
        if heat is not None and heat.ok:
            first, _ = self.meter[bench]
            self.meter[bench] = [heat.value if math.isnan(first) else first, heat.value]
            clock = judged.get(ch.wiring.clock)
            t_bench = clock.value if clock is not None and clock.ok else math.nan
            spans = self.spans[bench]
            if math.isnan(first):
                spans[0], spans[2] = t, t_bench
            spans[1], spans[3] = t, t_bench
            # the model's heat counts from the first good meter reading to the last one
            self.model_J[bench] += self.model_J_pending[bench]
            self.model_J_pending[bench] = 0.0

    def after_step(self, house: Any, dt: float) -> None:
        self.n_steps += 1
        for bench, ch in self.channels.items():
            if not math.isnan(self.meter[bench][0]):
                self.model_J_pending[bench] += house.get(ch.wiring.model_heat) * dt
        self.room.append((house.t, house.get("zone.T_room"), house.get("zone.T_set")))
        for bench in self.demand:
            self.demand[bench].append((house.t, dt, *self.channels[bench].wiring.demand(house)))

    def _room(self) -> dict[str, Any]:
        if not self.room:
            return {}
        t, T, T_set = (np.array(c) for c in zip(*self.room))
        deficit = np.clip(T_set - T, 0.0, None)
        dt = np.diff(t, prepend=t[0])
        cold = deficit > 0.5
        return {"T_room_min_degC": float(T.min()), "T_room_mean_degC": float(T.mean()),
                "degree_hours_below_set_Kh": float((deficit * dt).sum() / 3600.0),
                "hours_more_than_0_5K_below_set": float(dt[cold].sum() / 3600.0),
                "first_time_0_5K_below_set_s": float(t[cold][0]) if cold.any() else None}

    def report(self, house: Any, stop_reason: str, lateness: np.ndarray) -> dict[str, Any]:
        L = house.ledger()
        out: dict[str, Any] = {"stop_reason": stop_reason, "t_end_s": house.t, "steps": self.n_steps,
                               "room": self._room(), "benches": {}}
        if out["room"]:
            out["room"]["heat_to_room_kWh"] = L["heat_building"] / 3.6e6
        for bench, ch in self.channels.items():
            ex = np.array(self.exchange_s[bench]) * 1e3
            ex = ex[~np.isnan(ex)]             # NaN: not tried (a failed bench waiting for its retry)
            first, last = self.meter[bench]
            bench_kWh = last - first if not math.isnan(first) else math.nan
            model_kWh = self.model_J[bench] / 3.6e6
            t0, t1, b0, b1 = self.spans[bench]
            twin_span, bench_span = t1 - t0, b1 - b0     # NaN without a clock reading
            # a bench that draws a cumulative energy set-point catches up on its own: its meter is
            # compared as it is
            same_kWh = (bench_kWh if ch.wiring.cumulative else
                        bench_kWh * twin_span / bench_span if bench_span > 0 else math.nan)
            out["benches"][bench] = {
                "follow_rms": {s: (math.sqrt(self.sq[bench][s] / self.n_follow[bench][s])
                                   if self.n_follow[bench][s] else None) for s, _ in ch.wiring.pairs},
                "units": {s: ch.map.dmap.point(s).unit for s, _ in ch.wiring.pairs},
                "heat_bench_kWh": bench_kWh, "heat_model_kWh": model_kWh,
                "heat_error_pct": _error_pct(bench_kWh, model_kWh),
                "twin_span_s": twin_span, "bench_span_s": bench_span,
                "clock_drift_s": bench_span - twin_span,
                "heat_error_same_span_pct": _error_pct(same_kWh, model_kWh),
                "rejected": self.rejected[bench], "failed_exchanges": self.failures[bench],
                "setpoints_limited": dict(ch.limiter.clamped),
                "setpoint_range": {s: {"min": lo, "max": hi, "unit": ch.map.dmap.point(s).unit}
                                   for s, (lo, hi) in self.sent_range[bench].items() if lo <= hi},
                "safe_sent": self.safe_sent.get(bench),
                "exchange_ms": {"median": float(np.median(ex)) if len(ex) else None,
                                "p99": float(np.percentile(ex, 99)) if len(ex) else None},
            }
            if bench in self.demand:
                out["benches"][bench]["shortfalls"] = shortfalls(np.array(self.demand[bench]),
                                                                 np.array(self.room))
        step = np.array(self.step_s) * 1e3
        out["step_ms"] = {"median": float(np.median(step)) if len(step) else None,
                          "p99": float(np.percentile(step, 99)) if len(step) else None}
        late = lateness * 1e3
        out["lateness_ms"] = {"median": float(np.median(late)) if len(late) else None,
                              "p99": float(np.percentile(late, 99)) if len(late) else None}
        return out


def _grid_lines(grid: dict[str, Any]) -> list[str]:
    """The simulated grid's ledger, the heat it gave each house and its step's wall time."""
    others = grid.get("others") or []
    lines = [f"  grid ({grid['district']}, the house at node {grid['node']}; "
             + (f"other houses simulated: {', '.join(others)}" if others else "no other house drawing")
             + f"): plant {grid['plant_kWh']:.3f} kWh, pipe losses {grid['pipe_losses_kWh']:.3f} kWh, "
             f"to the houses {grid['to_houses_kWh']:.3f} kWh, stored {grid['delta_stored_kWh']:+.3f} kWh; "
             f"closure {grid['closure']:.1e}"]
    houses = grid.get("houses") or {}
    if houses:
        lines.append("    heat from the grid (grid's book / house's meter): " + "; ".join(
            f"{n} {h['grid_kWh']:.3f} / {h['metered_kWh']:.3f} kWh" for n, h in houses.items()))
    cost = grid.get("step_ms") or {}
    if cost.get("median") is not None:
        lines.append(f"    grid side's step (other houses + grid; every step, pre-run included): median {cost['median']:.3f} ms, "
                     f"p99 {cost['p99']:.3f} ms")
    return lines


def _error_pct(bench_kWh: float, model_kWh: float) -> float | None:
    return 100.0 * (bench_kWh - model_kWh) / model_kWh if model_kWh > 0 and not math.isnan(bench_kWh) else None


#: a shortfall: the measured flow below SHORT_SHARE of the request less SHORT_MARGIN l/min (the
#: bench's noise and its pump's lag stay inside), for at least SHORT_MIN_S, gaps < SHORT_GAP_S joined
SHORT_SHARE, SHORT_MARGIN, SHORT_MIN_S, SHORT_GAP_S = 0.9, 0.3, 300.0, 120.0


def shortfalls(demand: np.ndarray, room: np.ndarray) -> list[dict[str, Any]]:
    """When the bench could not deliver the flow the building requested, how much heat it missed
    (the heat delivered in the hour before, as a rate, less what it delivered), how cold the room
    got, when it was back within 0.1 K of its set-point, and the heat delivered until then above
    the hour before (the heat made up). demand rows: t, dt, flow set, flow measured, Q_req, Q_del
    (Q_req, m_set cp (T_sup_set - T_ret), overstates a cold radiator's need: not used for the
    deficit); room rows: t, T_room, T_set."""
    if not len(demand):
        return []
    t, dt, m_set, m_meas, Q_req, Q_del = demand.T
    short = m_meas < SHORT_SHARE * m_set - SHORT_MARGIN
    spans: list[list[int]] = []
    for i in np.flatnonzero(short):
        if spans and t[i] - t[spans[-1][1]] <= SHORT_GAP_S:
            spans[-1][1] = i
        else:
            spans.append([i, i])
    out = []
    for a, b in spans:
        if t[b] - t[a] + dt[b] < SHORT_MIN_S:
            continue
        before = (t >= t[a] - 3600.0) & (t < t[a])
        baseline = float(Q_del[before].mean()) if before.any() else 0.0
        after = np.flatnonzero((room[:, 0] > t[b]) & (room[:, 1] >= room[:, 2] - 0.1))
        back = float(room[after[0], 0]) if len(after) else None
        span = slice(a, b + 1)
        catch = (t > t[b]) & (t <= (back if back is not None else t[-1]))
        deficit = np.clip(room[:, 2] - room[:, 1], 0.0, None)
        within = (room[:, 0] >= t[a]) & (room[:, 0] <= (back if back is not None else t[-1]))
        out.append({
            "start_s": float(t[a] - dt[a]), "end_s": float(t[b]), "hours": float((t[b] - t[a] + dt[b]) / 3600.0),
            "flow_requested_l_per_min": float(m_set[span].mean()), "flow_measured_l_per_min": float(m_meas[span].mean()),
            "heat_missing_kWh": float(((baseline - Q_del[span]) * dt[span]).sum() / 3.6e6),
            "T_room_min_degC": float(room[within, 1].min()) if within.any() else None,
            "degree_hours_below_set_Kh": float((deficit[within] * np.diff(room[:, 0], prepend=room[0, 0])[within]).sum() / 3600.0),
            "room_back_within_0_1K_s": back,
            "heat_made_up_kWh": float(((Q_del[catch] - baseline) * dt[catch]).sum() / 3.6e6),
            "heat_before_W": baseline,
        })
    return out


def format_report(report: dict[str, Any]) -> str:
    """The report as text, one block per bench."""
    lines = [f"PHIL run: {report['t_end_s'] / 3600:.2f} h simulated, {report['steps']} steps; "
             f"stopped: {report['stop_reason']}"]
    room = report.get("room") or {}
    if room:
        lines.append(f"  room: min {room['T_room_min_degC']:.2f} degC, {room['degree_hours_below_set_Kh']:.2f} "
                     f"K h below set, {room['hours_more_than_0_5K_below_set']:.2f} h more than 0.5 K below; "
                     f"heat to the room {room['heat_to_room_kWh']:.3f} kWh")
    for bench, b in report["benches"].items():
        lines.append(f"  bench {bench}:")
        for s, rms in b["follow_rms"].items():
            lines.append(f"    {s:28s} RMS follow error {rms if rms is None else f'{rms:.3f}'} {b['units'][s]}")
        if b.get("setpoint_range"):
            lines.append("    set-points sent: " + "; ".join(f"{s} {r['min']:.6g} ... {r['max']:.6g} {r['unit']}"
                                                         for s, r in b["setpoint_range"].items()))
        err = b["heat_error_pct"]
        lines.append(f"    heat: bench {b['heat_bench_kWh']:.4f} kWh, model {b['heat_model_kWh']:.4f} kWh"
                     + (f" ({err:+.4f} %)" if err is not None else ""))
        same = b["heat_error_same_span_pct"]
        if same is not None:
            lines.append(f"    clocks: bench counted {b['bench_span_s']:.1f} s, twin {b['twin_span_s']:.1f} s "
                         f"(drift {b['clock_drift_s']:+.1f} s); heat over the same span {same:+.4f} %")
        lines.append(f"    rejected: {b['rejected'] or 'none'}; failed exchanges {b['failed_exchanges']}; "
                     f"exchange median {b['exchange_ms']['median']} ms, p99 {b['exchange_ms']['p99']} ms")
        for f in b.get("shortfalls", []):
            back = f["room_back_within_0_1K_s"]
            lines.append(f"    flow shortfall {f['start_s'] / 3600:.2f}-{f['end_s'] / 3600:.2f} h ({f['hours']:.2f} h): "
                         f"{f['flow_measured_l_per_min']:.2f} of {f['flow_requested_l_per_min']:.2f} l/min, "
                         f"{f['heat_missing_kWh']:.2f} kWh missing; room down to {f['T_room_min_degC']:.2f} degC, "
                         + (f"back within 0.1 K at {back / 3600:.2f} h" if back is not None else "not back by the end")
                         + f", {f['heat_made_up_kWh']:.2f} kWh made up above the hour before")
        if b["safe_sent"]:
            lines.append(f"    safe set-points sent: {b['safe_sent']}")
    grid = report.get("grid")
    if grid:
        lines += _grid_lines(grid)
    lat = report["lateness_ms"]
    lines.append(f"  step lateness: median {lat['median']} ms, p99 {lat['p99']} ms; the twin's step "
                 f"(exchanges + house): median {report['step_ms']['median']} ms, p99 {report['step_ms']['p99']} ms")
    if report.get("caught_up_s"):
        lines.append(f"  fell behind the wall clock: {report['caught_up_s']:g} simulated s made up in longer steps")
    phase = report.get("phase_s") or {}
    if phase.get("set") is not None and phase.get("kept_median") is not None:
        lines.append(f"  steps at {phase['kept_median']:.4f} s into each {report['cycle_s']:g} s cycle of the "
                     f"system clock (--phase {phase['set']:g})")
    return "\n".join(lines)

