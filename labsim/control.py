"""labsim controllers, written from the physics reference's words (§12.1, §12.2).

Supervisor (the published case-study rules, edge-triggered hysteresis switches, evaluated every
step on what the sensors report to the PLC, rounded to 0.1 K):
  * CHP on when the storage top sensor < 65 degC, boiler on when it is < 60 degC; each off when
    the storage bottom sensor > 70 degC. A running CHP is asked for 100 % modulation, a running
    boiler for 100 % (10 V on its 0-10 V input; the PLC's value is a percentage).
  * DHW charging pump on when the DHW top sensor < 50 degC and the heating storage top is warmer
    than it; off when the DHW top > 65 degC or the heating storage top falls below it.
Room thermostat (every 60 s): day set-point 21 degC (06:00-22:00 local time), night 18 degC.
Below set-point + 0.3 K: supply set-point 60 degC and a proportional flow, 15 l/min at 1.2 K below
set-point, at least 2 l/min, in 0.5 l/min steps; above: supply set-point 20 degC (the mixing valve
closes) with the pump circulating 2 l/min.
"""
from __future__ import annotations

L_MIN = 1.0 / 60.0  # kg/s per l/min


class Supervisor:
    def __init__(self):
        self.chp = self.boiler = self.dhw = False

    def step(self, T_top: float, T_bottom: float, T_dhw_top: float) -> None:
        T_top, T_bottom, T_dhw_top = (round(x, 1) for x in (T_top, T_bottom, T_dhw_top))
        if not self.chp and T_top < 65.0:
            self.chp = True
        elif self.chp and T_bottom > 70.0:
            self.chp = False
        if not self.boiler and T_top < 60.0:
            self.boiler = True
        elif self.boiler and T_bottom > 70.0:
            self.boiler = False
        if not self.dhw and T_dhw_top < 50.0 and T_top > T_dhw_top:
            self.dhw = True
        elif self.dhw and (T_dhw_top > 65.0 or T_top < T_dhw_top):
            self.dhw = False

    @property
    def boiler_percent(self) -> float:
        return 100.0 if self.boiler else 0.0


class Thermostat:
    PERIOD = 60.0

    def __init__(self):
        self.T_sup_set = 60.0
        self.m_flow_set = 0.0
        self.next = 0.0

    @staticmethod
    def set_point(hour: float) -> float:
        return 21.0 if 6.0 <= hour < 22.0 else 18.0

    def step(self, t: float, hour: float, T_room: float) -> None:
        if t + 1e-9 < self.next:
            return
        self.next = t + self.PERIOD
        e = self.set_point(hour) - round(T_room, 1)
        if e > -0.3:
            lmin = 15.0 * min(1.0, (e + 0.3) / 1.5)
            self.T_sup_set = 60.0
            self.m_flow_set = max(2.0, round(lmin * 2.0) / 2.0) * L_MIN
        else:
            self.T_sup_set = 20.0
            self.m_flow_set = 2.0 * L_MIN


__all__ = ["Supervisor", "Thermostat", "L_MIN"]
