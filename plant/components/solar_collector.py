"""Solar thermal collector with its solar pump and hysteresis control, delivering through a coil
in a storage, or through a three-way valve to one of two coils (the lab's solar circuit,
reference §12.1, §12.4).

Physics in words
----------------
The collector is one lumped node (absorber, fluid and glass) of heat capacity C = c_eff x area
at the temperature T_collector, which is also its outlet temperature. It absorbs
    S = area x eta0 x (K_beam(theta) G_beam + K_diffuse G_diffuse)            [W]
and loses to the outdoor air (EN ISO 9806 quasi-steady curve)
    Q_loss = area x (a1 (T_m - T_air) + a2 (T_m - T_air)^2)
at the mean fluid temperature T_m = (T_in + T_out)/2 while the pump runs (T_m = T_collector
when it stands still), so in steady state the delivered heat follows the efficiency curve
eta = eta0 - a1 (T_m - T_air)/G - a2 (T_m - T_air)^2/G exactly. G_beam, G_diffuse come from
the weather's horizontal beam and diffuse irradiance (plant/sun.py: sun position at the step's
local standard time, isotropic sky, ground reflection; the collector plane has the given tilt
and azimuth). The incidence-angle modifier is ASHRAE's K_beam = 1 - b0 (1/cos theta - 1)
(0 ... 1); diffuse and ground-reflected light take the modifier at 60 deg, K_diffuse = 1 - b0.

The node is advanced exactly over each step (the a2 term linearised about the start of the
step): inlet at the last return temperature, mean outlet sent to the coil. The loop's pipes
(`UA_loop`, `V_loop`, half on the supply, half on the return; plant/components/loop_pipe.py)
lose to the outdoor air on the way: without water held (V_loop = 0) each is the steady
exchanger, T_air + (T - T_air) exp(-UA_loop / (2 m cp)), losing only while the pump runs; with
water each is a mixed node whose standing water cools between runs and reaches the coil first
at the next. The supply and return signals are the coil's inlet and outlet, where a station at
the storage measures them (standing: the supply pipe's water where it holds some, else the
collector); T_collector is the collector's own. The coil is a
storage coil (plant/components/storage.py's exact segment-wise exchanger); its outlet is the
collector return. When the return comes back at another temperature than assumed, its
enthalpy difference goes into the node at the step's end, so the ledger closes to round-off:
    absorbed = heat to the storage + collector and pipe losses + change of collector and pipe heat.
Ledger: the irradiance on the aperture is `fuel`, the absorbed heat `heat` (optical losses are
the difference), thermal losses `loss`; the node's heat C x T_collector is stored energy.

Two coils (house 3, §12.4): with `top = { upper = ..., lower = ... }` and `bottom = { upper = ...,
lower = ... }` the collector's flow goes through a three-way valve (the lab's SwitchPort, §8.4)
either all through the upper coil (conductance UA_upper) or all through the lower one (UA); the
input `<name>.upper` (0/1) sets it. The house's rules write it (plant/controllers/
heat_pump_rules.py, solar_upper: upper when T_collector - T_BT9 > 3 K, lower below 2 K); driven
from outside, it is the controller's (the SiL's ST_A_V3_TL). The idle coil carries no flow and
exchanges nothing; the collector return is the outlet of the coil in use, so the ledger closes
as with one coil. A valve that does not close (`leak`, 0 ... 0.5) sends that share of the flow
through the other coil and the return is both outlets mixed by their flows (leak = 0 gives the
closing valve's numbers bit for bit). Signals Q_flow_upper and E_heat_upper give the upper
coil's share (below zero where its leak flow takes heat from the top of the tank).

Control (the lab's solar pump, §12.1): the pump switches on when T_collector - T_storage >
dT_on and off when it falls below dT_off (held in between), T_storage being a storage sensor
named by the link `sensor`; it stays off while that sensor is above T_storage_max. Flow when
on: m_flow_max x clamp((T_sup - T_ret - dT_flow_min)/(dT_flow_max - dT_flow_min), 0, 1) with
the last supply and return (`modulating = true`, the original's rule), else m_flow_max. The
inputs `on` and `m_flow_set` carry the commands; driven from outside (remote), they override
the built-in control (the SiL's ST_S_FW_ST_VL_set).

Parameters (SI)
---------------
| name | unit | meaning |
|---|---|---|
| area | m2 | aperture area (WolfCRK12 1.312 m2; the SiL export uses 2 m2) |
| eta0, a1, a2 | 1, W/(m2 K), W/(m2 K2) | efficiency curve on the aperture (WolfCRK12: 0.642, 0.885, 0.001) |
| c_eff | J/(m2 K) | effective heat capacity per aperture area (8416, "GreenCity units" read as J/(m2 K)) |
| b0 | 1 | incidence-angle modifier coefficient (0: none) |
| tilt, azimuth | deg | plane tilt from the horizontal, azimuth 180 = south (35 deg, south) |
| latitude, longitude | deg | site (Munich: 48.14 N, 11.58 E) |
| albedo | 1 | ground reflectance |
| m_flow_max | kg/s | solar pump flow at full speed (20 l/min) |
| dT_on, dT_off | K | pump hysteresis on T_collector - T_storage (3 K, 2 K) |
| dT_flow_min, dT_flow_max | K | flow modulation on T_sup - T_ret (3 K, 7 K) |
| modulating | - | flow modulation on (the original) or full flow whenever on |
| T_storage_max | degC | pump blocked above this storage temperature (no such limit upstream: 95 degC keeps the water below boiling) |
| UA | W/K | coil conductance, the lower coil's with two (house 1: 1.8 m2 x 675 W/(m2 K) = 1215 W/K) |
| UA_upper | W/K | the upper coil's conductance with two coils (house 3: 1.9 m2 x 675 = 1282.5 W/K); 0 with one |
| T_init | degC | initial collector temperature |
| leak | 1 | share of the loop's flow through the coil the valve is not set to (two coils; 0: it closes) |
| UA_loop | W/K | the loop pipes' conductance to the outdoor air, supply and return together (0: none; 10 m of DN 20 with 20 mm insulation: about 2.5 W/K per line) |
| V_loop | m3 | water in the loop's pipes, supply and return together (0: none held; 10 m of DN 20: 3.1 l per line) |

Assumptions: no stagnation or boiling model (the node's temperature follows the curve however
high); the loop pipes' water is one mixed node per line (no dead time; none with V_loop = 0);
the coil fluid holds no heat
(as every storage coil here). The collector in §12.1 is a CPC tube collector; the curve model
is the flat-plate one with its published coefficients (GreenCity's own model is not available,
reference §0.4).

Data source: reference §12.1, §12.4 (upstream DZinsmeister/CoSES_thermal_ProHMo, Houses/SF1.mo,
SF3.mo). Validated by tests/plant/test_solar.py (steady-state efficiency curve, daily energy
balance, pump hysteresis, a June week of house 1 with its collector) and
tests/plant/test_solar_valve.py (house 3's valve thresholds, heat into the upper coil's layers,
ledger closure, bad coil heights).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from .. import sun
from . import loop_pipe, solar_coils
from ..component import (REQUIRED, Instance, Kind as ComponentKind, SignalName, Valve, indices, link, pack,
                         param)
from ..water import CP, RHO

RHO_CP = RHO * CP  # J/(m3 K) of the loop's water


@dataclass(frozen=True)
class Params:
    area: float = param(1.312, "m2", "aperture area", 0.1, 1000.0)
    eta0: float = param(0.642, "1", "optical efficiency (zero-loss efficiency)", 0.0, 1.0)
    a1: float = param(0.885, "W/(m2 K)", "linear heat-loss coefficient", 0.0, 20.0)
    a2: float = param(0.001, "W/(m2 K2)", "quadratic heat-loss coefficient", 0.0, 1.0)
    c_eff: float = param(8416.0, "J/(m2 K)", "effective heat capacity per aperture area", 100.0, 1e6)
    b0: float = param(0.1, "1", "incidence-angle modifier coefficient K = 1 - b0 (1/cos - 1)", 0.0, 1.0)
    tilt: float = param(35.0, "deg", "tilt from the horizontal", 0.0, 90.0)
    azimuth: float = param(180.0, "deg", "azimuth of the plane's normal (90 east, 180 south, 270 west)", 0.0, 360.0)
    latitude: float = param(48.14, "deg", "site latitude (north positive)", -90.0, 90.0)
    longitude: float = param(11.58, "deg", "site longitude (east positive; clock is CET = 15 deg E)", -180.0, 180.0)
    albedo: float = param(0.2, "1", "ground reflectance", 0.0, 1.0)
    m_flow_max: float = param(0.333, "kg/s", "solar pump flow at full speed", 0.0, 10.0)
    dT_on: float = param(3.0, "K", "pump on above T_collector - T_storage", -10.0, 50.0)
    dT_off: float = param(2.0, "K", "pump off below T_collector - T_storage", -10.0, 50.0)
    dT_flow_min: float = param(3.0, "K", "no flow at or below this supply - return difference", 0.0, 50.0)
    dT_flow_max: float = param(7.0, "K", "full flow at or above this supply - return difference", 0.0, 50.0)
    modulating: bool = param(True, "1", "flow modulation on the supply - return difference (else full flow when on)")
    T_storage_max: float = param(95.0, "degC", "pump blocked above this storage temperature", 20.0, 100.0)
    UA: float = param(1215.0, "W/K", "conductance of the coil in the storage", 0.0, 1e6)
    T_init: float = param(20.0, "degC", "initial collector temperature", -30.0, 100.0)
    UA_upper: float = param(0.0, "W/K", "conductance of the upper coil behind the solar valve (0: one coil)", 0.0, 1e6)
    leak: float = param(0.0, "1", "share of the loop's flow through the coil the solar valve is not set to (two "
                                  "coils; 0: the valve closes)", 0.0, 0.5)
    UA_loop: float = param(0.0, "W/K", "conductance of the loop's pipes to the outdoor air, supply and return "
                                       "together (0: no pipe loss)", 0.0, 200.0)
    V_loop: float = param(0.0, "m3", "water in the loop's pipes, supply and return together (0: they hold none)",
                          0.0, 0.2)


STATES = ("T", "T_ret", "T_sup", "E_heat", "E_solar", "T_pipe_sup", "T_pipe_ret")
# positions in the packed parameters and the state vector, from the declarations
P = indices(Params)
X = indices(STATES)


def initial_state(params: Params) -> np.ndarray:
    return np.array([params.T_init, params.T_init, params.T_init, 0.0, 0.0, params.T_init, params.T_init],
                    dtype=np.float64)


@njit(cache=True)
def pipe(h, x, k, p, T_in, T_air, m):
    """One of the loop's two pipes (half its conductance and water; loop_pipe.step)."""
    return loop_pipe.step(h, x, k, 0.5 * p[P.V_loop] * RHO_CP, 0.5 * p[P.UA_loop], T_in, T_air, m)


@njit(cache=True)
def absorbed(p, beam, diffuse, cos_theta):
    """Heat the absorber takes from the plane irradiance [W] (optical efficiency and incidence
    modifier applied)."""
    k_beam = 0.0
    if cos_theta > 0.0:
        k_beam = min(1.0, max(0.0, 1.0 - p[P.b0] * (1.0 / cos_theta - 1.0)))
    k_diffuse = max(0.0, 1.0 - p[P.b0])
    return p[P.area] * p[P.eta0] * (k_beam * beam + k_diffuse * diffuse)


@njit(cache=True)
def control(x, p, on, T_storage):
    """Pump command (hysteresis on T_collector - T_storage, held between dT_off and dT_on) and
    flow request; returns (on, m_flow_set)."""
    dT = x[X.T] - T_storage
    if T_storage > p[P.T_storage_max]:
        on = 0.0
    elif dT > p[P.dT_on]:
        on = 1.0
    elif dT < p[P.dT_off]:
        on = 0.0
    m = p[P.m_flow_max]
    if p[P.modulating] > 0.5:
        span = p[P.dT_flow_max] - p[P.dT_flow_min]
        d = x[X.T] - x[X.T_ret] - p[P.dT_flow_min]
        y = (1.0 if d > 0.0 else 0.0) if span <= 0.0 else min(1.0, max(0.0, d / span))
        m = p[P.m_flow_max] * y
    return on, m


@njit(cache=True)
def advance(h, x, p, S, T_air, m):
    """Advance the collector node over h with the inlet at the last return temperature x[T_ret]
    (exact solution of the node's linear equation, a2 linearised about the step start).

    Returns (T_sup, Q_loss): the mean temperature at the coil inlet over the step (the collector's
    outlet through the supply pipe) and the mean thermal loss [W] of the collector, from the node's
    exact energy balance C (T_end - T_start) = h (S - Q_loss - m cp (T_out - T_in)), plus the supply
    pipe's."""
    C = p[P.c_eff] * p[P.area]
    T0 = x[X.T]
    if m > 0.0:
        T_in, w = x[X.T_ret], 0.5
    else:
        T_in, w = T0, 0.0
    Tm0 = w * T_in + (1.0 - w) * T0
    k = p[P.area] * (p[P.a1] + p[P.a2] * abs(Tm0 - T_air))
    # C dT/dt = alpha - beta T
    beta = k * (1.0 - w) + m * CP
    alpha = S - k * (w * T_in - T_air) + m * CP * T_in
    r = beta * h / C
    if r > 1e-12:
        T_inf = alpha / beta
        T1 = T_inf + (T0 - T_inf) * math.exp(-r)
        T_mean = T_inf + (T0 - T_inf) * (-math.expm1(-r) / r)
    else:
        T1 = T0 + alpha * h / C
        T_mean = 0.5 * (T0 + T1)
    x[X.T] = T1
    Q_loss = S - m * CP * (T_mean - T_in) - C * (T1 - T0) / h if h > 0.0 else 0.0
    T_coil, Q_pipe = pipe(h, x, X.T_pipe_sup, p, T_mean, T_air, m)
    Q_loss += Q_pipe
    # without flow the supply sensor reads the collector, or the pipe's standing water
    x[X.T_sup] = T_coil if m > 0.0 else (x[X.T_pipe_sup] if p[P.V_loop] > 0.0 else T1)
    return T_coil, Q_loss


@njit(cache=True)
def settle(h, x, p, m, T_ret, T_storage, T_air):
    """The return came back from the coil at T_ret, through the return pipe, instead of the assumed
    inlet: its enthalpy difference goes into the node. Without flow the return follows the storage
    sensor (what the flow modulation compares with at the next start). Returns the return pipe's
    loss [W]."""
    T_in, Q_pipe = pipe(h, x, X.T_pipe_ret, p, T_ret, T_air, m)
    if m > 0.0:
        x[X.T] += m * CP * h * (T_in - x[X.T_ret]) / (p[P.c_eff] * p[P.area])
        x[X.T_ret] = T_in
    else:
        x[X.T_ret] = T_storage
    return Q_pipe


class Kind(ComponentKind):
    """The collector, its pump and control, and its coil in a storage; emits itself."""

    name = "solar_collector"
    Params = Params
    role = "connection"
    # the station's pump is the kind's own control: a recording of it drives it (COMMANDS); its
    # supply and return sensors sit on the loop's pipes, which stand while the pump is off
    RUN, PIPES, COMMANDS = ("on", 0.5), ("T_sup", "T_ret"), ("on", "m_flow_set")
    COUNTER = "E_heat"
    LINKS = {"storage": link(REQUIRED, "the storage the solar coil is in", type=Instance, range=("storage",)),
             "top": link(REQUIRED, "height of the coil inlet [m above the storage bottom], or { upper = ..., "
                                   "lower = ... } for two coils behind the solar valve", type=Valve),
             "bottom": link(REQUIRED, "height of the coil outlet [m], or { upper = ..., lower = ... }", type=Valve),
             "sensor": link(REQUIRED, "the storage temperature the pump control compares with "
                                      "(a signal, e.g. \"dhw_storage.T_sensor_5\")", type=SignalName,
                            example="{storage}.T_sensor_5")}

    def initial_state(self, inst):
        return initial_state(inst.params)

    def stored_energy(self, inst, x):
        pipes = 0.5 * inst.params.V_loop * RHO_CP * (float(x[X.T_pipe_sup]) + float(x[X.T_pipe_ret]))
        return inst.params.c_eff * inst.params.area * float(x[X.T]) + pipes

    def emit(self, c, inst):
        o = inst.options
        st = o["storage"]
        valve = isinstance(o["top"], dict) or isinstance(o["bottom"], dict)
        top_up, top = c.port_layers(inst, "top", st)
        bottom_up, bottom = c.port_layers(inst, "bottom", st)
        solar_coils.check(c, inst, valve)
        if inst.params.dT_off > inst.params.dT_on:
            c.problems.append(f"{inst.at('dT_off')} = {inst.params.dT_off}: must not exceed dT_on = "
                              f"{inst.params.dT_on} K")
        x, p = c.state(inst, self.initial_state(inst)), c.param(inst, pack(inst.params))
        sky = sun.emit_plane(c, inst, p, P)
        k = c.storage_ports(st).add_coil(inst, top, bottom)
        k_up = c.storage_ports(st).add_coil(inst, top_up, bottom_up) if valve else None
        T_st = c.s(o["sensor"]) if isinstance(o["sensor"], str) else "0.0"
        on, m_set = self._emit_control(c, inst, x, p, T_st)
        beam, dif, S, m, T_sup, Q_loss = self._emit_collector(c, x, p, sky, on, m_set)
        Q, T_ret, Q_pipe = c.var("Q_solar"), c.var("T_ret"), c.var("Q_pipe")
        side, coil_out = self._emit_coils(c, inst, st, k, k_up, p, m, T_sup)
        c.emit("volumes",
               f"{T_ret} = {coil_out} if {m} > 0.0 else {x}[{X.T_ret}]",
               f"{Q} = {m} * CP * ({T_sup} - {T_ret})",
               f"{Q_pipe} = {c.module(__name__)}.settle(h, {x}, {p}, {m}, {T_ret}, {T_st}, T_air)",
               f"{x}[{X.E_heat}] += {Q} * h",
               f"{x}[{X.E_solar}] += ({beam} + {dif}) * {p}[{P.area}] * h")
        self._emit_signals(c, inst, x, p, beam, dif, S, m, T_ret, Q, (Q_loss, Q_pipe), side, k_up, T_sup)

    def _emit_control(self, c, inst, x, p, T_st):
        """The pump's inputs, written by the built-in control unless driven from outside."""
        on = c.signal(inst, "on", "1", "input", "solar pump command (0/1); the built-in hysteresis "
                                                "writes it unless driven from outside")
        m_set = c.signal(inst, "m_flow_set", "kg/s", "input", "solar pump flow when on; the built-in "
                                                             "modulation writes it unless driven from outside")
        mod = c.module(__name__)
        on_cmd, m_cmd = c.var("on"), c.var("m_set")
        c.emit("control", f"{on_cmd}, {m_cmd} = {mod}.control({x}, {p}, {on}, {T_st})")
        c.write_command("control", f"{inst.name}.on", on_cmd)
        c.write_command("control", f"{inst.name}.m_flow_set", m_cmd)
        return on, m_set

    def _emit_collector(self, c, x, p, sky, on, m_set):
        """The circuit flow and the collector node's step, under the irradiance sky (sun.emit_plane)."""
        mod = c.module(__name__)
        beam, dif, cos_t = sky
        S, m, T_sup, Q_loss = (c.var(v) for v in ("S", "m_solar", "T_sup", "Q_loss"))
        c.emit("hydraulics",
               f"{S} = {mod}.absorbed({p}, {beam}, {dif}, {cos_t})",
               f"{m} = min(max({m_set}, 0.0), {p}[{P.m_flow_max}]) if {on} > 0.5 else 0.0",
               f"{T_sup}, {Q_loss} = {mod}.advance(h, {x}, {p}, {S}, T_air, {m})")
        return beam, dif, S, m, T_sup, Q_loss

    def _emit_coils(self, c, inst, st, k, k_up, p, m, T_sup):
        """The coil requests of the step; returns (the valve-side local or None, the coil outlet
        expression)."""
        a = c.storage_ports(st).array
        if k_up is None:
            c.emit("hydraulics",
                   f"{a('coil_m')}[{k}] = {m}",
                   f"{a('coil_Tin')}[{k}] = {T_sup}",
                   f"{a('coil_UA')}[{k}] = {p}[{P.UA}]")
            return None, f"{a('coil_Tout')}[{k}]"
        up = c.signal(inst, "upper", "1", "input", "solar three-way valve: 1 = upper coil, 0 = lower coil "
                                                     "(the rules write it unless driven from outside)")
        side, leak = c.var("upper"), f"{p}[{P.leak}]"
        # a valve that does not close sends the share `leak` through the other coil; written so that
        # leak = 0 gives the closing valve's numbers bit for bit (m - m * 0.0 == m)
        c.emit("hydraulics",
               f"{side} = {up} > 0.5",
               f"{a('coil_m')}[{k}] = {m} * {leak} if {side} else {m} - {m} * {leak}",
               f"{a('coil_m')}[{k_up}] = {m} - {m} * {leak} if {side} else {m} * {leak}",
               f"{a('coil_Tin')}[{k}] = {T_sup}",
               f"{a('coil_Tin')}[{k_up}] = {T_sup}",
               f"{a('coil_UA')}[{k}] = {p}[{P.UA}]",
               f"{a('coil_UA')}[{k_up}] = {p}[{P.UA_upper}]")
        sel = f"({a('coil_Tout')}[{k_up}] if {side} else {a('coil_Tout')}[{k}])"
        other = f"({a('coil_Tout')}[{k}] if {side} else {a('coil_Tout')}[{k_up}])"
        # the return is the two coils' outlets mixed by their flows
        return side, f"({sel} + {leak} * ({other} - {sel}))"

    def _emit_signals(self, c, inst, x, p, beam, dif, S, m, T_ret, Q, losses, side, k_up, T_sup):
        """Output signals and ledger entries; with the valve, the upper coil's own heat. losses: the
        collector's and supply pipe's, the return pipe's."""
        Q_loss = f"({losses[0]} + {losses[1]})"
        sig = lambda local, unit, desc: c.signal(inst, local, unit, "output", desc)  # noqa: E731
        c.emit("signals",
               f"{sig('T_collector', 'degC', 'collector (absorber node) temperature')} = {x}[{X.T}]",
               f"{sig('T_sup', 'degC', 'coil inlet: the collector outlet through the supply pipe (mean over the step)')} = {x}[{X.T_sup}]",
               f"{sig('T_ret', 'degC', 'coil outlet, led back to the collector by the return pipe')} = {T_ret}",
               f"{sig('m_flow', 'kg/s', 'solar circuit flow')} = {m}",
               f"{sig('Q_flow', 'W', 'heat given by the coil to the storage')} = {Q}",
               f"{sig('Q_loss', 'W', 'heat loss of the collector and its loop pipes to the outdoor air')} = {Q_loss}",
               f"{sig('G_plane', 'W/m2', 'irradiance on the collector plane (beam + diffuse + ground)')} = {beam} + {dif}",
               f"{sig('E_heat', 'J', 'heat given to the storage since the start')} = {x}[{X.E_heat}]",
               f"{sig('E_solar', 'J', 'irradiation on the aperture since the start')} = {x}[{X.E_solar}]",
               f"{c.ledger_entry(inst, 'fuel')} += ({beam} + {dif}) * {p}[{P.area}] * h",
               f"{c.ledger_entry(inst, 'heat')} += {S} * h",
               f"{c.ledger_entry(inst, 'loss')} += {Q_loss} * h")
        if side is not None:
            a = c.storage_ports(inst.options["storage"]).array
            q_up = c.var("Q_upper")
            e_up = c.state(inst, np.zeros(1), suffix="_valve")
            c.emit("volumes", f"{q_up} = {a('coil_m')}[{k_up}] * CP * ({T_sup} - {a('coil_Tout')}[{k_up}]) "
                              f"if {a('coil_m')}[{k_up}] > 0.0 else 0.0",
                   f"{e_up}[0] += {q_up} * h")
            c.emit("signals",
                   f"{sig('Q_flow_upper', 'W', 'heat given by the upper coil (0 while it carries no flow)')} = {q_up}",
                   f"{sig('E_heat_upper', 'J', 'heat given by the upper coil since the start')} = {e_up}[0]")
