"""Micro-CHP RMB neoTower 2 (CoSES house 1): measured start-up, warm-up, steady state and cool-down with a water content.

Physics in words
----------------
The machine follows the CoSES ProHMo digital twin (upstream ``NeoTower2.mo``): in steady state
electric power and electric efficiency are linear in the modulation m (0.55…1, rate-limited at
±0.025 1/s), the total efficiency comes from a measured table over return temperature and
modulation, fuel = P_el/η_el and heat = fuel·(η_tot − η_el).  A start follows the measured start-up
table (825 s after ≥ t_amb downtime, "cold"; 200 s otherwise, "warm"); during start-up and warm-up a
downtime-dependent heat deficit P_heatup·H(τ), H = max(0, f0 − τ/t_steady), f0 = min(1, D/t_amb), is
withheld (1.2 MJ·f0² in total).  A stop follows the measured cool-down (pump run-on) table.  Above
T_ret_max the machine behaves as switched off.

Differences to the original (documented choices)
------------------------------------------------
* Water content.  The original imposes T_sup = 80 °C and back-calculates the flow (no inertia).
  Here the unit has a lumped water content V_water (state T_w, outlet temperature = T_w) heated by
  P_heat and flushed by the flow through the unit, m_flow = max(own pump flow, m_ext).  The balance
  C·dT_w/dt = P_heat + m_flow·CP·(T_in − T_w), C = CP·RHO·V_water, is integrated EXACTLY over the
  step for the (constant) heat and flow of the step (exponential solution), so it is stable for any
  dt and any external flow; the returned T_out is the step-mean outlet temperature, so that
  P_heat·dt = m_flow·CP·(T_out − T_in)·dt + C·ΔT_w holds to rounding.  (For a·dt < 1e-8,
  a = m·CP/C, the explicit Euler form with T_out = T_w at the step start is used — identical to first
  order.)  This deviates from the plain explicit scheme with T_out = T_w,old of the brief only in
  that it stays exact and stable when m·CP·dt > C (e.g. 60 s steps with a strong external flow).
* Internal pump.  Instead of the back-calculated flow: feed-forward m = P_heat/(CP·(T_set − T_in))
  plus a proportional correction C·(T_w − T_set)/(CP·(T_set − T_in)·τ_c), τ_c = max(tau_pump, 3·dt),
  clamped to [0, m_pump_max].  It holds T_w at T_sup_set in steady state; an external flow larger
  than the pump's lowers the outlet temperature (the "suction" effect the original cannot show).
* Start-up.  P_el (col 2), fuel (col 5) and the heat formula (col 4, minus the warm-up deficit) are
  those of the table.  The measured supply temperature (col 6) reads ≈22 °C while no water flows
  (stagnant pipe) and 63 °C when the pump starts, so the engine warms its coolant beforehand.  This
  coolant warming is modelled as extra heat into the water content, P_pre, taken from the fuel that
  the table shows as not delivered (P_pre ≤ P_fuel − max(P_el, 0) − P_tab, so fuel − el − heat ≥ 0
  always): before the first tabulated heat the content is warmed linearly towards the first
  measured flowing supply temperature (cold start) or T_sup_set (warm start), afterwards towards
  col 6.  The pump runs only while the tabulated heat is > 0: feed-forward on col 6 with only the
  flow-reducing side of the correction (a content warmer than the briefly falling table value is
  not flushed out).  With a small V_water (≤ 2 l) the outlet reproduces the rising part of col 6;
  with the default 12 l the fuel surplus (≈6 kW) can warm the content by only ≈0.12 K/s, so the
  outlet lags the measured 57 → 80 °C rise of 743–825 s (≈70 °C at 825 s, 80 °C at ≈950 s; the
  measured rise implies an effective hot volume of ≈2–3 l).
* Cool-down.  Own pump flow = col 3 · (pump flow just before the stop); the residual engine heat
  into the water is own_flow·CP·max(0, col 2 − T_in) (the original's delivered heat), which keeps
  the outlet at the tabulated temperature; P_el = col 4.  A cool-down happens only after a real
  start (not at simulation start).
* First start.  The original initialises the stop instant to the simulation start, so the first
  start is warm.  Here the downtime before the first start is t − t0 + initial_downtime (default
  36000 s), so the first start is cold unless the parameter is reduced.
* The 0.1 s start delay of the original is dropped; the rate limiter is a plain slew limit.

Parameters: see ``Params`` (units SI, temperatures in °C).
Data source: upstream repository DZinsmeister/CoSES_thermal_ProHMo,
``HeatGenerator/LaboratoryModels/Data/NeoTower2/`` (neoTower2_Efficiency/StartUp/CoolDown.txt),
copied to ``plant/data/chp_neotower2/`` (see NOTICE there).
Assumptions: one water node; no heat loss of the idle unit to the room; gas on LHV basis.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass
from math import exp, expm1
from pathlib import Path

import numpy as np
from numba import njit

from ..component import Knob, indices, param
from ..tables import interp1, interp2, read_tables
from ..water import CP, RHO
from .generator import IDLE, LOCKED_OUT, RUN_ON, START_UP, STEADY, WARM_UP, Generator, Mode, Outlet

DATA = Path(__file__).resolve().parent.parent / "data" / "chp_neotower2"


@dataclass(frozen=True)
class Params:
    P_el_max: float = param(1900.0, "W", "electric power at 100 % modulation", 100.0, 100e3)
    m_min: float = param(0.55, "1", "minimum modulation (electric-power based)", 0.0, 1.0)
    eta_el_max: float = param(0.24, "1", "electric efficiency at 100 % modulation", 0.01, 0.6)
    eta_el_min: float = param(0.18, "1", "electric efficiency at minimum modulation", 0.01, 0.6)
    eta_tot_max: float = param(0.90, "1", "total-efficiency scaling (table normalised by 0.90)", 0.1, 1.2)
    P_heatup: float = param(1000.0, "W", "heat withheld for warm-up after a long stop", 0.0, 100e3)
    t_start_cold: float = param(825.0, "s", "start-up length after downtime >= t_amb", 1.0, 3600.0)
    t_start_warm: float = param(200.0, "s", "start-up length after a shorter downtime", 1.0, 3600.0)
    t_steady: float = param(2400.0, "s", "time after start at which the warm-up deficit has vanished", 1.0, 86400.0)
    t_amb: float = param(36000.0, "s", "downtime after which the machine is fully cold", 1.0, 1e6)
    t_stop: float = param(84.0, "s", "length of the tabulated cool-down", 0.0, 600.0)
    T_sup_set: float = param(80.0, "degC", "supply temperature held by the internal pump", 30.0, 95.0)
    T_ret_max: float = param(75.0, "degC", "return temperature above which the unit behaves as off", 20.0, 95.0)
    T_ret_min: float = param(20.0, "degC", "lower clamp of the efficiency-table lookup", 0.0, 60.0)
    P_idle: float = param(35.0, "W", "stand-by electric consumption", 0.0, 1000.0)
    slew: float = param(0.025, "1/s", "rate limit of the effective modulation", 1e-4, 10.0)
    V_water: float = param(0.0025, "m3", "hot water content of the unit (thermal inertia; 2.5 l reproduces the measured start-up temperature rise)", 1e-5, 1.0)
    m_pump_max: float = param(0.25, "kg/s", "maximum flow of the internal pump", 1e-3, 5.0)
    tau_pump: float = param(5.0, "s", "time constant of the pump's temperature correction (>= 3 dt used)", 0.1, 600.0)
    initial_downtime: float = param(36000.0, "s", "downtime assumed before the simulation start", 0.0, 1e7)
    T_w0: float = param(20.0, "degC", "initial water-content temperature", 0.0, 100.0)


STATES = ("y", "T_w", "t_on", "t_off", "running", "m_pump", "m_stop", "f0", "t_start",
          "starts", "run_seconds", "E_fuel", "E_el", "E_heat")
# positions in the packed parameter vector and in the state vector, from the declarations
P = indices(Params)
X = indices(STATES)


def initial_state(params: Params) -> np.ndarray:
    x = np.zeros(len(STATES), dtype=np.float64)
    x[X.T_w] = params.T_w0
    x[X.t_off] = -params.initial_downtime
    return x


@functools.cache
def tables() -> tuple[np.ndarray, ...]:
    """(tab_eff, tab_start, tab_cool): Efficiency(11,3), StartUp(39,6), CoolDown(15,5)."""
    eff = read_tables(DATA / "neoTower2_Efficiency.txt")["Efficiency"]
    start = read_tables(DATA / "neoTower2_StartUp.txt")["StartUp"]
    cool = read_tables(DATA / "neoTower2_CoolDown.txt")["CoolDown"]
    return eff, start, cool


@njit(cache=True, inline="always")
def _water(Tw, P, m, T_in, C, dt):
    """Exact step of C dT/dt = P + m CP (T_in - T) for constant P, m: returns (dT_w, T_out mean)."""
    a_dt = m * CP * dt / C
    if a_dt < 1e-8:
        return dt * (P + m * CP * (T_in - Tw)) / C, Tw
    g = -expm1(-a_dt) / a_dt
    dT = g * dt * (P + m * CP * (T_in - Tw)) / C
    T_out = T_in + g * (Tw - T_in) + (1.0 - g) * P / (m * CP)
    return dT, T_out


@njit(cache=True, inline="always")
def _switch(t, x, p, on_eff):
    """Start (downtime, cold or warm start-up length) or stop (the pump flow the cool-down scales)."""
    if on_eff and x[X.running] < 0.5:
        D = t - x[X.t_off]
        x[X.t_on] = t
        x[X.running] = 1.0
        x[X.f0] = min(1.0, D / p[P.t_amb])
        x[X.t_start] = p[P.t_start_cold] if D >= p[P.t_amb] else p[P.t_start_warm]
        x[X.starts] += 1.0
    elif (not on_eff) and x[X.running] > 0.5:
        x[X.running] = 0.0
        x[X.t_off] = t
        x[X.m_stop] = x[X.m_pump]  # the pump flow of the last running step


@njit(cache=True, inline="always")
def _first_heat(tab_start, t_start, p):
    """(tau0, tau_pos, T_first): the last zero row of col 4 before the first positive one, that
    positive row's time and supply temperature; a start-up ending before it warms to T_sup_set."""
    n = tab_start.shape[0]
    i0 = n - 1
    for i in range(n - 1):
        if tab_start[i + 1, 3] > 0.0:
            i0 = i
            break
    tau0 = tab_start[i0, 0]
    tau_pos = tab_start[min(i0 + 1, n - 1), 0]
    T_first = tab_start[min(i0 + 1, n - 1), 5]
    if t_start <= tau0:
        tau0 = t_start
        T_first = p[P.T_sup_set]
    return tau0, tau_pos, T_first


@njit(cache=True, inline="always")
def _start_up(tau, t_start, dt, p, tab_start, eta_tot, H, P_fuel_nom, C, Tw, T_in):
    """The start-up table's step: returns (m_pump, P_el, P_fuel, P_heat)."""
    m_pump = 0.0
    ts = tab_start[:, 0]
    P_el = interp1(tau, ts, tab_start[:, 1]) * p[P.P_el_max]
    P_fuel = interp1(tau, ts, tab_start[:, 4]) * P_fuel_nom
    f_q = interp1(tau, ts, tab_start[:, 3])
    P_tab = max(0.0, f_q * P_fuel_nom * (eta_tot - p[P.eta_el_max]) - p[P.P_heatup] * H)
    surplus = max(0.0, P_fuel - max(P_el, 0.0) - P_tab)
    tau0, tau_pos, T_first = _first_heat(tab_start, t_start, p)
    if tau < tau0:
        # coolant pre-warming, no flow
        P_pre = C * (T_first - Tw) / max(tau0 - tau, dt)
        P_pre = min(surplus, max(0.0, P_pre))
        P_heat = P_pre
    else:
        T_tgt = T_first if tau + dt < tau_pos else interp1(tau + dt, ts, tab_start[:, 5])
        T_tgt = max(T_in + 1.0, T_tgt)
        P_pre = min(surplus, max(0.0, C * (T_tgt - Tw) / dt))
        P_heat = P_tab + P_pre
        if P_tab > 0.0:
            dTs = max(T_tgt - T_in, 1.0)
            tc = max(p[P.tau_pump], 3.0 * dt)
            m_ff = P_tab / (CP * dTs)
            # only the reducing side of the correction: a content warmer than the falling
            # table temperature is not flushed out (delivered heat stays the measured one)
            m_pump = m_ff + min(0.0, C * (Tw - T_tgt) / (CP * dTs * tc))
            m_pump = min(p[P.m_pump_max], max(0.0, m_pump))
    return m_pump, P_el, P_fuel, P_heat


@njit(cache=True, inline="always")
def _steady(m, dt, p, eta_tot, H, C, Tw, T_in):
    """Warm-up or steady state at modulation m: returns (mode, m_pump, P_el, P_fuel, P_heat)."""
    m_pump = 0.0
    mode = WARM_UP if H > 0.0 else STEADY
    span = 1.0 - p[P.m_min]
    frac = (m - p[P.m_min]) / span if span > 0.0 else 1.0
    eta_el = p[P.eta_el_min] + (p[P.eta_el_max] - p[P.eta_el_min]) * frac
    P_el = p[P.m_min] * p[P.P_el_max] + (p[P.P_el_max] - p[P.m_min] * p[P.P_el_max]) * frac
    P_fuel = P_el / eta_el
    P_heat = max(0.0, P_fuel * (eta_tot - eta_el) - p[P.P_heatup] * H)
    if P_heat > 0.0:
        T_tgt = p[P.T_sup_set]
        dTs = max(T_tgt - T_in, 1.0)
        tc = max(p[P.tau_pump], 3.0 * dt)
        m_pump = P_heat / (CP * dTs) + C * (Tw - T_tgt) / (CP * dTs * tc)
        m_pump = min(p[P.m_pump_max], max(0.0, m_pump))
    return mode, m_pump, P_el, P_fuel, P_heat


@njit(cache=True, inline="always")
def _running(t, dt, x, p, tab_eff, tab_start, y_set, T_in, C, Tw):
    """A running unit's step: returns (mode, m_pump, P_el, P_fuel, P_heat)."""
    tau = t - x[X.t_on]
    t_start = x[X.t_start]
    target_y = 1.0 if tau < t_start else min(1.0, max(0.0, y_set))
    dy = target_y - x[X.y]
    lim = p[P.slew] * dt
    x[X.y] += min(lim, max(-lim, dy))
    m = min(1.0, max(p[P.m_min], x[X.y]))
    H = max(0.0, x[X.f0] - tau / p[P.t_steady])
    Tk = max(T_in, p[P.T_ret_min]) + 273.15
    eta_tot = interp2(Tk, m, tab_eff) * p[P.eta_tot_max] / 0.90
    P_fuel_nom = p[P.P_el_max] / p[P.eta_el_max]
    if tau < t_start:
        mode = START_UP
        m_pump, P_el, P_fuel, P_heat = _start_up(tau, t_start, dt, p, tab_start, eta_tot, H, P_fuel_nom,
                                                 C, Tw, T_in)
    else:
        mode, m_pump, P_el, P_fuel, P_heat = _steady(m, dt, p, eta_tot, H, C, Tw, T_in)
    x[X.run_seconds] += dt
    return mode, m_pump, P_el, P_fuel, P_heat


@njit(cache=True, inline="always")
def _stopped(t, dt, x, p, tab_cool, on, T_in):
    """A stopped unit's step (cool-down after a real start, else idle or locked out): returns
    (mode, m_pump, P_el, P_fuel, P_heat)."""
    m_pump = 0.0
    P_heat = 0.0
    dy = -x[X.y]
    lim = p[P.slew] * dt
    x[X.y] += min(lim, max(-lim, dy))
    tau_off = t - x[X.t_off]
    if x[X.starts] > 0.5 and tau_off < p[P.t_stop]:
        mode = RUN_ON
        tc_ = tab_cool[:, 0]
        m_pump = interp1(tau_off, tc_, tab_cool[:, 2]) * x[X.m_stop]
        P_el = interp1(tau_off, tc_, tab_cool[:, 3])
        T_cd = interp1(tau_off, tc_, tab_cool[:, 1])
        P_heat = m_pump * CP * max(0.0, T_cd - T_in)
    else:
        P_el = -p[P.P_idle]
        mode = LOCKED_OUT if on > 0.5 else IDLE
    return mode, m_pump, P_el, 0.0, P_heat


@njit(cache=True)
def step(t, dt, x, p, tab_eff, tab_start, tab_cool, on, y_set, m_ext, T_in):
    """Advance the CHP by dt from time t; returns (m_flow, T_out, P_el, P_fuel, P_heat, mode)."""
    C = CP * RHO * p[P.V_water]
    Tw = x[X.T_w]
    on_eff = on > 0.5 and T_in < p[P.T_ret_max]
    _switch(t, x, p, on_eff)
    if x[X.running] > 0.5:
        mode, m_pump, P_el, P_fuel, P_heat = _running(t, dt, x, p, tab_eff, tab_start, y_set, T_in, C, Tw)
    else:
        mode, m_pump, P_el, P_fuel, P_heat = _stopped(t, dt, x, p, tab_cool, on, T_in)
    # the internal pump's own flow: what the unit's heat counter multiplies by its delta T
    x[X.m_pump] = m_pump
    m_flow = max(m_pump, m_ext)
    dT, T_out = _water(Tw, P_heat, m_flow, T_in, C, dt)
    x[X.T_w] = Tw + dT
    x[X.E_fuel] += P_fuel * dt
    x[X.E_el] += P_el * dt
    x[X.E_heat] += P_heat * dt
    return m_flow, T_out, P_el, P_fuel, P_heat, mode


class Kind(Generator):
    """The neoTower 2 as a generator on a coupling point (inputs on, y_set)."""

    name = "chp"
    Params = Params
    NOUN = "CHP"
    MODES = (Mode.IDLE, Mode.START_UP, Mode.WARM_UP, Mode.STEADY, Mode.RUN_ON, Mode.LOCKED_OUT, Mode.FAULT)
    MODE_WORDS = {Mode.RUN_ON: "cool-down"}
    RUN, RAN, PIPES, SUBSTITUTES = ("on", 0.5), ("P_el", 200.0), ("T_sup", "T_ret"), {"y_set": "on"}
    # A generator's water and metal delay its outlet (a CHP at 0.04 kg/s with 75 kJ/K: 450 s).
    # The file's 2.5 l reproduces the measured start-up table's rise, not a rig's unit with its
    # pipes; house 1's rig description gives 15 kg water and 40 kg steel, +-30 % (about 20 l of
    # water equivalent). Left at the file's value, labsim's drawn rigs (40-110 kJ/K) put a 400-520
    # s "sensor lag" on the CHP's outlet as a second effect. Calibrated first on that sensor
    # alone, once.
    KNOBS = (Knob("V_water", "m3", "water and metal of the CHP and its outlet pipe (water equivalent): how "
                  "its outlet follows a start, a stop and a change of flow", bounds=(0.0025, 0.03), rank=6,
                  joint=False, signals=("T_sup",)),)
    POWER = ("P_el", "Q_flow", "m_flow_pump", "Q_flow_meter", "P_fuel")
    ENERGIES = ("E_el", "E_heat", "E_fuel")
    DESCRIPTIONS = {"T_sup": "CHP supply (outlet) temperature", "T_ret": "CHP return (inlet) temperature",
                    "P_el": "electric power, + produced, - consumed",
                    "Q_flow": "heat delivered to the circuit m cp (T_sup - T_ret)",
                    "y": "effective electric modulation", "E_el": "electric energy produced (net)"}

    def initial_state(self, inst):
        return initial_state(inst.params)

    def stored_energy(self, inst, x):
        return CP * RHO * inst.params.V_water * float(x[X.T_w])

    def emit_pump_request(self, c, inst, T_in):
        """The flow the internal pump asks for this step with no flow forced through the unit
        (a scratch step of a copy of the state): what the unit's own heat counter sees."""
        x, p = c.views(inst)
        scratch, m = c.float_array(len(STATES)), c.var("m_pump")
        tabs = ", ".join(c.table(a) for a in tables())
        mod = c.module(__name__)
        c.emit("hydraulics", f"{scratch}[:] = {x}",
               f"{m} = {mod}.step(t, h, {scratch}, {p}, {tabs}, {c.s(inst.name + '.on')}, "
               f"{c.s(inst.name + '.y_set')}, 0.0, {T_in})[0]")
        return m

    def pump_stood(self, c, inst) -> str:
        # the internal pump's flow of the step before: it runs on through the cool-down
        x, _ = c.views(inst)
        return f"{x}[{X.m_pump}] <= 0.0"

    def emit_generator(self, c, inst, T_in, m_ext, m_pump=None):
        x, p = c.views(inst)
        out = Outlet.new(c)
        tabs = ", ".join(c.table(a) for a in tables())
        on = c.signal(inst, "on", "1", "input", "CHP run command (0/1)")
        y_set = c.signal(inst, "y_set", "1", "input", "CHP electric modulation request 0.55..1 (lower runs at 0.55)")
        mod = c.module(__name__)
        c.emit("hydraulics", f"{out.targets()} = {mod}.step(t, h, {x}, {p}, {tabs}, {on}, {y_set}, {m_ext}, {T_in})")
        # with a pressure-driven header the pump's request is a scratch step's (emit_pump_request)
        m_own = m_pump or f"{x}[{X.m_pump}]"
        meter = "the CHP own heat counter: internal-pump flow x (T_sup - T_ret), as the unit reports it"
        own = {"m_flow_pump": ("kg/s", "flow of the CHP internal pump (chp.m_flow is larger when the header "
                                       "forces flow through the unit)", m_own),
               "Q_flow_meter": ("W", meter, f"{m_own} * CP * ({c.s(inst.name + '.T_sup')} - {T_in})")}
        self.emit_outputs(c, inst, x, X, out, T_in, T_idle=f"{x}[{X.T_w}]", own=own)
        return out.m, out.T
