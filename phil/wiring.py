"""Wiring: which simulated signals make a bench's set-points, and where its measurements go.

One entry per bench kind (the map's id): `setpoints(house)` gives the §13.2 set-points in the
map's device units from the PHIL house (plant/houses/house1_phil.toml), `feed(house, values)`
sets the house's live measured boundary from judged measurements, `pairs` names each set-point
with the measurement that shows whether the bench followed it, and `heat` the measurement that
is the bench's heat meter [kWh].
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

L_PER_MIN = 60.0      # kg/s of water -> l/min (plant/units.py: 1 l = 1 kg)


@dataclass(frozen=True)
class Wiring:
    setpoints: Callable[[Any], dict[str, float]]
    feed: Callable[[Any, dict[str, float]], None]
    pairs: tuple[tuple[str, str], ...]
    heat: str
    #: simulated signals recorded beside the exchange
    signals: tuple[str, ...]
    #: the measured flow [l/min]: temperature pairs count towards the follow error only while
    #: it is above FLOWING (a temperature of standing water says nothing about following)
    flow: str = ""


FLOWING = 0.5


def _space_heating_setpoints(house: Any) -> dict[str, float]:
    return {"STM_HCVLaM_Set_degC": house.get("mixer.T_sup_set"),
            "SFW_HCRLbM_Set_l_per_min": house.get("mixer.m_flow_set") * L_PER_MIN,
            "STM_HCRL_Set_degC": house.get("mixer.T_ret")}


def _space_heating_feed(house: Any, values: dict[str, float]) -> None:
    house.set("mixer.T_sup", values["STM_HCVLaM_degC"])
    house.set("mixer.m_flow", values["SFW_HCRLbM_l_per_min"] / L_PER_MIN)


WIRINGS = {
    "space_heating": Wiring(
        setpoints=_space_heating_setpoints, feed=_space_heating_feed,
        pairs=(("STM_HCVLaM_Set_degC", "STM_HCVLaM_degC"),
               ("SFW_HCRLbM_Set_l_per_min", "SFW_HCRLbM_l_per_min"),
               ("STM_HCRL_Set_degC", "STM_HCRL_degC")),
        heat="E_HC_kWh", flow="SFW_HCRLbM_l_per_min",
        signals=("zone.T_room", "zone.T_set", "radiator.Q_flow", "mixer.Q_flow", "mixer.T_ret",
                 "mixer.T_sup_set", "mixer.m_flow_set", "weather.T_air")),
}
