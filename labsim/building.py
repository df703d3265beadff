"""labsim heating circuit and building: mixing station, radiator, two-node RC building.

Mixing station (reference 9.8, ideal three-way mixing): the circuit pump moves m_sec (the
commanded flow); the valve takes the share x = (T_set - T_ret) / (T_S - T_ret), clipped to 0..1,
from the supply header, the rest is recirculated radiator return. A leaking valve passes at least
`leak` of the circuit flow from the header even when closed (x >= leak).

Radiator: three water nodes in series (0.12 m3 of water with the circuit's pipes, 40 kg each),
each emitting Q_N/3 (dT / dT_N)^n with dT its over-temperature above the room, n = 1.3,
Q_N = 8778 W and dT_N = 31.5 K (the mean over-temperature at 60/45/21 degC; reference 9.7 and
12.1: 22 W/m2 x 2 floors x 199.5 m2).

Building (labsim's own lumping of house 1, 300 m2 on two floors, reference 9.2-9.3): an air node
(air, furniture, light inner walls: C_a = 8 MJ/K) and a mass node (slabs and outer walls:
C_m = 80 MJ/K); air to outdoor H_ao = 180 W/K (windows 58.5 m2 x 1.7 W/(m2 K) and 0.2 1/h of
ventilation and leakage of the 1037 m3), air to mass H_am = 2500 W/K (7.7 W/(m2 K) over ~320 m2 of
inner surfaces), mass to outdoor H_mo = 120 W/K (opaque walls 304 m2 x 0.5 W/(m2 K) less the share
of the unheated roof and cellar). Steady loss coefficient ~295 W/K. Gains: 110 W per person
present (6 people) and all household electricity into the air; solar 6 m2 x (beam + diffuse
horizontal) onto the mass.
"""
from __future__ import annotations

CP = 4180.0


class MixingStation:
    def __init__(self, leak: float = 0.0):
        self.leak = leak
        self.share = 0.0
        self.m_sec = 0.0

    def primary_target(self, m_sec: float, T_set: float, T_S: float, T_ret: float) -> float:
        """Primary flow the valve asks of the supply header for this step."""
        self.m_sec = m_sec
        if m_sec <= 0.0:
            self.share = 0.0
            return 0.0
        x = 1.0 if T_S - T_ret < 0.1 else (T_set - T_ret) / (T_S - T_ret)
        self.share = max(self.leak, min(1.0, max(0.0, x)))
        return self.share * m_sec

    def supply(self, q_primary: float, T_S: float, T_ret: float) -> float:
        """Circuit supply temperature for the primary flow the network delivered."""
        if self.m_sec <= 0.0:
            return T_ret
        q = min(q_primary, self.m_sec)
        return (q * T_S + (self.m_sec - q) * T_ret) / self.m_sec


class Radiator:
    NODES, MASS, Q_N, DT_N, EXP = 3, 120.0, 8778.0, 31.5, 1.3

    def __init__(self, T0: float = 30.0, Q_N: float = Q_N, mass: float = MASS):
        self.Q_N, self.MASS = Q_N, mass
        self.T = [T0] * self.NODES
        self.Q = 0.0

    def step(self, dt: float, m: float, T_in: float, T_room: float) -> float:
        """Advance the nodes; returns the emitted heat [W] (also self.Q)."""
        mk = self.MASS / self.NODES
        q_node = self.Q_N / self.NODES
        total = 0.0
        prev = T_in
        new = []
        for T in self.T:
            d = max(0.0, T - T_room)
            emit = q_node * (d / self.DT_N) ** self.EXP
            total += emit
            new.append(T + dt * (m * CP * (prev - T) - emit) / (mk * CP))
            prev = T
        self.T = new
        self.Q = total
        return total

    @property
    def T_ret(self) -> float:
        return self.T[-1]

    def energy(self) -> float:
        return sum(self.T) * self.MASS / self.NODES * CP


class Building:
    C_A, C_M, H_AO, H_AM, H_MO, A_SOL, PEOPLE, W_PERSON = 8e6, 80e6, 180.0, 2500.0, 120.0, 6.0, 6, 110.0

    def __init__(self, T_air: float = 20.5, T_mass: float = 20.0):
        self.T_air, self.T_mass = T_air, T_mass

    def step(self, dt: float, Q_heat: float, T_out: float, presence: float, P_el: float,
             E_glob: float) -> None:
        gains = presence * self.PEOPLE * self.W_PERSON + P_el
        solar = self.A_SOL * max(0.0, E_glob)
        q_am = self.H_AM * (self.T_air - self.T_mass)
        dTa = (Q_heat + gains - self.H_AO * (self.T_air - T_out) - q_am) / self.C_A
        dTm = (q_am + solar - self.H_MO * (self.T_mass - T_out)) / self.C_M
        self.T_air += dt * dTa
        self.T_mass += dt * dTm


__all__ = ["MixingStation", "Radiator", "Building", "CP"]
