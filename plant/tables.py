"""Readers for the measured look-up tables (MSL text format) and fast njit interpolation.

Format: a `#1` line, then blocks `double NAME(rows,cols)` followed by rows of numbers. At most the
declared number of rows is read (one upstream file carries stray rows after a table); a mismatch
is reported as a warning.  2-D tables: row 0 = dummy then column abscissae, column 0 = row
abscissae.  Interpolation is linear and clamps at the table edges (the models never rely on
extrapolation).
"""
from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np
from numba import njit

from .errors import DataError

_HEADER = re.compile(r"^\s*double\s+(\w+)\s*\(\s*(\d+)\s*,\s*(\d+)\s*\)")


def read_tables(path: str | Path) -> dict[str, np.ndarray]:
    """Read every table of an MSL text-table file into float64 arrays, keyed by table name."""
    path = Path(path)
    tables: dict[str, np.ndarray] = {}
    name, rows, cols, buf = None, 0, 0, []
    extra = 0

    def close():
        if name is None:
            return
        if len(buf) < rows:
            raise DataError(f"{path}: table {name} declares {rows} rows but has {len(buf)}; fix the header")
        if extra:
            warnings.warn(f"{path}: table {name}: {extra} rows beyond the declared {rows} ignored")
        tables[name] = np.array(buf, dtype=np.float64)

    with path.open() as fh:
        for lineno, line in enumerate(fh, 1):
            m = _HEADER.match(line)
            if m:
                close()
                name, rows, cols, buf, extra = m.group(1), int(m.group(2)), int(m.group(3)), [], 0
                continue
            s = line.strip()
            if not s or s.startswith("#") or name is None:
                continue
            if len(buf) >= rows:
                extra += 1
                continue
            try:
                vals = [float(v) for v in s.replace(";", " ").split()]
            except ValueError:
                raise DataError(f"{path}:{lineno}: not a row of numbers: {s[:60]!r}") from None
            if len(vals) != cols:
                raise DataError(f"{path}:{lineno}: table {name} has {cols} columns, row has {len(vals)}")
            buf.append(vals)
    close()
    if not tables:
        raise DataError(f"{path}: no 'double NAME(rows,cols)' table found")
    return tables


@njit(cache=True, inline="always")
def interp1(x, xs, ys):
    """Linear interpolation in a sorted abscissa xs, clamped at both ends."""
    n = xs.shape[0]
    if x <= xs[0]:
        return ys[0]
    if x >= xs[n - 1]:
        return ys[n - 1]
    lo, hi = 0, n - 1
    while hi - lo > 1:
        mid = (lo + hi) >> 1
        if xs[mid] <= x:
            lo = mid
        else:
            hi = mid
    w = (x - xs[lo]) / (xs[hi] - xs[lo])
    return ys[lo] + w * (ys[hi] - ys[lo])


@njit(cache=True, inline="always")
def _bracket(x, xs):
    n = xs.shape[0]
    if x <= xs[0]:
        return 0, 0.0
    if x >= xs[n - 1]:
        return n - 2, 1.0
    lo, hi = 0, n - 1
    while hi - lo > 1:
        mid = (lo + hi) >> 1
        if xs[mid] <= x:
            lo = mid
        else:
            hi = mid
    return lo, (x - xs[lo]) / (xs[hi] - xs[lo])


@njit(cache=True)
def interp2(u1, u2, table):
    """Bilinear interpolation in an MSL 2-D table (row abscissa u1, column abscissa u2), clamped.

    Rows with equal abscissae (the boiler tables repeat each row) are handled: the bracket search
    returns the last of equal values, giving the plateau-and-ramp shape of the original.
    """
    rows = table[1:, 0]
    cols = table[0, 1:]
    i, wi = _bracket(u1, rows)
    j, wj = _bracket(u2, cols)
    if rows.shape[0] == 1:
        i, wi = 0, 0.0
    if cols.shape[0] == 1:
        j, wj = 0, 0.0
    v00 = table[1 + i, 1 + j]
    v01 = table[1 + i, 1 + min(j + 1, cols.shape[0] - 1)]
    v10 = table[1 + min(i + 1, rows.shape[0] - 1), 1 + j]
    v11 = table[1 + min(i + 1, rows.shape[0] - 1), 1 + min(j + 1, cols.shape[0] - 1)]
    return (1 - wi) * ((1 - wj) * v00 + wj * v01) + wi * ((1 - wj) * v10 + wj * v11)


@njit(cache=True)
def interp_col(x, table, col):
    """Linear interpolation of column `col` of a time table over its column 0, clamped."""
    return interp1(x, table[:, 0], table[:, col])
