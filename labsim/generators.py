"""labsim generators: the neoTower 2 CHP and the Wolf CGB-14 condensing boiler (reference §2, §3).

Both are written as a pump-driven branch of labsim's pressure network (network.py): each step a
generator states the flow its own pump aims at (`q_target`) and the heat it puts into the water
(`P_heat`); the network gives the flow that actually passes; the outlet temperature follows from
the heat and that flow. The CHP's own heat counter (`Q_meter`) multiplies the pump's flow (what
the unit believes passes) with the outlet-return difference, as the unit's display does.

Energy: fuel = electricity + heat to the water + generator losses; the losses (flue, casing, the
heat withheld during warm-up and given back in the pump run-on) are the remainder by definition.
"""
from __future__ import annotations

import math

from .products import boiler_tables, chp_tables

CP = 4180.0


class CHP:
    """RMB neoTower 2. Times in s, powers in W, flows in kg/s, temperatures in degC."""

    P_EL_MAX, M_MIN, ETA_EL_MAX, ETA_EL_MIN = 1900.0, 0.55, 0.24, 0.18
    P_HEATUP, T_START_COLD, T_START_WARM, T_STEADY, T_AMB = 1000.0, 825.0, 200.0, 2400.0, 36000.0
    T_STOP, T_SUP, T_RET_MAX, SLEW, P_IDLE = 84.0, 80.0, 75.0, 0.025, 35.0

    def __init__(self, downtime_at_start: float = 36000.0):
        self.tab = chp_tables()
        self.running = False
        self.t_on = -1e9
        self.t_off = -downtime_at_start  # the machine has stood for this long at time 0
        self.f0 = 0.0
        self.t_start = self.T_START_COLD
        self.cooling = False
        self.q_stop = 0.0
        self.y = 0.0
        self.starts = 0
        self.q_target = self.P_heat = self.P_fuel = 0.0
        self.P_el = -self.P_IDLE
        self.T_sup_set = 20.0
        self.mode = 0  # 0 idle, 1 start-up, 2 warm-up, 3 steady, 4 cool-down

    def update(self, t: float, dt: float, on_cmd: bool, y_cmd: float, T_ret: float) -> None:
        """Decide this step's pump flow, heat, fuel and electricity from the commands and T_ret."""
        on = on_cmd and T_ret < self.T_RET_MAX
        if on and not self.running:
            down = t - self.t_off
            self.running, self.t_on, self.cooling = True, t, False
            self.f0 = min(1.0, down / self.T_AMB)
            self.t_start = self.T_START_COLD if down > self.T_AMB else self.T_START_WARM
            self.starts += 1
        elif not on and self.running:
            self.running, self.t_off, self.cooling, self.q_stop = False, t, True, self.q_target
        tab = self.tab
        if self.running:
            tau = t - self.t_on
            penalty = self.P_HEATUP * max(0.0, self.f0 - tau / self.T_STEADY)
            if tau < self.t_start:
                self.mode = 1
                y_req = 1.0
                fuel_full = self.P_EL_MAX / self.ETA_EL_MAX
                self.P_el = tab["startup"](tau, 1) * self.P_EL_MAX
                self.P_fuel = max(0.0, tab["startup"](tau, 4) * fuel_full)
                eta = tab["efficiency"](max(T_ret, 20.0), max(self.M_MIN, self.y))
                self.P_heat = max(0.0, tab["startup"](tau, 3) * fuel_full * (eta - self.ETA_EL_MAX) - penalty)
                self.T_sup_set = max(T_ret + 1.0, tab["startup"](tau, 5))
            else:
                self.mode = 2 if tau < self.T_STEADY else 3
                y_req = min(1.0, y_cmd)
                m = min(1.0, max(self.M_MIN, self.y))
                eta_el = self.ETA_EL_MIN + (self.ETA_EL_MAX - self.ETA_EL_MIN) * (m - self.M_MIN) / (1 - self.M_MIN)
                self.P_el = m * self.P_EL_MAX
                self.P_fuel = self.P_el / eta_el
                eta = tab["efficiency"](max(T_ret, 20.0), m)
                self.P_heat = max(0.0, self.P_fuel * (eta - eta_el) - penalty)
                self.T_sup_set = self.T_SUP
            self.q_target = self.P_heat / (CP * max(1.0, self.T_sup_set - T_ret))
        else:
            y_req = 0.0
            self.P_fuel = 0.0
            tau = t - self.t_off
            if self.cooling and tau < self.T_STOP:
                self.mode = 4
                self.T_sup_set = tab["cooldown"](tau, 1)
                self.q_target = tab["cooldown"](tau, 2) * self.q_stop
                self.P_heat = max(0.0, self.q_target * CP * (self.T_sup_set - T_ret))
                self.P_el = tab["cooldown"](tau, 3)
            else:
                self.cooling = False
                self.mode = 0
                self.q_target = self.P_heat = 0.0
                self.P_el = -self.P_IDLE
        step = self.SLEW * dt
        self.y += max(-step, min(step, y_req - self.y))

    def meter(self, T_ret: float, T_sup: float) -> float:
        """The unit's own heat counter: its pump's flow x (outlet - return)."""
        return self.q_target * CP * (T_sup - T_ret)


class Boiler:
    """Wolf CGB-14 on its 0-10 V input. `heat_factor` < 1 is a degraded unit (less heat, same fuel)."""

    P_NOM, M_MIN, ETA_MAX, DT_SET, T_START, T_STOP, SLEW, P_IDLE = 14000.0, 0.2, 1.05, 20.0, 300.0, 70.0, 0.025, 35.0

    def __init__(self, heat_factor: float = 1.0):
        self.tab = boiler_tables()
        self.heat_factor = heat_factor
        self.running = False
        self.locked = False
        self.t_on = self.t_off = -1e9
        self.cooling = False
        self.q_stop = self.P_stop = 0.0
        self.y = 0.0
        self.starts = 0
        self.q_target = self.P_heat = self.P_fuel = 0.0
        self.P_el = -self.P_IDLE
        self.mode = 0

    def steady(self, T_ret: float, m: float) -> tuple[float, float, float]:
        """(heat W, flow kg/s, fuel W) in steady state at return T_ret and modulation m."""
        tab = self.tab
        T = max(T_ret, 20.0)
        p_nominal = tab["heat"](T, m) * self.P_NOM
        spread = tab["spread"](T, m) * self.DT_SET
        eta = tab["efficiency"](T, m) * self.ETA_MAX
        heat = p_nominal * self.heat_factor
        return heat, heat / (CP * spread), p_nominal / eta

    def update(self, t: float, dt: float, U: float, T_ret: float) -> None:
        if T_ret > 75.0:
            self.locked = True
        elif T_ret < 70.0:
            self.locked = False
        on = U > 2.0 and not self.locked
        if on and not self.running:
            self.running, self.t_on, self.cooling = True, t, False
            self.starts += 1
        elif not on and self.running:
            self.running, self.t_off, self.cooling = False, t, True
            self.q_stop, self.P_stop = self.q_target, self.P_heat
        tab = self.tab
        if self.running:
            y_req = min(1.0, U / 10.0)
            m = min(1.0, max(self.M_MIN, self.y))
            heat, q, fuel = self.steady(T_ret, m)
            tau = t - self.t_on
            if tau < self.T_START:
                self.mode = 1
                self.P_heat = tab["startup"](tau, 1) * heat
                self.q_target = max(1e-4, tab["startup"](tau, 2) * q)
            else:
                self.mode = 2
                self.P_heat, self.q_target = heat, q
            self.P_fuel = fuel
            self.P_el = 0.0
        else:
            y_req = 0.0
            self.P_fuel = 0.0
            tau = t - self.t_off
            if self.cooling and tau < self.T_STOP:
                self.mode = 3
                self.P_heat = tab["cooldown"](tau, 1) * self.P_stop
                self.q_target = tab["cooldown"](tau, 2) * self.q_stop
                if self.q_target < 1e-4:
                    self.P_heat = 0.0
                self.P_el = -self.P_IDLE
            else:
                self.cooling = False
                self.mode = 0
                self.q_target = self.P_heat = 0.0
                self.P_el = -self.P_IDLE
        step = self.SLEW * dt
        self.y += max(-step, min(step, y_req - self.y))


def outlet(T_in: float, heat: float, q: float) -> tuple[float, float]:
    """(outlet temperature, heat actually put into the water) for a flow q through a generator."""
    if q < 1e-6:
        return T_in, 0.0
    return T_in + heat / (CP * q), heat


def massive_outlet(T_node: float, C: float, T_in: float, heat: float, q: float,
                   dt: float) -> tuple[float, float, float]:
    """A generator whose water and metal (C [J/K]) form one mixed node on its outlet, over dt:
    (node temperature after, mean outlet temperature, heat given to the water [W]). Exact for
    constant heat and flow (exponential approach to T_in + heat / (q c)), so any C and step are
    stable; what leaves with the water is the heat put in less the node's change of heat."""
    if q < 1e-6:
        return T_node + heat * dt / C, T_node, 0.0
    g = q * CP
    T_eq = T_in + heat / g
    T_new = T_eq + (T_node - T_eq) * math.exp(-g * dt / C)
    Q_water = heat - C * (T_new - T_node) / dt
    return T_new, T_in + Q_water / g, Q_water


__all__ = ["CHP", "Boiler", "outlet", "massive_outlet", "CP"]
