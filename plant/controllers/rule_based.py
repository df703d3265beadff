"""The case study's rule-based supervisory controller (edge-triggered hysteresis switches).

Published rule set: CHP on when the heating-storage top < 65 degC, boiler on when the top
< 60 degC, both off when the storage bottom > 70 degC; DHW charging on when the DHW top < 50 degC
and it is below the heating-storage top, off when the DHW top > 65 degC (and also when the
heating-storage top has fallen below the DHW top, so charging never cools the DHW tank).
"Top" and "bottom" are whichever signals the house file links as inputs T_top, T_bottom and
T_dhw_top (house 1: storage sensors 10 and 1 of TS_S_TM_BT_1..10, DHW sensor 10); its outputs are
linked to the inputs they drive (chp_on, chp_y, boiler_U, dhw_on). Each actuator keeps its
state between its on and off conditions. Outputs: CHP on + modulation 1, boiler 10 V demand,
DHW charging pump on. An actuator driven from outside (gateway) is not written by this controller.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from ..component import REQUIRED, Kind as ComponentKind, indices, link, param

STATES = ("chp_on", "boiler_on", "dhw_on", "since_scan")


@dataclass(frozen=True)
class Params:
    chp_on_below: float = param(65.0, "degC", "CHP starts when the storage top is below", 20, 95)
    boiler_on_below: float = param(60.0, "degC", "boiler starts when the storage top is below", 20, 95)
    off_above: float = param(70.0, "degC", "CHP and boiler stop when the storage bottom is above", 20, 95)
    dhw_on_below: float = param(50.0, "degC", "DHW charging starts when the DHW top is below", 20, 95)
    dhw_off_above: float = param(65.0, "degC", "DHW charging stops when the DHW top is above", 20, 95)
    chp_modulation: float = param(1.0, "1", "CHP modulation when on", 0.55, 1.0)
    boiler_demand: float = param(10.0, "V", "boiler 0-10 V demand when on", 2.1, 10.0)
    period: float = param(1.0, "s", "scan period: the rules are evaluated this often (a PLC's cycle)", 0.0, 3600.0)
    sensor_resolution: float = param(0.0, "K", "sensor resolution the rules see (0: exact; 0.1: as "
                                     "the 0.1 degC registers of the device maps)", 0.0, 5.0)


# positions in the packed parameters and the state vector, from the declarations
P = indices(Params)
X = indices(STATES)


@njit(cache=True)
def quantize(T, resolution):
    """T rounded to the sensor resolution, half away from zero (as the device-map codec)."""
    if resolution <= 0.0:
        return T
    q = T / resolution
    return (np.floor(q + 0.5) if q >= 0.0 else -np.floor(-q + 0.5)) * resolution


def initial_state(params: Params) -> np.ndarray:
    x = np.zeros(4, dtype=np.float64)
    x[X.since_scan] = 1e300  # the first step scans
    return x


@njit(cache=True)
def step(dt, x, p, T_top, T_bottom, T_dhw_top):
    """Scan when a period has passed; returns (chp_on, chp_y_set, boiler_U_set, dhw_pump_on)."""
    x[X.since_scan] += dt
    if x[X.since_scan] + 1e-9 < p[P.period]:
        return x[X.chp_on], x[X.chp_on] * p[P.chp_modulation], x[X.boiler_on] * p[P.boiler_demand], x[X.dhw_on]
    x[X.since_scan] = 0.0
    res = p[P.sensor_resolution]
    T_top, T_bottom, T_dhw_top = quantize(T_top, res), quantize(T_bottom, res), quantize(T_dhw_top, res)
    if T_bottom > p[P.off_above]:
        x[X.chp_on] = 0.0
        x[X.boiler_on] = 0.0
    else:
        if T_top < p[P.chp_on_below]:
            x[X.chp_on] = 1.0
        if T_top < p[P.boiler_on_below]:
            x[X.boiler_on] = 1.0
    if T_dhw_top > p[P.dhw_off_above] or T_top < T_dhw_top:
        x[X.dhw_on] = 0.0
    elif T_dhw_top < p[P.dhw_on_below] and T_dhw_top < T_top:
        x[X.dhw_on] = 1.0
    return x[X.chp_on], x[X.chp_on] * p[P.chp_modulation], x[X.boiler_on] * p[P.boiler_demand], x[X.dhw_on]


class Kind(ComponentKind):
    """The case-study rules: storage temperatures in (signal links), generator and DHW pump
    commands out."""

    name = "rule_based"
    Params = Params
    role = "controller"
    INPUTS = ("T_top", "T_bottom", "T_dhw_top")
    OUTPUTS = ("chp_on", "chp_y", "boiler_U", "dhw_on")
    LINKS = {"inputs": link(REQUIRED, "measurements: T_top, T_bottom, T_dhw_top = signal names", type=dict),
             "outputs": link(REQUIRED, "commands: chp_on, chp_y, boiler_U, dhw_on = input signal names", type=dict)}

    def initial_state(self, inst):
        return initial_state(inst.params)

    def emit(self, c, inst):
        from . import check_keys, emit_step

        check_keys(c, inst, self.INPUTS, self.OUTPUTS)
        x = emit_step(c, self, inst, __name__)
