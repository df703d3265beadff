"""The district-heating grid emulator bench: it supplies the lab's substation with grid water at the
supply temperature and differential pressure the twin's simulated grid has at the house's node.

The twin sends the grid's supply temperature (STM_TGVL_Set_degC) and differential pressure
(SDP_TG_Set_bar) at the node; the bench heats (or cools) the grid water the substation returns to
that supply temperature with a heater/chiller of limited capacity, and its pump holds the
differential pressure across the substation's grid connection, ramp- and head-limited. It sends
back the supply it achieved (STM_TGVL_degC), the substation's return (STM_TGRL_degC), the grid
flow through the substation (SFW_TG_l_per_min), the differential pressure (SDP_TG_bar), its
conditioning power (PEH_TG_kW) and its heat meter (E_TG_kWh).

Grid loop (water): supply node T_sup (volume V_supply, the emulator's heater up to its outlet
sensor) -> the lab's substation (grid side, node T_ret of volume V_exchanger) -> back.
  * pump: the differential pressure follows the set-point with the lag tau_pump, moving at most
    ramp_dp Pa/s, at most dp_max (SI inside the model; bar on the bus);
  * the lab's substation (its own controller is not modelled: a duty cycle) extracts for
    sub_on_s, rests sub_off_s, from sub_phase_s into its cycle; while extracting its grid-side
    valve asks for m_flow_demand, and the valve (Kvs [m3/h]) lets through at most
    Kvs / 3.6 sqrt(dp / 1 bar) kg/s; the flow follows with the lag tau_valve. Its exchanger (UA)
    gives the heat to the lab's storage side at T_house: Q_sub = UA (T_ret - T_house) while water
    flows;
  * conditioning as the heat-pump source emulator's (phil/emulator/model.py conditioning_power):
    set-point ramp ramp_T, PI plus feed-forward (flow and set-point rate), capacity
    [-P_cool_max, P_heat_max], lag tau_heater.
  C_sup dT_sup/dt = P + m cp (T_ret - T_sup),   C_hx dT_ret/dt = m cp (T_sup - T_ret) - Q_sub.
Ledger [J]: E_heater (integral of P) = E_substation (heat to the lab's storage side) + change of
both nodes' heat. The heat meter (E_TG_kWh) counts its own flow meter's reading (low-flow cut-off
included) times the true spread T_sup - T_ret: the heat the grid water brought the substation,
which PHIL compares with the heat the simulated grid gave the house.

| parameter | unit | meaning |
|---|---|---|
| dp_max, ramp_dp, tau_pump | Pa, Pa/s, s | pump head, its ramp limit and time constant |
| m_flow_demand | kg/s | the substation's grid-side flow while extracting |
| Kvs | m3/h | the substation valve's flow coefficient (fully open) |
| tau_valve | s | valve flow time constant |
| UA | W/K | the substation exchanger (§13.1: 2945 W/K) |
| T_house | degC | the lab storage side's water entering the exchanger |
| sub_on_s, sub_off_s, sub_phase_s | s | the substation's duty cycle (bench clock) |
| V_supply, V_exchanger | m3 | water in the heater and in the exchanger's grid side |
| P_heat_max, P_cool_max, tau_heater, ramp_T, K_p, T_i | W, W, s, K/s, W/K, s | conditioning |
| T_init | degC | water temperature at the start |
Tests: tests/phil/test_grid.py.
"""
from __future__ import annotations

import math

from .model import BenchModel, conditioning_power

CP = 4180.0
RHO = 1000.0
BAR = 1.0e5         # Pa: the valve coefficient Kvs is per sqrt(bar)


class GridBench(BenchModel):
    INPUTS = {"T_sup_set": 30.0, "dp_set": 0.0}
    READINGS = {"T_sup": "T_sup", "T_ret": "T_ret", "m_flow": "m_flow", "dp": "dp", "P": "P",
                "E_meter": "E_meter"}
    DEFAULTS = {"dp_max": 2.0e5, "ramp_dp": 5000.0, "tau_pump": 5.0, "m_flow_demand": 0.2, "Kvs": 1.2,
                "tau_valve": 10.0, "UA": 2945.0, "T_house": 40.0, "sub_on_s": 1200.0, "sub_off_s": 600.0,
                "sub_phase_s": 0.0, "V_supply": 0.02, "V_exchanger": 0.002, "P_heat_max": 30000.0,
                "P_cool_max": 5000.0, "tau_heater": 5.0, "ramp_T": 0.2, "K_p": 8000.0, "T_i": 60.0,
                "T_init": 40.0}

    def __init__(self, doc, seed: int = 0) -> None:
        super().__init__(doc, seed)
        T0 = self.p["T_init"]
        self.x = {"T_sup": T0, "T_ret": T0, "m_flow": 0.0, "dp": 0.0, "P": 0.0, "Q_sub": 0.0,
                  "T_target": T0, "i_T": 0.0, "E_meter": 0.0, "on": 0.0}
        self.ledger = {"E_heater": 0.0, "E_substation": 0.0}
        self._E0 = self.stored_energy()
        self.sample()

    def stored_energy(self) -> float:
        p, x = self.p, self.x
        return CP * RHO * (p["V_supply"] * x["T_sup"] + p["V_exchanger"] * x["T_ret"])

    def extracting(self) -> bool:
        p = self.p
        cycle = p["sub_on_s"] + p["sub_off_s"]
        return cycle > 0 and (self.t + p["sub_phase_s"]) % cycle < p["sub_on_s"]

    def advance(self, h: float) -> None:
        p, x, u = self.p, self.x, self.inputs
        want_dp = min(max(u["dp_set"], 0.0), p["dp_max"])
        change = (want_dp - x["dp"]) * min(h / p["tau_pump"], 1.0)
        x["dp"] += min(max(change, -p["ramp_dp"] * h), p["ramp_dp"] * h)
        x["on"] = 1.0 if self.extracting() else 0.0
        want_m = x["on"] * min(p["m_flow_demand"], p["Kvs"] / 3.6 * math.sqrt(max(x["dp"], 0.0) / BAR))
        x["m_flow"] += (want_m - x["m_flow"]) * min(h / p["tau_valve"], 1.0)
        m, T_sup, T_ret = x["m_flow"], x["T_sup"], x["T_ret"]
        C_sup, C_hx = CP * RHO * p["V_supply"], CP * RHO * p["V_exchanger"]
        conditioning_power(x, p, h, u["T_sup_set"], m * CP, T_ret, self.readings.get("T_sup", T_sup), C_sup)
        x["Q_sub"] = p["UA"] * (T_ret - p["T_house"]) if m > 1e-4 else 0.0
        Q_loop = m * CP * (T_sup - T_ret)
        x["T_sup"] = T_sup + h * (x["P"] - Q_loop) / C_sup
        x["T_ret"] = T_ret + h * (Q_loop - x["Q_sub"]) / C_hx
        self.ledger["E_heater"] += x["P"] * h
        self.ledger["E_substation"] += x["Q_sub"] * h
        # the heat meter: its own flow meter's reading (with its low-flow cut-off) x the true spread
        x["E_meter"] += self.readings.get("m_flow", m) * CP * (T_sup - T_ret) * h

    def balance(self) -> dict[str, float]:
        L = dict(self.ledger)
        L["delta_stored"] = self.stored_energy() - self._E0
        L["residual"] = L["E_heater"] - L["E_substation"] - L["delta_stored"]
        return L
