"""The repository's SOC-gated generator rules (reference §12.1 table, `SF1.mo`), used by the
houses SF4 (boiler, §12.5) and MF5 (CHP and boiler, §12.6).

Edge-triggered hysteresis switches: a generator starts when the storage's state of charge is
below its `soc_on` AND the start sensor (T_on, upstream T_BT8) is below its `on_below`; it stops
when the state of charge is above its `soc_off` OR the stop sensor (T_off, upstream T_BT3) is above
its `off_above` (the stop wins when both hold); in between it keeps its state.

  SF1.mo / MF5:  CHP    on SOC < 0.60 and T_BT8 < 65 degC, off SOC > 0.95 or T_BT3 > 70 degC
                 boiler on SOC < 0.50 and T_BT8 < 60 degC, off SOC > 0.65 or T_BT3 > 70 degC
  SF4:           boiler on SOC < 0.50 and T_BT8 < 55 degC, off SOC > 0.95 or T_BT3 > 70 degC

The SOC is whichever signal the house links (the storage's `SOC`, with the house's soc_T0 and
soc_Tmax: SF1/MF5 40/80 degC, SF4 30/90 degC). Outputs: chp_on (0/1), chp_y (modulation when on),
boiler_U (0 or boiler_demand V); a generator whose outputs are not linked is not evaluated.
The states are also the controller's output signals (`<name>.chp_on`, `<name>.boiler_on`).

SF4's electric heater (optional, evaluated when `heater_on` is linked): released when T_heater
(upstream T_BT5) < heater_T_max - heater_dT (85 degC), blocked above heater_T_max (90 degC);
its power limit `heater_P` is P_heater (6 kW), or with `pv_surplus = true` the PV surplus
max(0, P_pv - P_household) (inputs P_pv, P_household), capped at P_heater.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from ..component import REQUIRED, Kind as ComponentKind, indices, link, param
from .rule_based import quantize

STATES = ("chp_on", "boiler_on", "since_scan", "heater_on")


@dataclass(frozen=True)
class Params:
    chp_soc_on: float = param(0.60, "1", "CHP may start when the SOC is below", -1, 2)
    chp_on_below: float = param(65.0, "degC", "CHP starts when T_on is below (and the SOC is low)", 10, 95)
    chp_soc_off: float = param(0.95, "1", "CHP stops when the SOC is above", -1, 2)
    chp_off_above: float = param(70.0, "degC", "CHP stops when T_off is above", 10, 95)
    boiler_soc_on: float = param(0.50, "1", "boiler may start when the SOC is below", -1, 2)
    boiler_on_below: float = param(60.0, "degC", "boiler starts when T_on is below (and the SOC is low)", 10, 95)
    boiler_soc_off: float = param(0.65, "1", "boiler stops when the SOC is above", -1, 2)
    boiler_off_above: float = param(70.0, "degC", "boiler stops when T_off is above", 10, 95)
    chp_modulation: float = param(1.0, "1", "CHP modulation when on", 0.55, 1.0)
    boiler_demand: float = param(10.0, "V", "boiler 0-10 V demand when on", 2.1, 10.0)
    heater_T_max: float = param(90.0, "degC", "electric heater blocked when T_heater is above", 20, 99)
    heater_dT: float = param(5.0, "K", "electric heater released again this far below heater_T_max", 0.1, 50)
    P_heater: float = param(6000.0, "W", "electric heater power limit when released", 0, 1e6)
    pv_surplus: bool = param(False, "-", "true: the heater takes only the PV surplus (P_pv - P_household)")
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
def switch(on, soc, T_on, T_off, soc_on, on_below, soc_off, off_above):
    if soc > soc_off or T_off > off_above:
        return 0.0
    if soc < soc_on and T_on < on_below:
        return 1.0
    return on


@njit(cache=True)
def step(dt, x, p, soc, T_on, T_off, T_heater, P_pv, P_household, use_chp, use_boiler, use_heater):
    """Scan when a period has passed; returns (chp_on, chp_y, boiler_U, heater_on, heater_P)."""
    x[X.since_scan] += dt
    if x[X.since_scan] + 1e-9 >= p[P.period]:
        x[X.since_scan] = 0.0
        r = p[P.sensor_resolution]
        T_on, T_off = quantize(T_on, r), quantize(T_off, r)
        if use_chp:
            x[X.chp_on] = switch(x[X.chp_on], soc, T_on, T_off, p[P.chp_soc_on], p[P.chp_on_below], p[P.chp_soc_off],
                              p[P.chp_off_above])
        if use_boiler:
            x[X.boiler_on] = switch(x[X.boiler_on], soc, T_on, T_off, p[P.boiler_soc_on], p[P.boiler_on_below],
                                 p[P.boiler_soc_off], p[P.boiler_off_above])
        if use_heater:
            T_h = quantize(T_heater, r)
            if T_h > p[P.heater_T_max]:
                x[X.heater_on] = 0.0
            elif T_h < p[P.heater_T_max] - p[P.heater_dT]:
                x[X.heater_on] = 1.0
    P_h = min(p[P.P_heater], max(0.0, P_pv - P_household)) if p[P.pv_surplus] > 0.5 else p[P.P_heater]
    return x[X.chp_on], x[X.chp_on] * p[P.chp_modulation], x[X.boiler_on] * p[P.boiler_demand], x[X.heater_on], P_h


class Kind(ComponentKind):
    """SOC-gated CHP and boiler rules: SOC and two storage sensors in, generator commands out."""

    name = "soc_rules"
    Params = Params
    role = "controller"
    INPUTS = ("SOC", "T_on", "T_off", "T_heater", "P_pv", "P_household")
    OUTPUTS = ("chp_on", "chp_y", "boiler_U", "heater_on", "heater_P")
    LINKS = {"inputs": link(REQUIRED, "measurements: SOC, T_on, T_off (and T_heater, P_pv, P_household for the "
                                      "electric heater) = signal names", type=dict),
             "outputs": link(REQUIRED, "commands: chp_on, chp_y, boiler_U, heater_on, heater_P = input signal names",
                             type=dict)}

    def initial_state(self, inst):
        return initial_state(inst.params)

    def emit(self, c, inst):
        from . import check_keys, emit_step, read

        check_keys(c, inst, self.INPUTS, self.OUTPUTS)
        linked = inst.options["outputs"]
        use_chp, use_boiler = "chp_on" in linked or "chp_y" in linked, "boiler_U" in linked
        use_heater = "heater_on" in linked or "heater_P" in linked
        if not (use_chp or use_boiler or use_heater):
            c.problems.append(f"{inst.at('outputs')}: links no generator; link chp_on/chp_y, boiler_U or heater_on")
        surplus = inst.params.pv_surplus
        args = []
        for key in self.INPUTS:
            optional = (key == "T_heater" and not use_heater) or (key in ("P_pv", "P_household") and not surplus)
            args.append("0.0" if optional and key not in inst.options["inputs"] else read(c, inst, key))
        x = emit_step(c, self, inst, __name__, [*args, str(use_chp), str(use_boiler), str(use_heater)])
        sig = lambda local, desc: c.signal(inst, local, "1", "output", desc)  # noqa: E731
        c.emit("signals",
               f"{sig('chp_on', 'CHP command of the rules (0/1)')} = {x}[{X.chp_on}]",
               f"{sig('boiler_on', 'boiler command of the rules (0/1)')} = {x}[{X.boiler_on}]",
               f"{sig('heater_on', 'electric heater release of the rules (0/1)')} = {x}[{X.heater_on}]")
