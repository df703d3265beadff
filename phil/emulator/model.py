"""BenchModel: what every bench emulator shares: parameters from its file, inputs that fall back
to safe values, sensors with noise and resolution, sub-stepping, and its heat ledger.

A bench model is a small plant of its own (it shares no code with plant/): `t`, `get`, `set`,
`release`, `step(dt)` and `catalogue` are what gateway.device.plant_port.PlantPort needs, so the
gateway's Device and Modbus server serve it unchanged. Values are SI (degC, kg/s, W, J).
Readings are sampled once per model step (noise, then rounded to the resolution), so every
read between two steps sees the same value, as from a PLC's scan.
"""
from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any

import numpy as np

from plant.errors import ConfigError

#: Where each bench's parameter file lives (phil/benches/<name>.toml).
BENCHES_DIR = Path(__file__).resolve().parents[1] / "benches"


def read_params(name: str | Path) -> dict[str, Any]:
    """The parameter file of a bench (its name or a path): {'bench': {...}, 'params': {...}, 'sensors': {...}}."""
    path = Path(name)
    if path.suffix != ".toml":
        path = BENCHES_DIR / f"{name}.toml"
    if not path.exists():
        known = sorted(p.stem for p in BENCHES_DIR.glob("*.toml"))
        raise ConfigError(f"{path}: no such bench; known: {', '.join(known)}")
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{path}: {exc}; fix the TOML syntax") from exc
    doc["path"] = str(path)
    return doc


class BenchModel:
    """Base of the bench models. Subclasses declare INPUTS {name: safe value}, READINGS {name:
    true-state name}, DEFAULTS {parameter: value} and implement `advance(h)` (one sub-step)."""

    INPUTS: dict[str, float] = {}
    READINGS: dict[str, str] = {}
    DEFAULTS: dict[str, float] = {}

    def __init__(self, doc: dict[str, Any], seed: int = 0) -> None:
        params = doc.get("params", {})
        unknown = sorted(set(params) - set(self.DEFAULTS))
        if unknown:
            raise ConfigError(f"{doc.get('path', '?')} [params]: unknown {', '.join(unknown)}; "
                              f"known: {', '.join(sorted(self.DEFAULTS))}")
        self.p = {**self.DEFAULTS, **{k: float(v) for k, v in params.items()}}
        self.sensors = doc.get("sensors", {})
        self.h = float(doc.get("bench", {}).get("step_s", 0.5))
        self.rng = np.random.default_rng(seed)
        self.t = 0.0
        self.inputs = dict(self.INPUTS)
        self.x: dict[str, float] = {}     # true states and outputs
        self.ledger: dict[str, float] = {}
        self.readings: dict[str, float] = {}
        self.catalogue = frozenset(self.INPUTS) | frozenset(self.READINGS) | {"clock"}

    # --- the PlantPort face ------------------------------------------------------------------
    def get(self, name: str) -> float:
        if name in self.inputs:
            return self.inputs[name]
        return self.readings[name]

    def set(self, name: str, value: float) -> None:
        if name not in self.INPUTS:
            raise ConfigError(f"bench: no input {name!r}; inputs: {', '.join(self.INPUTS)}")
        self.inputs[name] = float(value)

    def release(self, name: str) -> None:
        """The bench PLC's own fallback when the twin stops sending: the input's safe value."""
        self.inputs[name] = self.INPUTS[name]

    def step(self, dt: float) -> None:
        """Advance by dt in sub-steps of at most the model step, then sample the sensors."""
        n = max(1, int(np.ceil(dt / self.h - 1e-9)))
        for _ in range(n):
            self.advance(dt / n)
            self.t += dt / n
            self.sample()

    # --- sensors -------------------------------------------------------------------------------
    def sample(self) -> None:
        # the PLC's own clock, sampled with the meters: the twin compares the heat both sides
        # counted over the span each side's clock says it lasted (phil/report.py)
        self.readings["clock"] = self.t
        for reading, state in self.READINGS.items():
            spec = self.sensors.get(reading, {})
            value = self.x[state] + float(spec.get("noise", 0.0)) * self.rng.standard_normal()
            resolution = float(spec.get("resolution", 0.0))
            value = round(value / resolution) * resolution if resolution > 0 else value
            # a meter's low-flow cut-off: below it the reading is 0 (noise on still water is not flow)
            self.readings[reading] = 0.0 if abs(self.x[state]) < float(spec.get("cutoff", -1.0)) else value

    def advance(self, h: float) -> None:
        raise NotImplementedError

    def stored_energy(self) -> float:
        return 0.0

    def balance(self) -> dict[str, float]:
        """The heat ledger [J] and its residual: heat in - heat out - change of stored heat."""
        return dict(self.ledger)


def pi_step(integral: float, error: float, h: float, k_p: float, t_i: float,
            lo: float, hi: float) -> tuple[float, float]:
    """One PI update with clamping anti-windup: (output, new integral)."""
    integral_new = integral + h * error / t_i if t_i > 0 else integral
    out = k_p * (error + integral_new)
    if out > hi or out < lo:
        integral_new = integral   # hold the integral while saturated
        out = k_p * (error + integral_new)
    return min(max(out, lo), hi), integral_new


def conditioning_power(x: dict[str, float], p: dict[str, float], h: float, T_set: float, mc: float,
                       T_in: float, T_sensor: float, C: float) -> None:
    """One step of a bench's heater/chiller that brings water arriving at T_in (flow capacity mc
    [W/K]) in a node of heat capacity C [J/K] to a set temperature: the followed set-point
    x['T_target'] moves towards T_set at most p['ramp_T'] K/s (its ramp limit); the feed-forward
    mc (T_target - T_in) + C dT_target/dt plus a PI (p['K_p'] W/K, p['T_i'] s) on the outlet
    sensor T_sensor ask for a power, clamped to [-P_cool_max, P_heat_max] (its capacity) and
    reached with the lag p['tau_heater']: x['P'] [W]; x['i_T'] is the PI's integral."""
    ramp = p["ramp_T"] * h
    change = min(max(T_set - x["T_target"], -ramp), ramp)
    x["T_target"] += change
    lo, hi = -p["P_cool_max"], p["P_heat_max"]
    feed_forward = mc * (x["T_target"] - T_in) + C * change / h
    correction, x["i_T"] = pi_step(x["i_T"], x["T_target"] - T_sensor, h, p["K_p"], p["T_i"],
                                   lo - feed_forward, hi - feed_forward)
    want = min(max(feed_forward + correction, lo), hi)
    x["P"] += (want - x["P"]) * min(h / p["tau_heater"], 1.0)
