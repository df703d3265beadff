"""Readers for the raw data tables in rigsim/data/ (own parser, no project code).

Text tables ("#1" files): a header line ``double Name(rows,cols)`` followed by rows of numbers;
at most the declared number of rows is read. The DHWcalc file is ``flow;minute`` per line.
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parent / "data"
_HEADER = re.compile(r"double\s+(\w+)\s*\(\s*(\d+)\s*,\s*(\d+)\s*\)")


def read_text_tables(path) -> dict[str, np.ndarray]:
    """All tables of one text-table file, as float arrays of the declared shape."""
    tables: dict[str, np.ndarray] = {}
    name, nrows, ncols, rows = None, 0, 0, []

    def close():
        if name is not None:
            tables[name] = np.array(rows[:nrows], dtype=float).reshape(-1, ncols)

    with open(path, encoding="latin-1") as fh:
        for line in fh:
            s = line.strip()
            if not s or s.startswith("#"):
                continue
            m = _HEADER.match(s)
            if m:
                close()
                name, nrows, ncols, rows = m.group(1), int(m.group(2)), int(m.group(3)), []
                continue
            if name is None or len(rows) >= nrows:
                continue
            vals = [float(v) for v in s.replace(",", " ").split()]
            if len(vals) >= ncols:
                rows.append(vals[:ncols])
    close()
    return tables


def table(file: str, name: str) -> np.ndarray:
    return read_text_tables(DATA / file)[name]


def dhwcalc_minutes(file: str = "SF1_wholeyear_Vdot.txt") -> np.ndarray:
    """Draw-off flow [l/h] for each minute of the year (index 0 = first minute of 1 January)."""
    flow = np.zeros(525600)
    with open(DATA / file) as fh:
        for line in fh:
            s = line.strip()
            if not s:
                continue
            a, b = s.split(";")[:2]
            k = int(b) - 1
            if 0 <= k < flow.size:
                flow[k] = float(a)
    return flow


def channel_list(file: str = "house1-channels.csv") -> list[dict]:
    """A DAQ channel list (house 1's lab: house1-channels.csv), t_s first."""
    import csv

    with open(DATA / file, encoding="utf-8") as fh:
        return [dict(r) for r in csv.DictReader(fh)]
