"""FmuHouse: a house whose whole plant is one FMU, with the House API the gateway uses.

    house = load_house("my_house.toml")          # [house] topology = "fmu" -> FmuHouse
    house.set("boiler.U_set", 10.0); house.step(1.0); house.get("storage.T_sensor_1")

The house file (syntax: plant/fmu/housefile.py) binds catalogue signals (plant/catalogue.py,
so the device maps bind by name) to FMU variables, with units converted where they differ
(plant.fmu.binding.unit_conversion).  Catalogue inputs bind to FMU inputs, outputs to FMU
outputs.  `catalogue` holds the bound signals only, in catalogue order; a signal the file does
not bind is absent: get() raises a SignalError naming the house file and the [bindings] table,
the map lint (`lint_all(maps, house.catalogue, house.name)`) reports each map point bound to it,
and a Modbus read of such a point is answered with exception 04 (the message in the log).

Time: step(dt) writes the inputs and advances the FMU by dt (one doStep, or for a model-exchange
FMU one integration over dt with fmpy's CVode/Euler; `max_step` in the file splits dt into
equal FMU steps), on the caller's clock - lock-step, paced real time or accelerated alike.

Inputs hold their value between steps.  Until set they hold the FMU's start value; release(name)
returns an input to that start value (the FMU's own "no command" state) - the FMU has no
built-in controller the twin could hand it to.  `controller` is accepted for load_house
compatibility and recorded; what the FMU does without commands is the FMU's business (e.g. the
exported house FMU's `use_builtin_controller` parameter, set in [parameters]).

Not available: snapshot/restore (an FMU's state cannot be copied portably), ledger() and
stored_energy() (no energy bookkeeping inside a foreign plant); each raises ConfigError.
"""
from __future__ import annotations

import math

import numpy as np

from ..catalogue import CATALOGUE
from ..errors import ConfigError, SignalError
from ..signals import Signal, SignalCatalogue
from .component import open_fmu


class FmuHouse:
    def __init__(self, spec, start: str | None = None, controller: str = "external"):
        self.spec = spec
        self.name = spec.name
        self.start = start or spec.start
        self.controller = controller
        bound = [s for s in CATALOGUE if s.name in spec.bindings]
        self.catalogue = SignalCatalogue([Signal(s.name, s.unit, s.causality, s.description) for s in bound])
        self._inputs = [s.name for s in self.catalogue if s.causality == "input"]
        self._outputs = [s.name for s in self.catalogue if s.causality != "input"]
        self._in_index = np.array([self.catalogue.index(n) for n in self._inputs], dtype=np.int64)
        self._out_index = np.array([self.catalogue.index(n) for n in self._outputs], dtype=np.int64)
        self._fmu = None
        self.reset()

    # --- state -----------------------------------------------------------------------------
    def _binding(self, name):
        var, unit = self.spec.bindings[name]
        return (var, CATALOGUE.signal(name).unit, unit) if unit is not None else (var, CATALOGUE.signal(name).unit)

    def reset(self) -> None:
        """(Re)instantiate the FMU at time 0; inputs back to the FMU's start values."""
        self.close()
        sp = self.spec
        options = {}
        if sp.solver is not None:
            options = {"solver": sp.solver, "relative_tolerance": sp.relative_tolerance}
            if sp.step_size is not None:
                options["step_size"] = sp.step_size
        self._fmu = open_fmu(sp.fmu, inputs={n: self._binding(n) for n in self._inputs},
                             outputs={n: self._binding(n) for n in self._outputs},
                             parameters=dict(sp.parameters), instance_name=self.name, **options)
        self.t = 0.0
        self._s = np.zeros(len(self.catalogue))
        self._s[self._in_index] = self._fmu.input_starts
        self._remote = np.zeros(len(self.catalogue), dtype=np.bool_)
        self._s[self._out_index] = self._fmu.read_outputs()

    def close(self) -> None:
        """Free the FMU instance; the house cannot step afterwards (reset() makes a new one)."""
        if self._fmu is not None:
            self._fmu.close()
            self._fmu = None

    def _no(self, what: str):
        return ConfigError(f"{self.name}: {what} is not available when the plant is an FMU "
                           f"({self.spec.fmu}, house file {self.spec.path})")

    def snapshot(self):
        raise self._no("snapshot/restore (the FMU's state cannot be copied)")

    def restore(self, snap) -> None:
        raise self._no("snapshot/restore (the FMU's state cannot be copied)")

    def ledger(self) -> dict[str, float]:
        raise self._no("the energy ledger")

    def stored_energy(self) -> float:
        raise self._no("the stored energy")

    # --- signals ---------------------------------------------------------------------------
    def _signal(self, name: str) -> Signal:
        if name in self.catalogue:
            return self.catalogue.signal(name)
        CATALOGUE.signal(name)  # SignalError with close matches for a name that is no signal at all
        raise SignalError(f"{name}: not provided by house {self.name!r}: its plant is the FMU "
                          f"{self.spec.fmu.name} and {self.spec.path} does not bind {name!r} in "
                          f"[bindings]; bound: {', '.join(self.catalogue.names)}")

    def get(self, name: str) -> float:
        return float(self._s[self._signal(name).index])

    def values(self) -> np.ndarray:
        """All bound signal values in `catalogue` order (a copy)."""
        return self._s.copy()

    def set(self, name: str, value: float) -> None:
        sig = self._signal(name)
        self._s[sig.index] = sig.input_value(value, self._inputs)
        self._remote[sig.index] = True

    def release(self, name: str) -> None:
        sig = self._signal(name)
        sig.require_input()
        self._remote[sig.index] = False
        self._s[sig.index] = self._fmu.input_starts[self._inputs.index(name)]

    def is_remote(self, name: str) -> bool:
        return bool(self._remote[self._signal(name).index])

    # --- time ------------------------------------------------------------------------------
    def step(self, dt: float) -> None:
        """Advance by dt seconds: inputs to the FMU, FMU step(s), outputs back."""
        if not dt > 0 or not math.isfinite(dt):
            raise ValueError(f"step: dt = {dt}; must be a positive number of seconds")
        if self._fmu is None:
            raise ConfigError(f"{self.name}: the FMU was closed; reset() instantiates it again")
        n = max(1, math.ceil(dt / self.spec.max_step - 1e-9)) if self.spec.max_step else 1
        self._fmu.set_inputs(self._s[self._in_index])
        for _ in range(n):
            y = self._fmu.step(dt / n)
        self._s[self._out_index] = y
        self.t += dt

    def run(self, duration: float, dt: float = 1.0, out_interval: float = 60.0, progress=None):
        """Like House.run: (times [s], rows [n, bound signals]) every out_interval seconds."""
        if not dt > 0:
            raise ValueError(f"run: dt = {dt}; must be positive")
        every = max(1, int(round(out_interval / dt)))
        if abs(every * dt - out_interval) > 1e-6 * out_interval:
            raise ValueError(f"run: out_interval = {out_interval} s must be a multiple of the step {dt} s")
        n = int(round(duration / dt))
        times, rows = [], []
        for k in range(1, n + 1):
            self.step(dt)
            if k % every == 0:
                times.append(self.t)
                rows.append(self._s.copy())
            if progress and k % max(1, int(86400 / dt)) == 0:
                progress(k * dt)
        return np.array(times), np.array(rows).reshape(len(rows), len(self.catalogue))


__all__ = ["FmuHouse"]
