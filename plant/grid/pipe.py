"""A district-heating pipe with plug flow: transport delay, heat loss to the ground, either direction.

Physics in words
----------------
The water in a pipe is a row of parcels (mass, temperature) from end `a` to end `b`. A flow from
`a` to `b` pushes a parcel in at `a` and the same mass leaves at `b` (the parcels nearest `b`,
split where needed); a flow from `b` to `a` does the reverse. Parcels do not mix with each other,
so a temperature front travels through the pipe at the water's speed and arrives after the
pipe's water mass divided by the flow (the transport delay), unsmeared. Each parcel loses heat to
its surroundings at T_env through the pipe's loss coefficient per metre U (W/(m K)):
    dT/dt = -(T - T_env) / tau,   tau = m_pipe cp / (U L)
integrated exactly over a step (the factor exp(-dt/tau) is the same for every parcel because the
loss is per metre and the parcels fill the pipe uniformly). The heat lost is counted from the
parcels' temperatures before and after, so the pipe's ledger closes to round-off whatever the step.

Assumptions: incompressible water at constant density and cp (plant/water.py); by default no axial
dispersion and no wall heat capacity (the original GreenCity pipe has neither in its transport
part); parcels closer than `merge` K to a neighbour are merged (mass-weighted, energy exact) to
keep their number bounded.

Options (default off: the pipe is then exactly the one above, bit for bit)
----------------------------------------------------------------------------
- `C_wall` [J/K], the heat capacity of the pipe wall (steel: its mass x cp; whatever else one
  lumps with it, e.g. the inner insulation layer). As in the district-heating pipe literature
  (van der Heijde et al. 2017; the Modelica Buildings PlugFlowPipe), the wall is lumped into
  well-mixed nodes the water passes through at the pipe's ends: a share `wall_share_b` at end b
  (1.0 = all at the outlet of a flow a -> b, the library's choice), the rest at end a. Water of
  mass m passing a node of capacity C (water-equivalent mass C/cp) leaves it, exactly for a
  constant inflow temperature over the step, after
      T_node' = T_in + (T_node - T_in) exp(-m cp / C),  H_out = m cp T_in - C (T_node' - T_node).
  The two halves of a symmetric split (0.5) delay a step by the same mean time C/(m_dot cp) as
  one node of C (the mean delays of lags in series add) and stay symmetric when the flow reverses.
  The nodes exchange no heat with the surroundings (the loss is the water's, per metre).
- `dispersion` [m2/s], an axial dispersion coefficient D smearing a front: neighbouring parcels
  exchange heat rho cp A D (T_i - T_j) / (distance of their centres), applied implicitly (backward
  Euler, unconditionally stable) in `lose()` over the same dt; the exchange is pairwise, so it
  moves no energy in or out. The parcels are then its grid: none is merged beyond 1/CELLS of the
  pipe's water (32 cells; a front spread over less than a cell is resolved no finer). For
  turbulent pipe flow Taylor (1954) gives D = 10.1 r u*
  (r the radius, u* the friction velocity): `taylor_dispersion()`.
The pipe's energy() includes the wall nodes, so in - out - loss - change of energy() closes to
round-off with either option on.

Parameters (the lab's network pipe, reference §13.4: d = 10 cm, L = 20 m, U = 0.19 W/(m K),
initial 30 degC)

| name | unit | meaning |
|---|---|---|
| length | m | pipe length |
| diameter | m | inner diameter |
| U | W/(m K) | heat loss per metre of pipe and kelvin above T_env |
| T_init | degC | water temperature at the start (and the wall's) |
| C_wall | J/K | wall heat capacity lumped at the ends (option, default 0) |
| wall_share_b | 1 | share of C_wall at end b (default 0.5) |
| dispersion | m2/s | axial dispersion coefficient (option, default 0) |
"""
from __future__ import annotations

import math

import numpy as np

from ..water import CP, RHO

MAX_PARCELS = 64
CELLS = MAX_PARCELS // 2   # with dispersion: the largest parcel is 1/CELLS of the pipe's water


def wall_capacity(length: float, diameter: float, thickness: float, density: float = 7850.0,
                  cp: float = 480.0) -> float:
    """Heat capacity [J/K] of a steel wall of `thickness` around an inner `diameter`."""
    return density * cp * math.pi / 4.0 * ((diameter + 2.0 * thickness) ** 2 - diameter ** 2) * length


def taylor_dispersion(diameter: float, m_flow: float, roughness: float = 1e-4) -> float:
    """Taylor's (1954) axial dispersion coefficient for turbulent pipe flow, D = 10.1 r u* [m2/s]
    (u* = v sqrt(f/8), Swamee-Jain friction factor; water near 60 degC, mu = 0.4 mPa s)."""
    v = abs(m_flow) / (RHO * math.pi * diameter ** 2 / 4.0)
    re = max(RHO * v * diameter / 4.0e-4, 2300.0)
    f = 0.25 / math.log10(roughness / (3.7 * diameter) + 5.74 / re ** 0.9) ** 2
    return 10.1 * diameter / 2.0 * v * math.sqrt(f / 8.0)


class Pipe:
    def __init__(self, length: float, diameter: float, U: float, T_init: float, merge: float = 0.01,
                 C_wall: float = 0.0, wall_share_b: float = 0.5, dispersion: float = 0.0):
        self.length, self.diameter, self.U = length, diameter, U
        self.mass = RHO * math.pi * diameter ** 2 / 4.0 * length
        self.tau = self.mass * CP / (U * length) if U > 0 else math.inf
        self.merge = merge
        self.m = np.array([self.mass])       # parcel masses from end a to end b [kg]
        self.T = np.array([float(T_init)])   # parcel temperatures [degC]
        self.E_loss = 0.0                    # heat lost to the surroundings since the start [J]
        if C_wall < 0.0 or not 0.0 <= wall_share_b <= 1.0 or dispersion < 0.0:
            raise ValueError(f"Pipe: C_wall = {C_wall} and dispersion = {dispersion} must be >= 0, "
                             f"wall_share_b = {wall_share_b} within 0 ... 1")
        self.C_end = (C_wall * (1.0 - wall_share_b), C_wall * wall_share_b)   # wall at ends a, b [J/K]
        self.T_end = [float(T_init), float(T_init)]                            # their temperatures
        self.dispersion = dispersion
        # with dispersion the parcels are its grid: no parcel grows beyond 1/CELLS of the pipe
        self.max_parcel = self.mass / CELLS if dispersion > 0.0 else math.inf
        if dispersion > 0.0:
            self.m = np.full(CELLS, self.mass / CELLS)
            self.T = np.full(CELLS, float(T_init))

    def energy(self) -> float:
        """Heat held by the water (and the wall nodes, if any) relative to 0 degC [J]."""
        if self.C_end[0] or self.C_end[1]:
            return float(CP * np.dot(self.m, self.T) + self.C_end[0] * self.T_end[0] + self.C_end[1] * self.T_end[1])
        return float(CP * np.dot(self.m, self.T))

    def lose(self, dt: float, T_env: float) -> None:
        """Heat loss over dt at surroundings T_env (exact for the step, counted in E_loss); with the
        dispersion option, also the axial dispersion over dt (energy-neutral)."""
        if self.dispersion > 0.0:
            self._disperse(dt)
        if self.tau == math.inf:
            return
        f = math.exp(-dt / self.tau)
        before = np.dot(self.m, self.T)
        self.T = T_env + (self.T - T_env) * f
        self.E_loss += CP * (before - np.dot(self.m, self.T))

    def _disperse(self, dt: float) -> None:
        """Axial dispersion over dt between neighbouring parcels (backward Euler, energy-neutral)."""
        n = len(self.m)
        if n < 2:
            return
        area = math.pi * self.diameter ** 2 / 4.0
        gap = (self.m[:-1] + self.m[1:]) / (2.0 * RHO * area)      # distance of the parcels' centres [m]
        g = dt * RHO * CP * area * self.dispersion / gap            # J/K exchanged per kelvin over dt
        a = np.diag(CP * self.m)
        i = np.arange(n - 1)
        a[i, i] += g
        a[i + 1, i + 1] += g
        a[i, i + 1] -= g
        a[i + 1, i] -= g
        self.T = np.linalg.solve(a, CP * self.m * self.T)

    def push(self, m_in: float, T_in: float) -> tuple[float, float]:
        """Push m_in kg at T_in: > 0 in at end a, < 0 in at end b. Returns the (mass, enthalpy
        [J] relative to 0 degC) that left at the other end (mass = |m_in|)."""
        if m_in == 0.0:
            return 0.0, 0.0
        if self.C_end[0] or self.C_end[1]:
            return self._push_through_wall(m_in, T_in)
        return self._push(m_in, T_in)

    def _push_through_wall(self, m_in: float, T_in: float) -> tuple[float, float]:
        """push() with the wall nodes: the water passes the node at the end it enters, the parcels,
        then the node at the end it leaves (each exact for its inflow's mean temperature)."""
        first, last = (0, 1) if m_in > 0 else (1, 0)
        m = abs(m_in)
        H = self._through_node(first, m, CP * m * T_in)
        m, H = self._push(m_in, H / (CP * m))
        return m, self._through_node(last, m, H)

    def _through_node(self, end: int, m: float, H_in: float) -> float:
        """Pass m kg carrying H_in through the wall node at `end`; returns the enthalpy leaving it."""
        C = self.C_end[end]
        if C == 0.0:
            return H_in
        T_in, T_old = H_in / (CP * m), self.T_end[end]
        T_new = T_in + (T_old - T_in) * math.exp(-m * CP / C)
        self.T_end[end] = T_new
        return H_in - C * (T_new - T_old)

    def _push(self, m_in: float, T_in: float) -> tuple[float, float]:
        m = abs(m_in)
        masses, temps = (self.m, self.T) if m_in > 0 else (self.m[::-1], self.T[::-1])
        masses = np.concatenate([[m], masses])
        temps = np.concatenate([[T_in], temps])
        # leave from the far end: whole parcels, then part of the last one
        cum = np.cumsum(masses[::-1])
        k = int(np.searchsorted(cum, m - 1e-12 * max(m, 1.0)))   # parcels [n-1-k .. n-1] leave
        n = len(masses)
        whole = cum[k - 1] if k > 0 else 0.0
        rest = m - whole
        out_H = CP * (np.dot(masses[n - k:], temps[n - k:]) + rest * temps[n - 1 - k])
        masses = masses[:n - k].copy()
        temps = temps[:n - k]
        masses[-1] -= rest
        if masses[-1] <= 1e-12 * self.mass:  # the split parcel left whole (round-off)
            masses, temps = masses[:-1], temps[:-1]
        if m_in < 0:
            masses, temps = masses[::-1], temps[::-1]
        self.m, self.T = self._merged(np.ascontiguousarray(masses), np.ascontiguousarray(temps))
        return m, float(out_H)

    def _merged(self, m: np.ndarray, T: np.ndarray):
        """Merge neighbours closer than `merge` K, and the closest pairs beyond MAX_PARCELS."""
        if len(m) < 2:
            return m, T
        keep_m, keep_T = [m[0]], [T[0]]
        for mi, Ti in zip(m[1:], T[1:]):
            if abs(Ti - keep_T[-1]) < self.merge and keep_m[-1] + mi <= self.max_parcel:
                total = keep_m[-1] + mi
                keep_T[-1] = (keep_m[-1] * keep_T[-1] + mi * Ti) / total
                keep_m[-1] = total
            else:
                keep_m.append(mi)
                keep_T.append(Ti)
        m, T = np.array(keep_m), np.array(keep_T)
        while len(m) > MAX_PARCELS:
            j = int(np.argmin(np.abs(np.diff(T)) * (m[:-1] + m[1:])))
            total = m[j] + m[j + 1]
            T[j] = (m[j] * T[j] + m[j + 1] * T[j + 1]) / total
            m[j] = total
            m, T = np.delete(m, j + 1), np.delete(T, j + 1)
        return m, T

    def outlet(self, direction: int) -> float:
        """Temperature of the water next to leave for a flow in `direction` (+1 a->b, -1 b->a)."""
        end = 1 if direction > 0 else 0
        if self.C_end[end]:
            return float(self.T_end[end])   # the outlet's wall node is well mixed
        return float(self.T[-1] if direction > 0 else self.T[0])
