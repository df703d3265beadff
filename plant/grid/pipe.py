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

Assumptions: incompressible water at constant density and cp (plant/water.py); no axial
conduction and no wall heat capacity (the original GreenCity pipe has neither in its transport
part); parcels closer than `merge` K to a neighbour are merged (mass-weighted, energy exact) to
keep their number bounded.

Parameters (the lab's network pipe, reference §13.4: d = 10 cm, L = 20 m, U = 0.19 W/(m K),
initial 30 degC)

| name | unit | meaning |
|---|---|---|
| length | m | pipe length |
| diameter | m | inner diameter |
| U | W/(m K) | heat loss per metre of pipe and kelvin above T_env |
| T_init | degC | water temperature at the start |
"""
from __future__ import annotations

import math

import numpy as np

from ..water import CP, RHO

MAX_PARCELS = 64


class Pipe:
    def __init__(self, length: float, diameter: float, U: float, T_init: float, merge: float = 0.01):
        self.length, self.diameter, self.U = length, diameter, U
        self.mass = RHO * math.pi * diameter ** 2 / 4.0 * length
        self.tau = self.mass * CP / (U * length) if U > 0 else math.inf
        self.merge = merge
        self.m = np.array([self.mass])       # parcel masses from end a to end b [kg]
        self.T = np.array([float(T_init)])   # parcel temperatures [degC]
        self.E_loss = 0.0                    # heat lost to the surroundings since the start [J]

    def energy(self) -> float:
        """Heat held by the water relative to 0 degC [J]."""
        return float(CP * np.dot(self.m, self.T))

    def lose(self, dt: float, T_env: float) -> None:
        """Heat loss over dt at surroundings T_env (exact for the step, counted in E_loss)."""
        if self.tau == math.inf:
            return
        f = math.exp(-dt / self.tau)
        before = np.dot(self.m, self.T)
        self.T = T_env + (self.T - T_env) * f
        self.E_loss += CP * (before - np.dot(self.m, self.T))

    def push(self, m_in: float, T_in: float) -> tuple[float, float]:
        """Push m_in kg at T_in: > 0 in at end a, < 0 in at end b. Returns the (mass, enthalpy
        [J] relative to 0 degC) that left at the other end (mass = |m_in|)."""
        if m_in == 0.0:
            return 0.0, 0.0
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
            if abs(Ti - keep_T[-1]) < self.merge:
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
        return float(self.T[-1] if direction > 0 else self.T[0])
