"""The tap-water emulator bench: draws hot water so that its drawn energy follows the set-point.

The twin sends the cumulative hot-water energy the simulated household has drawn (E_DHW_Set_kWh,
reference §13.2); the bench opens its draw valve so that its own heat meter catches up within
tau_follow, at most m_flow_max (the flow limit), taking water at T_hot (the lab's DHW storage)
and replacing it with cold water at T_cold (measured and sent back: STM_CCVL_degC).
Ledger [J]: E_drawn = integral of m cp (T_hot - T_cold).

| parameter | unit | meaning |
|---|---|---|
| T_hot, T_cold | degC | hot water delivered by the storage, cold mains water |
| m_flow_max | kg/s | draw valve flow limit |
| tau_follow | s | time in which the bench aims to close its energy gap |
"""
from __future__ import annotations

from .model import BenchModel

CP = 4180.0


class TapWaterBench(BenchModel):
    INPUTS = {"E_set": 0.0}
    READINGS = {"E_drawn": "E_drawn", "m_flow": "m_flow", "T_cold": "T_cold", "T_hot": "T_hot"}
    DEFAULTS = {"T_hot": 50.0, "T_cold": 12.0, "m_flow_max": 0.25, "tau_follow": 20.0}

    def __init__(self, doc, seed: int = 0) -> None:
        super().__init__(doc, seed)
        self.x = {"E_drawn": 0.0, "m_flow": 0.0, "T_cold": self.p["T_cold"], "T_hot": self.p["T_hot"]}
        self.ledger = {"E_drawn": 0.0}
        self.sample()

    def release(self, name: str) -> None:
        """Without fresh set-points the bench stops drawing: its target becomes what it drew."""
        self.inputs[name] = self.x["E_drawn"]

    def advance(self, h: float) -> None:
        p, x = self.p, self.x
        dT = max(p["T_hot"] - p["T_cold"], 1.0)
        gap = self.inputs["E_set"] - x["E_drawn"]
        x["m_flow"] = min(max(gap / (CP * dT * p["tau_follow"]), 0.0), p["m_flow_max"])
        x["E_drawn"] += x["m_flow"] * CP * dT * h
        self.ledger["E_drawn"] = x["E_drawn"]
