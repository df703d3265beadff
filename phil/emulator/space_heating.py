"""The space-heating emulator bench: a commercial mixing station with a heat exchanger.

Hydraulics (one circuit, mass flow m): hot inlet water T_inlet (the lab's storage) is mixed by a
three-way valve with the bench's own return, y T_inlet + (1 - y) T_ret; the mixture fills the
supply node (volume V_supply, the pipes up to the supply sensor), flows through the heat
exchanger node (V_exchanger), where cooling water at T_cooling takes
Q_hx = z eps m_cooling_max cp (T_ret - T_cooling), and returns to the valve.
  * valve: position y moves towards the supply PI controller's output at most 1/t_valve per s
    (actuator travel time); the PI acts on its own supply sensor (a thermowell, lag tau_sensor), and with
    the actuator's travel and that lag it oscillates slowly about the set-point, as the
    lab's bench does;
  * pump: the flow follows the set flow through a first-order lag, limited to m_flow_max;
  * exchanger: a PI with feed-forward moves the cooling-water valve z so that the measured return
    meets the set return; it cannot cool below T_cooling nor take more than its capacity.
Ledger [J]: heat from the inlet  m y cp (T_inlet - T_ret) = heat to the cooling water + change of
the two nodes' stored heat. `E_consumed` = integral of m cp (T_sup - T_ret): the heat the circuit
gave between the supply and the return sensor. The bench's heat meter (register E_HC_kWh)
counts it with its own flow meter's reading (low-flow cut-off included), as a real meter does;
PHIL compares that with the heat the simulated building took.

| parameter | unit | meaning |
|---|---|---|
| T_inlet | degC | hot inlet temperature (the lab storage's supply) |
| T_cooling | degC | cooling-water inlet temperature |
| m_flow_max | kg/s | pump maximum flow |
| tau_pump | s | pump flow time constant |
| t_valve | s | mixing-valve actuator travel time 0 -> 100 % |
| K_p_supply, T_i_supply | 1/K, s | supply-temperature PI |
| tau_sensor | s | time constant of the controller's own supply sensor (a thermowell) |
| V_supply, V_exchanger | m3 | water in the supply pipes and in the exchanger (node volumes) |
| m_cooling_max, eps | kg/s, 1 | cooling-water flow at a fully open valve, exchanger effectiveness |
| K_p_return, T_i_return | 1/K, s | return-temperature PI of the cooling-water valve |
| m_flow_limited, limited_from, limited_until | kg/s, s, s | a temporary flow limit (a fault to test with; < 0: none) between two times of the bench's clock |
Tests: tests/phil/test_bench.py (follows a constant set-point within its limits; ledger closes).
"""
from __future__ import annotations

from .model import BenchModel, pi_step

CP = 4180.0
RHO = 1000.0


class SpaceHeatingBench(BenchModel):
    INPUTS = {"T_sup_set": 20.0, "m_flow_set": 0.0, "T_ret_set": 20.0}
    READINGS = {"T_sup": "T_sup", "m_flow": "m_flow", "T_ret": "T_ret", "T_inlet": "T_inlet",
                "E_consumed": "E_meter"}
    DEFAULTS = {"T_inlet": 70.0, "T_cooling": 12.0, "m_flow_max": 0.5, "tau_pump": 5.0,
                "t_valve": 90.0, "K_p_supply": 0.05, "T_i_supply": 60.0, "V_supply": 0.004,
                "V_exchanger": 0.002, "m_cooling_max": 0.5, "eps": 0.8, "K_p_return": 0.2,
                "T_i_return": 5.0, "T_init": 30.0, "tau_sensor": 20.0, "m_flow_limited": -1.0,
                "limited_from": 0.0, "limited_until": 0.0}

    def __init__(self, doc, seed: int = 0) -> None:
        super().__init__(doc, seed)
        T0 = self.p["T_init"]
        self.x = {"T_sup": T0, "T_ret": T0, "m_flow": 0.0, "y": 0.0, "z": 0.0, "i_sup": 0.0,
                  "i_ret": 0.0, "T_sensor": T0, "T_inlet": self.p["T_inlet"], "E_meter": 0.0}
        self.ledger = {"heat_inlet": 0.0, "heat_cooling": 0.0, "E_consumed": 0.0}
        self._E0 = self.stored_energy()
        self.sample()

    def stored_energy(self) -> float:
        p, x = self.p, self.x
        return CP * RHO * (p["V_supply"] * x["T_sup"] + p["V_exchanger"] * x["T_ret"])

    def advance(self, h: float) -> None:
        p, x, u = self.p, self.x, self.inputs
        m_max = p["m_flow_max"]
        if p["m_flow_limited"] >= 0.0 and p["limited_from"] <= self.t < p["limited_until"]:
            m_max = min(m_max, p["m_flow_limited"])       # a pump fault or a throttled valve
        m_set = min(max(u["m_flow_set"], 0.0), m_max)
        x["m_flow"] += (m_set - x["m_flow"]) * min(h / p["tau_pump"], 1.0)
        m, T_sup, T_ret, T_in = x["m_flow"], x["T_sup"], x["T_ret"], x["T_inlet"]
        # supply PI on the measured supply; the actuator moves at most h / t_valve
        x["T_sensor"] += (T_sup - x["T_sensor"]) * min(h / p["tau_sensor"], 1.0)
        y_target, x["i_sup"] = pi_step(x["i_sup"], u["T_sup_set"] - x["T_sensor"],
                                       h, p["K_p_supply"], p["T_i_supply"], 0.0, 1.0)
        x["y"] += min(max(y_target - x["y"], -h / p["t_valve"]), h / p["t_valve"])
        # exchanger: feed-forward for the heat to take, PI on the measured return
        capacity = p["eps"] * p["m_cooling_max"] * CP * max(T_ret - p["T_cooling"], 0.0)
        need = m * CP * (T_sup - u["T_ret_set"])
        z_ff = need / capacity if capacity > 1.0 else 0.0
        z_fb, x["i_ret"] = pi_step(x["i_ret"], self.readings.get("T_ret", T_ret) - u["T_ret_set"], h,
                                   p["K_p_return"], p["T_i_return"], -1.0, 1.0)
        x["z"] = min(max(z_ff + z_fb, 0.0), 1.0)
        Q_hx = x["z"] * capacity
        Q_in = m * x["y"] * CP * (T_in - T_ret)           # the mixture minus the return it replaces
        Q_use = m * CP * (T_sup - T_ret)
        x["T_sup"] = T_sup + h * (Q_in + m * CP * (T_ret - T_sup)) / (CP * RHO * p["V_supply"])
        x["T_ret"] = T_ret + h * (Q_use - Q_hx) / (CP * RHO * p["V_exchanger"])
        self.ledger["heat_inlet"] += Q_in * h
        self.ledger["heat_cooling"] += Q_hx * h
        self.ledger["E_consumed"] += Q_use * h
        # the heat meter: its own flow meter's reading (with its low-flow cut-off) x the true spread
        x["E_meter"] += self.readings.get("m_flow", m) * CP * (T_sup - T_ret) * h

    def balance(self) -> dict[str, float]:
        L = dict(self.ledger)
        L["delta_stored"] = self.stored_energy() - self._E0
        L["residual"] = L["heat_inlet"] - L["heat_cooling"] - L["delta_stored"]
        return L
