"""Snapshots of a running Runtime as JSON-ready dicts: signals, devices, clients, clock, history.

Each function reads the plant under the runtime's PlantPort lock (the plant is not thread-safe)
and touches devices only through their thread-safe public calls, so the web server's thread can
call them while the clock and the bus servers run. Non-finite numbers become null (JSON has no
NaN).
"""
from __future__ import annotations

import math
import re
import threading
from collections import deque
from typing import Any

import numpy as np

from gateway.device.refusal import Refusal
from gateway.maps import codec

#: how many event dicts (writes, refusals, faults, watchdog, link) the page can show
RECENT_EVENTS = 200


def _num(x: Any) -> Any:
    if isinstance(x, (bool, str)) or x is None:
        return x
    x = float(x)
    return x if math.isfinite(x) else None


_STATE = re.compile(r"(\d+) ([a-z][a-z -]*?)\s*(?:,|$)")


def states(catalogue) -> dict[str, dict[str, str]]:
    """Names of the states of coded signals, from descriptions such as '0 idle, 1 start-up'."""
    out = {}
    for name in catalogue.names:
        sig = catalogue.signal(name)
        found = _STATE.findall(sig.description)
        if sig.unit == "1" and len(found) >= 2 and sig.description.startswith(found[0][0]):
            out[name] = {code: text for code, text in found}
    return out


def signals(rt) -> dict[str, Any]:
    """Every catalogue signal's current value and unit, read in one locked copy, and the state
    names of coded signals (chp.mode, boiler.mode)."""
    cat = rt.house.catalogue
    with rt.port.lock:
        t = float(rt.house.t)
        values = rt.house.values()
    names = cat.names
    return {"t": t, "values": {n: _num(v) for n, v in zip(names, values)},
            "units": {n: cat.signal(n).unit for n in names}, "states": states(cat)}


def device(dev) -> dict[str, Any]:
    """One device: identity, logic state (remote, faults, watchdog) and every point as served."""
    m = dev.map
    points = []
    for p in m.points:
        raw = dev.read_point(p.name) if p.readable else None
        entry = {"name": p.name, "table": p.table, "address": p.address, "type": p.type,
                 "access": p.access, "unit": p.unit, "binding": p.signal or p.command or
                 (f"@{p.state}" if p.state else "const"), "raw": None, "value": None, "text": None,
                 "refusal": None}
        if isinstance(raw, Refusal):
            entry["refusal"] = raw.reason
        elif raw is not None:
            entry["raw"] = _num(raw)
            entry["value"] = _num(codec.from_raw(p, raw))
            if p.enum and not isinstance(raw, (float, str)):
                entry["text"] = dict(p.enum).get(int(raw))
        points.append(entry)
    wd = dev.watchdog
    watchdog = None
    if wd is not None:
        now = dev.now()
        remaining = (wd.timeout_s - (now - wd.last_refresh)) if wd.last_refresh is not None else None
        watchdog = {"timeout_s": wd.timeout_s, "armed": wd.last_refresh is not None,
                    "expired": wd.expired, "last_refresh": wd.last_refresh,
                    "remaining_s": _num(remaining),
                    "state": "expired" if wd.expired else "armed" if wd.last_refresh is not None else "idle"}
    faults = dev.faults
    return {"id": dev.id, "kind": m.kind, "vendor": m.vendor, "model": m.model,
            "unit_id": m.unit_id, "node_id": m.canopen.node_id, "remote": dev.remote,
            "read_only": dev.read_only, "status_word": dev.status_word(),
            "fault_code": dev.fault_code(), "tripped": faults.tripped,
            "sensor_faults": {k: {"kind": v[0], "delta": v[1]} for k, v in faults.sensors.items()},
            "link_fault": {"mode": faults.link.mode, "delay_s": faults.link.delay_s},
            "watchdog": watchdog, "points": points}


def devices(rt) -> dict[str, Any]:
    return {"t": rt.port.t, "devices": [device(d) for d in rt.devices.values()]}


def _connections(transport) -> list[str]:
    """Peers with an open connection to a Modbus TCP transport (empty for other transports)."""
    server = getattr(getattr(transport, "_server", None), "_server", None)
    active = getattr(server, "active_connections", None)
    if not isinstance(active, dict):
        return []
    peers = []
    for proto in list(active.values()):  # a copy: the server's loop adds and drops entries
        tr = getattr(proto, "transport", None)
        peer = tr.get_extra_info("peername") if tr else None
        if isinstance(peer, tuple):
            peers.append(f"{peer[0]}:{peer[1]}")
    return sorted(peers)


def clients(rt, events: "EventLog | None" = None) -> dict[str, Any]:
    """The controller audit (per client: requests, poll rate, writes, refusals), open
    connections per transport, watchdog states, and the most recent events."""
    report = rt.audit.report()
    return {"t": rt.port.t,
            "clients": report["clients"],
            "connections": {tr.name: _connections(tr) for tr in rt.transports},
            "watchdogs": {d.id: ("expired" if d.watchdog.expired else "armed"
                                 if d.watchdog.last_refresh is not None else "idle")
                          for d in rt.devices.values() if d.watchdog is not None},
            "watchdog_expiries_open": report["watchdog_expiries_open"],
            "recoveries_after_expiry": report["recoveries_after_expiry"],
            "link_events": report["link_events"],
            "events": events.recent() if events else []}


def clock(rt) -> dict[str, Any]:
    """Clock mode and step, simulated time, and lateness of the paced clock's steps."""
    c = rt.clock
    late = c.lateness()
    walls = rt.step_wall[-1:] if rt.step_wall else []
    return {"house": rt.house.name, "start": str(getattr(rt.house, "start", "") or ""),
            "mode": c.mode, "dt": c.dt, "factor": getattr(c, "factor", None), "t": rt.port.t,
            "steps": len(rt.step_wall),
            "last_step_ms": walls[0] * 1e3 if walls else None,
            "last_lateness_ms": float(late[-1] * 1e3) if late.size else None,
            "lateness": rt.lateness_summary()}


class EventLog:
    """The last RECENT_EVENTS device events (subscribe `add` to each device)."""

    def __init__(self, size: int = RECENT_EVENTS) -> None:
        self._lock = threading.Lock()
        self._events: deque = deque(maxlen=size)

    def add(self, ev: dict) -> None:
        if ev.get("kind") == "request":
            return  # polls are counted by the audit; here they would push out everything else
        keep = {k: (_num(v) if isinstance(v, (int, float)) else v if isinstance(v, (str, bool, type(None)))
                    else str(v)) for k, v in ev.items()}
        with self._lock:
            self._events.append(keep)

    def recent(self) -> list[dict]:
        with self._lock:
            return list(self._events)[::-1]


class SignalHistory:
    """A ring of (t, all signal values) samples for the rolling plot, one per new plant time."""

    def __init__(self, n_signals: int, size: int = 1200) -> None:
        self._lock = threading.Lock()
        self._t = np.full(size, np.nan)
        self._v = np.full((size, n_signals), np.nan)
        self._n = 0

    def sample(self, rt) -> None:
        with rt.port.lock:
            t = float(rt.house.t)
            if self._n and self._t[(self._n - 1) % self._t.size] == t:
                return
            values = rt.house.values()
        with self._lock:
            i = self._n % self._t.size
            self._t[i], self._v[i] = t, values
            self._n += 1

    def series(self, rt, names: list[str]) -> dict[str, Any]:
        """Time and the named signals, oldest first; unknown names raise SignalError."""
        idx = [rt.house.catalogue.index(n) for n in names]
        with self._lock:
            n = min(self._n, self._t.size)
            order = (np.arange(self._n - n, self._n) % self._t.size)
            t = self._t[order]
            cols = self._v[order][:, idx]
        return {"t": [_num(x) for x in t],
                "series": {name: [_num(x) for x in cols[:, k]] for k, name in enumerate(names)}}
