"""labsim sensors and the lab's data acquisition.

A temperature sensor sits in a thermowell: a first-order lag (time constant `tau`, 15 s for pipe
and tank sensors) on the fluid temperature. In a pipe that stands still (no flow in its branch)
the sensor sees the pipe water cooling toward the plant room (20 degC, time constant 1200 s)
instead. Effects a suite case adds to one sensor: an extra first-order lag (a loose thermowell,
dry contact), an offset (calibration), a dead time (the reading arrives late).

The DAQ then logs each channel with noise and quantisation (Daq.log): temperatures
+ N(0, 0.05 K) rounded to 0.1 K; flows x (1 + N(0, 1 %)) with a low-flow cut-off of 0.2 l/min,
rounded to 0.1 l/min; powers x (1 + N(0, 1 %)) rounded to 0.01 kW.
"""
from __future__ import annotations

import math
from collections import deque

import numpy as np

T_PLANT_ROOM = 20.0
TAU_STAGNANT = 1200.0


class Sensor:
    def __init__(self, T0: float, tau: float = 15.0, extra_tau: float = 0.0, offset: float = 0.0,
                 delay: float = 0.0, dt: float = 10.0, T_room: float = T_PLANT_ROOM,
                 tau_stagnant: float = TAU_STAGNANT):
        self.tau, self.extra_tau, self.offset = tau, extra_tau, offset
        self.T_room, self.tau_stagnant = T_room, tau_stagnant
        self.pipe = T0      # water at the sensor (follows the stagnant pipe when nothing flows)
        self.well = T0      # thermowell temperature
        self.slow = T0      # after the extra lag
        n = int(round(delay / dt))
        self.queue = deque([T0] * (n + 1), maxlen=n + 1) if n > 0 else None
        self.value = T0 + offset

    def reset(self, T: float) -> None:
        """Settled at T (every stage and the dead-time queue)."""
        self.pipe = self.well = self.slow = T
        if self.queue is not None:
            self.queue.extend([T] * self.queue.maxlen)
        self.value = T + self.offset

    def update(self, dt: float, T_fluid: float, flowing: bool = True) -> float:
        if flowing:
            self.pipe = T_fluid
        else:
            self.pipe += (self.T_room - self.pipe) * (1.0 - math.exp(-dt / self.tau_stagnant))
        self.well += (self.pipe - self.well) * (1.0 - math.exp(-dt / self.tau))
        self.slow = self.well if self.extra_tau <= 0 else \
            self.slow + (self.well - self.slow) * (1.0 - math.exp(-dt / self.extra_tau))
        v = self.slow
        if self.queue is not None:
            self.queue.append(v)
            v = self.queue[0]
        self.value = v + self.offset
        return self.value


class Daq:
    """Noise and quantisation of the logged channels; kinds: T, flow (l/min), power (kW), cmd."""

    NOISE = {"T": 0.05, "flow": 0.01, "power": 0.01}
    QUANTUM = {"T": 0.1, "flow": 0.1, "power": 0.01}
    FLOW_CUTOFF = 0.2  # l/min

    def __init__(self, seed: int):
        self.rng = np.random.default_rng(seed)

    def log(self, kind: str, v: np.ndarray) -> np.ndarray:
        if kind not in self.NOISE:
            return v
        sd, q = self.NOISE[kind], self.QUANTUM[kind]
        if kind == "T":
            v = v + self.rng.normal(0.0, sd, v.shape)
        else:
            v = v * (1.0 + self.rng.normal(0.0, sd, v.shape))
            if kind == "flow":
                v = np.where(np.abs(v) < self.FLOW_CUTOFF, 0.0, v)
        v = np.round(v / q) * q
        v[v == 0] = 0.0
        return v


__all__ = ["Sensor", "Daq", "T_PLANT_ROOM"]
