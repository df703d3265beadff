"""Read a run directory written by Recorder back into arrays and event rows."""
from __future__ import annotations

import csv
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from plant.errors import ConfigError


@dataclass
class Recording:
    directory: Path
    meta: dict
    names: list[str]
    time: np.ndarray
    values: np.ndarray  # rows x signals
    events: list[dict]

    def signal(self, name: str) -> np.ndarray:
        try:
            return self.values[:, self.names.index(name)]
        except ValueError:
            raise ConfigError(f"{self.directory}: no signal {name!r} in signals.csv") from None


def read_recording(directory: str | Path) -> Recording:
    d = Path(directory)
    for f in ("signals.csv", "events.csv", "meta.json"):
        if not (d / f).exists():
            raise ConfigError(f"{d}: not a recording directory ({f} missing)")
    meta = json.loads((d / "meta.json").read_text())
    with open(d / "signals.csv", newline="") as fh:
        rows = list(csv.reader(fh))
    header, body = rows[0], rows[1:]
    # a crash can leave a half-written last line: keep only complete rows
    body = [r for r in body if len(r) == len(header)]
    data = np.array(body, dtype=float) if body else np.zeros((0, len(header)))
    with open(d / "events.csv", newline="") as fh:
        events = list(csv.DictReader(fh))
    return Recording(d, meta, header[1:], data[:, 0], data[:, 1:], events)
