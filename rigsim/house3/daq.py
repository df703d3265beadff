"""The house-3 DAQ: channel list (docs/lab/house3-channels.csv, copied to rigsim/data/), noise,
resolution, CSV and the columns file a user writes.

As house 2's (rigsim/house2/daq.py, both on rigsim/daq.py's kernels): instantaneous samples once a
minute (+-0.5 s) from the core's nearest 1 s step; temperatures 0.05 K RMS (the ground probe too),
flow and heat meters 1 % of reading, the electricity meter, PV and household meters and the
controller's COP 0.5 %; commands, set-points and the weather station's irradiances exact; then
rounded to the channel's resolution.
"""
from __future__ import annotations

import numpy as np

from .. import daq as _daq
from .. import tables
from . import layout
from .model import DATASHEET


def channel_list() -> list[dict]:
    """House 3's DAQ channel list (house3-channels.csv), t_s first."""
    return tables.channel_list("house3-channels.csv")


CHANNELS = _daq.channels_of(channel_list())
NAMES = [c["channel"] for c in CHANNELS]
if NAMES != layout.CH_NAMES:
    raise RuntimeError("rigsim.house3.layout.CH_NAMES differs from house3-channels.csv")

# commands and set-points (the PLC's) and the irradiances as logged; meters with their noise
_EXACT = {c["channel"] for c in CHANNELS if c["position"] == "PLC"} | {
    "DirectRadiation_W_per_m2", "DiffuseRadiation_W_per_m2"}
_ONE_PCT = {c["channel"] for c in CHANNELS
            if c["unit"] == "l/min" and c["channel"] not in _EXACT} | {"HP_P_heat_Tot", "ST_P_heat"}
_HALF_PCT = {"HP_P_elec_is", "HP_COP", "PV_P_gen", "P_elConsumption_kW"}


def apply_daq(rec: np.ndarray, seed: int) -> np.ndarray:
    rng = np.random.default_rng([int(seed), 99, 3])
    return _daq.add_noise(rec, rng, CHANNELS, _EXACT, _ONE_PCT, _HALF_PCT)


def write_csv(path, t_s: np.ndarray, data: np.ndarray) -> None:
    _daq.write_csv(path, t_s, data, CHANNELS)


def columns_toml(start: str, file: str = "recording.csv") -> str:
    """The columns file a user writes: datasheet sensor heights relative to the 1.84 m water
    height (as the channel list gives them), units as logged, scale -1 on the electricity meter
    (logged positive when consumed). Both valve commands are logged 1 = UPPER, as the twin's
    signals (no range). No [ports]: the tank has more port pairs than the diagnosis's one upper
    and one lower connection; their datasheet heights are the house file's."""
    H = DATASHEET["tank_height_m"]

    def entry(c):
        name, unit = c["channel"], c["unit"]
        if name == "HP_P_elec_is":
            return f'unit = "{unit}", scale = -1'
        if name.startswith("TS_S_TM_BT_"):
            h = DATASHEET["sensor_heights_m"][int(name.rsplit("_", 1)[1]) - 1] / H
            return f'unit = "{unit}", height = {h:.4f}'
        return None

    return _daq.columns_file(start, file, CHANNELS, entry)
