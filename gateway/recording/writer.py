"""Recorder: writes a run directory as it goes, flushed at least every second of wall time.

Layout (the reader in reader.py is its twin, guarded by a round-trip test):
  signals.csv  time [s] and one column per plant signal, one row per recorded step
  events.csv   t, kind, transport, client, device, point, value, accepted, reason, detail
               (bus writes with their refusal reason, injected faults, watchdog transitions,
               link events, controller audit at the end)
  meta.json    house, start, clock, maps, versions, columns; rewritten at close
A crash loses at most the last second: both files are flushed by a timer thread.
"""
from __future__ import annotations

import csv
import json
import platform
import threading
import time
from pathlib import Path
from typing import Any

EVENT_COLUMNS = ("t", "kind", "transport", "client", "device", "point", "value", "accepted",
                 "reason", "detail")


class Recorder:
    def __init__(self, directory: str | Path, names: list[str], meta: dict[str, Any],
                 interval: float = 1.0):
        self.dir = Path(directory)
        self.dir.mkdir(parents=True, exist_ok=True)
        self.names = list(names)
        self.interval = interval  # simulated seconds between signal rows
        self._next_row_t = 0.0
        self._lock = threading.Lock()
        self._sig_fh = open(self.dir / "signals.csv", "w", newline="")
        self._sig = csv.writer(self._sig_fh)
        self._sig.writerow(["time"] + self.names)
        self._ev_fh = open(self.dir / "events.csv", "w", newline="")
        self._ev = csv.writer(self._ev_fh)
        self._ev.writerow(EVENT_COLUMNS)
        self.meta = {"format": "house-twin recording 1", "columns": self.names,
                     "python": platform.python_version(), "started_wall": time.time(), **meta}
        self._write_meta()
        self._closed = False
        self._stop = threading.Event()
        self._flusher = threading.Thread(target=self._flush_loop, name="recorder-flush", daemon=True)
        self._flusher.start()

    def _write_meta(self) -> None:
        tmp = self.dir / "meta.json.tmp"
        tmp.write_text(json.dumps(self.meta, indent=2, default=str))
        tmp.replace(self.dir / "meta.json")

    def _flush_loop(self) -> None:
        while not self._stop.wait(min(1.0, 0.5)):
            self.flush()

    def flush(self) -> None:
        with self._lock:
            if not self._closed:
                self._sig_fh.flush()
                self._ev_fh.flush()

    def signals(self, t: float, values) -> None:
        """Record a row if at least `interval` simulated seconds passed since the last one."""
        if t + 1e-9 < self._next_row_t:
            return
        self._next_row_t = t + self.interval
        with self._lock:
            if not self._closed:
                self._sig.writerow([f"{t:.3f}"] + [f"{v:.6g}" for v in values])

    def event(self, ev: dict[str, Any]) -> None:
        if ev.get("kind") == "request":  # polling is summarised by the audit, not logged per frame
            return
        detail = {k: v for k, v in ev.items() if k not in EVENT_COLUMNS}
        row = [ev.get("t", ""), ev.get("kind", ""), ev.get("transport", ""), ev.get("client", ""),
               ev.get("device", ""), ev.get("point", ""), ev.get("value", ev.get("raw", "")),
               ev.get("accepted", ""), ev.get("reason", ""), json.dumps(detail, default=str) if detail else ""]
        with self._lock:
            if not self._closed:
                self._ev.writerow(row)

    def close(self, extra_meta: dict[str, Any] | None = None) -> None:
        self._stop.set()
        with self._lock:
            if self._closed:
                return
            self._closed = True
            self._sig_fh.close()
            self._ev_fh.close()
        if extra_meta:
            self.meta.update(extra_meta)
        self.meta["stopped_wall"] = time.time()
        self._write_meta()
