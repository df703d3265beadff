"""Wiring: which simulated signals make a bench's set-points, and where its measurements go.

One entry per bench kind (the map's id): `setpoints(house)` gives the §13.2 set-points in the
map's device units from the PHIL house (plant/houses/house<N>_phil.toml),
`feed(house, values)` sets the house's live measured boundary from judged measurements, `pairs`
names each set-point with the measurement that shows whether the bench followed it, `heat` the
measurement that is the bench's heat meter [kWh] and `model_heat` the simulated heat flow [W] it
is compared with, `clock` the bench PLC's clock [s] read with the meter, `ideal(house)`
(optional) what a perfect bench would measure, fed during the warm-up, `boundary` (optional) the
simulated side the bench needs beside the house. `used(measurements)` names every signal of the
house the wiring reads or sets: a house without them is not wired for the bench (phil/loop.py
refuses it before the run, naming what is missing: house 4 has no solar collector).

  space_heating  supply and flow the thermostat requests, the radiator return -> measured supply
                 and flow feed the radiators (mixer.T_sup, mixer.m_flow)
  tap_water      cumulative demand energy dhw.E_set -> measured cold water feeds the demand
  solar          collector outlet, heat and temperature -> measured return and flow feed the
                 collector (solar.T_ret, solar.m_flow)
  brine          (SF3) the ground collector's brine outlet and ground temperature -> measured
                 brine from the lab's heat pump and its flow feed the collector (ground.T_ret,
                 ground.m_flow; plant/houses/house3_phil.toml,
                 plant/components/phil_boundary.py)
  grid           (a district house) the simulated grid's supply temperature and differential
                 pressure at the house's node (the district's other houses drawing too unless
                 --others none) -> measured grid flow and return of the lab's substation are the
                 house's draw on the grid (grid.m_flow, grid.T_return; phil/grid.py, which
                 `boundary` adds to the house)
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
    #: simulated signals recorded beside the exchange (those the house has: radiator or floor)
    signals: tuple[str, ...]
    #: the simulated heat flow [W] whose integral the bench's meter is compared with
    model_heat: str = ""
    #: the bench's clock [s], read with its meter: the span the meter counted on the bench's clock
    clock: str = "T_PLC_s"
    #: the measured flow [l/min]: temperature pairs count towards the follow error only while
    #: it is above FLOWING (a temperature of standing water says nothing about following)
    flow: str = ""
    ideal: Callable[[Any], None] | None = None
    #: cumulative set-points (an energy to draw): sent as the increase since the first exchange
    cumulative: tuple[str, ...] = ()
    #: what the building asked and got, for the shortfall report: (flow requested, flow measured
    #: [l/min], heat requested, heat delivered [W])
    demand: Callable[[Any], tuple[float, float, float, float]] | None = None
    #: the simulated side the bench needs beside the house (the district grid): (house, options)
    #: -> the house and it as one plant (phil/grid.py HouseOnGrid)
    boundary: Callable[[Any, Any], Any] | None = None

    def used(self, measurements: tuple[str, ...]) -> set[str]:
        """The house signals this wiring reads or sets (found by running it on a probe)."""
        probe = _Probe()
        self.setpoints(probe)
        self.feed(probe, dict.fromkeys(measurements, 1.0))
        for call in (self.ideal, self.demand):
            if call:
                call(probe)
        return probe.names | ({self.model_heat} if self.model_heat else set())


class _Probe:
    """A stand-in house that notes the names asked for."""

    def __init__(self) -> None:
        self.names: set[str] = set()

    def get(self, name: str) -> float:
        self.names.add(name)
        return 1.0

    def set(self, name: str, value: float) -> None:
        self.names.add(name)


FLOWING = 0.5


def _space_heating_setpoints(house: Any) -> dict[str, float]:
    return {"STM_HCVLaM_Set_degC": house.get("mixer.T_sup_set"),
            "SFW_HCRLbM_Set_l_per_min": house.get("mixer.m_flow_set") * L_PER_MIN,
            "STM_HCRL_Set_degC": house.get("mixer.T_ret")}


def _space_heating_feed(house: Any, values: dict[str, float]) -> None:
    house.set("mixer.T_sup", values["STM_HCVLaM_degC"])
    house.set("mixer.m_flow", values["SFW_HCRLbM_l_per_min"] / L_PER_MIN)


CP = 4180.0


def _space_heating_demand(house: Any) -> tuple[float, float, float, float]:
    m_set, T_ret = house.get("mixer.m_flow_set"), house.get("mixer.T_ret")
    return (m_set * L_PER_MIN, house.get("mixer.m_flow") * L_PER_MIN,
            m_set * CP * max(house.get("mixer.T_sup_set") - T_ret, 0.0), house.get("mixer.Q_flow"))


def _space_heating_ideal(house: Any) -> None:
    house.set("mixer.T_sup", house.get("mixer.T_sup_set"))
    house.set("mixer.m_flow", house.get("mixer.m_flow_set"))


J_PER_KWH = 3.6e6


def _tap_water_setpoints(house: Any) -> dict[str, float]:
    return {"E_DHW_Set_kWh": house.get("dhw.E_set") / J_PER_KWH}


def _tap_water_feed(house: Any, values: dict[str, float]) -> None:
    house.set("dhw.T_cold", values["STM_CCVL_degC"])


def _solar_setpoints(house: Any) -> dict[str, float]:
    return {"STM_STVL_Set_degC": house.get("solar.T_sup"),
            "PEH_ST_Set_kW": house.get("solar.Q_flow") / 1e3,
            "T_collector_degC": house.get("solar.T_collector")}


def _solar_feed(house: Any, values: dict[str, float]) -> None:
    house.set("solar.T_ret", values["STM_STRL_degC"])
    house.set("solar.m_flow", values["SFW_STVL_l_per_min"] / L_PER_MIN)


def _brine_setpoints(house: Any) -> dict[str, float]:
    return {"STM_BCRLaM_Set_degC": house.get("ground.T_sup"), "T_ground_degC": house.get("ground.T_ground")}


def _brine_feed(house: Any, values: dict[str, float]) -> None:
    house.set("ground.T_ret", values["STM_BCVL_degC"])
    house.set("ground.m_flow", values["SFW_BC_l_per_min"] / L_PER_MIN)


PA_PER_BAR = 1.0e5


def _grid_setpoints(house: Any) -> dict[str, float]:
    return {"STM_TGVL_Set_degC": house.get("grid.T_sup"), "SDP_TG_Set_bar": house.get("grid.dp") / PA_PER_BAR}


def _grid_feed(house: Any, values: dict[str, float]) -> None:
    house.set("grid.T_return", values["STM_TGRL_degC"])
    house.set("grid.m_flow", values["SFW_TG_l_per_min"] / L_PER_MIN)


def _grid_boundary(house: Any, options: Any) -> Any:
    from phil.grid import GridSide, HouseOnGrid

    # the others on the PHIL house's profiles: its start and type day
    typeday = {"profiles.typeday": options.typeday} if options.typeday else None
    return HouseOnGrid(house, GridSide(options.district, house.decl.name, others=options.others,
                                       start=getattr(house, "start", None), overrides=typeday))


WIRINGS = {
    "space_heating": Wiring(
        setpoints=_space_heating_setpoints, feed=_space_heating_feed,
        pairs=(("STM_HCVLaM_Set_degC", "STM_HCVLaM_degC"),
               ("SFW_HCRLbM_Set_l_per_min", "SFW_HCRLbM_l_per_min"),
               ("STM_HCRL_Set_degC", "STM_HCRL_degC")),
        heat="E_HC_kWh", model_heat="mixer.Q_flow", flow="SFW_HCRLbM_l_per_min",
        ideal=_space_heating_ideal, demand=_space_heating_demand,
        signals=("zone.T_room", "zone.T_set", "radiator.Q_flow", "floor.Q_flow", "mixer.Q_flow", "mixer.T_ret",
                 "mixer.T_sup_set", "mixer.m_flow_set", "weather.T_air")),
    "tap_water": Wiring(
        setpoints=_tap_water_setpoints, feed=_tap_water_feed,
        pairs=(("E_DHW_Set_kWh", "E_DHW_kWh"),),
        heat="E_DHW_kWh", model_heat="dhw.Q_flow", cumulative=("E_DHW_Set_kWh",),
        signals=("dhw.m_flow_demand", "dhw.Q_flow", "dhw.E_set", "dhw.T_cold")),
    "solar": Wiring(
        setpoints=_solar_setpoints, feed=_solar_feed,
        pairs=(("STM_STVL_Set_degC", "STM_STVL_degC"), ("PEH_ST_Set_kW", "PEH_ST_kW")),
        heat="E_ST_kWh", model_heat="solar.Q_flow", flow="SFW_STVL_l_per_min",
        signals=("solar.T_collector", "solar.T_sup", "solar.Q_flow", "solar.T_ret", "solar.m_flow",
                 "solar.G_plane", "weather.T_air")),
    "brine": Wiring(
        setpoints=_brine_setpoints, feed=_brine_feed,
        pairs=(("STM_BCRLaM_Set_degC", "STM_BCRLaM_degC"),),
        heat="E_BC_kWh", model_heat="ground.Q_flow", flow="SFW_BC_l_per_min",
        signals=("ground.T_sup", "ground.T_ret", "ground.m_flow", "ground.Q_flow", "ground.T_ground",
                 "ground.T_undisturbed", "weather.T_air")),
    "grid": Wiring(
        setpoints=_grid_setpoints, feed=_grid_feed,
        pairs=(("STM_TGVL_Set_degC", "STM_TGVL_degC"), ("SDP_TG_Set_bar", "SDP_TG_bar")),
        heat="E_TG_kWh", model_heat="grid.Q_flow", flow="SFW_TG_l_per_min", boundary=_grid_boundary,
        signals=("grid.T_sup", "grid.T_ret", "grid.dp", "grid.m_flow", "grid.T_return", "grid.Q_flow",
                 "grid.Q_plant", "grid.m_plant")),
}
