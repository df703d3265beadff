"""The registry of component and connection kinds a house file may name (`kind = "..."`)."""
from __future__ import annotations

from . import boundary
from .components import boiler, chp, dhw, heat_pump, mixing_station, pipe, radiator, storage_kind, zone
from .connections import branch, coil, coupling_point, measured
from .controllers import room_thermostat, rule_based
from .controllers import heat_pump_rules, soc_rules, substation_rules
from .fmu import storage_kind as storage_fmu
from .components import pv, sensor, solar_collector
from .components import floor_heating, ground_collector
from .components import electric_heater, substation
from .components import phil_boundary

KINDS = {k.name: k for k in (
    boundary.Kind(), chp.Kind(), boiler.Kind(), heat_pump.AirKind(), storage_kind.Kind(), zone.Kind(), radiator.Kind(),
    mixing_station.Kind(), pipe.Kind(), dhw.Kind(), dhw.CoilKind(), coil.Kind(), coupling_point.Kind(), branch.Kind(),
    measured.ConsumerKind(), measured.DrawKind(), measured.GeneratorKind(), measured.CircuitKind(),
    measured.ZoneKind(), measured.SupplyKind(),
    rule_based.Kind(), room_thermostat.Kind(), storage_fmu.Kind(),
    heat_pump_rules.Kind(), soc_rules.Kind(), substation_rules.Kind(),
    pv.Kind(), solar_collector.Kind(), sensor.Kind(),
    heat_pump.BrineKind(), ground_collector.Kind(), floor_heating.Kind(),
    electric_heater.Kind(), substation.Kind(),
    phil_boundary.DemandKind(), phil_boundary.SolarKind(), phil_boundary.GroundKind(),
)}
