"""House: a house declaration compiled into one step (plant/compiler.py), stepped in SI units.

    house = load_house("house1")                 # or a path to a .toml
    house.step(60.0)                             # advance 60 s (split into steps <= 5 s)
    house.get("storage.T_top")                   # any catalogue signal
    house.set("boiler.U_set", 10.0)              # drive an input from outside ...
    house.release("boiler.U_set")                # ... and hand it back to the built-in control
    times, rows = house.run(86400, dt=1.0, out_interval=60.0)

This is the Plant protocol every user outside plant/ relies on: step/advance, get/set/release,
drive (a command table), snapshot/restore, ledger, the catalogue. Deterministic: the same house
file, start and inputs give the same results bit for bit. Not thread-safe: callers that serve it
to several clients serialise access.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from . import boundary, compiler, declaration
from .compiler import Instance
from .errors import ConfigError, closest
from .schedule import drive_steps, n_steps, run_steps

CONTROLLERS = ("rule_based", "external")
SUPERVISORY = ("rule_based", "heat_pump_rules", "soc_rules", "substation_rules")  # whose commands "external" hands to the gateway


@dataclass(frozen=True)
class Snapshot:
    t: float
    x: np.ndarray
    signals: np.ndarray
    remote: np.ndarray
    ledger: np.ndarray


def load_spec(name_or_path: str | Path = "house1", overrides: dict | None = None):
    """Read and check a house file without building it: a Declaration (native house) or an
    FmuHouseSpec ([house] topology = "fmu"); every problem of the file at once."""
    path = declaration.resolve(name_or_path)
    doc = declaration.read(path)
    if isinstance(doc.get("house"), dict) and doc["house"].get("topology") == "fmu":
        from .fmu.housefile import load as load_fmu

        if overrides:
            raise ConfigError(f"{path}: overrides ({', '.join(overrides)}) apply to native houses only; "
                              "this house's plant is an FMU ([house] topology = \"fmu\")")
        return load_fmu(path)
    decl = declaration.load(path, overrides)
    compiler.catalogue_of(path, overrides)  # the compiler's checks (ports, links, signals)
    return decl


def load_house(name_or_path: str | Path = "house1", start: str | None = None,
               controller: str = "rule_based", overrides: dict | None = None):
    """Assemble a house from its file; every problem is reported before the first step.

    overrides: {"instance.key": value}, e.g. {"storage.UA_loss": 25.0,
    "switch.idle_flow.chp": 0.2}, validated like the file's own values.
    A house file with [house] topology = "fmu" gives an FmuHouse (plant/fmu/house.py).
    """
    if controller not in CONTROLLERS:
        raise ConfigError(f"controller = {controller!r}: unknown; allowed: {', '.join(CONTROLLERS)}")
    path = declaration.resolve(name_or_path)
    doc = declaration.read(path)
    if isinstance(doc.get("house"), dict) and doc["house"].get("topology") == "fmu":
        from .fmu.house import FmuHouse

        return FmuHouse(load_spec(path, overrides), start=start, controller=controller)
    # the document just read is parsed (declaration.load would read it again)
    return House(declaration.parse(doc, path, path.read_text(), overrides), start=start, controller=controller)


class House:
    def __init__(self, decl: declaration.Declaration, start: str | None = None,
                 controller: str = "rule_based"):
        if controller not in CONTROLLERS:
            raise ConfigError(f"controller = {controller!r}: unknown; allowed: {', '.join(CONTROLLERS)}")
        self.decl = decl
        self.name = decl.name
        self.start = start or decl.start
        weather = Instance("weather", "profiles", None, {"tau0": boundary.tau0(self.start, decl.typeday)},
                           f"{decl.path} [profiles]", -1)
        decl = replace(decl, instances={"weather": weather, **{k: v for k, v in decl.instances.items()
                                                              if k != "weather"}},
                       prof=boundary.profiles(decl.typeday, decl.household_kwh_per_year,
                                              decl.dhw_litres_per_day, decl.dhw_series))
        self.decl = decl
        plant = compiler.compile_plant(decl)
        plant.module = compiler.load_module(plant.source)
        self._plant = plant
        self.catalogue = plant.catalogue
        self._inputs = tuple(s.name for s in self.catalogue.inputs())
        self._controller = controller
        self._supervised = [n for inst in decl.instances.values() if inst.kind in SUPERVISORY
                            for n in _output_signals(inst)]
        from .kinds import KINDS

        self._runtimes = [inst for inst in decl.instances.values() if getattr(KINDS[inst.kind], "runtime", False)]
        self._running: dict[str, int] = {}
        self.reset()

    # --- state -----------------------------------------------------------------------------
    def reset(self) -> None:
        P = self._plant
        self.t = 0.0
        self._x = P.x0.copy()
        self._ia = tuple(a.copy() for a in P.ia)
        self._fa = tuple(a.copy() for a in P.fa)
        self._s = np.zeros(len(self.catalogue))
        self._remote = np.zeros(len(self.catalogue), dtype=np.bool_)
        self._ledger = np.zeros(len(P.ledger))
        self.unbind()
        self._start_runtimes()
        if self._controller == "external":
            for name in self._supervised:
                self._remote[self.catalogue.index(name)] = True
        self._E0 = self.stored_energy()
        self._advance(0.0, 1)  # one zero-length step fills every signal

    def _start_runtimes(self) -> None:
        """(Re)start the instances that run outside the compiled step (FMUs) at time 0."""
        from .kinds import KINDS

        self.close()
        for inst in self._runtimes:
            a, b = self._plant.x_slices[inst.name]
            pa, pb = self._plant.p_slices[inst.name + "_fmu"]
            self._running[inst.name] = KINDS[inst.kind].start(inst, self._x[a:b], self._plant.p[pa:pb])

    def close(self) -> None:
        """Free the FMU instances (if any); the house cannot step afterwards."""
        from .kinds import KINDS

        for inst in self._runtimes:
            if inst.name in self._running:
                KINDS[inst.kind].stop(self._running.pop(inst.name))

    def snapshot(self) -> Snapshot:
        if self._runtimes:
            raise ConfigError(f"{self.name}: snapshot/restore are not available while "
                              f"{', '.join(i.name for i in self._runtimes)} runs as an FMU (its state "
                              "cannot be copied)")
        return Snapshot(self.t, self._x.copy(), self._s.copy(), self._remote.copy(), self._ledger.copy())

    def restore(self, snap: Snapshot) -> None:
        self.t = snap.t
        self._x = snap.x.copy()
        self._s = snap.signals.copy()
        self._remote = snap.remote.copy()
        self._ledger = snap.ledger.copy()

    def state(self, instance: str) -> np.ndarray:
        """A copy of one instance's state vector (e.g. the storage layer temperatures, top first)."""
        if instance not in self._plant.x_slices:
            raise ConfigError(f"{self.name}: no state of {instance!r}; instances with a state: "
                              + ", ".join(closest(instance, self._plant.x_slices)
                                          or sorted(self._plant.x_slices)))
        a, b = self._plant.x_slices[instance]
        return self._x[a:b].copy()

    def set_state(self, instance: str, values) -> None:
        """Overwrite one instance's state (e.g. storage layers from measured sensors) and refresh
        every signal with a zero-length step."""
        a, b = self._plant.x_slices[instance] if instance in self._plant.x_slices else (None, None)
        if a is None:
            self.state(instance)  # ConfigError naming the instances with a state
        values = np.asarray(values, dtype=np.float64)
        if values.shape != (b - a,) or not np.all(np.isfinite(values)):
            raise ValueError(f"set_state {instance}: {b - a} finite values expected, got shape {values.shape}")
        self._x[a:b] = values
        self._advance(0.0, 1)

    # --- signals ---------------------------------------------------------------------------
    def get(self, name: str) -> float:
        return float(self._s[self.catalogue.index(name)])

    def values(self) -> np.ndarray:
        """All signal values in catalogue order (a copy)."""
        return self._s.copy()

    def set(self, name: str, value: float) -> None:
        sig = self.catalogue.signal(name)
        self._s[sig.index] = sig.input_value(value, self._inputs)
        self._remote[sig.index] = True

    def release(self, name: str) -> None:
        sig = self.catalogue.signal(name)
        sig.require_input()
        self._remote[sig.index] = False

    def is_remote(self, name: str) -> bool:
        return bool(self._remote[self.catalogue.index(name)])

    # --- time ------------------------------------------------------------------------------
    def _args(self):
        P = self._plant
        return (self._x, P.p, self._s, self._remote, self._ledger, P.tabs, P.prof, self._ia, self._fa,
                self._bind)

    def _advance(self, dt: float, n: int, out=None, rec_every: int = 0) -> int:
        h = dt / n
        out = out if out is not None else np.zeros((0, len(self.catalogue) + 1))
        rows = self._plant.module.advance(run_steps(self.t, h, n), *self._args(), out, rec_every)
        self.t += dt
        return rows

    # --- bindings: inputs that follow a time series ------------------------------------------
    def bind(self, names: list[str], times, values, interpolation: str = "linear") -> None:
        """Inputs `names` follow the columns of `values` [len(times), len(names)] over `times`
        [s since start]: the one way anything outside drives an input over time (replay of
        commands, measured boundaries of a cut, FMU inputs). "linear" interpolates at each step's
        midpoint, "hold" keeps a sample until the next. Bound inputs are remote (the house's own
        controllers leave them alone); replaces earlier bindings of the same inputs."""
        if interpolation not in ("linear", "hold"):
            raise ValueError(f"bind: interpolation = {interpolation!r}; allowed: linear, hold")
        idx = []
        for n in names:
            sig = self.catalogue.signal(n)
            sig.require_input()
            idx.append(sig.index)
        times = np.ascontiguousarray(times, dtype=np.float64)
        values = np.ascontiguousarray(values, dtype=np.float64).reshape(len(times), len(idx))
        if len(times) == 0 or not np.all(np.diff(times) > 0):
            raise ValueError("bind: times must be increasing, at least one sample")
        bt, bv, bidx, bmode = self._bind
        keep = [j for j, i in enumerate(bidx) if i not in idx]
        mode = 1 if interpolation == "linear" else 0
        if keep and not np.array_equal(bt, times):  # one time grid: bring the kept ones onto it
            bv_old = np.column_stack([np.interp(times, bt, bv[:, j]) if bmode[j] else
                                      bv[np.clip(np.searchsorted(bt, times, "right") - 1, 0, len(bt) - 1), j]
                                      for j in keep])
        else:
            bv_old = bv[:, keep] if keep else np.zeros((len(times), 0))
        self._bind = (times, np.ascontiguousarray(np.column_stack([bv_old, values])),
                      np.array([bidx[j] for j in keep] + idx, dtype=np.int64),
                      np.array([bmode[j] for j in keep] + [mode] * len(idx), dtype=np.int64))
        self._remote[idx] = True

    def unbind(self, names: list[str] | None = None) -> None:
        """Stop following the series of `names` (all when None); they keep their last value."""
        if names is None or not hasattr(self, "_bind"):
            self._bind = (np.zeros(1), np.zeros((1, 0)), np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64))
            return
        drop = {self.catalogue.index(n) for n in names}
        bt, bv, bidx, bmode = self._bind
        keep = [j for j, i in enumerate(bidx) if i not in drop]
        self._bind = (bt, np.ascontiguousarray(bv[:, keep]), bidx[keep], bmode[keep])

    def advance(self, t: float) -> None:
        """Advance to time t [s since start] (the Plant protocol's clock-driven form of step)."""
        if t > self.t:
            self.step(t - self.t)

    def drive(self, times: np.ndarray, names: list[str], cmd: np.ndarray) -> np.ndarray:
        """Replay a command table from t = 0: the inputs `names` hold cmd[i] from times[i] to
        times[i + 1] (a change is applied at the midpoint); returns the signals at `times`
        [len(times), signals]. Spans are cut at whole minutes and split into steps of at most
        5 s. The inputs are set remote (the house's own controller no longer writes them)."""
        times = np.ascontiguousarray(times, dtype=np.float64)
        cmd = np.ascontiguousarray(cmd, dtype=np.float64).reshape(len(times), len(names))
        if self.t != 0.0 or not np.all(np.diff(times) > 0) or times[0] < 0:
            raise ValueError("drive: starts at t = 0 with increasing sample times >= 0")
        # the commands are bound, held from the midpoint between two samples (when they changed)
        switch = np.concatenate([[min(0.0, times[0])], 0.5 * (times[:-1] + times[1:])])
        self.bind(names, switch, cmd, interpolation="hold")
        out = np.empty((len(times), len(self.catalogue)))
        self._plant.module.advance(drive_steps(times, cmd), *self._args(), out, 0)
        self.t = float(times[-1])
        return out

    def step(self, dt: float) -> None:
        """Advance by dt seconds (split into equal internal steps of at most 5 s)."""
        if not dt > 0 or not math.isfinite(dt):
            raise ValueError(f"step: dt = {dt}; must be a positive number of seconds")
        self._advance(dt, n_steps(dt))

    def run(self, duration: float, dt: float = 1.0, out_interval: float = 60.0, progress=None):
        """Simulate `duration` seconds at step dt; returns (times [s], rows [n, signals]).

        Rows are recorded every out_interval seconds (a multiple of dt); progress(t_done) is
        called about once per simulated day.
        """
        if not dt > 0:
            raise ValueError(f"run: dt = {dt}; must be positive")
        sub = n_steps(dt)
        h = dt / sub
        rec_every = max(1, int(round(out_interval / h)))
        if abs(rec_every * h - out_interval) > 1e-6 * out_interval:
            raise ValueError(f"run: out_interval = {out_interval} s must be a multiple of the step {dt} s")
        n_total = int(round(duration / h))
        chunk = max(rec_every, (int(86400 / h) // rec_every) * rec_every)
        out = np.zeros((n_total // rec_every, len(self.catalogue) + 1))
        rows = 0
        done = 0
        while done < n_total:
            n = min(chunk, n_total - done)
            rows += self._advance(n * h, n, out[rows:], rec_every)
            done += n
            if progress:
                progress(done * h)
        return out[:rows, 0], out[:rows, 1:]

    # --- energy ----------------------------------------------------------------------------
    def stored_energy(self) -> float:
        """Heat stored in all water volumes relative to 0 degC [J]."""
        from .kinds import KINDS

        E = 0.0
        for name, (a, b) in self._plant.x_slices.items():
            if name not in self.decl.instances:
                continue  # an instance's second state (filters, pressures): holds no water
            inst = self.decl.instances[name]
            E += KINDS[inst.kind].stored_energy(inst, self._x[a:b])
        return E

    def ledger(self) -> dict[str, float]:
        """Energy ledger since reset [J], per instance (fuel_chp, loss_storage ...) and summed,
        with the closure of the water-side balance."""
        L = {key: float(v) for (key, _, _), v in zip(self._plant.ledger, self._ledger)}
        total = {cat: 0.0 for cat in compiler.LEDGER_CATEGORIES}
        for (key, _, cat), v in zip(self._plant.ledger, self._ledger):
            total[cat] += float(v)
        heat_in = total["heat"]
        losses = total["loss"]
        dE = self.stored_energy() - self._E0
        L["fuel"] = total["fuel"]
        L["el_net"] = total["el"]
        L["heat_generators"] = heat_in
        L["heat_building"] = total["building"]
        L["heat_dhw"] = total["dhw"]
        L["dhw_missing"] = total["missing"]
        L["generator_losses"] = total["fuel"] - total["el"] - heat_in
        L["losses"] = losses
        L["delta_stored"] = dE
        L["residual"] = heat_in - (total["building"] + total["dhw"] + losses + dE)
        L["closure"] = abs(L["residual"]) / L["fuel"] if L["fuel"] > 0 else abs(L["residual"])
        return L


def _output_signals(inst) -> list[str]:
    out = []
    for link in (inst.options.get("outputs") or {}).values():
        out.append(link.get("signal") if isinstance(link, dict) else link)
    return [n for n in out if isinstance(n, str)]
