"""The heat-pump source emulator bench (SF3's brine interface): it conditions the brine the lab's
ground-source heat pump takes, in place of the ground collector.

The twin sends the brine temperature its simulated ground collector gives back to the heat pump
(STM_BCRLaM_Set_degC) and the ground temperature (T_ground_degC, logged by the bench PLC); the
bench brings the brine returning from the heat pump's evaporator back to that temperature with a
heater/chiller of limited capacity, and sends back the brine the heat pump sends towards the
ground (STM_BCVL_degC), the brine flow (SFW_BC_l_per_min), the temperature it achieved
(STM_BCRLaM_degC), its conditioning power (PEH_BC_kW) and its heat meter (E_BC_kWh).

Brine loop (water properties, as the reference's model, §5): supply node T_sup (volume V_supply,
the conditioning unit up to its outlet sensor) -> the lab heat pump's evaporator (node T_ret,
volume V_evaporator) -> back to the supply node.
  * the lab's heat pump (its own controller is not modelled: a duty cycle) runs hp_on_s, stops
    hp_off_s, from hp_phase_s into its cycle; while it runs its brine pump moves m_flow_max (lag
    tau_pump) and its evaporator takes Q_evap = Q_source_nominal (1 + k_source T_sup) m /
    m_flow_max, reached with the compressor's lag tau_compressor after a start, 0 at once at a stop;
  * conditioning (phil/emulator/model.py conditioning_power): the followed set-point moves at most
    ramp_T K/s; a PI (K_p, T_i) on the outlet sensor plus the feed-forward m cp (T_set - T_ret) +
    C_sup dT_set/dt asks for a power, clamped to [-P_cool_max, P_heat_max] (the capacity limit)
    and reached with the lag tau_heater.
  C_sup dT_sup/dt = P + m cp (T_ret - T_sup),   C_evap dT_ret/dt = m cp (T_sup - T_ret) - Q_evap.
Ledger [J]: E_heater (integral of P) = E_evaporator (heat to the heat pump) + change of both nodes'
heat. The heat meter (E_BC_kWh) counts its own flow meter's reading (low-flow cut-off included)
times the true spread T_sup - T_ret: the heat the brine brought the heat pump, which PHIL compares
with the heat the simulated ground collector gave the brine.

| parameter | unit | meaning |
|---|---|---|
| m_flow_max | kg/s | the lab heat pump's brine pump flow |
| tau_pump | s | brine pump flow time constant |
| Q_source_nominal | W | evaporator heat at 0 degC brine and full flow |
| k_source | 1/K | relative change of the evaporator heat per K of brine temperature |
| tau_compressor | s | evaporator heat time constant after a start |
| hp_on_s, hp_off_s, hp_phase_s | s | the lab heat pump's duty cycle (bench clock) |
| V_supply, V_evaporator | m3 | brine in the conditioning unit and in the evaporator |
| P_heat_max, P_cool_max | W | heater and chiller capacity |
| tau_heater | s | conditioning power time constant |
| ramp_T | K/s | largest change of the followed set-point |
| K_p, T_i | W/K, s | outlet-temperature PI |
| T_init | degC | brine temperature at the start |
Tests: tests/phil/test_brine.py.
"""
from __future__ import annotations

from .model import BenchModel, conditioning_power

CP = 4180.0
RHO = 1000.0
NO_FLOW = 1e-3      # kg/s: below it the evaporator takes nothing (the heat pump's flow switch)


class BrineBench(BenchModel):
    INPUTS = {"T_set": 10.0, "T_ground": 10.0}
    READINGS = {"T_sup": "T_sup", "T_ret": "T_ret", "m_flow": "m_flow", "P": "P", "E_meter": "E_meter"}
    DEFAULTS = {"m_flow_max": 0.41, "tau_pump": 10.0, "Q_source_nominal": 8000.0, "k_source": 0.025,
                "tau_compressor": 30.0, "hp_on_s": 1200.0, "hp_off_s": 600.0, "hp_phase_s": 0.0,
                "V_supply": 0.01, "V_evaporator": 0.004, "P_heat_max": 10000.0, "P_cool_max": 3000.0,
                "tau_heater": 5.0, "ramp_T": 0.2, "K_p": 4000.0, "T_i": 60.0, "T_init": 10.0}

    def __init__(self, doc, seed: int = 0) -> None:
        super().__init__(doc, seed)
        T0 = self.p["T_init"]
        self.x = {"T_sup": T0, "T_ret": T0, "m_flow": 0.0, "P": 0.0, "Q_evap": 0.0, "T_target": T0,
                  "i_T": 0.0, "E_meter": 0.0, "on": 0.0}
        self.ledger = {"E_heater": 0.0, "E_evaporator": 0.0}
        self._E0 = self.stored_energy()
        self.sample()

    def stored_energy(self) -> float:
        p, x = self.p, self.x
        return CP * RHO * (p["V_supply"] * x["T_sup"] + p["V_evaporator"] * x["T_ret"])

    def running(self) -> bool:
        p = self.p
        cycle = p["hp_on_s"] + p["hp_off_s"]
        return cycle > 0 and (self.t + p["hp_phase_s"]) % cycle < p["hp_on_s"]

    def advance(self, h: float) -> None:
        p, x, u = self.p, self.x, self.inputs
        x["on"] = 1.0 if self.running() else 0.0
        x["m_flow"] += (x["on"] * p["m_flow_max"] - x["m_flow"]) * min(h / p["tau_pump"], 1.0)
        m, T_sup, T_ret = x["m_flow"], x["T_sup"], x["T_ret"]
        share = m / p["m_flow_max"] if m > NO_FLOW else 0.0
        want_Q = x["on"] * share * max(p["Q_source_nominal"] * (1.0 + p["k_source"] * T_sup), 0.0)
        # the compressor starts with its lag and stops at once (the brine pump runs on)
        x["Q_evap"] += (want_Q - x["Q_evap"]) * min(h / p["tau_compressor"], 1.0) if want_Q > 0.0 else -x["Q_evap"]
        C_sup, C_evap = CP * RHO * p["V_supply"], CP * RHO * p["V_evaporator"]
        conditioning_power(x, p, h, u["T_set"], m * CP, T_ret, self.readings.get("T_sup", T_sup), C_sup)
        Q_loop = m * CP * (T_sup - T_ret)
        x["T_sup"] = T_sup + h * (x["P"] - Q_loop) / C_sup
        x["T_ret"] = T_ret + h * (Q_loop - x["Q_evap"]) / C_evap
        self.ledger["E_heater"] += x["P"] * h
        self.ledger["E_evaporator"] += x["Q_evap"] * h
        # the heat meter: its own flow meter's reading (with its low-flow cut-off) x the true spread
        x["E_meter"] += self.readings.get("m_flow", m) * CP * (T_sup - T_ret) * h

    def balance(self) -> dict[str, float]:
        L = dict(self.ledger)
        L["delta_stored"] = self.stored_energy() - self._E0
        L["residual"] = L["E_heater"] - L["E_evaporator"] - L["delta_stored"]
        return L
