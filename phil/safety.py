"""Safety between the twin and real hardware: set-points limited, measurements judged.

SetpointLimiter: every set-point is clamped to its map range and may change by at most its map
rate limit per second of simulated time; it starts from the map's safe value.
MeasurementGuard: a measurement that is NaN, out of its map range, or not fresh (no successful
exchange) is rejected with the interface named; the last good value is held and flagged. A
measurement rejected (or never good) for longer than `stale_s` of wall time is stale; past
`stop_s` the guard asks the loop to send the safe set-points and stop.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from phil.benchmap import BenchMap


class SetpointLimiter:
    """Clamp to range, then to the rate limit, per set-point of one bench (device units)."""

    def __init__(self, bench: BenchMap) -> None:
        self.bench = bench
        self.last = {i.name: float(i.safe) for i in bench.setpoints()}
        self.clamped = {i.name: 0 for i in bench.setpoints()}

    def limit(self, wanted: dict[str, float], dt: float) -> dict[str, float]:
        out = {}
        for i in self.bench.setpoints():
            lo, hi = self.bench.dmap.point(i.name).range
            want = wanted.get(i.name, i.safe)
            want = i.safe if want is None or math.isnan(want) else want
            value = min(max(want, lo), hi)
            step = i.rate_limit * dt
            value = min(max(value, self.last[i.name] - step), self.last[i.name] + step)
            if abs(value - want) > 1e-9:
                self.clamped[i.name] += 1
            self.last[i.name] = out[i.name] = value
        return out

    def safe(self) -> dict[str, float]:
        return {i.name: float(i.safe) for i in self.bench.setpoints()}


@dataclass
class Judged:
    """One measurement after the guard: the value used, whether it was rejected, and why."""

    value: float
    ok: bool
    reason: str = ""


@dataclass
class GuardState:
    good: float = math.nan
    since_good: float | None = None      # wall time of the last good value
    rejected: dict[str, int] = field(default_factory=dict)


class MeasurementGuard:
    """Judges each exchange's measurements of one bench (device units, wall-time limits)."""

    def __init__(self, bench: BenchMap, stale_s: float | None = None, stop_s: float | None = None,
                 start_wall: float = 0.0) -> None:
        self.bench = bench
        self.stale_s = bench.stale_s if stale_s is None else stale_s
        self.stop_s = bench.stop_s if stop_s is None else stop_s
        self.state = {i.name: GuardState(since_good=start_wall) for i in bench.measurements()}

    def judge(self, measured: dict[str, float] | None, wall: float, failure: str = "",
              reasons: dict[str, str] | None = None) -> dict[str, Judged]:
        """Measured values (None: the exchange failed, `failure` says how; `reasons`: why single
        measurements came without a value, as from a silent bench PLC) -> judged values."""
        out = {}
        for i in self.bench.measurements():
            st = self.state[i.name]
            value = math.nan if measured is None else measured.get(i.name, math.nan)
            reason = self._reject(i.name, value) if measured is not None else (failure or "no answer")
            if measured is not None and reasons and i.name in reasons:
                reason = reasons[i.name]
            if not reason:
                st.good, st.since_good = value, wall
                out[i.name] = Judged(value, True)
                continue
            if wall - st.since_good > self.stale_s:
                reason = f"stale ({reason})"
            st.rejected[reason.split(" ")[0]] = st.rejected.get(reason.split(" ")[0], 0) + 1
            out[i.name] = Judged(st.good, False, reason)
        return out

    def _reject(self, name: str, value: float) -> str:
        if math.isnan(value):
            return "NaN"
        lo, hi = self.bench.dmap.point(name).range
        if not lo <= value <= hi:
            return f"out of range ({value:g} outside {lo:g}…{hi:g} {self.bench.dmap.point(name).unit})"
        return ""

    def must_stop(self, wall: float) -> str:
        """'' while running; otherwise the interface and why the run must stop."""
        for name, st in self.state.items():
            if wall - st.since_good > self.stop_s:
                return (f"{self.bench.id}.{name}: no good value for {wall - st.since_good:.1f} s "
                        f"(limit {self.stop_s:g} s)")
        return ""
