"""The house-2 DAQ: channel list (docs/lab/house2-channels.csv, copied to rigsim/data/), noise,
resolution, CSV and the columns file a user writes.

Samples are instantaneous values at the logger's time stamps (one a minute, +-0.5 s, from the
core's nearest 1 s step). Noise: temperatures 0.05 K RMS, flow and heat meters 1 % of reading,
electricity and gas meters and the controller's COP 0.5 %; commands, set-points and the weather
station's irradiances as logged (exact); then rounded to the channel's resolution.
"""
from __future__ import annotations

import numpy as np

from .. import daq as _daq
from .. import tables
from . import layout
from .model import DATASHEET


def channel_list() -> list[dict]:
    """House 2's DAQ channel list (house2-channels.csv), t_s first."""
    return tables.channel_list("house2-channels.csv")


CHANNELS = _daq.channels_of(channel_list())
NAMES = [c["channel"] for c in CHANNELS]
if NAMES != layout.CH_NAMES:
    raise RuntimeError("rigsim.house2.layout.CH_NAMES differs from house2-channels.csv")

_EXACT = {"ASHP_ASHP_on", "ASHP_Modulation_set", "ASHP_AuxModulation_set", "ASHP_A_V3_TL",
          "EB_EB_power_kW_set", "ST_PUMP_CMD", "ST_S_FW_ST_VL_set", "STM_HCVLaM_Set_degC",
          "SFW_HCRLbM_Set_l_per_min", "DirectRadiation_W_per_m2", "DiffuseRadiation_W_per_m2"}
_ONE_PCT = {"HP_S_FW_HC", "CB_S_FW", "ST_S_FW_ST_VL", "SFW_HCRLbM_l_per_min",
            "SFW_HCVLbM_l_per_min", "HS_S_FW_HW", "HP_P_heat_Tot", "CB_P_heat", "ST_P_heat"}
_HALF_PCT = {"HP_P_elec_is", "HP_COP", "CB_P_gas", "PV_P_gen", "P_elConsumption_kW"}


def apply_daq(rec: np.ndarray, seed: int) -> np.ndarray:
    rng = np.random.default_rng([int(seed), 99, 2])
    return _daq.add_noise(rec, rng, CHANNELS, _EXACT, _ONE_PCT, _HALF_PCT)


def write_csv(path, t_s: np.ndarray, data: np.ndarray) -> None:
    _daq.write_csv(path, t_s, data, CHANNELS)


def columns_toml(start: str, file: str = "recording.csv") -> str:
    """The columns file a user writes: datasheet sensor heights (relative to the 1.60 m water
    height of the channel list), units as logged, the channel list's ranges and scales. No
    [ports]: the diagnosis's [ports] gives one upper and one lower connection per tank, and this
    tank has five pairs (heat pump upper and lower, boiler, heating, draw); their datasheet
    heights are the house file's."""
    H = DATASHEET["tank_height_m"]

    def entry(c):
        name, unit = c["channel"], c["unit"]
        if name == "ASHP_A_V3_TL":
            return "range = [0, 1, 1, 0]"
        if name == "EB_EB_power_kW_set":
            return "range = [2, 20, 2, 10]"
        if name == "HP_P_elec_is":
            return f'unit = "{unit}", scale = -1'
        if name.startswith("TS_S_TM_BT_"):
            h = DATASHEET["sensor_heights_m"][int(name.rsplit("_", 1)[1]) - 1] / H
            return f'unit = "{unit}", height = {h:.4f}'
        return None

    return _daq.columns_file(start, file, CHANNELS, entry)
