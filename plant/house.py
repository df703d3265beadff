"""House: a simulated house assembled from its house file, stepped in SI units.

    house = load_house("house1")                 # or a path to a .toml
    house.step(60.0)                             # advance 60 s (split into steps <= 5 s)
    house.get("storage.T_top")                   # any catalogue signal
    house.set("boiler.U_set", 10.0)              # drive an input from outside ...
    house.release("boiler.U_set")                # ... and hand it back to the built-in control
    times, rows = house.run(86400, dt=1.0, out_interval=60.0)

Deterministic: the same house file, start and inputs give the same results bit for bit.
Not thread-safe: callers that serve it to several clients serialise access.

Heating storage as an FMU ([storage] fmu = ... in the house file, see plant/housefile.py): every
internal step then runs solver.before_storage (compiled), the FMU's doStep through
plant.fmu.component.FmuComponent, and solver.after_storage (compiled), from Python - the same
clock and step order as the native loop, about 100x slower.  The FMU's T_out and Q_loss enter
the ledger; its T_layer outputs are the storage state (sensors, SOC, stored energy).
snapshot/restore are not available then (the FMU's state cannot be copied).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING
from pathlib import Path

import numpy as np

from profiles import loaders

from . import housefile, solver
from .catalogue import CATALOGUE
from .component import pack
from .components import boiler, chp, mixing_station, pipe, radiator, storage, zone
from .controllers import room_thermostat, rule_based
from .errors import ConfigError
from .water import CP, RHO

_INPUT_NAMES = tuple(s.name for s in CATALOGUE.inputs())  # named in the error for a non-input

if TYPE_CHECKING:  # a house whose plant is an FMU (topology = "fmu")
    from .fmu.house import FmuHouse

STATE_ORDER = ("chp", "boiler", "storage", "dhw_storage", "zone", "radiator", "mixer",
               "supply_header", "return_header", "controller", "thermostat")
CONTROLLERS = ("rule_based", "external")
# inputs the case-study controller drives; "external" hands them to the gateway from the start
SUPERVISORY_INPUTS = ("chp.on", "chp.y_set", "boiler.U_set", "dhw_pump.on")


@dataclass(frozen=True)
class Snapshot:
    t: float
    states: tuple
    signals: np.ndarray
    remote: np.ndarray
    ledger: np.ndarray


def load_house(name_or_path: str | Path = "house1", start: str | None = None,
               controller: str = "rule_based", overrides: dict | None = None) -> "House | FmuHouse":
    """Assemble a house from its file; every problem is reported before the first step.

    overrides: {"section.key": value}, e.g. {"storage.UA_loss": 25.0,
    "connections.idle_flow_chp": 0.2}, validated like the file's own values.
    A house file with [house] topology = "fmu" gives an FmuHouse (plant/fmu/house.py).
    """
    spec = housefile.load(name_or_path, overrides)
    if isinstance(spec, housefile.FmuHouseSpec):
        from .fmu.house import FmuHouse

        return FmuHouse(spec, start=start, controller=controller)
    return House(spec, start=start, controller=controller)


class House:
    def __init__(self, spec: housefile.HouseSpec, start: str | None = None, controller: str = "rule_based"):
        if controller not in CONTROLLERS:
            raise ConfigError(f"controller = {controller!r}: unknown; allowed: {', '.join(CONTROLLERS)}")
        self.spec = spec
        self.name = spec.name
        self.catalogue = CATALOGUE
        self.start = start or spec.start
        P = spec.params
        self._params = P
        modules = {"chp": chp, "boiler": boiler, "storage": storage, "dhw_storage": storage,
                   "zone": zone, "radiator": radiator, "mixer": mixing_station,
                   "supply_header": pipe, "return_header": pipe, "controller": rule_based,
                   "thermostat": room_thermostat}
        self._x0 = tuple(np.ascontiguousarray(modules[k].initial_state(P[k]), dtype=np.float64)
                         for k in STATE_ORDER)
        c = spec.connections
        st, dw = P["storage"], P["dhw_storage"]
        sys = np.zeros(solver.N_SYS)
        sys[solver.SYS_M_DHW_PUMP] = c.dhw_pump_flow
        sys[solver.SYS_SOC_T0], sys[solver.SYS_SOC_TMAX] = c.storage_soc_T0, c.storage_soc_Tmax
        sys[solver.SYS_DHW_SOC_T0], sys[solver.SYS_DHW_SOC_TMAX] = c.dhw_soc_T0, c.dhw_soc_Tmax
        sys[solver.SYS_DHW_COIL_UA] = c.dhw_coil_UA
        for key, name in ((solver.SYS_CHP_X_STARTS, "starts"), (solver.SYS_CHP_X_RUNSEC, "run_seconds"),
                          (solver.SYS_CHP_X_EEL, "E_el"), (solver.SYS_CHP_X_EHEAT, "E_heat"),
                          (solver.SYS_CHP_X_EFUEL, "E_fuel")):
            sys[key] = chp.STATES.index(name)
        for key, name in ((solver.SYS_B_X_STARTS, "starts"), (solver.SYS_B_X_RUNSEC, "run_seconds"),
                          (solver.SYS_B_X_EHEAT, "E_heat"), (solver.SYS_B_X_EFUEL, "E_fuel"),
                          (solver.SYS_B_X_Y, "y")):
            sys[key] = boiler.STATES.index(name)
        if spec.typeday:  # a type-day block: time 0 = the block's first midnight
            sys[solver.SYS_TAU0] = loaders.typeday_offset(spec.typeday)
        else:
            sys[solver.SYS_TAU0] = loaders.start_offset(self.start)
        sys[solver.SYS_IDLE_FLOW_CHP] = c.idle_flow_chp
        sys[solver.SYS_PUMP_COUPLING_CHP] = c.pump_coupling_chp
        mix_layers = c.storage_inlet_mixing / (st.volume / st.n_layers)
        sys[solver.SYS_ST_INLET_MIX] = mix_layers
        n_in = 1 + math.ceil(mix_layers - 1e-12) if mix_layers > 0.0 else 1
        sys[solver.SYS_ST_TOP_LAYER] = storage.port_layer(c.storage_top_port, st)
        sys[solver.SYS_ST_BOTTOM_LAYER] = storage.port_layer(c.storage_bottom_port, st)
        self._p = tuple(pack(P[k]) for k in STATE_ORDER) + (pack(P["dhw"]), sys)
        self._tabs = tuple(np.ascontiguousarray(a, dtype=np.float64) for a in chp.tables() + boiler.tables())
        if spec.typeday:
            td = loaders.typeday(spec.typeday, spec.household_kwh_per_year, spec.dhw_litres_per_day)
            w, pres, pel, draw = td, td["presence"], td["P_el"], td["draw"]
        else:
            w = loaders.weather()
            pres = loaders.presence()
            pel = loaders.electricity(spec.household_kwh_per_year)
            draw = loaders.hot_water(spec.dhw_litres_per_day)
        self._prof = ((w["T_air"].values, w["E_dir"].values, w["E_dif"].values, pres.values,
                       pel.values, draw.values),
                      (w["T_air"].step, pres.step, pel.step, draw.step))
        n_max = max(st.n_layers, dw.n_layers)
        i64 = lambda *v: np.array(v, dtype=np.int64)  # noqa: E731
        f64 = lambda n: np.zeros(n, dtype=np.float64)  # noqa: E731
        self._ports = (
            (np.zeros(n_in, dtype=np.int64), i64(0)),
            (f64(n_in), f64(n_in), f64(1), f64(1), f64(1), f64(1), f64(1), f64(1), f64(n_max),
             f64(1), f64(1), f64(1), f64(1), f64(0)),
            (i64(storage.port_layer(c.dhw_cold_port, dw)), i64(storage.port_layer(c.dhw_draw_port, dw)),
             i64(storage.port_layer(c.dhw_coil_top, dw)), i64(storage.port_layer(c.dhw_coil_bottom, dw)),
             np.zeros(0, dtype=np.int64)),
        )
        self._controller = controller
        if spec.storage_fmu and n_in > 1:
            raise ConfigError(f"{spec.path}: [connections] storage_inlet_mixing = {c.storage_inlet_mixing:g}: "
                              "not with a storage FMU (its ports are one layer each); set it to 0")
        self._fmu = FmuStorage(spec.storage_fmu, st.n_layers) if spec.storage_fmu else None
        self.reset()

    # --- state -----------------------------------------------------------------------------
    def reset(self) -> None:
        self.t = 0.0
        self._x = tuple(a.copy() for a in self._x0)
        if self._fmu is not None:
            self._fmu.reset(self._x[STATE_ORDER.index("storage")])
        self._s = np.zeros(len(CATALOGUE))
        self._remote = np.zeros(len(CATALOGUE), dtype=np.bool_)
        self._ledger = np.zeros(len(solver.LEDGER_NAMES))
        if self._controller == "external":
            for name in SUPERVISORY_INPUTS:
                self._remote[CATALOGUE.index(name)] = True
        self._E0 = self.stored_energy()
        self._advance(0.0, 1)  # one zero-length step fills every signal
        if abs(self._s[CATALOGUE.index("zone.T_room")] - self._x[4][0]) > 1e-9:
            raise RuntimeError("compiled plant kernel is stale (signal catalogue changed): delete the "
                               "__pycache__ folders under plant/ and run again")

    def close(self) -> None:
        """Free the storage FMU's instance (if any); the house cannot step afterwards."""
        if self._fmu is not None:
            self._fmu.close()

    def snapshot(self) -> Snapshot:
        if self._fmu is not None:
            raise ConfigError(f"{self.name}: snapshot/restore are not available while the heating "
                              "storage is an FMU (its state cannot be copied)")
        return Snapshot(self.t, tuple(a.copy() for a in self._x), self._s.copy(), self._remote.copy(),
                        self._ledger.copy())

    def restore(self, snap: Snapshot) -> None:
        self.t = snap.t
        self._x = tuple(a.copy() for a in snap.states)
        self._s = snap.signals.copy()
        self._remote = snap.remote.copy()
        self._ledger = snap.ledger.copy()

    # --- signals ---------------------------------------------------------------------------
    def get(self, name: str) -> float:
        return float(self._s[CATALOGUE.index(name)])

    def values(self) -> np.ndarray:
        """All signal values in catalogue order (a copy)."""
        return self._s.copy()

    def set(self, name: str, value: float) -> None:
        sig = CATALOGUE.signal(name)
        self._s[sig.index] = sig.input_value(value, _INPUT_NAMES)
        self._remote[sig.index] = True

    def release(self, name: str) -> None:
        sig = CATALOGUE.signal(name)
        sig.require_input()
        self._remote[sig.index] = False

    def is_remote(self, name: str) -> bool:
        return bool(self._remote[CATALOGUE.index(name)])

    # --- time ------------------------------------------------------------------------------
    def _advance(self, dt: float, n: int, out=None, rec_every: int = 0) -> int:
        h = dt / n
        out = out if out is not None else np.zeros((0, len(CATALOGUE) + 1))
        if self._fmu is not None:
            rows = self._fmu.advance(self, n, h, out, rec_every)
            self.t += dt
            return rows
        rows = solver.run(n, h, self.t, self._x, self._p, self._tabs, self._prof, self._ports,
                          self._s, self._remote, self._ledger, out, rec_every)
        self.t += dt
        return rows

    def drive(self, times: np.ndarray, names: list[str], cmd: np.ndarray) -> np.ndarray:
        """Replay a command table from t = 0: the inputs `names` hold cmd[i] from times[i] to
        times[i + 1] (a change is applied at the midpoint); returns the signals at `times`
        [len(times), signals]. Spans are cut at whole minutes and split into steps of at most
        5 s. The inputs are set remote (the house's own controller no longer writes them)."""
        for n in names:
            CATALOGUE.signal(n).require_input()
        idx = np.array([CATALOGUE.index(n) for n in names], dtype=np.int64)
        times = np.ascontiguousarray(times, dtype=np.float64)
        cmd = np.ascontiguousarray(cmd, dtype=np.float64).reshape(len(times), len(idx))
        if self.t != 0.0 or not np.all(np.diff(times) > 0) or times[0] < 0:
            raise ValueError("drive: starts at t = 0 with increasing sample times >= 0")
        self._remote[idx] = True
        out = np.empty((len(times), len(CATALOGUE)))
        if self._fmu is None:
            solver.drive(times, cmd, idx, self._x, self._p, self._tabs, self._prof, self._ports,
                         self._s, self._remote, self._ledger, out)
            self.t = float(times[-1])
            return out
        # a storage FMU steps from Python: the same plan, one span at a time
        for a, b, row, rec in solver.drive_plan(times, cmd):
            self._s[idx] = cmd[int(row)]
            if b > a:
                self._advance(b - a, solver.n_steps(b - a))
            if rec >= 0:
                out[int(rec)] = self._s
        return out

    def step(self, dt: float) -> None:
        """Advance by dt seconds (split into equal internal steps of at most 5 s)."""
        if not dt > 0 or not math.isfinite(dt):
            raise ValueError(f"step: dt = {dt}; must be a positive number of seconds")
        self._advance(dt, solver.n_steps(dt))

    def run(self, duration: float, dt: float = 1.0, out_interval: float = 60.0, progress=None):
        """Simulate `duration` seconds at step dt; returns (times [s], rows [n, signals]).

        Rows are recorded every out_interval seconds (a multiple of dt); progress(t_done) is
        called about once per simulated day.
        """
        if not dt > 0:
            raise ValueError(f"run: dt = {dt}; must be positive")
        sub = solver.n_steps(dt)
        h = dt / sub
        rec_every = max(1, int(round(out_interval / h)))
        if abs(rec_every * h - out_interval) > 1e-6 * out_interval:
            raise ValueError(f"run: out_interval = {out_interval} s must be a multiple of the step {dt} s")
        n_total = int(round(duration / h))
        chunk = max(rec_every, (int(86400 / h) // rec_every) * rec_every)
        out = np.zeros((n_total // rec_every, len(CATALOGUE) + 1))
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
        P = self._params
        x = dict(zip(STATE_ORDER, self._x))
        E = 0.0
        for k in ("storage", "dhw_storage"):
            E += CP * RHO * P[k].volume / P[k].n_layers * float(x[k].sum())
        for k in ("supply_header", "return_header"):
            E += CP * RHO * P[k].V * float(x[k][0])
        E += CP * RHO * P["radiator"].V_water * float(x["radiator"][0])
        E += CP * RHO * P["chp"].V_water * float(x["chp"][chp.STATES.index("T_w")])
        return E

    def ledger(self) -> dict[str, float]:
        """Energy ledger since reset [J], with the closure of the water-side balance."""
        L = dict(zip(solver.LEDGER_NAMES, map(float, self._ledger)))
        heat_in = L["heat_chp"] + L["heat_boiler"]
        losses = L["loss_storage"] + L["loss_dhw_storage"] + L["loss_pipes"]
        dE = self.stored_energy() - self._E0
        fuel = L["fuel_chp"] + L["fuel_boiler"]
        L["fuel"] = fuel
        L["el_net"] = L["el_chp"] + L["el_boiler"]
        L["generator_losses"] = fuel - L["el_net"] - heat_in
        L["losses"] = losses
        L["delta_stored"] = dE
        L["residual"] = heat_in - (L["heat_building"] + L["heat_dhw"] + losses + dE)
        L["closure"] = abs(L["residual"]) / fuel if fuel > 0 else abs(L["residual"])
        return L


class FmuStorage:
    """The heating storage as a co-simulation FMU, stepped between solver.before_storage and
    solver.after_storage (see the module docstring)."""

    def __init__(self, spec: housefile.StorageFmuSpec, n_layers: int):
        self.spec = spec
        self.n = n_layers
        self._comp = None

    def reset(self, T_st: np.ndarray) -> None:
        """(Re)instantiate the FMU at time 0 and take its initial layer temperatures as the state."""
        from .fmu.component import FmuComponent

        self.close()
        b = self.spec.bindings
        roles = housefile.STORAGE_ROLES
        inputs = {r: (b[r][0], roles[r][1], b[r][1]) for r in ("m_flow", "T_in_top", "T_in_bottom")}
        var, unit = b["T_layer"]
        outputs = {f"T_layer_{i}": (var.replace("{i}", str(i)), "degC", unit) for i in range(1, self.n + 1)}
        outputs["T_out"] = (b["T_out"][0], "degC", b["T_out"][1])
        outputs["Q_loss"] = (b["Q_loss"][0], "W", b["Q_loss"][1])
        self._extra = []  # (signal index, output position) of optional roles
        for role, signal in (("T_top", "storage.T_top"), ("T_bottom", "storage.T_bot"),
                             *((f"T_sensor_{i}", f"storage.T_sensor_{i}") for i in range(1, 11))):
            if role in b:
                self._extra.append((CATALOGUE.index(signal), len(outputs)))
                outputs[role] = (b[role][0], "degC", b[role][1])
        self._comp = FmuComponent(self.spec.path, inputs=inputs, outputs=outputs,
                                  parameters=self.spec.parameters, start_time=0.0)
        y = self._comp.read_outputs()
        T_st[:] = y[:self.n]
        self._y = y

    def advance(self, house: "House", n: int, h: float, out: np.ndarray, rec_every: int) -> int:
        x, p, ports, s = house._x, house._p, house._ports, house._s
        T_st = x[STATE_ORDER.index("storage")]
        out_T = ports[1][3]
        comp, N = self._comp, self.n
        rows = 0
        for k in range(n):
            t = house.t + k * h
            mid = solver.before_storage(t, h, x, p, house._tabs, house._prof, ports, s, house._remote)
            comp.set_inputs((mid[solver.M_M_CHARGE] - mid[solver.M_M_DISCHARGE], mid[solver.M_T_SH],
                             mid[solver.M_T_RH]))
            y = comp.step(h) if h > 0.0 else self._y
            self._y = y
            T_st[:] = y[:N]
            out_T[0] = y[N]
            solver.after_storage(t, h, x, p, ports, s, house._ledger, mid, float(y[N + 1]))
            for i_sig, i_out in self._extra:
                s[i_sig] = y[i_out]
            if rec_every > 0 and (k + 1) % rec_every == 0 and rows < out.shape[0]:
                out[rows, 0] = t + h
                out[rows, 1:] = s
                rows += 1
        return rows

    def close(self) -> None:
        if self._comp is not None:
            self._comp.close()
            self._comp = None
