"""The solar emulator bench: an electric heater in the lab's solar circuit stands in for the
collector. The twin sends the outlet temperature (STM_STVL_Set_degC) and heat (PEH_ST_Set_kW)
the simulated collector delivers, and the collector temperature (T_collector_degC); the bench
heats the water the lab returns (T_in, its own solar pump's flow m) with the set heat (at most
the heater limit P_max; no heating without flow: the heater's flow interlock), and sends back the
return temperature and flow it sees (STM_STRL_degC, SFW_STVL_l_per_min), the outlet temperature
and heater power it achieved, and its heat meter (E_ST_kWh).

The lab's solar pump is the lab's own controller's, as house 1's (plant/components/
solar_collector.py): it runs while the simulated collector is more than dT_on above the return
and stops below dT_off; while on its flow is m_flow_max x clamp((T_collector - T_in -
dT_flow_min) / (dT_flow_max - dT_flow_min), 0, 1), with a first-order lag tau_pump.

Heater (water volume V_heater, outlet node T_out):  C dT_out/dt = P - m cp (T_out - T_in), the
power P following the set heat with the lag tau_heater.
Ledger [J]: E_heater = integral of P = E_heat (m cp (T_out - T_in), to the lab) + change of the
node's heat. E_ST_kWh is the heater's energy meter (E_heater): the heat the bench put into the
lab's circuit in place of the collector, compared with the simulated collector's heat.

| parameter | unit | meaning |
|---|---|---|
| T_in | degC | return temperature of the lab's solar circuit (its storage coil) |
| m_flow_max | kg/s | the lab's solar pump flow at full speed |
| dT_on, dT_off | K | pump on above T_collector - T_in, off below (held between) |
| dT_flow_min, dT_flow_max | K | flow modulation on T_collector - T_in |
| tau_pump | s | pump flow time constant |
| P_max | W | heater limit |
| tau_heater | s | heater power time constant |
| V_heater | m3 | water in the heater up to the outlet sensor |
"""
from __future__ import annotations

from .model import BenchModel

CP = 4180.0
RHO = 1000.0
NO_FLOW = 1e-3      # kg/s: below it the heater's flow switch keeps the heater off


class SolarBench(BenchModel):
    INPUTS = {"T_out_set": 20.0, "Q_set": 0.0, "T_collector": 20.0}
    READINGS = {"T_in": "T_in", "m_flow": "m_flow", "T_out": "T_out", "P": "P", "E_heater": "E_heater"}
    DEFAULTS = {"T_in": 30.0, "m_flow_max": 0.1, "P_max": 6000.0, "tau_heater": 10.0, "dT_on": 3.0,
                "dT_off": 2.0, "dT_flow_min": 3.0, "dT_flow_max": 7.0, "tau_pump": 5.0,
                "V_heater": 0.002}

    def __init__(self, doc, seed: int = 0) -> None:
        super().__init__(doc, seed)
        T0 = self.p["T_in"]
        self.x = {"T_in": T0, "m_flow": 0.0, "T_out": T0, "P": 0.0, "E_heat": 0.0, "E_heater": 0.0,
                  "on": 0.0}
        self.ledger = {"E_heater": 0.0, "E_heat": 0.0}
        self._E0 = self.stored_energy()
        self.sample()

    def stored_energy(self) -> float:
        return CP * RHO * self.p["V_heater"] * self.x["T_out"]

    def advance(self, h: float) -> None:
        p, x, u = self.p, self.x, self.inputs
        dT = u["T_collector"] - x["T_in"]
        x["on"] = 1.0 if dT > p["dT_on"] else 0.0 if dT < p["dT_off"] else x["on"]
        span = max(p["dT_flow_max"] - p["dT_flow_min"], 1e-9)
        want_m = x["on"] * p["m_flow_max"] * min(max((dT - p["dT_flow_min"]) / span, 0.0), 1.0)
        x["m_flow"] += (want_m - x["m_flow"]) * min(h / p["tau_pump"], 1.0)
        m = x["m_flow"]
        want = min(max(u["Q_set"], 0.0), p["P_max"]) if m > NO_FLOW else 0.0
        x["P"] = want if m <= NO_FLOW else x["P"] + (want - x["P"]) * min(h / p["tau_heater"], 1.0)
        Q_out = m * CP * (x["T_out"] - x["T_in"])
        x["T_out"] += h * (x["P"] - Q_out) / (CP * RHO * p["V_heater"])
        x["E_heat"] += Q_out * h
        x["E_heater"] += x["P"] * h
        self.ledger["E_heater"] = x["E_heater"]
        self.ledger["E_heat"] = x["E_heat"]

    def balance(self) -> dict[str, float]:
        L = dict(self.ledger)
        L["delta_stored"] = self.stored_energy() - self._E0
        L["residual"] = L["E_heater"] - L["E_heat"] - L["delta_stored"]
        return L
