"""The lab's DAQ as rigsim models it: the channel list, noise, resolution, CSV and columns file.

Samples are instantaneous values at the logger's time stamps (one a minute, +-0.5 s, taken from
the core's nearest step). Noise: temperatures 0.05 K RMS, flow meters 1 % of reading, heat meters
1 %, gas and electricity meters 0.5 %; commands and set-points exact. Values are then rounded to
the channel's resolution.
"""
from __future__ import annotations

import re

import numpy as np

from .model import DATASHEET
from .tables import channel_list


def channels_of(rows) -> list[dict]:
    """The logged channels of a channel list's rows (t_s left out): name, unit, resolution,
    twin signal and position."""
    return [
        {"channel": r["channel"], "unit": r["unit"], "resolution": float(r["resolution"]),
         "signal": r["twin signal (for a columns file)"], "position": r["position or source"]}
        for r in rows if r["channel"] != "t_s"
    ]


CHANNELS = channels_of(channel_list())
NAMES = [c["channel"] for c in CHANNELS]

_EXACT = {"CHP_ON_CMD", "CHP_MOD_SET", "CB_MOD_SET", "DHW_PUMP_CMD", "HC_TSUP_SET", "HC_FLOW_SET"}
_FLOW = {"CB_FLOW", "HC_FLOW", "DHW_CHG_FLOW", "DHW_TAP_FLOW"}
_HEAT = {"CHP_QTH", "CB_QTH"}
_METER = {"CHP_PEL", "CHP_PGAS", "CB_PGAS"}


def add_noise(rec: np.ndarray, rng, channels, exact, one_pct, half_pct) -> np.ndarray:
    """The DAQ's noise and resolution on samples x channels: the exact channels as logged,
    temperatures (unit °C) 0.05 K RMS, the one_pct channels 1 % of reading, the half_pct
    channels 0.5 %, the rest as logged; then every value rounded to its channel's resolution."""
    out = rec.copy()
    for i, c in enumerate(channels):
        name, x = c["channel"], out[:, i]
        if name in exact:
            pass
        elif c["unit"] == "°C":
            x = x + rng.normal(0.0, 0.05, x.size)
        elif name in one_pct:
            x = x * (1.0 + rng.normal(0.0, 0.01, x.size))
        elif name in half_pct:
            x = x * (1.0 + rng.normal(0.0, 0.005, x.size))
        res = c["resolution"]
        out[:, i] = np.round(x / res) * res
    return out


def apply_daq(rec: np.ndarray, seed: int) -> np.ndarray:
    rng = np.random.default_rng([int(seed), 99])
    return add_noise(rec, rng, CHANNELS, _EXACT, _FLOW | _HEAT, _METER)


def _decimals(res: float) -> int:
    return max(0, -int(np.floor(np.log10(res) + 1e-9)))


def write_csv(path, t_s: np.ndarray, data: np.ndarray, channels=CHANNELS) -> None:
    fmts = ["%.3f"] + [f"%.{_decimals(c['resolution'])}f" for c in channels]
    header = ",".join(["t_s"] + [c["channel"] for c in channels])
    table = np.column_stack([t_s, data])
    # -0.0 -> 0.0 for tidy files
    table = np.where(table == 0.0, 0.0, table)
    np.savetxt(path, table, delimiter=",", header=header, comments="", fmt=fmts)


def _signal_name(c) -> str:
    return re.split(r"\s*\(", c["signal"].strip().strip('"'))[0].strip()


def columns_file(start: str, file: str, channels, entry, ports=()) -> str:
    """A columns file: [recording], the [ports] lines if any, [columns] with each channel's twin
    signal and what entry(channel) gives after it (None: the channel's unit)."""
    lines = ["[recording]", f'start = "{start}"', f'file = "{file}"', 'time = "t_s"', ""]
    if ports:
        lines += ["[ports]", *ports, ""]
    lines.append("[columns]")
    for c in channels:
        more = entry(c) or f'unit = "{c["unit"]}"'
        lines.append(f'"{c["channel"]}" = {{ signal = "{_signal_name(c)}", {more} }}')
    return "\n".join(lines) + "\n"


def columns_toml(start: str, file: str = "recording.csv") -> str:
    """The columns file a user writes: datasheet heights and ports, units as logged."""
    Hb, Hd = DATASHEET["buffer_height_m"], DATASHEET["dhw_height_m"]
    ports = [f"storage = {{ top = {DATASHEET['buffer_port_top_m'] / Hb:.4f}, "
             f"bottom = {DATASHEET['buffer_port_bottom_m'] / Hb:.4f} }}"]

    def entry(c):
        name, unit = c["channel"], c["unit"]
        if name == "CB_MOD_SET":
            return "range = [0, 100, 0, 10]"
        if name.startswith("BT_T"):
            h = DATASHEET["buffer_sensor_heights_m"][int(name[4:]) - 1] / Hb
            return f'unit = "{unit}", height = {h:.4f}'
        if name.startswith("WWS_T"):
            h = DATASHEET["dhw_sensor_heights_m"][int(name[5:]) - 1] / Hd
            return f'unit = "{unit}", height = {h:.4f}'
        return None

    return columns_file(start, file, CHANNELS, entry, ports)
