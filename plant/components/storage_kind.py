"""The stratified storage as a component kind: its ports, sensors, signals and ledger in the step.

Connections attach to a storage by height (plant/compiler.py StoragePorts): inlets, outlets and
coils in any number. The kernel (plant/components/storage.py) takes them as arrays, so a storage
with five inlets, a coil and a draw costs one call per step.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..component import Kind as ComponentKind, is_number, link, pack
from ..water import CP, RHO
from . import storage


@njit(cache=True, inline="always")
def _at(T, z):
    """The temperature at relative height z (0 = bottom, 1 = top), linear between layer centres."""
    n = T.shape[0]
    pos = (1.0 - z) * n - 0.5  # position in layer-centre coordinates, layer 0 = top
    if pos <= 0.0:
        return T[0]
    if pos >= n - 1:
        return T[n - 1]
    i = int(pos)
    w = pos - i
    return T[i] * (1.0 - w) + T[i + 1] * w


@njit(cache=True)
def sensors(T, s, first, n_sensors):
    """Write n_sensors temperatures (1 = bottom ... n = top) at equally spaced heights."""
    for k in range(n_sensors):
        s[first + k] = _at(T, (k + 0.5) / n_sensors)


@njit(cache=True)
def sensors_at(T, s, first, z):
    """Write sensor temperatures at relative heights z (0 = bottom, 1 = top), first = sensor 1."""
    for k in range(z.shape[0]):
        s[first + k] = _at(T, z[k])


@njit(cache=True)
def lag(s, first, x_lag, tau, h, update):
    """Replace sensor signals by first-order filtered ones (time constants tau [s], 0 = none):
    a sensor in a thermowell. Called after `sensors`; the filter advances only when `update`."""
    for k in range(tau.shape[0]):
        if tau[k] > 0.0:
            raw = s[first + k]
            if not math.isfinite(x_lag[k]):
                x_lag[k] = raw
            if update:
                x_lag[k] += -math.expm1(-h / tau[k]) * (raw - x_lag[k])
            s[first + k] = x_lag[k]


class Kind(ComponentKind):
    name = "storage"
    Params = storage.Params
    role = "storage"
    UNMEASURED = ("E_stored", "m_flow")
    LINKS = {"sensors": link(10, "number of temperature sensors at equally spaced heights (1 = bottom)",
                             type=int, range=(1, 100)),
             "sensor_heights": link(None, "relative heights 0 (bottom) ... 1 (top) of the sensors, sensor 1 "
                                          "first (instead of equally spaced ones)", type=list),
             "sensor_lag": link({}, "sensor number = first-order time constant [s] (an effect: thermowell lag)",
                                type=dict)}

    def initial_state(self, inst):
        return storage.initial_state(inst.params)

    def stored_energy(self, inst, x):
        return CP * RHO * inst.params.volume / inst.params.n_layers * float(x.sum())

    def emit(self, c, inst):
        x, p, Ql = self.emit_signals(c, inst)
        Qc = c.var("Q_coil")
        c.values[f"{inst.name}.Q_coil"] = Qc  # the coils' heat of the kernel, for allocate
        ports = c.storage_ports(inst.name, ask=False)  # the names of its arrays, in the kernel's order
        arrays = ", ".join(map(ports.array, ports.ARRAYS))
        c.emit("storages", f"{Ql}, {Qc} = {c.module(storage.__name__)}.step_into(h, {x}, {p}, {arrays})")

    def emit_signals(self, c, inst):
        """State, parameters, sensors, signals and ledger of a storage; returns (state view,
        parameter view, the local its step's heat loss goes into)."""
        x = c.state(inst, self.initial_state(inst))
        p = c.param(inst, pack(inst.params))
        n = inst.options["sensors"]
        heights = inst.options.get("sensor_heights")
        if heights is not None:
            if (not isinstance(heights, list) or not heights or len(heights) > 100
                    or any(not is_number(z) or not 0 <= z <= 1 for z in heights)):
                c.problems.append(f"{inst.at('sensor_heights')} = {heights!r}: a list of relative heights "
                                  "0 (bottom) … 1 (top), sensor 1 first")
                heights = None
            else:
                n = len(heights)
        for i in range(1, n + 1):
            c.signal(inst, f"T_sensor_{i}", "degC", "output", f"sensor {i} of {n} (1 = bottom, {n} = top)")
        first = c.signal_index(f"{inst.name}.T_sensor_1")
        # the heights are a parameter of the step, the equally spaced ones (sensors' (k + 0.5) / n) too:
        # a plant read at a columns file's heights is the same compiled plant as the house file's
        z = np.array(heights if heights is not None else [(k + 0.5) / n for k in range(n)], dtype=float)
        read = f"{c.module(__name__)}.sensors_at({x}, s, {first}, {c.param(inst, z, suffix='_z')})"
        c.emit("sense", read)
        lag_call = self._lag(c, inst, n, first)
        if lag_call:
            c.emit("sense", lag_call.format(update="False"))
        Ql = c.var("Q_loss")
        i_vol, i_t0, i_tmax = storage.P.volume, storage.P.soc_T0, storage.P.soc_Tmax
        mean = c.var("mean")
        sig = lambda local, unit, desc: c.signal(inst, local, unit, "output", desc)  # noqa: E731
        c.emit("signals",
               read,  # end-of-step values: what the next step's controller sees
               *([lag_call.format(update="True")] if lag_call else []),
               f"{mean} = {x}.mean()",
               f"{sig('T_top', 'degC', 'top layer')} = {x}[0]",
               f"{sig('T_bot', 'degC', 'bottom layer')} = {x}[{x}.shape[0] - 1]",
               f"{sig('SOC', '1', 'state of charge (mean - soc_T0)/(soc_Tmax - soc_T0)')} = "
               f"({mean} - {p}[{i_t0}]) / ({p}[{i_tmax}] - {p}[{i_t0}])",
               f"{sig('E_stored', 'J', 'stored heat above soc_T0')} = CP * RHO * {p}[{i_vol}] * ({mean} - {p}[{i_t0}])",
               f"{sig('Q_loss', 'W', 'heat loss to the room')} = {Ql}",
               f"{c.ledger_entry(inst, 'loss')} += {Ql} * h")
        return x, p, Ql

    def _lag(self, c, inst, n, first):
        """The lag call (with {update} to fill in), or None when no sensor lags."""
        table = inst.options.get("sensor_lag") or {}
        if not isinstance(table, dict):
            c.problems.append(f"{inst.at('sensor_lag')} = {table!r}: expected {{ sensor = seconds }}")
            return None
        if not table:
            return None
        tau = np.zeros(n)
        for key, v in table.items():
            ok = str(key).isdigit() and 1 <= int(key) <= n
            if not ok or not is_number(v) or not v >= 0:
                c.problems.append(f"{inst.at('sensor_lag')}.{key} = {v!r}: sensor 1 … {n}, time constant >= 0 s")
                continue
            tau[int(key) - 1] = float(v)
        x_lag = c.state(inst, np.full(n, np.nan), suffix="_lag")
        p_lag = c.param(inst, tau, suffix="_lag")
        return f"{c.module(__name__)}.lag(s, {first}, {x_lag}, {p_lag}, h, {{update}})"

    def allocate(self, c, inst, ports):
        """The port arrays, once every connection has asked for its slots; and each coil's heat
        (`ports.coil_heat(k)`): the kernel's own sum when the coil is the only one, else from
        the coil's flow and temperatures."""
        a = ports.array
        for k in range(ports.n_coil):
            q = c.values.get(f"{inst.name}.Q_coil") if ports.n_coil == 1 else None
            c.emit("storages", f"{ports.coil_heat(k)} = "
                   + (q or f"{a('coil_m')}[{k}] * CP * ({a('coil_Tin')}[{k}] - {a('coil_Tout')}[{k}])"))
        in_layer = np.zeros(ports.n_in, dtype=np.int64)
        for slot, layer in ports.fixed_in:
            in_layer[slot] = layer
        out_layer = np.zeros(ports.n_out, dtype=np.int64)
        for slot, layer in ports.fixed_out:
            out_layer[slot] = layer
        top = [t for _, t, _ in sorted(ports.coils)]
        bot = [b for _, _, b in sorted(ports.coils)]
        c.header.extend([
            f"{a('in_layer')} = {c.int_array(in_layer)}", f"{a('in_m')} = {c.float_array(ports.n_in)}",
            f"{a('in_T')} = {c.float_array(ports.n_in)}",
            f"{a('out_layer')} = {c.int_array(out_layer)}", f"{a('out_m')} = {c.float_array(ports.n_out)}",
            f"{a('out_T')} = {c.float_array(ports.n_out)}",
            f"{a('coil_top')} = {c.int_array(top)}", f"{a('coil_bot')} = {c.int_array(bot)}",
            f"{a('coil_UA')} = {c.float_array(ports.n_coil)}", f"{a('coil_m')} = {c.float_array(ports.n_coil)}",
            f"{a('coil_Tin')} = {c.float_array(ports.n_coil)}", f"{a('coil_Tout')} = {c.float_array(ports.n_coil)}",
            f"{a('q')} = {c.float_array(inst.params.n_layers)}",
            f"{a('fin_layer')} = {c.int_array(np.zeros(ports.n_in))}", f"{a('fin_m')} = {c.float_array(ports.n_in)}",
            f"{a('fout_layer')} = {c.int_array(np.zeros(ports.n_out))}", f"{a('fout_m')} = {c.float_array(ports.n_out)}"])
