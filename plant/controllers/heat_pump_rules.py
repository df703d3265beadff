"""The built-in rules of the heat-pump houses SF2 and SF3 (reference §12.3, §12.4): the heat
pump's three-way valve, its on/off command and back-up heater, and (where linked) the boiler of
SF2 and the solar three-way valve of SF3.

Edge-triggered hysteresis switches, as upstream: each actuator switches on when its on-condition
holds, off when its off-condition holds (the off-condition wins when both hold), and keeps its
state in between. One scan evaluates them in this order, each seeing the new state of those
before it (valve -> heat pump -> back-up heater; boiler and solar valve are independent):

  valve (1 = upper)  upper when T_valve_on < valve_upper_below (T_BT8 < 55 degC),
                     lower when T_valve_off > valve_lower_above (T_BT7 > 60 degC)
  heat pump          on when the valve is upper or T_hp_on < hp_on_below (T_BT3 < 43 degC),
                     off when the valve is lower and T_hp_off > hp_off_above (T_BT2 > 45 degC)
  back-up heater     on when the heat pump is on and (T_valve_on < aux_upper_below (T_BT8 < 50)
                     or T_hp_on < aux_lower_below (T_BT3 < 35)); off when the heat pump is off or
                     ((T_valve_off > aux_upper_above (T_BT7 > 55) or the valve is lower) and
                     T_hp_off > aux_lower_above (T_BT2 > 40)); its request is aux_level (1 = 6 kW)
  boiler (SF2)       on when T_boiler_top < boiler_top_below (T_BT10 < 55) or
                     T_boiler < boiler_on_below (T_BT5 < 35 = the 40 degC floor-heating request
                     - 5 K); off when T_boiler > boiler_off_above (T_BT5 > 60)
  solar valve (SF3)  upper coil when T_collector - T_solar > solar_upper_above (T_BT9 + 3 K),
                     lower coil when it is below solar_lower_below (2 K)

Which storage sensors the roles read is the house file's choice (inputs). The boiler and the
solar valve are optional: they are evaluated when their outputs are linked, and then their
inputs must be linked too. Outputs: valve_upper (0/1), hp_on (0/1), hp_y (modulation when on),
aux (0 ... 1 heater request), boiler_U (0 or boiler_demand V), solar_upper (0/1); the states are
also the controller's own output signals (`<name>.valve_upper` ...), so a valve that is not
connected in a house still shows what the rules ask for. An actuator driven from outside
(gateway) is not written.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from ..component import REQUIRED, Kind as ComponentKind, indices, link, param
from .rule_based import quantize

STATES = ("valve_upper", "hp_on", "aux_on", "boiler_on", "solar_upper", "since_scan")


@dataclass(frozen=True)
class Params:
    valve_upper_below: float = param(55.0, "degC", "valve to the upper ports when T_valve_on is below", 10, 95)
    valve_lower_above: float = param(60.0, "degC", "valve back to the lower ports when T_valve_off is above", 10, 95)
    hp_on_below: float = param(43.0, "degC", "heat pump on when T_hp_on is below (or the valve is upper)", 10, 95)
    hp_off_above: float = param(45.0, "degC", "heat pump off when T_hp_off is above and the valve is lower", 10, 95)
    aux_upper_below: float = param(50.0, "degC", "back-up heater on when T_valve_on is below", 10, 95)
    aux_lower_below: float = param(35.0, "degC", "back-up heater on when T_hp_on is below", 10, 95)
    aux_upper_above: float = param(55.0, "degC", "back-up heater may stop when T_valve_off is above", 10, 95)
    aux_lower_above: float = param(40.0, "degC", "back-up heater stops when T_hp_off is above (and upper done)", 10, 95)
    aux_level: float = param(1.0, "1", "back-up heater request when on (1: all three 2 kW stages)", 0.0, 1.0)
    hp_modulation: float = param(1.0, "1", "heat pump modulation when on", 0.2, 1.0)
    boiler_top_below: float = param(55.0, "degC", "boiler on when T_boiler_top is below", 10, 95)
    boiler_on_below: float = param(35.0, "degC", "boiler on when T_boiler is below (supply request - 5 K)", 10, 95)
    boiler_off_above: float = param(60.0, "degC", "boiler off when T_boiler is above", 10, 95)
    boiler_demand: float = param(10.0, "V", "boiler 0-10 V demand when on", 2.1, 10.0)
    solar_upper_above: float = param(3.0, "K", "solar valve to the upper coil when T_collector - T_solar is above", 0, 50)
    solar_lower_below: float = param(2.0, "K", "solar valve to the lower coil when T_collector - T_solar is below", -50, 50)
    period: float = param(1.0, "s", "scan period: the rules are evaluated this often", 0.0, 3600.0)
    sensor_resolution: float = param(0.0, "K", "sensor resolution the rules see (0: exact)", 0.0, 5.0)


# positions in the packed parameters and the state vector, from the declarations
P = indices(Params)
X = indices(STATES)


def initial_state(params: Params) -> np.ndarray:
    x = np.zeros(len(STATES), dtype=np.float64)
    x[X.since_scan] = 1e300  # the first step scans
    return x


@njit(cache=True)
def step(dt, x, p, T_valve_on, T_valve_off, T_hp_on, T_hp_off, T_boiler_top, T_boiler, T_collector, T_solar):
    """Scan when a period has passed; returns (valve_upper, hp_on, hp_y, aux, boiler_U, solar_upper)."""
    x[X.since_scan] += dt
    if x[X.since_scan] + 1e-9 >= p[P.period]:
        x[X.since_scan] = 0.0
        r = p[P.sensor_resolution]
        T8, T7, T3, T2 = quantize(T_valve_on, r), quantize(T_valve_off, r), quantize(T_hp_on, r), quantize(T_hp_off, r)
        if T7 > p[P.valve_lower_above]:
            x[X.valve_upper] = 0.0
        elif T8 < p[P.valve_upper_below]:
            x[X.valve_upper] = 1.0
        upper = x[X.valve_upper] > 0.5
        if not upper and T2 > p[P.hp_off_above]:
            x[X.hp_on] = 0.0
        elif upper or T3 < p[P.hp_on_below]:
            x[X.hp_on] = 1.0
        hp = x[X.hp_on] > 0.5
        if not hp or ((T7 > p[P.aux_upper_above] or not upper) and T2 > p[P.aux_lower_above]):
            x[X.aux_on] = 0.0
        elif T8 < p[P.aux_upper_below] or T3 < p[P.aux_lower_below]:
            x[X.aux_on] = 1.0
        T10, T5 = quantize(T_boiler_top, r), quantize(T_boiler, r)
        if T5 > p[P.boiler_off_above]:
            x[X.boiler_on] = 0.0
        elif T10 < p[P.boiler_top_below] or T5 < p[P.boiler_on_below]:
            x[X.boiler_on] = 1.0
        dT = quantize(T_collector, r) - quantize(T_solar, r)
        if dT < p[P.solar_lower_below]:
            x[X.solar_upper] = 0.0
        elif dT > p[P.solar_upper_above]:
            x[X.solar_upper] = 1.0
    return (x[X.valve_upper], x[X.hp_on], x[X.hp_on] * p[P.hp_modulation], x[X.aux_on] * p[P.aux_level],
            x[X.boiler_on] * p[P.boiler_demand], x[X.solar_upper])


class Kind(ComponentKind):
    """SF2/SF3 rules: storage sensors in, heat pump valve, heat pump, back-up heater, boiler
    and solar valve out."""

    name = "heat_pump_rules"
    Params = Params
    role = "controller"
    INPUTS = ("T_valve_on", "T_valve_off", "T_hp_on", "T_hp_off", "T_boiler_top", "T_boiler",
              "T_collector", "T_solar")
    OUTPUTS = ("valve_upper", "hp_on", "hp_y", "aux", "boiler_U", "solar_upper")
    OPTIONAL = {"boiler_U": ("T_boiler_top", "T_boiler"), "solar_upper": ("T_collector", "T_solar")}
    LINKS = {"inputs": link(REQUIRED, "measurements: T_valve_on, T_valve_off, T_hp_on, T_hp_off (and T_boiler_top, "
                                      "T_boiler for boiler_U; T_collector, T_solar for solar_upper) = signal names",
                            type=dict),
             "outputs": link(REQUIRED, "commands: valve_upper, hp_on, hp_y, aux, boiler_U, solar_upper = input signal "
                                        "names", type=dict)}

    def initial_state(self, inst):
        return initial_state(inst.params)

    def emit(self, c, inst):
        from . import check_keys, emit_step, read

        check_keys(c, inst, self.INPUTS, self.OUTPUTS)
        linked = inst.options["outputs"]
        args = []
        for key in self.INPUTS:
            needed_by = [o for o, keys in self.OPTIONAL.items() if key in keys]
            if needed_by and not any(o in linked for o in needed_by) and key not in inst.options["inputs"]:
                args.append("math.nan")  # an optional part nobody listens to: it never switches
            else:
                args.append(read(c, inst, key))
        x = emit_step(c, self, inst, __name__, args)
        sig = lambda local, desc: c.signal(inst, local, "1", "output", desc)  # noqa: E731
        c.emit("signals",
               f"{sig('valve_upper', 'heat pump three-way valve the rules ask for (1 = upper ports)')} = {x}[{X.valve_upper}]",
               f"{sig('hp_on', 'heat pump command of the rules (0/1)')} = {x}[{X.hp_on}]",
               f"{sig('aux_on', 'back-up heater command of the rules (0/1)')} = {x}[{X.aux_on}]",
               f"{sig('boiler_on', 'boiler command of the rules (0/1)')} = {x}[{X.boiler_on}]",
               f"{sig('solar_upper', 'solar three-way valve the rules ask for (1 = upper coil)')} = {x}[{X.solar_upper}]")
