"""Samples for `twin diagnose`: a recording read by profiles/recording.py, repaired, in catalogue units.

Any recording profiles.recording.read_recording reads: a run directory (signals.csv, events.csv,
meta.json: columns are catalogue names in catalogue units, meta.json holds the start), a CSV with
a `time` column [s] (or ISO date-times; [recording] time names another column) through a columns
file ([recording] start, [columns] "user column" =
"catalogue signal", [units] "user column" = unit of plant/units.py), a directory holding
columns.toml (`twin make-recording`), or a CSV whose columns are catalogue names.

Bad input is repaired with a warning that says what was done, or rejected (ConfigError/DataError)
with a message that says why: unsorted timestamps are sorted, duplicate timestamps keep the last
row, gaps longer than 3 median intervals are held (commands) and excluded from scoring, NaN
samples of measured signals are excluded, NaN commands are held; unknown columns are ignored;
units that are unknown, of another kind than the signal's, or whose values are implausible for
the unit are rejected.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from profiles.columns import COLUMNS_FILE, write_columns
from profiles.recording import read_recording
from profiles.recording import write_csv as write_table

from .. import units as unit_table
from ..errors import ConfigError, DataError, closest
from .requirements import profile_differs

# plausible range of a converted value per catalogue unit (catches e.g. Kelvin labelled degC)
PLAUSIBLE = {"degC": (-40.0, 130.0), "kg/s": (-5.0, 5.0), "W": (-2e5, 2e5), "V": (-1.0, 11.0)}


@dataclass
class Samples:
    """Samples in catalogue units: time [s since start], data {signal: array} (NaN = missing)."""

    source: str
    start: str
    time: np.ndarray
    data: dict
    warnings: list = field(default_factory=list)
    valid: np.ndarray | None = None  # samples usable for scoring (False inside gaps)
    columns: dict = field(default_factory=dict)  # signal -> user column name
    heights: dict = field(default_factory=dict)  # storage sensor signal -> relative height 0 ... 1
    ports: dict = field(default_factory=dict)    # storage -> {top, bottom}: relative port heights ([ports])
    substituted: dict = field(default_factory=dict)  # command not recorded -> the output replayed for it

    def sensor_overrides(self) -> dict:
        """House overrides that put the twin's storage sensors where the recording's are."""
        out = {}
        for storage in sorted({s.split(".", 1)[0] for s in self.heights}):
            mine = {int(s.rsplit("_", 1)[1]): h for s, h in self.heights.items() if s.startswith(storage + ".")}
            if mine:
                n = max(10, max(mine))
                out[f"{storage}.sensor_heights"] = [mine.get(k, (k - 0.5) / n) for k in range(1, n + 1)]
        return out

    def has(self, name: str) -> bool:
        return name in self.data

    def on(self, name: str) -> np.ndarray:
        """Samples at which a recorded command (0/1) is on: above one half, a missing sample off;
        all off where the recording lacks it."""
        if name not in self.data:
            return np.zeros(self.time.size, bool)
        return np.nan_to_num(np.asarray(self.data[name], float)) > 0.5

    def __len__(self) -> int:
        return len(self.time)


def load(path: str | Path, mapping: str | Path | None = None, start: str | None = None,
         house_start: str = "2021-01-10", house="house1") -> Samples:
    """Read a recording (+ columns file) through profiles.recording; repair or reject bad input.
    Its signals are `house`'s (a name or a house file: its catalogue names and units)."""
    from .roles import of

    cat = of(house).catalogue
    p = Path(path)
    warnings: list[str] = []
    run = p.is_dir() and (p / "signals.csv").exists()
    if mapping is None and p.is_dir() and not run:
        mapping = p / COLUMNS_FILE
    rec = read_recording(p, mapping)
    header = ["time"] + rec.names
    raw = np.column_stack([rec.time, rec.values])
    if mapping is None:
        colmap, units = _catalogue_columns(p, rec, run, warnings, cat)
    else:
        colmap, units = _mapped_columns(p, rec, mapping, warnings, cat, house)
    start = start or rec.start
    if rec.dropped_rows:
        warnings.append(f"{rec.dropped_rows} row(s) with the wrong number of fields dropped")
    if raw.shape[0] < 3:
        raise DataError(f"{p}: fewer than 3 samples")
    raw, t = _repair_time(raw, raw[:, header.index("time")], warnings)
    transforms = rec.meta.get("columns", {}) if mapping is not None else {}
    ports = rec.meta.get("ports", {}) if mapping is not None else {}
    _check_ports(ports, mapping, cat)
    data, heights = _convert_columns(raw, header, colmap, units, transforms, mapping, warnings, cat)
    if not start:
        start = _start_of(t, data, house_start, warnings)
    _check_places(heights, {sig: col for col, sig in colmap.items()}, mapping)
    valid = _gaps(t, warnings)
    _hold_or_exclude_missing(data, warnings, cat)
    return Samples(str(p), str(start), t, data, warnings, valid,
                   {sig: col for col, sig in colmap.items()}, heights, ports)


def _start_of(t: np.ndarray, data: dict, house_start: str, warnings: list) -> str:
    """A recording without a date: the day of the profile year whose outdoor air the recorded one
    matches (as the replay's boundary check judges a match), else the house file's start. A twin's
    own run written by `twin simulate --out` carries its weather but not its date."""
    from profiles.loaders import YEAR_S, start_offset, weather

    base = "no start date in the recording or mapping ([recording] start)"
    T = data.get("weather.T_air")
    ok = np.isfinite(T) if T is not None else None
    if T is not None and ok.sum() >= 10 and t[-1] - t[0] < YEAR_S:
        air = weather()["T_air"]
        days = np.arange(365) * 86400.0
        err = np.array([np.sqrt(np.mean((air.at(d + t[ok]) - T[ok]) ** 2)) for d in days])
        k = int(np.argmin(err))
        y = air.at(days[k] + t[ok])
        if not profile_differs(float(err[k]), float(np.std(y)), "weather.T_air"):
            day = (np.datetime64("2021-01-01") + np.timedelta64(k, "D")).astype(str)
            own = err[int(start_offset(house_start) // 86400) % 365]
            warnings.append(f"{base}; its weather.T_air matches the weather profile from {day} (RMS {err[k]:.2g} K; "
                            f"the house file's start {house_start}: {own:.2g} K): started there")
            return day
    warnings.append(f"{base}; assumed the house file's start {house_start}")
    return house_start


def _catalogue_columns(p: Path, rec, run: bool, warnings: list, cat) -> tuple[dict, dict]:
    """Without a columns file: the columns named like catalogue signals, in catalogue units ->
    ({column: signal}, {column: unit}). A run directory's other columns are named one warning
    each; any other recording must have a catalogue column, and the rest are listed in one."""
    colmap = {n: n for n in rec.names if n in cat}
    units = {n: cat.signal(n).unit for n in colmap}
    ignored = [n for n in rec.names if n not in cat]
    if run:
        warnings += [f"column {n!r}: not a catalogue signal; ignored" for n in ignored]
    elif not colmap:
        raise ConfigError(f"{p}: no column is a catalogue signal name; pass --map columns.toml")
    elif ignored:
        warnings.append("columns not in the catalogue ignored: " + ", ".join(ignored))
    return colmap, units


def _mapped_columns(p: Path, rec, mapping, warnings: list, cat, house) -> tuple[dict, dict]:
    """The columns file's [columns] and [units] checked against the catalogue and the recording
    -> ({column: signal}, {column: unit}). Every problem goes into one ConfigError, so that the
    file can be fixed in one go rather than one line per attempt."""
    colmap = {}
    problems = []
    for col, sig in rec.signals.items():
        if sig not in cat:
            close = closest(sig, cat.names, n=2)
            problems.append(f"{mapping}: [columns] {col!r} = {sig!r}: unknown signal"
                            + (f"; did you mean {', '.join(close)}?" if close else
                               f"; list them with `twin signals {house}`"))
            continue
        if col not in rec.names:
            close = closest(col, rec.names, n=2)
            problems.append(f"{mapping}: [columns] {col!r}: no such column in {p.name}"
                            + (f"; did you mean {', '.join(close)}?" if close else ""))
            continue
        colmap[col] = sig
    units = _mapped_units(rec, colmap, mapping, problems, cat)
    owners = {n.split(".", 1)[0] for n in cat.names}
    foreign = sorted({s.split(".", 1)[0] for s in rec.signals.values() if s not in cat} - owners)
    if foreign:
        problems.insert(0, f"{mapping}: its columns name instances {house} does not have ({', '.join(foreign)}): "
                           "a recording of another house? Give its own house file (--house), or map the columns "
                           f"onto {house}'s signals (`twin signals {house}`)")
    if problems:
        raise ConfigError("\n".join(problems))
    extra = [h for h in rec.names if h not in colmap]
    if extra:
        warnings.append(f"{len(extra)} column(s) not in the mapping ignored: " + ", ".join(extra[:8])
                        + (" ..." if len(extra) > 8 else ""))
    return colmap, units


def _mapped_units(rec, colmap: dict, mapping, problems: list, cat) -> dict:
    """{column: declared unit} for the mapped columns (the signal's catalogue unit where none is
    declared); an unknown unit or one of another kind than the signal's goes to problems."""
    units = {}
    for col, sig in colmap.items():
        u = rec.units.get(col)
        cat_unit = cat.signal(sig).unit
        if u is None:
            units[col] = cat_unit
            continue
        if u not in unit_table.UNITS:
            problems.append(f"{mapping}: [units] {col!r} = {u!r}: unknown unit; allowed: "
                            + ", ".join(sorted(n for n in unit_table.UNITS if n)))
            continue
        if not unit_table.convertible(u, cat_unit):
            problems.append(f"{mapping}: [units] {col!r} = {u!r}: wrong unit for {sig} "
                            f"(a {cat_unit} signal)")
            continue
        units[col] = u
    return units


def _repair_time(raw: np.ndarray, t: np.ndarray, warnings: list) -> tuple[np.ndarray, np.ndarray]:
    """Rows without a finite time dropped, rows sorted by time (stable), of duplicate timestamps
    the last row kept -> (raw, t)."""
    keep = np.isfinite(t)
    if not keep.all():
        warnings.append(f"{int((~keep).sum())} row(s) without a valid time dropped")
        raw, t = raw[keep], t[keep]
    if np.any(np.diff(t) < 0):
        order = np.argsort(t, kind="stable")
        warnings.append(f"timestamps not sorted ({int(np.sum(np.diff(t) < 0))} backward step(s)); "
                        "rows sorted by time")
        raw, t = raw[order], t[order]
    dup = np.concatenate([np.diff(t) == 0, [False]])
    if dup.any():
        warnings.append(f"{int(dup.sum())} duplicate timestamp(s); kept the last row of each")
        raw, t = raw[~dup], t[~dup]
    return raw, t


def _check_ports(ports: dict, mapping, cat) -> None:
    """[ports] may only name storages the twin has (those with T_sensor_N signals)."""
    storages = sorted({s.split(".", 1)[0] for s in cat.names if ".T_sensor_" in s})
    for name in ports:
        if name not in storages:
            close = closest(name, storages, n=2)
            raise ConfigError(f"{mapping}: [ports] {name}: not a storage of the twin"
                              + (f"; did you mean {', '.join(close)}?" if close else f"; storages: {', '.join(storages)}"))


def _convert_columns(raw: np.ndarray, header: list, colmap: dict, units: dict, transforms: dict, mapping,
                     warnings: list, cat) -> tuple[dict, dict]:
    """Each mapped column in its signal's catalogue unit -> ({signal: values}, {signal: declared
    sensor height}); of two columns mapped onto one signal the later wins, with a warning."""
    data = {}
    heights = {}
    for col, sig in colmap.items():
        u = units[col]
        cat_unit = cat.signal(sig).unit
        tr = transforms.get(col, {})
        x = raw[:, header.index(col)]
        if "height" in tr:
            if ".T_sensor_" not in sig:
                storages = sorted({s.split(".", 1)[0] for s in cat.names if ".T_sensor_" in s})
                raise ConfigError(f"{mapping}: [columns] {col!r} height: only for storage sensors "
                                  f"({', '.join(f'{s}.T_sensor_N' for s in storages)})")
            heights[sig] = tr["height"]
        if "range" in tr:
            a, b, c, d = tr["range"]
            v = c + (x - a) * (d - c) / (b - a)
        else:
            f, off = unit_table.factors(u, cat_unit)
            v = (x * tr.get("scale", 1.0) + tr.get("offset", 0.0)) * f + off
        _check_plausible(v, col, sig, u, cat_unit)
        if sig in data:
            warnings.append(f"{sig}: mapped from two columns; the later one ({col!r}) used")
        data[sig] = v
    return data, heights


def _check_plausible(v: np.ndarray, col: str, sig: str, u: str, cat_unit: str) -> None:
    """A DataError when the converted column's median lies outside PLAUSIBLE for its unit: a
    wrongly declared unit (Kelvin labelled degC, l/min labelled kg/s) would otherwise be replayed
    as a huge mismatch and diagnosed."""
    lo_hi = PLAUSIBLE.get(cat_unit)
    if lo_hi is None:
        return
    fin = v[np.isfinite(v)]
    if fin.size:
        med = float(np.median(fin))
        if not lo_hi[0] <= med <= lo_hi[1]:
            hint = ""
            if cat_unit == "degC" and 230 < med < 400:
                hint = " (looks like Kelvin: declare the unit \"K\")"
            elif cat_unit == "kg/s" and med > 5:
                hint = " (looks like l/min or l/h: declare the unit)"
            elif cat_unit == "W" and abs(med) < 1e-3:
                hint = ""
            raise DataError(f"column {col!r} -> {sig}: median {med:g} {cat_unit} after unit "
                            f"conversion from {u!r} is implausible{hint}")


def _gaps(t: np.ndarray, warnings: list) -> np.ndarray:
    """The samples usable for scoring: False within the hour after each gap longer than 3 median
    sample intervals (the replay held the commands through it and needs time to settle)."""
    dts = np.diff(t)
    med = float(np.median(dts))
    valid = np.ones(len(t), dtype=bool)
    gaps = np.nonzero(dts > 3.0 * med)[0]
    if gaps.size:
        total = float(np.sum(dts[gaps]))
        warnings.append(f"{gaps.size} gap(s) longer than 3 sample intervals ({total / 3600:.2f} h in all; "
                        f"longest {dts[gaps].max() / 60:.1f} min): commands held through the gaps, "
                        "the first hour after each gap excluded from scoring")
        for g in gaps:
            valid[(t > t[g]) & (t <= t[g + 1] + 3600.0)] = False
    return valid


def _hold_or_exclude_missing(data: dict, warnings: list, cat) -> None:
    """NaN samples in place: a command (causality input) is held at its last value, since the
    replay must be driven at every step; a measured signal keeps its NaN (excluded from scoring)."""
    for sig, v in data.items():
        nan = ~np.isfinite(v)
        if nan.any():
            causality = cat.signal(sig).causality
            if causality == "input":
                first = np.flatnonzero(~nan)
                if first.size == 0:
                    raise DataError(f"{sig}: every sample is missing")
                idx = np.where(~nan, np.arange(len(v)), first[0])
                np.maximum.accumulate(idx, out=idx)
                data[sig] = v[idx]
                warnings.append(f"{sig}: {int(nan.sum())} missing command sample(s) held at the last value")
            else:
                warnings.append(f"{sig}: {int(nan.sum())} missing sample(s) excluded from scoring")


def _check_places(heights: dict, columns: dict, mapping) -> None:
    """The twin numbers a storage's sensors from the bottom (T_sensor_1 lowest): declared heights
    must rise with the number, or the twin cannot place the sensors (its neighbours, gradients and
    sensor candidates follow the numbering)."""
    for storage in sorted({s.split(".", 1)[0] for s in heights}):
        mine = sorted((int(s.rsplit("_", 1)[1]), h, s) for s, h in heights.items() if s.startswith(storage + "."))
        for (k1, h1, s1), (k2, h2, s2) in zip(mine, mine[1:]):
            if h2 <= h1:
                raise ConfigError(
                    f"{mapping}: [columns] {columns.get(s2, s2)!r} -> {s2} at height {h2:g} is not above "
                    f"{columns.get(s1, s1)!r} -> {s1} at height {h1:g}: the twin numbers {storage}'s sensors "
                    f"from the bottom, so it cannot place them; map the lab's columns onto {storage}.T_sensor_N "
                    "in the order of their heights (the lowest onto the smallest N)")


def write_csv(path: str | Path, time: np.ndarray, data: dict, mapping_path: str | Path | None = None,
              start: str | None = None, units: dict | None = None, columns: dict | None = None,
              house="house1") -> None:
    """Write samples of `house` as CSV (+ columns file); columns {signal: user column} renames them."""
    from .roles import of

    cat = of(house).catalogue
    names = list(data)
    cols = [(columns or {}).get(n, n) for n in names]
    write_table(path, time, {c: data[n] for c, n in zip(cols, names)})
    if mapping_path:
        write_columns(mapping_path, dict(zip(cols, names)),
                      {c: (units or {}).get(n, cat.signal(n).unit) for c, n in zip(cols, names)},
                      start=start)
