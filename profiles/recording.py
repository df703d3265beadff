"""Recordings: the one writer of run directories and the one reader of every recording.

A run directory (`twin serve --record DIR`), written by Recorder as the run goes:
  signals.csv  `time` [s] and one column per plant signal (catalogue names and units), one row
               per recorded step
  events.csv   t, kind, transport, client, device, point, value, accepted, reason, detail
               (bus writes with their refusal reason, injected faults, watchdog transitions,
               link events, controller audit at the end)
  meta.json    house, start, clock, maps, versions, columns; rewritten at close
Both CSV files are flushed by a timer thread at least every second of wall time, so a crash
loses at most the last second and a reader sees the rows written so far while the run goes on.

A user's CSV (or CSV.gz): a `time` column in seconds since the recording start (or ISO 8601
date-times) plus user columns, read through a columns file (profiles/columns.py: [recording]
start, file and time, [columns] user column -> signal, [units]).

A directory holding columns.toml (and the CSV it names) is read the same way: that is the
format of `twin make-recording` (profiles/recordings/). Without a columns file each column is
taken to be named after its signal.

    rec = read_recording("runs/today")                       # a run directory
    rec = read_recording("lab.csv", "columns.toml")          # a user CSV through a columns file
    rec.time, rec.names, rec.values, rec.signals, rec.units, rec.start, rec.meta, rec.events

The reader returns values as written (the caller converts units with plant/units.py) and checks
only what needs no plant: files, the `time` column, the columns file's shape. Rows with the wrong
number of fields (a half-written last line) are dropped and counted; unreadable cells are NaN.
The round trip writer -> reader is guarded by tests/profiles/test_recording.py.
"""
from __future__ import annotations

import csv
import gzip
import io
import json
import platform
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from plant.errors import ConfigError, DataError, closest

from .columns import COLUMNS_FILE, column_entries, read_columns, storage_ports

FORMAT = "house-twin recording 1"
EVENT_COLUMNS = ("t", "kind", "transport", "client", "device", "point", "value", "accepted",
                 "reason", "detail")
RUN_FILES = ("signals.csv", "events.csv", "meta.json")


class Recorder:
    """Writes a run directory as it goes (see the module text for the layout)."""

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
        self.meta = {"format": FORMAT, "columns": self.names,
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
        while not self._stop.wait(0.5):
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


@dataclass
class Recording:
    """A recording as written: time [s since start] and one column per name, in `units`."""

    source: Path
    names: list[str]                 # column names as written (without `time`)
    time: np.ndarray
    values: np.ndarray               # rows x names; NaN where a cell was empty or unreadable
    start: str | None = None         # date (or date-time) of time 0, from meta.json or [recording]
    signals: dict[str, str] = field(default_factory=dict)  # column -> catalogue signal
    units: dict[str, str] = field(default_factory=dict)    # column -> unit, where declared
    meta: dict = field(default_factory=dict)
    events: list[dict] = field(default_factory=list)       # events.csv rows (run directories)
    dropped_rows: int = 0            # rows with the wrong number of fields

    @property
    def data(self) -> dict[str, np.ndarray]:
        """{column: values}."""
        return {n: self.values[:, i] for i, n in enumerate(self.names)}

    def column(self, name: str) -> np.ndarray:
        try:
            return self.values[:, self.names.index(name)]
        except ValueError:
            raise ConfigError(f"{self.source}: no column {name!r}; columns: "
                              f"{', '.join(self.names[:12])}{' ...' if len(self.names) > 12 else ''}") from None

    def signal(self, name: str) -> np.ndarray:
        """The column that holds catalogue signal `name` (as written, in its column's unit)."""
        for col, sig in self.signals.items():
            if sig == name:
                return self.column(col)
        raise ConfigError(f"{self.source}: no column holds signal {name!r}")


def read_recording(path: str | Path, columns: str | Path | None = None) -> Recording:
    """Read a run directory, a directory with columns.toml, or a CSV (+ columns file)."""
    p = Path(path)
    if p.is_dir():
        if (p / "signals.csv").exists() or not (p / COLUMNS_FILE).exists():
            return _read_run(p)
        columns = columns or p / COLUMNS_FILE
    elif not p.exists():
        raise ConfigError(f"{p}: no such recording (a run directory, or a CSV with a `time` column)")
    doc = read_columns(columns) if columns is not None else {}
    f = p / doc.get("recording", {}).get("file", "recording.csv") if p.is_dir() else p
    if not f.exists():
        raise ConfigError(f"{columns}: [recording] file = {f.name!r}: no such file beside it")
    tcol = str(doc.get("recording", {}).get("time", "time"))
    header, data, dropped, cells = _read_csv(f, text_column=tcol)
    if tcol not in header:
        close = closest(tcol, header, n=3, cutoff=0.5)
        raise DataError(f"{f}: needs a {tcol!r} column (seconds since [recording] start, or ISO date-times"
                        + ("; another name: [recording] time = \"column\" in the columns file" if tcol == "time" else "")
                        + ")" + (f"; did you mean {', '.join(close)}?" if close else "")
                        + f" Columns are: {', '.join(header[:12])}{' ...' if len(header) > 12 else ''}")
    i = header.index(tcol)
    names = [h for h in header if h != tcol]
    values = np.delete(data, i, axis=1)
    signals, units, columns_meta = column_entries(doc, columns) if doc else ({n: n for n in names}, {}, {})
    start = doc.get("recording", {}).get("start")
    time, start = _times(cells, None if start is None else str(start), f"{f}: column {tcol!r}")
    meta = {"columns": columns_meta, "ports": storage_ports(doc, columns) if doc else {}}
    return Recording(p, names, time, values, start, signals, units, meta, [], dropped)


def _times(cells: list[str], start: str | None, where: str) -> tuple[np.ndarray, str | None]:
    """The time column: seconds since the start, or ISO 8601 date-times (2021-01-10 00:01:00,
    2021-01-10T00:01:00+01:00) turned into seconds since [recording] start (read in the earliest
    stamp's UTC offset when it has none), else since the earliest stamp, which then is the start.
    Unreadable cells are NaN (their rows are dropped by the caller, with a warning)."""
    try:
        seconds = np.array(cells, dtype=float)
    except ValueError:  # blank or non-numeric cells (date-times): cell by cell
        seconds = np.array([_number(c) for c in cells], dtype=float)
    if np.isfinite(seconds).any() or not any(c.strip() for c in cells):
        return seconds, start
    from datetime import datetime

    stamps = []
    for c in cells:
        try:
            stamps.append(datetime.fromisoformat(c.strip()))
        except ValueError:
            stamps.append(None)
    ok = [d for d in stamps if d is not None]
    if not ok:
        raise DataError(f"{where}: neither seconds nor ISO date-times (e.g. 2021-01-10T00:01:00); "
                        f"first cell {cells[0]!r}")
    if len({d.tzinfo is None for d in ok}) > 1:
        raise DataError(f"{where}: mixes date-times with and without a UTC offset; give all or none")
    if start is None:
        t0 = min(ok)
        start = t0.replace(tzinfo=None).isoformat(timespec="seconds")
    else:
        try:
            t0 = datetime.fromisoformat(start)
        except ValueError:
            raise DataError(f"{where}: [recording] start = {start!r} is not an ISO date or date-time") from None
        if t0.tzinfo is None and ok[0].tzinfo is not None:
            t0 = t0.replace(tzinfo=min(ok).tzinfo)  # a start without an offset: the earliest stamp's
    return np.array([(d - t0).total_seconds() if d is not None else np.nan for d in stamps]), start


def _read_run(d: Path) -> Recording:
    for f in RUN_FILES:
        if not (d / f).exists():
            raise ConfigError(f"{d}: not a recording directory ({f} missing); give a `twin serve "
                              f"--record` directory, a CSV, or a directory with {COLUMNS_FILE}")
    meta = json.loads((d / "meta.json").read_text())
    header, data, dropped, _ = _read_csv(d / "signals.csv")
    with open(d / "events.csv", newline="") as fh:
        events = list(csv.DictReader(fh))
    names = header[1:]
    units = meta.get("units", {})
    return Recording(d, names, data[:, 0], data[:, 1:], meta.get("start"), {n: n for n in names},
                     units, meta, events, dropped)


def _open(path: Path):
    return gzip.open(path, "rt", newline="") if path.suffix == ".gz" else open(path, newline="")


def _read_csv(path: Path, text_column: str | None = None) -> tuple[list[str], np.ndarray, int, list | None]:
    """(header, rows x columns as float with NaN for unreadable cells, rows dropped, the cells of
    text_column as written (None: no such column); that column's floats are NaN)."""
    with _open(path) as fh:
        rows = list(csv.reader(fh))
    if not rows:
        raise DataError(f"{path}: empty file")
    header = [h.strip() for h in rows[0]]
    n = len(header)
    body = [r for r in rows[1:] if r and any(c.strip() for c in r)]
    kept = [r for r in body if len(r) == n]
    cells = None
    if text_column in header:
        j = header.index(text_column)
        cells = [r[j] for r in kept]
        kept = [r[:j] + ["nan"] + r[j + 1:] for r in kept]
    if not kept:
        return header, np.zeros((0, n)), len(body), cells
    try:
        data = np.array(kept, dtype=float)
    except ValueError:  # empty or non-numeric cells: NaN, cell by cell
        data = np.array([[_number(c) for c in r] for r in kept], dtype=float)
    return header, data, len(body) - len(kept), cells


def _number(cell: str) -> float:
    cell = cell.strip()
    try:
        return float(cell) if cell not in ("", "NA") else np.nan
    except ValueError:
        return np.nan


def write_csv(path: str | Path, time: np.ndarray, data: dict[str, np.ndarray],
              fmt: str | list[str] = "%.6g", gzip_above: int | None = None) -> Path:
    """Write `time` and one column per entry of data; gzip (path + '.gz') above gzip_above bytes.

    fmt is one printf format or one per column (time first). Returns the path written."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    buf = io.StringIO()
    buf.write(",".join(["time", *data]) + "\n")
    np.savetxt(buf, np.column_stack([time, *data.values()]), delimiter=",", fmt=fmt)
    text = buf.getvalue()
    if gzip_above is not None and len(text) > gzip_above:
        path = path.with_name(path.name + ".gz")
        with gzip.open(path, "wt", compresslevel=9) as fh:
            fh.write(text)
    else:
        path.write_text(text)
    return path


__all__ = ["Recorder", "Recording", "read_recording", "write_csv", "EVENT_COLUMNS", "FORMAT"]
