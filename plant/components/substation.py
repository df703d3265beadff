"""Bidirectional district-heating substation: a counterflow heat exchanger between the grid and a
house's coupling point (the lab's CHN connection, reference §8.1-8.3, §13.1).

Sign convention (the one place it is written)
---------------------------------------------
Positive = extraction: heat and house-side flow from the grid into the house. `m_flow_set > 0`
extracts, `< 0` feeds in; `Q_flow > 0` is heat into the house, `< 0` heat given to the grid;
`m_flow` and `m_flow_grid` carry the same sign. Why: the plant's ledger counts energy into the
house as positive (fuel), and the switch's own code, which is what the original computes,
takes extraction = max(q, 0) and feed-in = max(-q, 0) (§8.2). The switch's documentation text
("< 0: Feed In; > 0: Extraction") agrees; the house interface text ("positive: feed in, negative:
extraction") is the contradicting one (§14 item 5), and this kind does not follow it: a map of
the lab's CHN_S_FW_HC_set written in that sense needs a scale of -1.

Physics in words
----------------
Extraction (the kind called as a generator of a coupling point or branch): the house-side pump
takes m = min(m_flow_set, m_flow_max) from the return header (at least a forced flow m_ext) and
sends it, heated, to the supply header. Feed-in (called as a consumer of a coupling point): it
takes m = min(-m_flow_set, m_flow_max) from the supply header and sends it, cooled, to the
return header. The grid side carries m_grid = min(m_flow_grid_set, m_flow_grid_max) entering at
T_grid_sup (extraction: the grid's supply) or at T_grid_ret (feed-in: the grid's return, heated
and sent to the grid's supply). The exchanger is counterflow, steady, without water content:
    Q = epsilon C_min (T_grid_in - T_house_in),  C = m CP per side,
    epsilon = (1 - exp(-NTU (1 - Cr))) / (1 - Cr exp(-NTU (1 - Cr))),  NTU = UA/C_min,
    Cr = C_min/C_max  (Cr = 1: NTU/(1 + NTU)),  or a fixed `epsilon` when given (>= 0);
house outlet T_house_in + Q/C_house, grid outlet T_grid_in - Q/C_grid. Q follows the temperatures
in either mode (a grid colder than the house takes heat while "extracting"); no flow on either
side, no heat.

Applicability and assumptions: the SiL substation is a GreenCity heat exchanger (0.506 m2, k =
5820 W/(m2 K), UA = 2945 W/K, 0.44 l per side, §13.1); its equations are not available (§0.4),
so the exchanger is the textbook steady counterflow one and its 0.44 l are dropped. No grid-side
valve: the grid flow is a set-point as the lab's CHN_S_FW_TG_set; no pressures, the house-side
flow is imposed like every branch flow of the ideal switch (§8.1).

How it sits in a house file (one instance in both lists of one coupling point):
    [substation]
    kind = "substation"
    [switch]
    generators = ["boiler", "substation"]        # extraction (required: every substation extracts)
    consumers = ["mixer", "substation"]          # feed-in (optional)
Listed only as a generator (or a branch's generator) it extracts only; a negative m_flow_set
then moves nothing. The kind has the roles `generator` and `consumer` (ROLES): one instance may be named in both lists.

Inputs: `m_flow_set` (kg/s, signed: the lab's CHN_S_FW_HC_set), `m_flow_grid_set` (kg/s, >= 0:
CHN_S_FW_TG_set), `T_grid_sup`, `T_grid_ret` (degC; the kind writes the parameters' values
unless driven from outside; CHN_S_TM_TG is the one of them that enters the exchanger).
Outputs: `m_flow`, `T_sup` (house supply-header side), `T_ret` (return-header side),
`m_flow_grid`, `T_grid_in`, `T_grid_out`, `Q_flow`, `epsilon`, `E_extracted`, `E_fed_in`
(heat meters, J, both >= 0), `M_extracted`, `M_fed_in` (the meters' water counters, kg of grid
water through the exchanger, both >= 0: with the heat meters they give a district grid the exact
mass and enthalpy a house exchanged over an exchange step).
Ledger: extracted heat is "fuel" (energy into the house) and "heat" (into its water), so the
substation has no generator losses; heat fed in leaves the water as "building" (an export, like
the heat a consumer takes; key building_<name>).

Parameters
----------
| name | unit | meaning |
|---|---|---|
| UA | W/K | exchanger conductance (SiL: 0.506 m2 x 5820 W/(m2 K) = 2945 W/K) |
| epsilon | 1 | fixed effectiveness; < 0 (default): from UA and the flows (counterflow) |
| m_flow_max | kg/s | house-side pump maximum (§8.1: 0.25 l/s = 15 l/min) |
| m_flow_grid_max | kg/s | grid-side flow maximum |
| T_grid_sup | degC | grid supply temperature unless driven (70 degC) |
| T_grid_ret | degC | grid return temperature unless driven (40 degC) |

Tests: tests/plant/test_substation.py (effectiveness against an integrated counterflow exchanger
and the formula, extraction and feed-in in a house-1 variant with the ledger closed to
round-off, the sign convention, bad declarations).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from ..component import Kind as ComponentKind, indices, pack, param
from ..water import CP


@dataclass(frozen=True)
class Params:
    UA: float = param(2945.0, "W/K", "exchanger conductance", 0.0, 1e7)
    epsilon: float = param(-1.0, "1", "fixed effectiveness; < 0: from UA and the flows (counterflow)", -1.0, 1.0)
    m_flow_max: float = param(0.25, "kg/s", "house-side pump maximum", 0.0, 100.0)
    m_flow_grid_max: float = param(1.0, "kg/s", "grid-side flow maximum", 0.0, 100.0)
    T_grid_sup: float = param(70.0, "degC", "grid supply temperature unless driven from outside", 0.0, 150.0)
    T_grid_ret: float = param(40.0, "degC", "grid return temperature unless driven from outside", 0.0, 150.0)


STATES = ("E_extracted", "E_fed_in", "M_extracted", "M_fed_in")
# positions in the packed parameters and the state vector, from the declarations
P = indices(Params)
X = indices(STATES)


@njit(cache=True)
def effectiveness(p, C_house, C_grid):
    """Counterflow effectiveness from UA (or the fixed one), 0 without flow on a side."""
    C_min, C_max = min(C_house, C_grid), max(C_house, C_grid)
    if C_min <= 0.0:
        return 0.0
    if p[P.epsilon] >= 0.0:
        return p[P.epsilon]
    ntu = p[P.UA] / C_min
    cr = C_min / C_max
    if 1.0 - cr < 1e-9:
        return ntu / (1.0 + ntu)
    e = math.exp(-ntu * (1.0 - cr))
    return (1.0 - e) / (1.0 - cr * e)


@njit(cache=True)
def exchange(p, m_house, m_grid, T_house_in, T_grid_in):
    """(Q into the house [W], house outlet, grid outlet, effectiveness)."""
    C_house, C_grid = m_house * CP, m_grid * CP
    eps = effectiveness(p, C_house, C_grid)
    if eps <= 0.0:
        return 0.0, T_house_in, T_grid_in, 0.0
    Q = eps * min(C_house, C_grid) * (T_grid_in - T_house_in)
    return Q, T_house_in + Q / C_house, T_grid_in - Q / C_grid, eps


@njit(cache=True)
def extract(p, m_set, m_grid_set, m_ext, T_in, T_grid_sup):
    """The generator side: (house flow, house outlet, grid flow, grid outlet, effectiveness)."""
    if m_set < 0.0:
        return 0.0, T_in, 0.0, T_grid_sup, 0.0
    m = max(min(m_set, p[P.m_flow_max]), m_ext)
    m_grid = min(max(m_grid_set, 0.0), p[P.m_flow_grid_max])
    Q, T_out, T_grid_out, eps = exchange(p, m, m_grid, T_in, T_grid_sup)
    return m, T_out, m_grid, T_grid_out, eps


@njit(cache=True)
def feed_in(p, m_set, m_grid_set, T_sup, T_grid_ret):
    """The consumer side: (house flow, house outlet, grid flow, grid outlet, effectiveness)."""
    if m_set >= 0.0:
        return 0.0, T_sup, 0.0, T_grid_ret, 0.0
    m = min(-m_set, p[P.m_flow_max])
    m_grid = min(max(m_grid_set, 0.0), p[P.m_flow_grid_max])
    Q, T_out, T_grid_out, eps = exchange(p, m, m_grid, T_sup, T_grid_ret)
    return m, T_out, m_grid, T_grid_out, eps


class Kind(ComponentKind):
    """A generator when extracting, a consumer when feeding in; one instance, one state."""

    name = "substation"
    Params = Params
    role = "generator"
    ROLES = ("generator", "consumer")

    def _slots(self, c, inst):
        """State, parameters and inputs, allocated at the first of the two protocol calls."""
        key = f"{inst.name}.substation"
        if key not in c.values:
            x = c.state(inst, np.zeros(len(STATES)))
            p = c.param(inst, pack(inst.params))
            sig = lambda local, unit, desc: c.signal(inst, local, unit, "input", desc)  # noqa: E731
            slots = {"x": x, "p": p,
                     "m_set": sig("m_flow_set", "kg/s", "house-side flow: > 0 extraction from the grid, < 0 feed-in"),
                     "m_grid_set": sig("m_flow_grid_set", "kg/s", "grid-side flow through the exchanger (>= 0)"),
                     "T_grid_sup": sig("T_grid_sup", "degC", "grid supply temperature (enters when extracting)"),
                     "T_grid_ret": sig("T_grid_ret", "degC", "grid return temperature (enters when feeding in)")}
            c.write_command("control", f"{inst.name}.T_grid_sup", f"{p}[{P.T_grid_sup}]")
            c.write_command("control", f"{inst.name}.T_grid_ret", f"{p}[{P.T_grid_ret}]")
            c.values[key] = slots
        return c.values[key]

    def pump_stood(self, c, inst) -> str:
        return f"{self._slots(c, inst)['m_set']} <= 0.0"

    def emit_generator(self, c, inst, T_in, m_ext, m_pump=None):
        k = self._slots(c, inst)
        m, T, mg, Tg, eps = (c.var(v) for v in ("m_dh", "T_dh", "m_grid", "T_grid", "eps"))
        c.emit("hydraulics", f"{m}, {T}, {mg}, {Tg}, {eps} = {c.module(__name__)}.extract({k['p']}, "
                             f"{k['m_set']}, {k['m_grid_set']}, {m_ext}, {T_in}, {k['T_grid_sup']})")
        k["gen"] = (m, T_in, T, mg, Tg, eps)
        return m, T

    def emit_consumer(self, c, inst, T_sup):
        k = self._slots(c, inst)
        m, T, mg, Tg, eps = (c.var(v) for v in ("m_dh", "T_dh", "m_grid", "T_grid", "eps"))
        c.emit("hydraulics", f"{m}, {T}, {mg}, {Tg}, {eps} = {c.module(__name__)}.feed_in({k['p']}, "
                             f"{k['m_set']}, {k['m_grid_set']}, {T_sup}, {k['T_grid_ret']})")
        k["con"] = (m, T_sup, T, mg, Tg, eps)
        return m, T

    def emit(self, c, inst):
        """Signals, heat meters and ledger, once both protocol calls are in (connections emit
        before this role)."""
        k = c.values.get(f"{inst.name}.substation")
        if k is None:
            return  # on no coupling point: reported by the declaration
        x = k["x"]
        lines, Q = [], "0.0"
        if "gen" in k:
            m_g, Tin_g, Tout_g, mg_g, Tg_g, eps_g = k["gen"]
            Q = c.var("Q_extracted")
            lines += [f"{Q} = {m_g} * CP * ({Tout_g} - {Tin_g})",
                      f"{c.ledger_entry(inst, 'fuel')} += {Q} * h",
                      f"{c.ledger_entry(inst, 'heat')} += {Q} * h"]
        if "con" in k:
            m_c, Tin_c, Tout_c, mg_c, Tg_c, eps_c = k["con"]
            Q_c = c.var("Q_fed_in")
            lines += [f"{Q_c} = {m_c} * CP * ({Tin_c} - {Tout_c})",
                      f"{c.ledger_entry(inst, 'building')} += {Q_c} * h"]
            Q_net = c.var("Q_dh")
            lines.append(f"{Q_net} = {Q} - {Q_c}")
            Q = Q_net
        else:  # extraction only
            m_c, Tin_c, Tout_c, mg_c, Tg_c, eps_c = "0.0", k["gen"][2], k["gen"][1], "0.0", k["T_grid_ret"], "0.0"
        if "gen" not in k:  # feed-in only
            m_g, Tin_g, Tout_g, mg_g, Tg_g, eps_g = "0.0", Tout_c, Tin_c, "0.0", k["T_grid_sup"], "0.0"
        fed = f"{k['m_set']} < 0.0"
        sig = lambda local, unit, desc: c.signal(inst, local, unit, "output", desc)  # noqa: E731
        c.emit("signals", *lines,
               f"{x}[{X.E_extracted}] += max({Q}, 0.0) * h",
               f"{x}[{X.E_fed_in}] += max(-{Q}, 0.0) * h",
               f"{x}[{X.M_extracted}] += {mg_g} * h",
               f"{x}[{X.M_fed_in}] += {mg_c} * h",
               f"{sig('m_flow', 'kg/s', 'house-side flow (+ extraction from the grid, - feed-in)')} = {m_g} - {m_c}",
               f"{sig('T_sup', 'degC', 'house side at the supply header (outlet when extracting, inlet when feeding in)')} = "
               f"{Tin_c} if {fed} else {Tout_g}",
               f"{sig('T_ret', 'degC', 'house side at the return header (inlet when extracting, outlet when feeding in)')} = "
               f"{Tout_c} if {fed} else {Tin_g}",
               f"{sig('m_flow_grid', 'kg/s', 'grid-side flow (+ while extracting, - while feeding in)')} = {mg_g} - {mg_c}",
               f"{sig('T_grid_in', 'degC', 'grid water entering the exchanger')} = "
               f"{k['T_grid_ret']} if {fed} else {k['T_grid_sup']}",
               f"{sig('T_grid_out', 'degC', 'grid water leaving the exchanger')} = {Tg_c} if {fed} else {Tg_g}",
               f"{sig('Q_flow', 'W', 'heat into the house (+ extraction, - feed-in)')} = {Q}",
               f"{sig('epsilon', '1', 'exchanger effectiveness this step (0 without flow)')} = {eps_c} if {fed} else {eps_g}",
               f"{sig('E_extracted', 'J', 'heat meter: heat taken from the grid since the start')} = {x}[{X.E_extracted}]",
               f"{sig('E_fed_in', 'J', 'heat meter: heat given to the grid since the start')} = {x}[{X.E_fed_in}]",
               f"{sig('M_extracted', 'kg', 'heat meter: grid water through the exchanger while extracting')} = "
               f"{x}[{X.M_extracted}]",
               f"{sig('M_fed_in', 'kg', 'heat meter: grid water through the exchanger while feeding in')} = "
               f"{x}[{X.M_fed_in}]")
