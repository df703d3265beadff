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

_ALL = channel_list()
CHANNELS = [
    {"channel": r["channel"], "unit": r["unit"], "resolution": float(r["resolution"]),
     "signal": r["twin signal (for a columns file)"], "position": r["position or source"]}
    for r in _ALL if r["channel"] != "t_s"
]
NAMES = [c["channel"] for c in CHANNELS]

_EXACT = {"CHP_ON_CMD", "CHP_MOD_SET", "CB_MOD_SET", "DHW_PUMP_CMD", "HC_TSUP_SET", "HC_FLOW_SET"}
_FLOW = {"CB_FLOW", "HC_FLOW", "DHW_CHG_FLOW", "DHW_TAP_FLOW"}
_HEAT = {"CHP_QTH", "CB_QTH"}
_METER = {"CHP_PEL", "CHP_PGAS", "CB_PGAS"}


def apply_daq(rec: np.ndarray, seed: int) -> np.ndarray:
    rng = np.random.default_rng([int(seed), 99])
    out = rec.copy()
    for i, c in enumerate(CHANNELS):
        name, x = c["channel"], out[:, i]
        if name in _EXACT:
            pass
        elif c["unit"] == "°C":
            x = x + rng.normal(0.0, 0.05, x.size)
        elif name in _FLOW or name in _HEAT:
            x = x * (1.0 + rng.normal(0.0, 0.01, x.size))
        elif name in _METER:
            x = x * (1.0 + rng.normal(0.0, 0.005, x.size))
        res = c["resolution"]
        out[:, i] = np.round(x / res) * res
    return out


def _decimals(res: float) -> int:
    return max(0, -int(np.floor(np.log10(res) + 1e-9)))


def write_csv(path, t_s: np.ndarray, data: np.ndarray) -> None:
    fmts = ["%.3f"] + [f"%.{_decimals(c['resolution'])}f" for c in CHANNELS]
    header = ",".join(["t_s"] + NAMES)
    table = np.column_stack([t_s, data])
    # -0.0 -> 0.0 for tidy files
    table = np.where(table == 0.0, 0.0, table)
    np.savetxt(path, table, delimiter=",", header=header, comments="", fmt=fmts)


def _signal_name(c) -> str:
    return re.split(r"\s*\(", c["signal"].strip().strip('"'))[0].strip()


def columns_toml(start: str, file: str = "recording.csv") -> str:
    """The columns file a user writes: datasheet heights and ports, units as logged."""
    Hb, Hd = DATASHEET["buffer_height_m"], DATASHEET["dhw_height_m"]
    lines = ["[recording]", f'start = "{start}"', f'file = "{file}"', 'time = "t_s"', "",
             "[ports]",
             f"storage = {{ top = {DATASHEET['buffer_port_top_m'] / Hb:.4f}, "
             f"bottom = {DATASHEET['buffer_port_bottom_m'] / Hb:.4f} }}", "", "[columns]"]
    for c in CHANNELS:
        name, sig, unit = c["channel"], _signal_name(c), c["unit"]
        if name == "CB_MOD_SET":
            lines.append(f'"{name}" = {{ signal = "{sig}", range = [0, 100, 0, 10] }}')
        elif name.startswith("BT_T"):
            h = DATASHEET["buffer_sensor_heights_m"][int(name[4:]) - 1] / Hb
            lines.append(f'"{name}" = {{ signal = "{sig}", unit = "{unit}", height = {h:.4f} }}')
        elif name.startswith("WWS_T"):
            h = DATASHEET["dhw_sensor_heights_m"][int(name[5:]) - 1] / Hd
            lines.append(f'"{name}" = {{ signal = "{sig}", unit = "{unit}", height = {h:.4f} }}')
        else:
            lines.append(f'"{name}" = {{ signal = "{sig}", unit = "{unit}" }}')
    return "\n".join(lines) + "\n"
