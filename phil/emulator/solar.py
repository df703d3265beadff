"""The solar emulator bench: an electric heater in the lab's solar circuit stands in for the
collector. The twin sends the outlet temperature (STM_STVL_Set_degC) and heat (PEH_ST_Set_kW)
the simulated collector delivers; the bench heats the water the lab returns (T_in, its own solar
pump's flow m) to the set outlet temperature, with at most the set heat and the heater limit P_max,
and sends back the return temperature and flow it sees (STM_STRL_degC, SFW_STVL_l_per_min) and
what it achieved. Ledger [J]: E_heat = integral of the heater power = m cp (T_out - T_in).

| parameter | unit | meaning |
|---|---|---|
| T_in | degC | return temperature of the lab's solar circuit (its storage coil) |
| m_flow | kg/s | the lab's solar pump flow |
| P_max | W | heater limit |
| tau_heater | s | heater power time constant |
"""
from __future__ import annotations

from .model import BenchModel

CP = 4180.0


class SolarBench(BenchModel):
    INPUTS = {"T_out_set": 20.0, "Q_set": 0.0}
    READINGS = {"T_in": "T_in", "m_flow": "m_flow", "T_out": "T_out", "P": "P", "E_heat": "E_heat"}
    DEFAULTS = {"T_in": 30.0, "m_flow": 0.1, "P_max": 6000.0, "tau_heater": 10.0}

    def __init__(self, doc, seed: int = 0) -> None:
        super().__init__(doc, seed)
        self.x = {"T_in": self.p["T_in"], "m_flow": self.p["m_flow"], "T_out": self.p["T_in"],
                  "P": 0.0, "E_heat": 0.0}
        self.ledger = {"E_heat": 0.0}
        self.sample()

    def advance(self, h: float) -> None:
        p, x, u = self.p, self.x, self.inputs
        m = x["m_flow"]
        want = min(max(u["Q_set"], 0.0), max(m * CP * (u["T_out_set"] - x["T_in"]), 0.0), p["P_max"])
        x["P"] += (want - x["P"]) * min(h / p["tau_heater"], 1.0)
        x["T_out"] = x["T_in"] + (x["P"] / (m * CP) if m > 0 else 0.0)
        x["E_heat"] += x["P"] * h
        self.ledger["E_heat"] = x["E_heat"]
