"""The §13.2 outputs of a PHIL house that no emulator bench takes: what the lab's PHIL export
gives besides the benches' set-points (room and outdoor temperature, irradiance, the household's
electricity, SF2's and SF3's PV power, SF2's humidity), recorded every step under their §13.2
names and units (columns `lab.<name>` of signals.csv).

Reference §13.2: SF1's outputs are the benches' set-points plus P_elConsumption_kW,
T_roomIs/T_roofIs/T_cellarIs_degC, T_ambient_degC, T_collector_degC, Direct/DiffuseRadiation_W_per_m2
and Modeltime_s; SF2 adds PV_P_gen and RelativHumidityAir_percent; SF3 adds PV_P_gen (and the
brine's, which the brine bench takes); SF4 and MF5 have only the heating, DHW and weather signals.
Not here: T_roofIs and T_cellarIs (the twin's building is one zone with one envelope mass, no roof
or cellar node: as the SiL lists say, plant/houses/house1_sil.toml), T_collector_degC (the solar
bench takes it), Modeltime_s (the recording's time column).

The humidity is the weather file's relative humidity (column 8 of profiles/weather and
profiles/typedays, reference §11.1), which the house's weather boundary does not carry (it has
T_air, E_dir and E_dif): read here at the house's local time, step-wise per 15 min and shifted
from UTC to CET as the loaders shift the other columns (profiles/loaders.py).
"""
from __future__ import annotations

from functools import cache
from typing import Any, Callable

import numpy as np

from plant import boundary
from profiles import loaders

SHIFT = 4          # 15-min samples: UTC -> CET, as profiles/loaders.py
HUMIDITY_COLUMN = 7

#: §13.2 name -> (house signal, factor to the export's unit)
COMMON = {"P_elConsumption_kW": ("household.P_el", 1e-3), "T_roomIs_degC": ("zone.T_room", 1.0),
          "T_ambient_degC": ("weather.T_air", 1.0), "DirectRadiation_W_per_m2": ("weather.E_dir", 1.0),
          "DiffuseRadiation_W_per_m2": ("weather.E_dif", 1.0)}
PV = {"PV_P_gen": ("pv.P_el", 1e-3)}
#: per house (the PHIL house's [house] name): its §13.2 outputs besides the benches'
EXPORTS = {"house1": COMMON, "house2": {**COMMON, **PV, "RelativHumidityAir_percent": ("humidity", 1.0)},
           "house3": {**COMMON, **PV}, "house4": COMMON, "house5": COMMON}


@cache
def _humidity(typeday: int) -> np.ndarray:
    if typeday:
        table = loaders.read_tables(loaders.HERE / "typedays" / "SF1_Typeday.txt")["Weather"][:-1]
    else:
        table = loaders.read_tables(loaders.HERE / "weather" / "Weather_2021_Munich_15min.txt")["Weather"][:35040]
    return np.roll(table[:, HUMIDITY_COLUMN].copy(), SHIFT)


def humidity(house: Any) -> float:
    """Relative humidity [%] of the weather file at the house's local time."""
    values = _humidity(int(house.decl.typeday))
    tau = boundary.tau0(house.start, house.decl.typeday) + house.t
    return float(loaders.sample(values, 900.0, False, tau))


def exports(house: Any, names: set[str]) -> dict[str, Callable[[Any], float]]:
    """The house's §13.2 outputs it has the signals for: column -> value(house)."""
    out: dict[str, Callable[[Any], float]] = {}
    for name, (signal, factor) in EXPORTS.get(house.decl.name, COMMON).items():
        if signal == "humidity":
            out[f"lab.{name}"] = humidity
        elif signal in names:
            out[f"lab.{name}"] = lambda h, s=signal, f=factor: h.get(s) * f
    return out
