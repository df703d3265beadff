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
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import sun
from ..component import Kind as ComponentKind, indices, pack, param
from . import solar_collector as collector


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
        shift = c.param(inst, np.array([sun.calendar_shift(getattr(c, "decl", None))]), suffix="_sun")
        T_in = c.signal(inst, "T_ret", "degC", "input", "measured return from the lab = collector inlet (live boundary)")
        m_in = c.signal(inst, "m_flow", "kg/s", "input", "measured solar flow (live boundary)")
        c.write_command("sense", f"{inst.name}.T_ret", f"{x}[{collector.X.T}]")
        c.write_command("sense", f"{inst.name}.m_flow", "0.0")
        mod, smod = c.module(collector.__name__), c.module(sun.__name__)
        beam, dif, cos_t, S, m, T_sup, Q_loss, Q = (c.var(v) for v in (
            "G_beam", "G_diffuse", "cos_theta", "S", "m_solar", "T_sup", "Q_loss", "Q_solar"))
        c.emit("hydraulics",
               f"{beam}, {dif}, {cos_t} = {smod}.plane(tau + {shift}[0], E_dir, E_dif, {p}[{collector.P.latitude}], "
               f"{p}[{collector.P.longitude}], {p}[{collector.P.tilt}], {p}[{collector.P.azimuth}], {p}[{collector.P.albedo}])",
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
