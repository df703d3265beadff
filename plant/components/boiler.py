"""Condensing gas boiler Wolf CGB-14 (also CGB-20/-50 by P_nom): measured steady state, start-up, run-on, lock-out and anti-cycling.

Physics in words
----------------
Follows the CoSES ProHMo twin (upstream ``WolfCGB.mo`` with the ``WolfCGB14_GC`` wrapper).  The
native input is a 0–10 V analogue demand: U ≤ U_min (2 V) is off, otherwise the modulation request
is U/10, rate-limited at ±slew and clamped to [m_min, 1].  In steady state "power follows
modulation, flow follows power": with T* = max(T_in, T_ret_min)
    P_heat = Tab_PHeat(T*, m)·P_nom,   ΔT = Tab_DeltaT(T*, m)·dT_set,   η = Tab_Eff(T*, m)·eta_max,
    P_fuel = P_heat/η,  m_flow = P_heat/(CP·ΔT),  T_out = T_in + ΔT.
Start-up (t_start = 300 s) scales heat by the start-up table's column 2 at full steady fuel input;
the flow uses column 2 as well, as upstream does (column 3, which by its shape is the measured flow
factor, is used instead if use_flow_column is true).  After a stop the pump runs on for t_stop =
70 s: heat = cool-down col 2 · steady power (at the current, decaying modulation), flow = col 3 ·
flow before the stop, no fuel.  Return above T_ret_max (75 °C) locks the burner out until the
return falls below T_ret_release (70 °C).

Note on the measured tables versus the publication's "constant flow, 10 K spread": the standard
tables give a flow that follows power with a measured spread of ≈13 K (20 % load, 50–70 °C
return) to ≈20 K (full load, low return), and 6–18 kW output for a 14 kW label.  The "paper"
table variant (``tables("paper")``, use dT_set = 10 K and eta_max = 1.015) has a spread independent
of modulation.

Additions to the original (documented choices)
----------------------------------------------
* Anti-short-cycling: after a burner stop the burner may not restart before t_anti_cycle (Wolf's
  "burner anti-cycling time", default 300 s); mode Mode.ANTI_CYCLE (6) while waiting.  Set 0 for the original.
* No water content (as upstream): P_heat = m_flow·CP·(T_out − T_in) exactly.  The flow through the
  unit is max(own flow, m_ext); T_out is computed from the energy balance with that flow.  Where a
  table phase would give a spread above 1.5·dT_set with a tiny flow (end of the run-on), the
  reported heat is limited to m_flow·CP·1.5·dT_set (the rest counts as loss); upstream divides by
  max(flow, 1e-5 m3/s) instead, which breaks the energy balance.
* P_el: −P_idle when not firing (also during the run-on), 0 while firing (as upstream).

Data sets (link ``data``)
------------------------
* ``wolf_cgb14`` (default): the CGB-14 laboratory tables, upstream DZinsmeister/CoSES_thermal_ProHMo
  ``HeatGenerator/LaboratoryModels/Data/WolfCGB14/``, copied to ``plant/data/boiler_wolf_cgb/``;
  P_nom scales the normalised power (CGB-50: P_nom = 50000, no table of its own exists upstream).
* ``wolf_cgb20``: the CGB-20's data-sheet curves (``plant/data/boiler_wolf_cgb20/Wolf_CBG_20.txt``:
  Q_CB_max and eta_norm at return 30…70 °C, Q_CB_min at 30 and 60 °C).  The steady tables keep the
  CGB-14's measured shape and are anchored on them: at every row of the CGB-14 grid (25…70 °C)
      P(T, m) = Q_min(T) + (Q_max(T) − Q_min(T))·s(T, m),  s = the CGB-14's (P(m) − P(0.2))/(P(1) − P(0.2)),
      η(T, m) = eta_norm(T)·Eff14(T, m)/Eff14(T, 1),       ΔT: the CGB-14's,
  with Q_max, Q_min, eta_norm interpolated linearly in T and held beyond their ends; the power is
  normalised by 20 kW (P_nom = 20000 reproduces the data sheet).  So at full modulation the model
  gives Q_CB_max and eta_norm, at the minimum modulation (m_min = 0.2) Q_CB_min, at their points
  (tests/validation/test_boiler_cgb20.py).  Start-up and run-on: the CGB-14's tables.

Parameters: see ``Params``.  Assumptions: gas on LHV basis (η up to 1.05).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numba import njit

from ..component import DataSet, indices, link, pack, param
from ..tables import interp1, interp2, read_tables
from ..water import CP, RHO
from .generator import ANTI_CYCLE, IDLE, LOCKED_OUT, RUN_ON, START_UP, STEADY, Generator, Mode, Outlet

DATA = Path(__file__).resolve().parent.parent / "data" / "boiler_wolf_cgb"
DATA_CGB20 = DATA.parent / "boiler_wolf_cgb20"
DATA_SETS = ("wolf_cgb14", "wolf_cgb20")


@dataclass(frozen=True)
class Params:
    P_nom: float = param(14000.0, "W", "nominal power scaling the normalised power table", 1000.0, 1e6)
    m_min: float = param(0.20, "1", "minimum modulation", 0.0, 1.0)
    eta_max: float = param(1.05, "1", "scaling of the normalised efficiency table (LHV)", 0.5, 1.2)
    dT_set: float = param(20.0, "K", "scaling of the normalised spread table", 1.0, 60.0)
    T_ret_max: float = param(75.0, "degC", "return temperature above which the burner locks out", 20.0, 100.0)
    T_ret_release: float = param(70.0, "degC", "return temperature below which the lock-out is released", 10.0, 100.0)
    T_ret_min: float = param(20.0, "degC", "lower clamp of the table lookups", 0.0, 60.0)
    t_start: float = param(300.0, "s", "length of the tabulated start-up", 1.0, 300.0)
    t_stop: float = param(70.0, "s", "length of the tabulated run-on", 0.0, 70.0)
    P_idle: float = param(35.0, "W", "stand-by electric consumption", 0.0, 1000.0)
    slew: float = param(0.025, "1/s", "rate limit of the modulation", 1e-4, 10.0)
    t_anti_cycle: float = param(300.0, "s", "minimum time between a burner stop and the next start", 0.0, 3600.0)
    U_min: float = param(2.0, "V", "analogue demand at or below which the boiler is off", 0.0, 10.0)
    use_flow_column: bool = param(False, "1", "start-up flow from table column 3 instead of column 2 (upstream)")


STATES = ("y", "t_on", "t_off", "running", "locked", "m_last", "m_stop",
          "starts", "run_seconds", "E_fuel", "E_el", "E_heat")
# positions in the packed parameters and the state vector, from the declarations
P = indices(Params)
X = indices(STATES)

SPREAD_CAP = 1.5  # max spread in start-up/run-on, in units of dT_set


def initial_state(params: Params) -> np.ndarray:
    x = np.zeros(len(STATES), dtype=np.float64)
    x[X.t_off] = -1e9
    return x


@functools.cache
def tables(variant: str = "standard") -> tuple[np.ndarray, ...]:
    """(tab_P, tab_dT, tab_eff, tab_start, tab_cool); variant 'standard' or 'paper' (the CGB-14's
    steady-state tables) or 'wolf_cgb20' (the CGB-20 data sheet on the CGB-14's shape)."""
    if variant == "wolf_cgb20":
        return _cgb20(*tables("standard"))
    name = {"standard": "WolfCGB14_SteadyState.txt", "paper": "WolfCGB14_SteadyState_Paper.txt"}[variant]
    ss = read_tables(DATA / name)
    start = read_tables(DATA / "WolfCGB14_StartUp.txt")["StartUp"]
    cool = read_tables(DATA / "WolfCGB14_CoolDown.txt")["CoolDown"]
    return ss["PHeat"], ss["DeltaT"], ss["EffHeat"], start, cool


CGB20_RATING = 20000.0  # W: the power the wolf_cgb20 table is normalised by


def _cgb20(tab_P, tab_dT, tab_eff, start, cool):
    """The CGB-20 steady tables on the CGB-14 grid (module docstring, "Data sets")."""
    sheet = read_tables(DATA_CGB20 / "Wolf_CBG_20.txt")
    T = tab_P[1:, 0]
    q_max = np.interp(T, sheet["Q_CB_max"][:, 0], sheet["Q_CB_max"][:, 1])
    q_min = np.interp(T, sheet["Q_CB_min"][:, 0], sheet["Q_CB_min"][:, 1])
    eta = np.interp(T, sheet["eta_norm"][:, 0], sheet["eta_norm"][:, 1])
    P14 = tab_P[1:, 1:]
    shape = (P14 - P14[:, :1]) / (P14[:, -1:] - P14[:, :1])
    P, E = tab_P.copy(), tab_eff.copy()
    P[1:, 1:] = (q_min[:, None] + (q_max - q_min)[:, None] * shape) / CGB20_RATING
    E14 = tab_eff[1:, 1:]
    E[1:, 1:] = eta[:, None] * (E14 / E14[:, -1:]) / Params().eta_max
    return P, tab_dT, E, start, cool


@njit(cache=True)
def measured(dt, x, p, tab_eff, U_set, m_meas, T_meas, T_in):
    """The boiler at its measured outlet (flow m_meas, temperature T_meas): the heat is what the
    water took, the gas what the efficiency table gives for it at the commanded modulation and
    the return; returns (m_flow, T_out, P_el, P_fuel, P_heat, mode) like step."""
    m_flow = max(m_meas, 0.0)
    T_out = T_meas if m_flow > 0.0 else T_in
    P_heat = m_flow * CP * (T_out - T_in)  # the water's: below zero where it cooled in the boiler
    running = P_heat > 0.0 and U_set > p[P.U_min]
    if running and x[X.running] < 0.5:
        x[X.starts] += 1.0
    x[X.running] = 1.0 if running else 0.0
    x[X.y] = min(1.0, U_set / 10.0) if running else 0.0
    m = min(1.0, max(p[P.m_min], x[X.y]))
    eta = interp2(max(T_in, p[P.T_ret_min]) + 273.15, m, tab_eff) * p[P.eta_max]
    P_fuel = P_heat / eta if running else 0.0
    P_el = 0.0 if running else -p[P.P_idle]
    if running:
        x[X.run_seconds] += dt
    x[X.E_fuel] += P_fuel * dt
    x[X.E_el] += P_el * dt
    x[X.E_heat] += P_heat * dt
    return m_flow, T_out, P_el, P_fuel, P_heat, STEADY if running else IDLE


@njit(cache=True)
def step(t, dt, x, p, tab_P, tab_dT, tab_eff, tab_start, tab_cool, U_set, m_ext, T_in):
    """Advance the boiler by dt from time t; returns (m_flow, T_out, P_el, P_fuel, P_heat, mode)."""
    if T_in > p[P.T_ret_max]:
        x[X.locked] = 1.0
    elif T_in < p[P.T_ret_release]:
        x[X.locked] = 0.0
    req = U_set > p[P.U_min]
    on_eff = req and x[X.locked] < 0.5
    waiting = False
    if on_eff and x[X.running] < 0.5:
        if x[X.starts] > 0.5 and t - x[X.t_off] < p[P.t_anti_cycle]:
            waiting = True
        else:
            x[X.running] = 1.0
            x[X.t_on] = t
            x[X.starts] += 1.0
    elif (not on_eff) and x[X.running] > 0.5:
        x[X.running] = 0.0
        x[X.t_off] = t
        x[X.m_stop] = x[X.m_last]
    running = x[X.running] > 0.5
    target = min(1.0, U_set / 10.0) if running else 0.0
    lim = p[P.slew] * dt
    x[X.y] += min(lim, max(-lim, target - x[X.y]))
    m = min(1.0, max(p[P.m_min], x[X.y]))
    Tk = max(T_in, p[P.T_ret_min]) + 273.15
    P_ss = interp2(Tk, m, tab_P) * p[P.P_nom]
    dT_ss = interp2(Tk, m, tab_dT) * p[P.dT_set]
    eta = interp2(Tk, m, tab_eff) * p[P.eta_max]
    q_ss = P_ss / (CP * dT_ss)
    m_own = 0.0
    P_heat = 0.0
    P_fuel = 0.0
    P_el = -p[P.P_idle]
    mode = IDLE
    if running:
        P_el = 0.0
        P_fuel = P_ss / eta
        tau = t - x[X.t_on]
        if tau < p[P.t_start]:
            mode = START_UP
            f = interp1(tau, tab_start[:, 0], tab_start[:, 1])
            fq = interp1(tau, tab_start[:, 0], tab_start[:, 2]) if p[P.use_flow_column] > 0.5 else f
            P_heat = f * P_ss
            m_own = fq * q_ss
        else:
            mode = STEADY
            P_heat = P_ss
            m_own = q_ss
        x[X.m_last] = m_own
        x[X.run_seconds] += dt
    else:
        tau_off = t - x[X.t_off]
        if x[X.starts] > 0.5 and tau_off < p[P.t_stop]:
            mode = RUN_ON
            P_heat = interp1(tau_off, tab_cool[:, 0], tab_cool[:, 1]) * P_ss
            m_own = interp1(tau_off, tab_cool[:, 0], tab_cool[:, 2]) * x[X.m_stop]
        elif waiting:
            mode = ANTI_CYCLE
        elif req and x[X.locked] > 0.5:
            mode = LOCKED_OUT
    m_flow = max(m_own, m_ext)
    P_heat = min(P_heat, m_flow * CP * SPREAD_CAP * p[P.dT_set])
    T_out = T_in + P_heat / (CP * m_flow) if m_flow > 0.0 else T_in
    x[X.E_fuel] += P_fuel * dt
    x[X.E_el] += P_el * dt
    x[X.E_heat] += P_heat * dt
    return m_flow, T_out, P_el, P_fuel, P_heat, mode


class Kind(Generator):
    """The Wolf CGB as a generator on a coupling point (input: the 0-10 V demand U_set)."""

    name = "boiler"
    Params = Params
    LINKS = {"data": link("wolf_cgb14", "steady-state data set: wolf_cgb14 (CGB-14 laboratory tables, scaled by "
                                        "P_nom) or wolf_cgb20 (the CGB-20 data sheet, P_nom = 20000)",
                          type=DataSet, range=DATA_SETS),
             "outlet": link("simulated", "simulated (the model's outlet), or measured: the outlet temperature and "
                                         "flow are inputs (m_flow_measured, T_sup_measured: a recording's), the gas "
                                         "follows from the heat by the efficiency table", type=str,
                            range=("simulated", "measured"))}
    NOUN = "boiler"
    MODES = (Mode.IDLE, Mode.START_UP, Mode.STEADY, Mode.RUN_ON, Mode.LOCKED_OUT, Mode.ANTI_CYCLE, Mode.FAULT)
    POWER = ("Q_flow", "P_fuel", "P_el")
    ENERGIES = ("E_heat", "E_fuel")
    DESCRIPTIONS = {"starts": "number of burner starts", "run_hours": "burner operating hours"}
    RUN, RAN, PIPES = ("U_set", 2.0), ("Q_flow", 500.0), ("T_sup", "T_ret")

    def initial_state(self, inst):
        return initial_state(inst.params)

    def pump_stood(self, c, inst) -> str:
        # not running: standing, or in the run-on, whose flow the state does not keep
        x, _ = c.views(inst)
        return f"{x}[{X.running}] < 0.5"

    def emit_generator(self, c, inst, T_in, m_ext):
        x, p = c.views(inst)
        out = Outlet.new(c)
        data = inst.options.get("data", "wolf_cgb14")  # one of DATA_SETS (the declaration checked it)
        tabs = ", ".join(c.table(a) for a in tables("standard" if data == "wolf_cgb14" else data))
        U = c.signal(inst, "U_set", "V", "input", "boiler 0-10 V demand: <= 2 V off, above: modulation U/10")
        mod = c.module(__name__)
        if inst.options.get("outlet") == "measured":
            m_in, T_meas = self.measured_outlet(c, inst)
            eff = c.table(tables("standard" if data == "wolf_cgb14" else data)[2])
            c.emit("hydraulics", f"{out.targets()} = {mod}.measured(h, {x}, {p}, {eff}, {U}, {m_in}, {T_meas}, {T_in})")
        else:
            c.emit("hydraulics", f"{out.targets()} = {mod}.step(t, h, {x}, {p}, {tabs}, {U}, {m_ext}, {T_in})")
        self.emit_outputs(c, inst, x, X, out, T_in)
        return out.m, out.T
