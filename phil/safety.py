"""Safety between the twin and real hardware: set-points limited, measurements judged.

SetpointLimiter: every set-point is clamped to its map range and may change by at most its map
rate limit per second of simulated time; it starts from the map's safe value.
MeasurementGuard: a measurement that is NaN, out of its map range, or not fresh (no successful
exchange) is rejected with the interface named; the last good value is held and flagged. A
measurement rejected (or never good) for longer than `stale_s` of wall time is stale; past
`stop_s` the guard asks the loop to send the safe set-points and stop.

Wrong unit: a measurement paired with a set-point (the wiring's pairs) is checked for
plausibility against it. When, for UNIT_WINDOW exchanges in a row with the set-point active, the
measurement is far from the set-point (more than UNIT_OFF relative) but within UNIT_FIT of the
set-point converted to a unit commonly mistaken for the map's (l/h for l/min, W for kW, K or
degF for degC ...), it is rejected as `wrong unit`, naming both units, until it fits again.
"""
from __future__ import annotations

import math
from collections import deque
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


#: units a bench may report in place of the map's: (name, a, b) with reading = a x value + b.
#: Only those that read far above the set-point: a reading far below it (l/s for l/min) is what a
#: bench that cannot follow shows too, and must stay that bench's (held, then stale) case.
UNIT_SUSPECTS: dict[str, tuple[tuple[str, float, float], ...]] = {
    "l/min": (("l/h", 60.0, 0.0),),
    "°C": (("K", 1.0, 273.15), ("°F", 1.8, 32.0)),
    "kW": (("W", 1000.0, 0.0),),
    "kWh": (("Wh", 1000.0, 0.0), ("MJ", 3.6, 0.0)),
}
UNIT_WINDOW, UNIT_OFF, UNIT_FIT = 8, 0.3, 0.1
#: a set-point is active (says something about the reading) above this share of its range's span
UNIT_ACTIVE = 0.03


class UnitCheck:
    """The wrong-unit test of one measurement against its set-point (see the module text)."""

    def __init__(self, unit: str, span: float) -> None:
        self.unit, self.span = unit, span
        self.suspects = UNIT_SUSPECTS.get(unit, ())
        self.verdicts: deque[str] = deque(maxlen=UNIT_WINDOW)

    def verdict(self, setpoint: float, value: float) -> str:
        """'' while plausible; else the unit the readings look like."""
        if not self.suspects or math.isnan(value) or abs(setpoint) < UNIT_ACTIVE * self.span:
            return self.verdicts[-1] if len(self.verdicts) == UNIT_WINDOW and len(set(self.verdicts)) == 1 else ""
        near = lambda want: abs(value - want) <= UNIT_FIT * max(abs(want), 1e-9)  # noqa: E731
        guess = ""
        if abs(value - setpoint) > UNIT_OFF * abs(setpoint):
            guess = next((name for name, a, b in self.suspects if near(a * setpoint + b)), "")
        self.verdicts.append(guess)
        if len(self.verdicts) == UNIT_WINDOW and guess and all(v == guess for v in self.verdicts):
            return guess
        return ""


class MeasurementGuard:
    """Judges each exchange's measurements of one bench (device units, wall-time limits)."""

    def __init__(self, bench: BenchMap, stale_s: float | None = None, stop_s: float | None = None,
                 start_wall: float = 0.0) -> None:
        self.bench = bench
        self.stale_s = bench.stale_s if stale_s is None else stale_s
        self.stop_s = bench.stop_s if stop_s is None else stop_s
        self.state = {i.name: GuardState(since_good=start_wall) for i in bench.measurements()}
        self.pairs: dict[str, tuple[str, UnitCheck]] = {}

    def check_units(self, pairs: tuple[tuple[str, str], ...]) -> "MeasurementGuard":
        """Check these (set-point, measurement) pairs for a wrong unit (see the module text)."""
        for s, m in pairs:
            p = self.bench.dmap.point(m)
            if p.unit in UNIT_SUSPECTS and p.range:
                self.pairs[m] = (s, UnitCheck(p.unit, p.range[1] - p.range[0]))
        return self

    def judge(self, measured: dict[str, float] | None, wall: float, failure: str = "",
              reasons: dict[str, str] | None = None, sent: dict[str, float] | None = None) -> dict[str, Judged]:
        """Measured values (None: the exchange failed, `failure` says how; `reasons`: why single
        measurements came without a value, as from a silent bench PLC) -> judged values."""
        out = {}
        for i in self.bench.measurements():
            st = self.state[i.name]
            value = math.nan if measured is None else measured.get(i.name, math.nan)
            reason = self._reject(i.name, value) if measured is not None else (failure or "no answer")
            if measured is not None and reasons and i.name in reasons:
                reason = reasons[i.name]
            elif measured is not None and sent and i.name in self.pairs:
                s, check = self.pairs[i.name]
                unit = check.verdict(sent[s], value)
                if unit:
                    reason = (f"wrong unit ({value:g} for a set-point of {sent[s]:g} {check.unit}: reads like "
                              f"{unit}; the map says {check.unit}: fix the bench PLC's scaling or the map's unit)")
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

    def restart(self, wall: float) -> None:
        """The exchanges begin now (after the unpaced pre-run): no measurement is late yet."""
        for st in self.state.values():
            st.since_good = wall

    def must_stop(self, wall: float) -> str:
        """'' while running; otherwise the interface and why the run must stop."""
        for name, st in self.state.items():
            if wall - st.since_good > self.stop_s:
                return (f"{self.bench.id}.{name}: no good value for {wall - st.since_good:.1f} s "
                        f"(limit {self.stop_s:g} s)")
        return ""
