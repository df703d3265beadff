"""The PHIL house's live boundaries for hot water and solar heat: the household's hot-water demand
with the lab's measured cold water, and a solar collector whose circuit is the lab's.

In power hardware in the loop (reference §13.2, phil/, docs/phil.md) the DHW storage, the solar
coil and the solar pump are the lab's hardware; the twin simulates only the demand and the
collector and exchanges with the tap-water and solar emulator benches every step.

`measured_dhw_demand` (instance `dhw`): the household draws the profile's mixed-water flow m_draw
at the tap temperature T_set; the heat that takes from the lab's hot water, with the cold water
at the bench's measured temperature `dhw.T_cold` (live input; T_cold of the parameters until a
bench sets it), is
    Q_flow = m_draw cp (T_set - T_cold)
and its integral `dhw.E_set` [J] is the cumulative energy the tap-water bench is told to draw
(E_DHW_Set_kWh). The lab's storage supplies it: heat in (`heat`, `fuel`) = heat to hot water
(`dhw`) in the ledger.

`measured_solar_circuit` (instance `solar`): the collector node of plant/components/
solar_collector.py (same parameters, same absorbed heat and exact node step) with its inlet at
the lab's measured return `solar.T_ret` and flow `solar.m_flow` (the lab's solar pump, live
inputs). Its outputs are the set-points of the solar bench: the outlet temperature `solar.T_sup`
(STM_STVL_Set_degC, mean over the step) and the heat the water takes
    Q_flow = m cp (T_sup - T_ret)          (PEH_ST_Set_kW)
and the collector temperature `solar.T_collector` (T_collector_degC, what the lab's solar
controller switches its pump on). Without a measured flow the node stands still and the heat is 0.
Ledger: irradiance on the aperture is `fuel`; the absorbed heat less what the water takes to the
lab is `heat` (the lab's side is not simulated); thermal losses are `loss`; the node's heat
C T_collector is stored. So absorbed = losses + to the lab + stored closes to round-off.

| parameter | unit | meaning |
|---|---|---|
| T_set (dhw) | degC | tap temperature of the demand profile (45 degC) |
| T_cold (dhw) | degC | cold-water temperature until the bench's measurement arrives |
| (solar) | | plant/components/solar_collector.py's collector parameters; pump and coil ones unused |

Assumptions: no pipe between collector and lab (its delay and losses are the lab's); the demand
profile's flow is at T_set whatever the lab's hot-water temperature (the bench's mixing valve).
Tests: tests/phil/test_boundary.py (ledger closure, demand energy with a measured cold water,
collector heat with a measured return and flow).

`measured_ground_collector` (instance `ground`, SF3):
In power hardware in the loop for SF3 (reference §13.2, docs/phil.md) the heat pump, its brine
pump and the storage are the lab's hardware; the twin simulates the ground collector and the
lab's heat-pump source emulator (phil/emulator/brine.py) stands where the ground would be. The
twin takes the brine the lab's heat pump sends into the collector, measured (`<name>.T_ret`,
STM_BCVL_degC; flow `<name>.m_flow`, SFW_BC_l_per_min; live inputs), and computes what the
collector gives back: the brine return to the heat pump `<name>.T_sup` (STM_BCRLaM_Set_degC, the
emulator's set-point) and the ground temperature `<name>.T_ground` (T_ground_degC).

`measured_ground_collector` has plant/components/ground_collector.py's parameters, states and
ground (the undisturbed profile `undisturbed`, the soil node around the pipes coupled to it
through H_ground, the exchanger of conductance UA between brine and node, water properties for
the brine as upstream). What differs is what drives it: there the heat pump tells the collector
the heat it takes; here the measured inlet and flow set it, the collector being the same heat
exchanger against its ground node,
    eps = 1 - exp(-UA / (m cp)),   Q = eps m cp (T_ground - T_in),   T_sup = T_in + Q / (m cp),
with the node's temperature at the start of the step (explicit, as the collector's own step);
without a measured flow the brine rests at the node's temperature and Q = 0. The parameter
`m_flow` (the heat pump's brine flow) is unused: the flow is the lab's.
Energy: as house 3's collector, E_ground (undisturbed ground -> node) - E (node -> brine, the
heat the lab's heat pump got) = C_ground (T_g - T_g,0) exactly; the node holds soil and stays
outside the house's water-side ledger (the heat leaves to the lab's hardware, not simulated).

Tests: tests/phil/test_brine.py (energy of the node, exchanger against the formula, the closed
loop against the heat-pump source emulator).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from .. import sun
from ..component import Kind as ComponentKind, indices, pack, param
from . import ground_collector
from . import solar_collector as collector
from ..water import CP


@dataclass(frozen=True)
class DemandParams:
    T_set: float = param(45.0, "degC", "tap (mixed) temperature of the demand profile", 30, 70)
    T_cold: float = param(10.0, "degC", "cold-water temperature until the bench measures it", 1, 30)


DEMAND_STATES = ("E_set",)
# positions in the packed parameters and the state vector, from the declarations
PD = indices(DemandParams)
XD = indices(DEMAND_STATES)


class DemandKind(ComponentKind):
    """The household's hot-water demand as the energy a tap-water bench draws (no storage)."""

    name = "measured_dhw_demand"
    Params = DemandParams
    role = "component"

    def initial_state(self, inst):
        return np.zeros(1)

    def emit(self, c, inst):
        x, p = c.state(inst, self.initial_state(inst)), c.param(inst, pack(inst.params))
        T_cold = c.signal(inst, "T_cold", "degC", "input", "measured cold-water temperature (live boundary)")
        c.write_command("sense", f"{inst.name}.T_cold", f"{p}[{PD.T_cold}]")
        Q = c.var("Q_demand")
        c.emit("draws", f"{Q} = max(m_draw, 0.0) * CP * max({p}[{PD.T_set}] - {T_cold}, 0.0)",
               f"{x}[{XD.E_set}] += {Q} * h")
        sig = lambda local, unit, desc: c.signal(inst, local, unit, "output", desc)  # noqa: E731
        c.emit("signals",
               f"{sig('m_flow_demand', 'kg/s', 'tap draw at the set temperature (profile)')} = m_draw",
               f"{sig('Q_flow', 'W', 'heat the demand takes from the lab hot water')} = {Q}",
               f"{sig('E_set', 'J', 'cumulative hot-water energy drawn (the bench set-point)')} = {x}[{XD.E_set}]",
               f"{c.ledger_entry(inst, 'fuel')} += {Q} * h",
               f"{c.ledger_entry(inst, 'heat')} += {Q} * h",
               f"{c.ledger_entry(inst, 'dhw')} += {Q} * h")


class SolarKind(ComponentKind):
    """A solar collector whose circuit (return temperature and flow) is measured live."""

    name = "measured_solar_circuit"
    Params = collector.Params
    role = "component"

    def initial_state(self, inst):
        return collector.initial_state(inst.params)

    def stored_energy(self, inst, x):
        return inst.params.c_eff * inst.params.area * float(x[collector.X.T])

    def emit(self, c, inst):
        x, p = c.state(inst, self.initial_state(inst)), c.param(inst, pack(inst.params))
        beam, dif, cos_t = sun.emit_plane(c, inst, p, collector.P)
        T_in = c.signal(inst, "T_ret", "degC", "input", "measured return from the lab = collector inlet (live boundary)")
        m_in = c.signal(inst, "m_flow", "kg/s", "input", "measured solar flow (live boundary)")
        c.write_command("sense", f"{inst.name}.T_ret", f"{x}[{collector.X.T}]")
        c.write_command("sense", f"{inst.name}.m_flow", "0.0")
        mod = c.module(collector.__name__)
        S, m, T_sup, Q_loss, Q = (c.var(v) for v in ("S", "m_solar", "T_sup", "Q_loss", "Q_solar"))
        c.emit("hydraulics",
               f"{S} = {mod}.absorbed({p}, {beam}, {dif}, {cos_t})",
               f"{m} = max({m_in}, 0.0)",
               f"{x}[{collector.X.T_ret}] = {T_in}",
               f"{T_sup}, {Q_loss} = {mod}.advance(h, {x}, {p}, {S}, T_air, {m})",
               f"{Q} = {m} * CP * ({T_sup} - {T_in})")
        c.emit("volumes", f"{x}[{collector.X.E_heat}] += {Q} * h",
               f"{x}[{collector.X.E_solar}] += ({beam} + {dif}) * {p}[{collector.P.area}] * h")
        sig = lambda local, unit, desc: c.signal(inst, local, unit, "output", desc)  # noqa: E731
        c.emit("signals",
               f"{sig('T_collector', 'degC', 'collector (absorber node) temperature')} = {x}[{collector.X.T}]",
               f"{sig('T_sup', 'degC', 'collector outlet (mean over the step; the bench set-point)')} = {x}[{collector.X.T_sup}]",
               f"{sig('Q_flow', 'W', 'heat the lab water takes from the collector (the bench set-point)')} = {Q}",
               f"{sig('Q_loss', 'W', 'collector heat loss to the outdoor air')} = {Q_loss}",
               f"{sig('G_plane', 'W/m2', 'irradiance on the collector plane (beam + diffuse + ground)')} = {beam} + {dif}",
               f"{sig('E_heat', 'J', 'heat given to the lab water since the start')} = {x}[{collector.X.E_heat}]",
               f"{c.ledger_entry(inst, 'fuel')} += ({beam} + {dif}) * {p}[{collector.P.area}] * h",
               f"{c.ledger_entry(inst, 'heat')} += ({S} - {Q}) * h",
               f"{c.ledger_entry(inst, 'loss')} += {Q_loss} * h")


@njit(cache=True)
def measured_step(dt, x, p, tau, T_in, m):
    """Advance the ground node by dt with the brine entering at T_in [degC] at m [kg/s]; returns
    (T_undisturbed, Q_ground into the node [W], Q to the brine [W], brine outlet T_sup [degC])."""
    T_u = ground_collector.undisturbed(p, tau)
    T_g = x[ground_collector.X.T_ground]
    if m > 0.0:
        mc = m * CP
        eps = 1.0 - math.exp(-p[ground_collector.P.UA] / mc)
        Q = eps * mc * (T_g - T_in)
        T_sup, T_ret = T_in + Q / mc, T_in
    else:
        Q, T_sup, T_ret = 0.0, T_g, T_g
    Q_g = p[ground_collector.P.H_ground] * (T_u - T_g)
    x[ground_collector.X.T_ground] = T_g + dt * (Q_g - Q) / p[ground_collector.P.C_ground]
    x[ground_collector.X.T_sup], x[ground_collector.X.T_ret] = T_sup, T_ret
    x[ground_collector.X.E] += Q * dt
    x[ground_collector.X.E_ground] += Q_g * dt
    return T_u, Q_g, Q, T_sup


class GroundKind(ComponentKind):
    """A ground collector whose brine loop (inlet temperature and flow) is measured live."""

    name = "measured_ground_collector"
    Params = ground_collector.Params
    role = "component"

    def initial_state(self, inst, tau0: float = 0.0):
        return ground_collector.initial_state(inst.params, tau0)

    def emit(self, c, inst):
        weather = c.instances.get("weather")
        tau0 = weather.options.get("tau0", 0.0) if weather is not None else 0.0
        x, p = c.state(inst, self.initial_state(inst, tau0)), c.param(inst, pack(inst.params))
        T_in = c.signal(inst, "T_ret", "degC", "input",
                        "measured brine from the lab's heat pump = collector inlet (live boundary)")
        m_in = c.signal(inst, "m_flow", "kg/s", "input", "measured brine flow (live boundary)")
        c.write_command("sense", f"{inst.name}.T_ret", f"{x}[{ground_collector.X.T_ground}]")
        c.write_command("sense", f"{inst.name}.m_flow", "0.0")
        mod = c.module(__name__)
        T_u, Q_g, Q, T_sup = (c.var(v) for v in ("T_undisturbed", "Q_ground", "Q_brine", "T_brine"))
        c.emit("volumes", f"{T_u}, {Q_g}, {Q}, {T_sup} = {mod}.measured_step(h, {x}, {p}, tau, {T_in}, max({m_in}, 0.0))")
        sig = lambda local, unit, desc: c.signal(inst, local, unit, "output", desc)  # noqa: E731
        c.emit("signals",
               f"{sig('T_ground', 'degC', 'ground-node temperature around the pipes (T_ground_degC)')} = {x}[{ground_collector.X.T_ground}]",
               f"{sig('T_undisturbed', 'degC', 'undisturbed ground temperature at the collector depth')} = {T_u}",
               f"{sig('T_sup', 'degC', 'brine leaving the collector to the lab (the bench set-point)')} = {T_sup}",
               f"{sig('Q_flow', 'W', 'heat the brine takes from the ground node (to the lab)')} = {Q}",
               f"{sig('Q_flow_ground', 'W', 'heat from the undisturbed ground into the ground node')} = {Q_g}",
               f"{sig('E', 'J', 'heat delivered to the brine since the start')} = {x}[{ground_collector.X.E}]",
               f"{sig('E_ground', 'J', 'heat from the undisturbed ground since the start')} = {x}[{ground_collector.X.E_ground}]")
