"""Device: one emulated field device = its map + live state + logic, shared by every transport.

The same Device object is served by Modbus TCP, Modbus RTU and CANopen at once; it is the only
place that validates writes. Transports translate frames into these calls and Refusals into
protocol answers (gateway.device.refusal.REASONS), nothing more.

Public API (all methods are thread-safe; plant access goes through one PlantPort lock):

    dev = Device(dmap, port, now=None, on_event=None, read_only=False)
      dmap: gateway.maps.model.DeviceMap; port: gateway.device.plant_port.PlantPort
      now:  callable giving gateway-clock time in s (default: plant time port.t); never wall time

  Point level (CANopen uses this; raw = the point's wire value: int, float for float32,
  bool for coils, str for strings; same scaling as the Modbus registers):
    dev.read_point(name) -> raw | Refusal        # "write_only" for access "W", "address" if unknown
    dev.write_point(name, raw, client="", transport="") -> Refusal | None
    dev.value(name) -> float | str               # device-unit value as served (tests, tables)

  Register level (Modbus uses this; tables "coil", "discrete", "input", "holding"; bits as 0/1):
    dev.check_function(fc) -> Refusal | None     # the map's function-code whitelist
    dev.read_registers(table, address, count) -> list[int] | Refusal
    dev.write_registers(table, address, words, client="", transport="") -> Refusal | None

  Time and logic:
    dev.tick(t)                                  # watchdog; call after each plant step
    dev.reset()                                  # power-cycle the device state (tests)
    dev.status_word() -> int; dev.fault_code() -> int; dev.remote -> bool

  Faults (each reported as an event):
    dev.inject_sensor_fault(point, kind="open" | "drift", delta=0.0)  # open: serves point.invalid
    dev.inject_trip(code=None)        # latches map fault.trip_code; cleared by writing 1 to reset
    dev.set_link_fault(mode, delay_s=0.0)  # "none" | "silent" | "late" | "drop" | "bad_crc"
    dev.clear_faults(trip=True)       # sensors + link; trip too unless trip=False
    dev.link -> LinkFault             # transports consult it per request

  Events: every write (accepted or refused), fault and watchdog transition is passed as a dict to
  each subscriber (`on_event` or dev.subscribe(fn)). Keys: t, kind ("write" | "fault" |
  "watchdog" | "link"), device, plus for writes transport, client, point, raw, value, accepted,
  reason. Transports report link-level events with dev.report(dict).
"""
from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

from gateway.device.faults import SENSOR_KINDS, FaultState, LinkFault
from gateway.device.plant_port import PlantPort
from gateway.device.refusal import Refusal
from gateway.device.watchdog import Watchdog
from gateway.maps import codec
from gateway.maps.model import BIT_TABLES, DeviceMap, Point

Event = dict[str, Any]
FC_TABLE = {1: "coil", 2: "discrete", 3: "holding", 4: "input", 5: "coil", 6: "holding",
            15: "coil", 16: "holding", 23: "holding"}
MAX_COUNT = {"coil": 2000, "discrete": 2000, "input": 125, "holding": 125}


class Device:
    """A map plus live state (commanded values, watchdog, faults, counters from the plant)."""

    def __init__(self, dmap: DeviceMap, port: PlantPort, *, now: Callable[[], float] | None = None,
                 on_event: Callable[[Event], None] | None = None, read_only: bool = False) -> None:
        self.map = dmap
        self.id = dmap.id
        self.unit_id = dmap.unit_id
        self.port = port
        self.now = now or (lambda: port.t)
        self.read_only = read_only
        self.faults = FaultState()
        self.watchdog = Watchdog(dmap.watchdog) if dmap.watchdog else None
        self._lock = threading.RLock()
        self._subscribers: list[Callable[[Event], None]] = [on_event] if on_event else []
        self._commanded: dict[str, float] = {}      # point -> device value while remote-driven
        self._words: dict[str, list[int]] = {}      # point -> encoded words, see read_registers
        self._cache_key: tuple[float, int] = (float("nan"), -1)
        self._generation = 0
        self._index: dict[tuple[str, int], tuple[Point, int]] = {}
        for p in dmap.points:
            for w in range(p.words):
                self._index[(p.table, p.address + w)] = (p, w)

    # ----------------------------------------------------------------- events
    def subscribe(self, fn: Callable[[Event], None]) -> None:
        self._subscribers.append(fn)

    def report(self, event: Event) -> None:
        """Pass an event (from this device or its transports) to every subscriber."""
        if event.get("kind") != "request":
            self._generation += 1  # served values may have changed: drop the encoded words
        event = {"t": self.now(), "device": self.id, **event}
        for fn in list(self._subscribers):
            fn(event)

    # ------------------------------------------------------------ point level
    def value(self, name: str) -> float | str:
        with self._lock:
            return self._value(self.map.point(name))

    def read_point(self, name: str) -> int | float | str | bool | Refusal:
        if name not in self.map:
            return Refusal("address", f"{self.id}: no point {name!r}")
        p = self.map.point(name)
        if not p.readable:
            return Refusal("write_only", f"{self.id}.{name} is write-only")
        with self._lock:
            return self._raw(p)

    def write_point(self, name: str, raw: Any, client: str = "", transport: str = "") -> Refusal | None:
        if name not in self.map:
            return Refusal("address", f"{self.id}: no point {name!r}")
        p = self.map.point(name)
        with self._lock:
            checked = self._check(p, raw)
            if isinstance(checked, Refusal):
                self._write_event(p, raw, None, checked, client, transport)
                return checked
            self._apply(p, checked, client, transport, raw)
        return None

    # --------------------------------------------------------- register level
    def check_function(self, fc: int) -> Refusal | None:
        if fc not in self.map.functions:
            return Refusal("function", f"{self.id}: function code {fc} not supported; "
                           f"allowed {sorted(self.map.functions)}")
        return None

    def read_registers(self, table: str, address: int, count: int) -> list[int] | Refusal:
        if not 1 <= count <= MAX_COUNT[table]:
            return Refusal("length", f"count {count}: must be 1…{MAX_COUNT[table]}")
        out: list[int] = []
        with self._lock:
            # Encoded words are reused until the plant steps or the device changes state (every
            # state change is an event): polling clients then cost a dict lookup per point.
            key = (self.port.t, self._generation)
            if key != self._cache_key:
                self._words.clear()
                self._cache_key = key
            cache = self._words
            for a in range(address, address + count):
                hit = self._index.get((table, a))
                if hit is None:
                    return Refusal("address", f"{self.id}: {table} {a} not mapped")
                p, w = hit
                if p.name not in cache:
                    # Write-only points read as 0 (Dachs PIN register behaviour).
                    cache[p.name] = (codec.to_registers(p, self._raw(p)) if p.readable
                                     else [0] * p.words)
                out.append(cache[p.name][w])
        return out

    def write_registers(self, table: str, address: int, words: list[int], client: str = "",
                        transport: str = "") -> Refusal | None:
        if not 1 <= len(words) <= (1968 if table in BIT_TABLES else 123):
            return Refusal("length", f"{len(words)} values in one write")
        plan: list[tuple[Point, Any, Any]] = []
        with self._lock:
            a, end = address, address + len(words)
            while a < end:
                hit = self._index.get((table, a))
                if hit is None:
                    return self._refuse_at(table, a, Refusal("address", f"{table} {a} not mapped"),
                                           client, transport)
                p, w = hit
                if w != 0 or a + p.words > end:
                    return self._refuse_at(table, a, Refusal(
                        "partial", f"{p.name} spans {p.address}…{p.address + p.words - 1}"),
                        client, transport, p)
                raw = codec.from_registers(p, words[a - address:a - address + p.words])
                checked = self._check(p, raw)
                if isinstance(checked, Refusal):
                    self._write_event(p, raw, None, checked, client, transport)
                    return checked
                plan.append((p, checked, raw))
                a += p.words
            for p, value, raw in plan:  # all points valid: apply together, like one frame
                self._apply(p, value, client, transport, raw)
        return None

    # ------------------------------------------------------------------ logic
    @property
    def remote(self) -> bool:
        return bool(self._commanded)

    @property
    def link(self) -> LinkFault:
        return self.faults.link

    def tick(self, t: float) -> None:
        """Advance device logic to gateway time t (watchdog expiry)."""
        with self._lock:
            if self.watchdog and self.watchdog.tick(t):
                released = sorted(self._commanded)
                for name in released:
                    self._release(self.map.point(name))
                self.report({"kind": "watchdog", "state": "expired", "released": released,
                             "timeout_s": self.watchdog.timeout_s})

    def status_word(self) -> int:
        with self._lock:
            word = 0
            for bit, source in self.map.status_bits:
                if self._flag(source):
                    word |= 1 << bit
            return word

    def fault_code(self) -> int:
        if self.faults.tripped:
            return self.faults.trip_code
        return self.map.fault.sensor_code if self.faults.sensor_fault else 0

    def reset(self) -> None:
        """Power-cycle: forget remote commands, faults, watchdog and read-only mode (no plant I/O)."""
        with self._lock:
            self._commanded.clear()
            self.faults = FaultState()
            self.read_only = False
            if self.watchdog:
                self.watchdog = Watchdog(self.map.watchdog)
            self._generation += 1

    # ----------------------------------------------------------------- faults
    def inject_sensor_fault(self, point: str, kind: str = "open", delta: float = 0.0) -> None:
        p = self.map.point(point)
        if kind not in SENSOR_KINDS or not p.signal:
            raise ValueError(f"{self.id}.{point}: sensor fault {kind!r} needs a signal point and "
                             f"kind in {SENSOR_KINDS}")
        with self._lock:
            self.faults.sensors[point] = (kind, float(delta))
        self.report({"kind": "fault", "fault": f"sensor_{kind}", "point": point, "delta": delta})

    def inject_trip(self, code: int | None = None) -> None:
        code = code or self.map.fault.trip_code
        if not code or not self.map.fault.trip_forces:
            raise ValueError(f"{self.id}: map declares no [fault] trip_code/trip_forces")
        with self._lock:
            self.faults.trip_code = code
            for command, value in self.map.fault.trip_forces:
                self.port.set(command, value)
        self.report({"kind": "fault", "fault": "trip", "code": code})

    def set_link_fault(self, mode: str, delay_s: float = 0.0) -> None:
        with self._lock:
            self.faults.link = LinkFault(mode, delay_s)
        self.report({"kind": "fault", "fault": f"link_{mode}", "delay_s": delay_s})

    def clear_faults(self, trip: bool = True) -> None:
        with self._lock:
            self.faults.sensors.clear()
            self.faults.link = LinkFault()
            if trip and self.faults.tripped:
                self._reset_trip()
        self.report({"kind": "fault", "fault": "cleared", "trip": trip})

    # -------------------------------------------------------------- internals
    def _flag(self, source: str) -> bool:
        flags = {
            "@remote": self.remote,
            "@watchdog": bool(self.watchdog and self.watchdog.expired),
            "@fault": self.faults.tripped or self.faults.sensor_fault,
            "@tripped": self.faults.tripped,
            "@sensor_fault": self.faults.sensor_fault,
            "@read_only": self.read_only,
            "@link_fault": self.faults.link.mode != "none",
        }
        if source in flags:
            return flags[source]
        return abs(self.port.get(source)) > 1e-9

    def _value(self, p: Point) -> float | str:
        if p.signal:
            value = codec.to_device(p, self.port.get(p.signal))
            kind, delta = self.faults.sensors.get(p.name, ("", 0.0))
            return value + delta if kind == "drift" else value
        if p.command:
            if p.name in self._commanded:
                return self._commanded[p.name]
            return float(p.default) if p.default is not None else 0.0
        if p.const is not None:
            return p.const
        return self._state(p)

    def _state(self, p: Point) -> float | str:
        ident = self.map.identity
        states: dict[str, Any] = {
            "status": lambda: float(self.status_word()),
            "fault_code": lambda: float(self.fault_code()),
            "fault_reset": lambda: 0.0,
            "heartbeat": lambda: 0.0,
            "watchdog_timeout": lambda: self.watchdog.timeout_s if self.watchdog else 0.0,
            "identity.vendor": lambda: ident.vendor, "identity.product": lambda: ident.product,
            "identity.serial": lambda: ident.serial, "identity.firmware": lambda: ident.firmware,
        }
        return states[p.state]()

    def _raw(self, p: Point) -> Any:
        if self.faults.sensors.get(p.name, ("",))[0] == "open":
            if p.type == "float32":
                return float("nan")
            return p.invalid if p.invalid is not None else codec.LIMITS.get(p.type, (0, 0))[1]
        return codec.to_raw(p, self._value(p))

    def _check(self, p: Point, raw: Any) -> float | str | Refusal:
        """Validate one write (device-interfaces §2.4); returns the device value to apply."""
        if self.read_only:
            return Refusal("locked", "gateway is in read-only mode")
        if not p.writable:
            return Refusal("read_only", f"{p.name} is read-only")
        if p.command and self.faults.tripped and any(
                p.command == c for c, _ in self.map.fault.trip_forces):
            return Refusal("state", f"{p.name}: locked out by fault {self.faults.trip_code}; "
                           f"write 1 to {self.map.fault.reset_point}")
        if p.type == "string":
            return str(raw)
        try:
            value = codec.from_raw(p, raw)
        except (TypeError, ValueError):
            return Refusal("range", f"{p.name}: {raw!r} is not a {p.type}")
        if value != value:  # NaN
            return Refusal("range", f"{p.name}: NaN")
        if p.enum and int(raw) not in dict(p.enum):
            return Refusal("range", f"{p.name} = {raw}: not one of {dict(p.enum)}")
        if p.release_value is not None and value == p.release_value:
            return value
        if p.range:
            lo, hi = p.range
            if value < lo or value > hi:
                if p.on_bad == "clamp":
                    return min(hi, max(lo, value))
                return Refusal("too_low" if value < lo else "too_high",
                               f"{p.name} = {value:g} {p.unit}: allowed {lo:g}…{hi:g} {p.unit}")
        return value

    def _apply(self, p: Point, value: Any, client: str, transport: str, raw: Any) -> None:
        if p.command:
            if p.release_value is not None and value == p.release_value:
                self._release(p)
            else:
                self._commanded[p.name] = value
                self.port.set(p.command, codec.to_si(p, value))
        elif p.state == "watchdog_timeout" and self.watchdog:
            self.watchdog.timeout_s = float(value)
        elif p.state == "fault_reset" and value == 1 and self.faults.tripped:
            self._reset_trip()
        if self.watchdog and self.watchdog.refreshes(p.name):
            if self.watchdog.refresh(self.now()):
                self.report({"kind": "watchdog", "state": "recovered", "by": p.name})
        self._write_event(p, raw, value, None, client, transport)

    def _release(self, p: Point) -> None:
        """Hand a command back to the built-in control (after writing its safe default)."""
        self._commanded.pop(p.name, None)
        if self.faults.tripped and any(p.command == c for c, _ in self.map.fault.trip_forces):
            return  # the trip keeps forcing it; released at reset
        if p.default is not None:
            self.port.set(p.command, codec.to_si(p, float(p.default)))
        self.port.release(p.command)

    def _reset_trip(self) -> None:
        code, self.faults.trip_code = self.faults.trip_code, 0
        for command, _ in self.map.fault.trip_forces:
            driver = next((p for p in self.map.commands
                           if p.command == command and p.name in self._commanded), None)
            if driver:
                self.port.set(command, codec.to_si(driver, self._commanded[driver.name]))
            else:
                self.port.release(command)
        self.report({"kind": "fault", "fault": "trip_reset", "code": code})

    def _refuse_at(self, table: str, address: int, refusal: Refusal, client: str, transport: str,
                   p: Point | None = None) -> Refusal:
        self.report({"kind": "write", "transport": transport, "client": client,
                     "point": p.name if p else f"{table}:{address}", "raw": None, "value": None,
                     "accepted": False, "reason": refusal.reason, "detail": refusal.detail})
        return refusal

    def _write_event(self, p: Point, raw: Any, value: Any, refusal: Refusal | None, client: str,
                     transport: str) -> None:
        self.report({"kind": "write", "transport": transport, "client": client, "point": p.name,
                     "raw": raw, "value": value, "accepted": refusal is None,
                     "reason": refusal.reason if refusal else "ok",
                     "detail": refusal.detail if refusal else ""})
