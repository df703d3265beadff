"""The columns file: how a user's CSV maps onto the twin's signals (TOML).

    [recording]
    start = "2021-01-10"            # date (or YYYY-MM-DDTHH:MM) of time = 0, local standard time
                                    # (date-time stamps without it: the earliest stamp)
    file = "recording.csv"          # optional: the CSV beside the columns file
    time = "Timestamp"              # optional: the time column's name (default "time")
    [columns]
    "TS_CHP_out" = "chp.T_sup"      # user column -> catalogue signal
    "CB_CMD" = { signal = "boiler.U_set", range = [0, 100, 0, 10] }   # or a table (column_entries)
    [units]
    "TS_CHP_out" = "degC"           # the column's unit (plant/units.py); default: the signal's
    [ports]                         # optional: the lab tank's connection heights (its datasheet),
    storage = { top = 0.951, bottom = 0.049 }   # relative like the sensors' (0 = bottom, 1 = top)

Read (shape and entries checked, every problem named at once) and written here; the CSV it
describes is read by profiles/recording.py.
"""
from __future__ import annotations

import tomllib
from pathlib import Path

from plant.errors import ConfigError, closest

COLUMNS_FILE = "columns.toml"


def read_columns(path: str | Path) -> dict:
    """The columns file as a dict, its shape checked ([columns] a table of strings)."""
    p = Path(path)
    if not p.exists():
        raise ConfigError(f"{p}: no such columns file")
    try:
        doc = tomllib.loads(p.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{p}: not valid TOML: {exc}") from None
    if "columns" not in doc or not isinstance(doc["columns"], dict):
        raise ConfigError(f"{p}: needs a [columns] table: \"user column\" = \"signal.name\" (or a table "
                          "{ signal = ..., unit = ..., scale = ..., offset = ..., range = [...], height = ... })")
    if any(not isinstance(doc.get(k, {}), dict) for k in ("units", "recording", "ports")):
        raise ConfigError(f"{p}: [units], [recording] and [ports] must be tables")
    return doc


COLUMN_KEYS = ("signal", "unit", "scale", "offset", "range", "height")


def column_entries(doc: dict, path) -> tuple[dict, dict, dict]:
    """[columns] entries: "col" = "signal" or { signal, unit, scale, offset, range, height };
    returns (column -> signal, column -> unit, column -> {scale, offset, range, height}).

    scale/offset: value x scale + offset, in `unit`; range = [a, b, c, d]: the column's a ... b
    maps linearly onto c ... d of the signal's own unit (e.g. a boiler command logged as
    0 ... 100 % onto 0 ... 10 V); height: a storage sensor's relative height 0 (bottom) ... 1 (top)."""
    signals, units, extra, problems = {}, {}, {}, []
    units.update({str(c): str(u) for c, u in doc.get("units", {}).items()})
    for col, entry in doc["columns"].items():
        col = str(col)
        where = f"{path}: [columns] {col!r}"
        if isinstance(entry, str):
            signals[col] = entry
            continue
        if not isinstance(entry, dict) or not isinstance(entry.get("signal"), str):
            problems.append(f"{where} = {entry!r}: expected \"signal.name\" or {{ signal = \"...\", unit = ..., "
                            "scale = ..., offset = ..., range = [a, b, c, d], height = 0 ... 1 }")
            continue
        for key in entry:
            if key not in COLUMN_KEYS:
                close = closest(key, COLUMN_KEYS, n=2)
                problems.append(f"{where} {key}: unknown key; " + (f"did you mean {', '.join(close)}?" if close
                                                                  else f"allowed: {', '.join(COLUMN_KEYS)}"))
        signals[col] = entry["signal"]
        if "unit" in entry:
            units[col] = str(entry["unit"])
        t = {}
        for key in ("scale", "offset"):
            if key in entry:
                v = entry[key]
                if isinstance(v, bool) or not isinstance(v, (int, float)) or (key == "scale" and v == 0):
                    problems.append(f"{where} {key} = {v!r}: must be a number" + (" other than 0" if key == "scale" else ""))
                else:
                    t[key] = float(v)
        if "range" in entry:
            r = entry["range"]
            if (not isinstance(r, list) or len(r) != 4 or any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in r)
                    or r[0] == r[1]):
                problems.append(f"{where} range = {r!r}: must be [a, b, c, d] with a != b: the column's a ... b "
                                "onto c ... d of the signal, e.g. [0, 100, 0, 10] for 0-100 % onto 0-10 V")
            elif "unit" in entry or "scale" in entry or "offset" in entry:
                problems.append(f"{where}: range maps straight onto the signal's unit; leave out unit, scale and offset")
            else:
                t["range"] = [float(v) for v in r]
        if "height" in entry:
            h = entry["height"]
            if isinstance(h, bool) or not isinstance(h, (int, float)) or not 0.0 <= h <= 1.0:
                problems.append(f"{where} height = {h!r}: outside 0 … 1 (relative height of the sensor in its "
                                "storage: 0 = bottom, 1 = top)")
            else:
                t["height"] = float(h)
        if t:
            extra[col] = t
    if problems:
        raise ConfigError("\n".join(problems))
    return signals, units, extra


def storage_ports(doc: dict, path) -> dict:
    """[ports] entries: storage -> {top, bottom}, the relative heights 0 (bottom) ... 1 (top) of
    the connections through which the storage takes and gives the coupling point's flows."""
    out, problems = {}, []
    for name, entry in doc.get("ports", {}).items():
        where = f"{path}: [ports] {name}"
        if not isinstance(entry, dict) or set(entry) != {"top", "bottom"}:
            problems.append(f"{where} = {entry!r}: expected {{ top = ..., bottom = ... }}, the relative heights "
                            "of the tank's upper and lower connection (0 = bottom, 1 = top)")
            continue
        bad = [k for k in ("top", "bottom") if isinstance(entry[k], bool) or not isinstance(entry[k], (int, float))
               or not 0.0 <= entry[k] <= 1.0]
        if bad:
            problems += [f"{where} {k} = {entry[k]!r}: outside 0 … 1 (relative height of the connection: "
                         "0 = bottom, 1 = top)" for k in bad]
        elif entry["top"] <= entry["bottom"]:
            problems.append(f"{where}: top = {entry['top']!r} must lie above bottom = {entry['bottom']!r}")
        else:
            out[str(name)] = {"top": float(entry["top"]), "bottom": float(entry["bottom"])}
    if problems:
        raise ConfigError("\n".join(problems))
    return out


def write_columns(path: str | Path, signals: dict[str, str], units: dict[str, str],
                  start: str | None = None, file: str | None = None, comment: str | None = None) -> None:
    """Write a columns file: [recording] start (and file), [columns] and [units] per column."""
    lines = [f"# {comment}"] if comment else []
    lines += ["[recording]", f'start = "{start or "2021-01-10"}"']
    lines += [f'file = "{file}"'] if file else []
    lines += ["", "[columns]"] + [f'"{c}" = "{s}"' for c, s in signals.items()]
    lines += ["", "[units]"] + [f'"{c}" = "{u}"' for c, u in units.items()]
    Path(path).write_text("\n".join(lines) + "\n")
