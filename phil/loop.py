"""PhilLoop: the simulated side of a house exchanging with its benches every step, in real time.

One step (docs/phil.md): the PHIL house's requests become set-points (phil/wiring.py), limited
(phil/safety.py) and written to each bench as Modbus TCP master (phil/master.py), as the server
its PLC polls (phil/served.py) or as CANopen master by PDO (phil/canopen_link.py); the bench's
measurements are read back, judged, and set as the house's live measured boundary; the house
steps by dt; one row is recorded (profiles/recording.py: signals.csv flushed every step,
events.csv for every rejection and the stop). The run ends at its duration, on an operator stop
(SIGINT/SIGTERM or the stop file appearing) or when a measurement stays bad past its stop limit;
in every case the safe set-points are written to every bench (writable points only) and the
recording is closed intact. The per-interface report is phil/report.py's.
"""
from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from gateway.clock import PacedClock
from gateway.transports.can_bus import parse_bus_spec
from phil.benchmap import BenchMap, load_bench_map
from phil.canopen_link import CanopenBus, CanopenLink
from phil.exports import exports
from phil.master import BenchLink, ExchangeError
from phil.options import BenchAddress, PhilOptions, house_file
from phil.served import ServedLink, SharedServer
from phil.report import Tally
from phil.safety import MeasurementGuard, SetpointLimiter
from phil.wiring import WIRINGS
from plant.errors import ConfigError
from plant.house import load_house
from profiles.recording import Recorder


@dataclass
class BenchChannel:
    """Everything the loop keeps per bench."""

    map: BenchMap
    link: BenchLink | ServedLink | CanopenLink
    limiter: SetpointLimiter
    guard: MeasurementGuard
    wiring: Any
    sent: dict[str, float] = field(default_factory=dict)
    origin: dict[str, float] | None = None     # cumulative set-points at the first exchange
    failed_at: float | None = None             # wall time of the last failed exchange
    failure: str = ""


def kept_phase(phases: Any, around: float, cycle: float) -> float | None:
    """Median phase [s] of the steps in the cycle, taken around `around` so that steps just
    either side of the cycle's start (phase 0) do not average to half a cycle."""
    if not len(phases):
        return None
    offset = (np.asarray(phases) - around + cycle / 2) % cycle - cycle / 2
    return float((around + np.median(offset)) % cycle)


class PhilLoop:
    def __init__(self, house: str, benches: dict[str, tuple[str, int] | BenchAddress],
                 options: PhilOptions) -> None:
        self.o = options
        overrides = {"profiles.typeday": options.typeday} if options.typeday else None
        self.house = load_house(house_file(house), controller="rule_based", overrides=overrides)
        self.channels: dict[str, BenchChannel] = {}
        self.addresses = {n: a if isinstance(a, BenchAddress) else BenchAddress(*a) for n, a in benches.items()}
        servers: list[SharedServer] = []
        opened: list[BenchLink | ServedLink | CanopenLink] = []
        buses: dict[str, CanopenBus] = {}       # by bus spec: one network and one SYNC per bus
        try:
            for name, where in self.addresses.items():
                self.channels[name] = self._channel(name, where, servers, opened, buses)
            for ch in self.channels.values():
                if ch.wiring.boundary:      # the simulated side a bench needs beside the house (the grid)
                    self.house = ch.wiring.boundary(self.house, options)
            self.names = set(self.house.catalogue.names) | set(getattr(self.house, "boundary_signals", ()))
            self._check_wired(house)
        except BaseException:
            # a refused configuration leaves no bus connection, socket or bus thread behind
            for link in opened:
                link.close()
            for bus in buses.values():
                if bus.network.bus is not None:
                    bus.network.disconnect()
            raise
        self.exports = exports(self.house, self.names)
        self.recorder = None
        for server in servers:
            server.start()
        self.served = {n: f"{ch.link.address[0]}:{ch.link.address[1]}" for n, ch in self.channels.items()
                       if isinstance(ch.link, ServedLink)}
        self.tally = Tally(self.channels)
        self.columns = self._columns()
        self.recorder = Recorder(options.record, self.columns, {
            "house": house, "kind": "phil", "speed": options.speed, "dt": options.dt,
            "typeday": options.typeday, "start_h": options.start_h, "phase_s": options.phase_s,
            "benches": {n: str(a) for n, a in self.addresses.items()}, "served": self.served,
            **({"district": options.district, "others": options.others}
               if any(ch.wiring.boundary for ch in self.channels.values()) else {}),
        }, interval=0.0) if options.record else None
        self.stop_reason = ""
        self.warmed = 0.0
        self.t0 = 0.0
        self._stop = threading.Event()
        self._done = threading.Event()
        self.clock: PacedClock | None = None

    def _channel(self, name: str, where: BenchAddress, servers: list[SharedServer], opened: list,
                 buses: dict[str, CanopenBus]) -> BenchChannel:
        """The link to one bench (polled, served or a CANopen node) with its limiter, guard and
        wiring; the link goes into `opened` as soon as it exists."""
        bmap = load_bench_map(name)
        if bmap.id not in WIRINGS:
            raise ConfigError(f"--bench {name}: not wired into the PHIL loop yet; wired: {', '.join(WIRINGS)}")
        if where.serve:
            server = SharedServer.at(where.host, where.port)
            servers += [server] if server not in servers else []
            link: BenchLink | ServedLink | CanopenLink = ServedLink(bmap, server, self.o.served_age_s)
            link.device.subscribe(self._bus_event)
        elif where.bus:
            spec = str(parse_bus_spec(where.bus))
            if spec not in buses:
                buses[spec] = CanopenBus(where.bus)
            link = buses[spec].link(bmap, self.o.timeout_s, self.o.pdo_age_s)
        else:
            link = BenchLink(bmap, where.host, where.port, self.o.timeout_s, self.o.retries)
        opened.append(link)
        guard = MeasurementGuard(bmap, self.o.stale_s, self.o.stop_s, time.monotonic())
        return BenchChannel(bmap, link, SetpointLimiter(bmap), guard.check_units(WIRINGS[bmap.id].pairs),
                            WIRINGS[bmap.id])

    def _check_wired(self, house: str) -> None:
        """Every bench's wiring finds its signals in the house (house 4 has no solar collector),
        checked before anything is exchanged."""
        problems = []
        for name, ch in self.channels.items():
            missing = sorted(ch.wiring.used(tuple(i.name for i in ch.map.measurements())) - self.names)
            if missing:
                problems.append(f"--bench {name}: the PHIL house {house_file(house)} has no {', '.join(missing)}")
        if problems:
            wired = [b for b, w in WIRINGS.items() if w.boundary or not w.used(
                tuple(i.name for i in load_bench_map(b).measurements())) - self.names]
            raise ConfigError("; ".join(problems) + f"; benches this house is wired for: {', '.join(wired)}")

    def _columns(self) -> list[str]:
        cols = []
        for name, ch in self.channels.items():
            cols += [f"{name}.{i.name}" for i in ch.map.setpoints()]
            cols += [f"{name}.{i.name}" for i in ch.map.measurements()]
            cols += [f"{name}.{i.name}.used" for i in ch.map.measurements()]
            cols += [f"{name}.{i.name}.flag" for i in ch.map.measurements()]
            cols += [f"{name}.exchange_ms"]
            cols += [s for s in ch.wiring.signals if s not in cols and s in self.names]
        return cols + list(self.exports) + ["lateness_ms"]

    # --- one step ------------------------------------------------------------------------------
    def step(self, dt: float) -> None:
        """Exchange with every bench, then advance the house by dt (runs on the clock's thread;
        a step that makes up missed cycles ends at the run's end, not past it)."""
        if self._done.is_set():
            return
        dt = min(dt, max(self._end() - self.house.t, self.o.dt))
        began = time.perf_counter()
        try:
            warming = self.warmed < self.o.warmup_s
            row = self._exchange_all(dt, counted=not warming)
            if warming:
                # the benches settle on the set-points while the house settles on an ideal
                # bench (measured = requested) where its wiring says what that is; nothing of
                # it is counted
                for ch in self.channels.values():
                    if ch.wiring.ideal:
                        ch.wiring.ideal(self.house)
                self.warmed += dt
            self.house.step(dt)
            if not warming:
                self.tally.after_step(self.house, dt)
                self.tally.step_s.append(time.perf_counter() - began)
            self._record(row, self.house.t)
            reason = self._why_stop()
            if reason:
                self._finish(reason)
        except Exception as exc:  # the clock thread's boundary: stop safely, keep the recording
            self._finish(f"internal error: {exc!r}")

    def _exchange_all(self, dt: float, counted: bool = True) -> dict[str, float]:
        row: dict[str, float] = {}
        answers: dict[str, tuple[dict[str, float] | None, str, bool]] = {}
        for name, ch in self.channels.items():
            if name not in answers:
                answers.update(self._exchange(name, dt))
            measured, failure, tried = answers[name]
            exchange_s = ch.link.last_exchange_s if tried else math.nan
            judged = ch.guard.judge(measured, time.monotonic(), failure, getattr(ch.link, "reasons", None), ch.sent)
            for iname, j in judged.items():
                if not j.ok:
                    self._event({"kind": "rejected", "device": name, "point": iname,
                                 "value": (measured or {}).get(iname, math.nan), "reason": j.reason})
            used = {k: j.value for k, j in judged.items()}
            if all(not math.isnan(v) for v in used.values()):
                ch.wiring.feed(self.house, used)
            if counted:
                self.tally.exchange(name, ch.sent, measured, judged, exchange_s, self.house.t)
            row.update({f"{name}.{k}": v for k, v in ch.sent.items()})
            for k, j in judged.items():
                row[f"{name}.{k}"] = (measured or {}).get(k, math.nan)
                row[f"{name}.{k}.used"] = j.value
                row[f"{name}.{k}.flag"] = 0.0 if j.ok else 1.0
            row[f"{name}.exchange_ms"] = exchange_s * 1e3
        return row

    def _exchange(self, name: str, dt: float) -> dict[str, tuple[dict[str, float] | None, str, bool]]:
        """Set-points and exchange for bench `name` or, CANopen, for all on its bus at once (their
        set-points, then one SYNC) -> (measurements or None, failure, tried) each."""
        bus = getattr(self.channels[name].link, "bus", None)        # a CanopenLink's CanopenBus
        chs = {n: ch for n, ch in self.channels.items() if n == name or bus and getattr(ch.link, "bus", None) is bus}
        for ch in chs.values():
            wanted = ch.wiring.setpoints(self.house)
            ch.origin = ch.origin if ch.origin is not None else {k: wanted[k] for k in ch.wiring.cumulative}
            ch.sent = ch.limiter.limit({k: v - ch.origin.get(k, 0.0) for k, v in wanted.items()}, dt)
        # a bench that failed is tried again after retry_s: a dead bench must not stall the others
        out = {n: (None, ch.failure, False) for n, ch in chs.items()
               if ch.failed_at is not None and time.monotonic() - ch.failed_at < self.o.retry_s}
        due = {n: ch for n, ch in chs.items() if n not in out}
        answers = bus.exchange({ch.link: ch.sent for ch in due.values()}) if bus and due else {}
        for n, ch in due.items():
            try:
                answer = answers[ch.link] if bus else ch.link.exchange(ch.sent)
            except ExchangeError as exc:
                answer = exc
            if isinstance(answer, ExchangeError):
                ch.failure, ch.failed_at = f"{answer.kind}: {answer.detail}", time.monotonic()
                out[n] = (None, ch.failure, True)
            else:
                ch.failed_at, out[n] = None, (answer, "", True)
        return out

    def _record(self, row: dict[str, float], t: float) -> None:
        if not self.recorder:
            return
        for name in self.columns:
            if name in self.exports:
                row[name] = self.exports[name](self.house)
            elif name not in row and name != "lateness_ms":
                row[name] = self.house.get(name)
        late = self.clock.lateness() if self.clock else []
        row["lateness_ms"] = float(late[-1]) * 1e3 if len(late) else 0.0
        self.recorder.signals(t, [row[c] for c in self.columns])
        self.recorder.flush()

    def _bus_event(self, ev: dict[str, Any]) -> None:
        """A served bench's bus events (its Device's, on the server thread): refused writes of
        the bench PLC are recorded, accepted ones are the measurements in signals.csv."""
        if self.recorder and ev.get("kind") == "write" and not ev.get("accepted", True):
            self.recorder.event({**ev, "t": self.house.t, "kind": "refused"})

    def _event(self, ev: dict[str, Any]) -> None:
        if self.recorder:
            self.recorder.event({"t": self.house.t, **ev})

    def _why_stop(self) -> str:
        if self._stop.is_set():
            return "operator stop"
        if self.o.stop_file and Path(self.o.stop_file).exists():
            return f"operator stop (stop file {self.o.stop_file})"
        wall = time.monotonic()
        for ch in self.channels.values():
            reason = ch.guard.must_stop(wall)
            if reason:
                return reason
        if self.house.t >= self._end() - 1e-9:
            return "end of run"
        return ""

    def _end(self) -> float:
        return self.t0 + self.o.warmup_s + self.o.hours * 3600.0

    # --- run and stop --------------------------------------------------------------------------
    def request_stop(self) -> None:
        """Operator stop (signal handler): the next step sends the safe set-points and ends."""
        self._stop.set()

    def _finish(self, reason: str) -> None:
        if self._done.is_set():
            return
        self.stop_reason = reason
        for name, ch in self.channels.items():
            try:
                ch.link.write(ch.limiter.safe())
                self._event({"kind": "safe", "device": name, "reason": reason, "accepted": True})
            except ExchangeError as exc:
                self._event({"kind": "safe", "device": name, "reason": reason, "accepted": False,
                             "detail": str(exc)})
            self.tally.safe_sent[name] = ch.limiter.safe()
        self._event({"kind": "stop", "reason": reason})
        self._done.set()

    def _prerun(self) -> None:
        """Advance the house unpaced to `start_h` with what an ideal bench would measure (benches
        whose wiring has no ideal keep the live inputs' defaults): nothing is exchanged."""
        end = self.o.start_h * 3600.0
        while self.house.t < end - 1e-9:
            for ch in self.channels.values():
                if ch.wiring.ideal:
                    ch.wiring.ideal(self.house)
            self.house.step(min(self.o.dt, end - self.house.t))
        self.t0 = self.house.t

    def run(self) -> dict[str, Any]:
        """Run paced until the end or a stop; returns the report (also stored as report.json)."""
        self._prerun()
        for ch in self.channels.values():
            ch.guard.restart(time.monotonic())
        # the benches keep running while the twin stalls: slots it missed go into its next step
        # (catch_up), so its simulated span stays the wall clock's and the heat the benches gave
        # meanwhile is on the model's side too
        self.clock = PacedClock(self.o.speed, self.o.dt, self.o.phase_s, catch_up=True)
        self.clock.bind(self.step)
        self.clock.start()
        while not self._done.wait(0.1):
            if self._stop.is_set() and not self.clock._thread.is_alive():
                self._finish("operator stop")
        self.clock.stop()
        if self.served:
            # the bench PLCs poll on their own cycle: serve the safe set-points long enough for
            # each to read them once before the server closes
            time.sleep(min(self.o.served_age_s, 2.0))
        for ch in self.channels.values():
            ch.link.close()
        report = self.tally.report(self.house, self.stop_reason, self.clock.lateness())
        report["cycle_s"] = self.o.dt / self.o.speed
        report["caught_up_s"] = self.clock.missed * self.o.dt    # simulated s made up in longer steps
        report["phase_s"] = {"set": self.o.phase_s, "kept_median": kept_phase(
            self.clock.phases(), self.o.phase_s or 0.0, report["cycle_s"])}
        boundary = getattr(self.house, "boundary_report", None)     # the simulated grid's ledger
        if boundary:
            report.update(boundary())
        if self.recorder:
            self.recorder.close({"report": report})
            import json
            (Path(self.o.record) / "report.json").write_text(json.dumps(report, indent=2, default=str))
        return report
