"""Controller audit: how each client behaved — polling, watchdog refreshes, refusals, link loss.

Fed with the devices' event stream (writes, refusals, watchdog transitions, link events) and
with request events from the transports (kind "request"), and with malformed-frame counts and
refused or idle-closed connections (kinds "malformed" and "link") from the Modbus TCP server.
Times are gateway-clock seconds, so a lock-step test gets the same report every time.
"""
from __future__ import annotations

import threading
from collections import Counter, defaultdict
from typing import Any

import numpy as np


class Audit:
    def __init__(self) -> None:
        self._lock = threading.Lock()
        self.requests: dict[str, list[float]] = defaultdict(list)
        self.accepted: Counter = Counter()
        self.refused: dict[str, Counter] = defaultdict(Counter)
        self.write_times: dict[tuple[str, str], list[float]] = defaultdict(list)  # (client, device)
        self.expiries: list[tuple[float, str]] = []  # (t, device)
        self.recoveries: list[tuple[str, float]] = []  # (device, seconds until next accepted write)
        self.link: Counter = Counter()
        self.malformed: dict[str, Counter] = defaultdict(Counter)  # client -> kind -> frames

    def event(self, ev: dict[str, Any]) -> None:
        kind = ev.get("kind")
        t = float(ev.get("t", 0.0) or 0.0)
        client = f"{ev.get('transport', '')}:{ev.get('client', '')}"
        with self._lock:
            if kind == "request":
                self.requests[client].append(t)
            elif kind == "write":
                if ev.get("accepted"):
                    self.accepted[client] += 1
                    dev = ev.get("device", "")
                    self.write_times[(client, dev)].append(t)
                    for i, (te, d) in enumerate(self.expiries):
                        if d == dev and te <= t:
                            self.recoveries.append((dev, t - te))
                            self.expiries.pop(i)
                            break
                else:
                    self.refused[client][ev.get("reason", "?")] += 1
            elif kind == "watchdog" and ev.get("state", ev.get("event", "")) in ("expired", "expire"):
                self.expiries.append((t, ev.get("device", "")))
            elif kind == "link":
                self.link[f"{client} {ev.get('event', '')}"] += 1
            elif kind == "malformed":
                self.malformed[client][ev.get("reason", "?")] += 1

    def report(self) -> dict[str, Any]:
        with self._lock:
            clients = sorted(set(self.requests) | set(self.accepted) | set(self.refused))
            out: dict[str, Any] = {"clients": {}}
            for c in clients:
                times = np.array(self.requests.get(c, []))
                span = times.max() - times.min() if times.size > 1 else 0.0
                refresh = {}
                for (cl, dev), ts in self.write_times.items():
                    if cl == c and len(ts) > 1:
                        gaps = np.diff(ts)
                        refresh[dev] = {"median_s": float(np.median(gaps)), "max_s": float(gaps.max())}
                out["clients"][c] = {
                    "requests": int(times.size),
                    "poll_rate_hz": float((times.size - 1) / span) if span > 0 else 0.0,
                    "writes_accepted": int(self.accepted.get(c, 0)),
                    "writes_refused": dict(self.refused.get(c, {})),
                    "write_refresh": refresh,
                }
            out["watchdog_expiries_open"] = [{"t": t, "device": d} for t, d in self.expiries]
            out["recoveries_after_expiry"] = [{"device": d, "seconds": s} for d, s in self.recoveries]
            out["link_events"] = dict(self.link)
            out["malformed_frames"] = {c: dict(k) for c, k in self.malformed.items()}
            return out

    def text(self) -> str:
        r = self.report()
        lines = ["controller audit:"]
        if not r["clients"]:
            lines.append("  no client talked to the gateway")
        for c, a in r["clients"].items():
            lines.append(f"  {c}: {a['requests']} requests ({a['poll_rate_hz']:.2f}/s sim time), "
                         f"{a['writes_accepted']} writes accepted, refused: {a['writes_refused'] or 'none'}")
            for dev, g in a["write_refresh"].items():
                lines.append(f"    {dev}: command refresh every {g['median_s']:.1f} s (max {g['max_s']:.1f} s)")
        for e in r["watchdog_expiries_open"]:
            lines.append(f"  watchdog of {e['device']} expired at t={e['t']:.0f} s and was never recovered")
        for e in r["recoveries_after_expiry"]:
            lines.append(f"  {e['device']}: controller resumed {e['seconds']:.0f} s after the watchdog expired")
        for k, n in r["link_events"].items():
            lines.append(f"  link: {k} x{n}")
        for c, kinds in r["malformed_frames"].items():
            lines.append(f"  malformed frames from {c}: {sum(kinds.values())} ("
                         + ", ".join(f"{k} x{n}" for k, n in sorted(kinds.items())) + ")")
        return "\n".join(lines)
