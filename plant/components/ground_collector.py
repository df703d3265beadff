"""Ground collector: the brine source of a ground-source heat pump (a horizontal collector in a ground node).

The original (GreenCity `GroundCollector`) is not available, so this is a model of our own whose
assumptions are written down here. It is the brine side of the Wolf BWS-1-10 (`heat_pump_brine`,
plant/components/heat_pump.py), which links it as `collector`.

Physics in words
----------------
* Undisturbed ground at the collector depth z follows the ProHMo environment's analytic profile
  (reference §11.2): T_u(z, τ) = T_mean + G·z + (T_max_month − T_mean)·e^(−ξ)·cos(2π·τ/P − 2π·7/12 − ξ),
  ξ = z·√(π/(a·P)), P = one year, τ = local time since the profile year's start (the weather's
  clock). Defaults are the environment's constants (annual mean air 9.76 °C, warmest month
  19.1 °C, a = λ/(ρc) = 1.45/(1800·1339) m²/s, G = 0.025 K/m); T_max_month = T_mean gives a
  constant ground temperature.
* The soil around the pipes is one node (capacity C_ground) coupled to the undisturbed ground
  through H_ground: C_ground·dT_g/dt = H_ground·(T_u − T_g) − Q_brine.
* The brine loop has no heat capacity of its own (its ~0.4 m³ settle within minutes, the ground
  node within days): the collector delivers exactly the heat the heat pump takes from the brine,
  Q_brine = the heat pump's source heat (E_source). With the brine pump running (flow m_flow,
  water properties as upstream) the collector is a heat exchanger of effectiveness
  ε = 1 − exp(−UA/(m_flow·CP)) against the ground node, so for a given Q_brine
      T_ret = T_g − Q_brine/(ε·m_flow·CP)   (brine from the heat pump into the collector)
      T_sup = T_ret + Q_brine/(m_flow·CP)    (brine from the collector to the heat pump).
  With the pump off the brine rests at the ground-node temperature.
* The heat pump reads T_sup of the previous step (start-of-step coupling, as everywhere in the
  compiled step): the brine temperatures are set from the node's end-of-step temperature and
  this step's source heat. The node steps explicitly and conservatively.

Energy: E_ground (undisturbed ground → node) − E (node → brine) = C_ground·(T_g − T_g,0) exactly.
The node holds soil, not water: it is outside the house's water-side ledger, where the heat pump
books E as "fuel" (energy into the system).

Default sizing (a horizontal collector for the BWS-1-10, source heat ~8.5 kW at B0/W35): 340 m²
of collector at 1.5 m depth (VDI 4640's ~25 W/m²), 700 m of PE 32×2.9 pipe; the node is the 1 m
soil layer around the pipes (340 m³ · 1800 kg/m³ · 1339 J/(kg K) = 8.2·10⁸ J/K), coupled to the
undisturbed ground above and below over ~1 m (2·λ·A/1 m ≈ 1000 W/K); pipe to node: soil shell
16 → 250 mm and the pipe wall, ≈ 0.38 m·K/W, i.e. UA ≈ 1800 W/K; brine flow 0.41 kg/s (upstream's
5 K spread at the nominal source heat). Applicability: heating-season operation, hours to
months; no freezing of the soil (latent heat), no regeneration by cooling, no lateral
interaction with the building.

| parameter | unit | meaning |
|---|---|---|
| depth | m | collector depth z |
| T_mean | degC | annual mean of the undisturbed surface ground (= annual mean air) |
| T_max_month | degC | warmest monthly mean air temperature (amplitude T_max_month − T_mean) |
| diffusivity | m2/s | ground thermal diffusivity a = λ/(ρ c) |
| gradient | K/m | geothermal gradient G |
| C_ground | J/K | heat capacity of the ground node |
| H_ground | W/K | conductance node ↔ undisturbed ground |
| UA | W/K | conductance brine ↔ ground node (pipe wall and soil shell) |
| m_flow | kg/s | brine flow while the heat pump runs |
| dT_init | K | ground node below the undisturbed temperature at the start (earlier extraction) |

Validated by tests/plant/test_ground_collector.py (undisturbed profile, steady state against the
analytic solution, energy balance) and tests/plant/test_heat_pump.py (in a house).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from ..component import Kind as ComponentKind, indices, pack, param
from ..water import CP

YEAR = 365.0 * 86400.0


@dataclass(frozen=True)
class Params:
    depth: float = param(1.5, "m", "collector depth", 0.3, 200.0)
    T_mean: float = param(9.76, "degC", "annual mean undisturbed surface ground temperature", -10.0, 30.0)
    T_max_month: float = param(19.1, "degC", "warmest monthly mean (amplitude = T_max_month - T_mean)", -10.0, 40.0)
    diffusivity: float = param(6.016e-7, "m2/s", "ground thermal diffusivity lambda/(rho c)", 1e-8, 1e-5)
    gradient: float = param(0.025, "K/m", "geothermal gradient", 0.0, 0.2)
    C_ground: float = param(8.2e8, "J/K", "heat capacity of the ground node around the pipes", 1e5, 1e12)
    H_ground: float = param(1000.0, "W/K", "conductance ground node to undisturbed ground", 0.0, 1e6)
    UA: float = param(1800.0, "W/K", "conductance brine to ground node", 1.0, 1e6)
    m_flow: float = param(0.41, "kg/s", "brine flow while the heat pump runs", 0.01, 100.0)
    dT_init: float = param(0.0, "K", "ground node below the undisturbed temperature at the start", -10.0, 20.0)


STATES = ("T_ground", "T_sup", "T_ret", "E", "E_ground")
# positions in the packed parameters and the state vector, from the declarations
P = indices(Params)
X = indices(STATES)


@njit(cache=True)
def undisturbed(p, tau):
    """Undisturbed ground temperature [degC] at the collector depth, local time tau [s]."""
    z = p[P.depth]
    xi = z * math.sqrt(math.pi / (p[P.diffusivity] * YEAR))
    return (p[P.T_mean] + p[P.gradient] * z + (p[P.T_max_month] - p[P.T_mean]) * math.exp(-xi)
            * math.cos(2.0 * math.pi * tau / YEAR - 2.0 * math.pi * 7.0 / 12.0 - xi))


def initial_state(params: Params, tau0: float = 0.0) -> np.ndarray:
    """Ground node dT_init below the undisturbed ground at local time tau0; brine at rest in it."""
    T = undisturbed(pack(params), tau0) - params.dT_init
    return np.array([T, T, T, 0.0, 0.0], dtype=np.float64)


@njit(cache=True)
def brine(p, T_ground, Q, pump):
    """(T_sup, T_ret) of the brine for the heat Q [W] taken from it (quasi-steady exchanger)."""
    if pump <= 0.5:
        return T_ground, T_ground
    mc = p[P.m_flow] * CP
    eps = 1.0 - math.exp(-p[P.UA] / mc)
    T_ret = T_ground - Q / (eps * mc)
    return T_ret + Q / mc, T_ret


@njit(cache=True)
def step(dt, x, p, tau, Q, pump):
    """Advance by dt: the brine takes Q [W] (the heat pump's source heat) while the pump runs
    (pump > 0.5); returns (T_undisturbed, Q_ground into the node [W])."""
    T_u = undisturbed(p, tau)
    T_g = x[X.T_ground]
    Q_g = p[P.H_ground] * (T_u - T_g)
    x[X.T_ground] = T_g + dt * (Q_g - Q) / p[P.C_ground]
    x[X.T_sup], x[X.T_ret] = brine(p, x[X.T_ground], Q, pump)  # what the heat pump sees next step
    x[X.E] += Q * dt
    x[X.E_ground] += Q_g * dt
    return T_u, Q_g


class Kind(ComponentKind):
    """The collector as the source of a brine heat pump (the heat pump links it as `collector`
    and hands it its source heat and pump state)."""

    name = "ground_collector"
    Params = Params
    role = "source"

    def initial_state(self, inst, tau0: float = 0.0):
        return initial_state(inst.params, tau0)

    def views(self, c, inst):
        """The state and parameter views (allocated by whichever of collector and heat pump
        emits first; the initial ground temperature at the weather's start time)."""
        weather = c.instances.get("weather")
        tau0 = weather.options.get("tau0", 0.0) if weather is not None else 0.0
        return c.views(inst, self.initial_state(inst, tau0))

    def source_temperature(self, c, inst) -> str:
        """The brine temperature a heat pump sees at the start of the step (collector outlet)."""
        x, _ = self.views(c, inst)
        return f"{x}[{X.T_sup}]"

    def brine_temperatures(self, c, inst) -> tuple[str, str]:
        """(brine into the heat pump, brine back into the collector) at the end of the step."""
        x, _ = self.views(c, inst)
        return f"{x}[{X.T_sup}]", f"{x}[{X.T_ret}]"

    def attach(self, c, inst, user, Q: str, pump: str) -> None:
        """A heat pump takes Q [W] from this collector while pump > 0.5 (one heat pump each)."""
        key = f"{inst.name}.source"
        if key in c.values or f"{inst.name}.emitted" in c.values:
            c.problems.append(f"{user.at('collector')} = {inst.name!r}: the collector feeds another heat "
                              "pump already; give each heat pump its own ground_collector")
            return
        c.values[key] = (Q, pump)

    def emit(self, c, inst):
        x, p = self.views(c, inst)
        Q, pump = c.values.get(f"{inst.name}.source", ("0.0", "0.0"))
        c.values[f"{inst.name}.emitted"] = True
        T_u, Q_g = c.var("T_undisturbed"), c.var("Q_ground")
        mod = c.module(__name__)
        c.emit("volumes", f"{T_u}, {Q_g} = {mod}.step(h, {x}, {p}, tau, {Q}, {pump})")
        sig = lambda local, unit, desc: c.signal(inst, local, unit, "output", desc)  # noqa: E731
        c.emit("signals",
               f"{sig('T_ground', 'degC', 'ground-node temperature around the pipes')} = {x}[{X.T_ground}]",
               f"{sig('T_undisturbed', 'degC', 'undisturbed ground temperature at the collector depth')} = {T_u}",
               f"{sig('T_sup', 'degC', 'brine leaving the collector (to the heat pump)')} = {x}[{X.T_sup}]",
               f"{sig('T_ret', 'degC', 'brine entering the collector (from the heat pump)')} = {x}[{X.T_ret}]",
               f"{sig('m_flow', 'kg/s', 'brine flow')} = {p}[{P.m_flow}] if {pump} > 0.5 else 0.0",
               f"{sig('Q_flow', 'W', 'heat the brine takes from the ground node')} = {Q}",
               f"{sig('Q_flow_ground', 'W', 'heat from the undisturbed ground into the ground node')} = {Q_g}",
               f"{sig('E', 'J', 'heat delivered to the brine since the start')} = {x}[{X.E}]",
               f"{sig('E_ground', 'J', 'heat from the undisturbed ground since the start')} = {x}[{X.E_ground}]")
