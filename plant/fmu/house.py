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

Bindings and replay as the native house (the Plant protocol, plant/protocol.py): bind() makes
inputs follow a time series (linear at each step's midpoint, or hold), drive() replays a command
table from t = 0 with a change applied at the midpoint between two samples.

Not available: snapshot/restore (an FMU's state cannot be copied portably), ledger() and
stored_energy() (no energy bookkeeping inside a foreign plant), state()/set_state() (an FMU has
no per-instance state vector the twin could address); each raises ConfigError naming it.
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
        self._series: dict[int, tuple] = {}  # bound input index -> (times, values, linear)

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

    def state(self, instance: str) -> np.ndarray:
        raise self._no(f"state({instance!r}) (an FMU has no per-instance state vector)")

    def set_state(self, instance: str, values) -> None:
        raise self._no(f"set_state({instance!r}) (an FMU has no per-instance state vector)")

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

    # --- bindings: inputs that follow a time series ------------------------------------------
    def bind(self, names: list[str], times, values, interpolation: str = "linear") -> None:
        """Inputs `names` follow the columns of `values` [len(times), len(names)] over `times`
        [s since start], as House.bind: "linear" at each step's midpoint, "hold" keeps a sample
        until the next; bound inputs are remote."""
        if interpolation not in ("linear", "hold"):
            raise ValueError(f"bind: interpolation = {interpolation!r}; allowed: linear, hold")
        times = np.asarray(times, dtype=np.float64)
        values = np.asarray(values, dtype=np.float64).reshape(len(times), len(names))
        if len(times) == 0 or not np.all(np.diff(times) > 0):
            raise ValueError("bind: times must be increasing, at least one sample")
        for j, n in enumerate(names):
            sig = self._signal(n)
            sig.require_input()
            self._series[sig.index] = (times, values[:, j].copy(), interpolation == "linear")
            self._remote[sig.index] = True

    def unbind(self, names: list[str] | None = None) -> None:
        """Stop following the series of `names` (all when None); they keep their last value."""
        if names is None:
            self._series.clear()
            return
        for n in names:
            self._series.pop(self._signal(n).index, None)

    def _follow(self, t: float) -> None:
        """Bound inputs at time t (a step's midpoint)."""
        for i, (times, values, linear) in self._series.items():
            if linear:
                self._s[i] = np.interp(t, times, values)
            else:
                self._s[i] = values[max(0, int(np.searchsorted(times, t, side="right")) - 1)]

    def advance(self, t: float) -> None:
        """Advance to time t [s since start]."""
        if t > self.t:
            self.step(t - self.t)

    def drive(self, times: np.ndarray, names: list[str], cmd: np.ndarray) -> np.ndarray:
        """Replay a command table from t = 0, as House.drive: the inputs `names` hold cmd[i] from
        the midpoint before times[i] to the midpoint after it; returns the bound signals at
        `times` [len(times), signals]. A span is split at the midpoint and into steps of at most
        5 s (the native house's internal step)."""
        times = np.asarray(times, dtype=np.float64)
        cmd = np.asarray(cmd, dtype=np.float64).reshape(len(times), len(names))
        if self.t != 0.0 or not np.all(np.diff(times) > 0) or times[0] < 0:
            raise ValueError("drive: starts at t = 0 with increasing sample times >= 0")
        switch = np.concatenate([[min(0.0, times[0])], 0.5 * (times[:-1] + times[1:])])
        self.bind(names, switch, cmd, interpolation="hold")
        out = np.empty((len(times), len(self.catalogue)))
        for i, t in enumerate(times):
            edges = [e for e in (switch[i],) if self.t < e < t] + [t]
            for e in edges:
                while e - self.t > 1e-9:
                    self.step(min(5.0, e - self.t))
            self._follow(t)
            out[i] = self._s
        return out

    # --- time ------------------------------------------------------------------------------
    def step(self, dt: float) -> None:
        """Advance by dt seconds: inputs to the FMU, FMU step(s), outputs back."""
        if not dt > 0 or not math.isfinite(dt):
            raise ValueError(f"step: dt = {dt}; must be a positive number of seconds")
        if self._fmu is None:
            raise ConfigError(f"{self.name}: the FMU was closed; reset() instantiates it again")
        n = max(1, math.ceil(dt / self.spec.max_step - 1e-9)) if self.spec.max_step else 1
        self._follow(self.t + 0.5 * dt)
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
