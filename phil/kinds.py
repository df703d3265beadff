"""The PHIL house's live brine boundary: house 3's ground collector with its brine loop measured.

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

Registration: the kind is added to the house compiler's registry (plant/kinds.py KINDS) when this
module is imported (phil/loop.py, cli/phil.py), so plant/houses/house3_phil.toml loads where the
PHIL side is loaded. Its home would be plant/components/phil_boundary.py beside the other PHIL
boundaries (docs/phil.md, "Not yet built").
Tests: tests/phil/test_brine.py (energy of the node, exchanger against the formula, the closed
loop against the heat-pump source emulator).
"""
from __future__ import annotations

import math

from numba import njit

from plant.component import Kind as ComponentKind, pack
from plant.components import ground_collector as collector
from plant.components.ground_collector import P, X, undisturbed
from plant.water import CP


@njit(cache=True)
def measured_step(dt, x, p, tau, T_in, m):
    """Advance the ground node by dt with the brine entering at T_in [degC] at m [kg/s]; returns
    (T_undisturbed, Q_ground into the node [W], Q to the brine [W], brine outlet T_sup [degC])."""
    T_u = undisturbed(p, tau)
    T_g = x[X.T_ground]
    if m > 0.0:
        mc = m * CP
        eps = 1.0 - math.exp(-p[P.UA] / mc)
        Q = eps * mc * (T_g - T_in)
        T_sup, T_ret = T_in + Q / mc, T_in
    else:
        Q, T_sup, T_ret = 0.0, T_g, T_g
    Q_g = p[P.H_ground] * (T_u - T_g)
    x[X.T_ground] = T_g + dt * (Q_g - Q) / p[P.C_ground]
    x[X.T_sup], x[X.T_ret] = T_sup, T_ret
    x[X.E] += Q * dt
    x[X.E_ground] += Q_g * dt
    return T_u, Q_g, Q, T_sup


class GroundKind(ComponentKind):
    """A ground collector whose brine loop (inlet temperature and flow) is measured live."""

    name = "measured_ground_collector"
    Params = collector.Params
    role = "component"

    def initial_state(self, inst, tau0: float = 0.0):
        return collector.initial_state(inst.params, tau0)

    def emit(self, c, inst):
        weather = c.instances.get("weather")
        tau0 = weather.options.get("tau0", 0.0) if weather is not None else 0.0
        x, p = c.state(inst, self.initial_state(inst, tau0)), c.param(inst, pack(inst.params))
        T_in = c.signal(inst, "T_ret", "degC", "input",
                        "measured brine from the lab's heat pump = collector inlet (live boundary)")
        m_in = c.signal(inst, "m_flow", "kg/s", "input", "measured brine flow (live boundary)")
        c.write_command("sense", f"{inst.name}.T_ret", f"{x}[{X.T_ground}]")
        c.write_command("sense", f"{inst.name}.m_flow", "0.0")
        mod = c.module(__name__)
        T_u, Q_g, Q, T_sup = (c.var(v) for v in ("T_undisturbed", "Q_ground", "Q_brine", "T_brine"))
        c.emit("volumes", f"{T_u}, {Q_g}, {Q}, {T_sup} = {mod}.measured_step(h, {x}, {p}, tau, {T_in}, max({m_in}, 0.0))")
        sig = lambda local, unit, desc: c.signal(inst, local, unit, "output", desc)  # noqa: E731
        c.emit("signals",
               f"{sig('T_ground', 'degC', 'ground-node temperature around the pipes (T_ground_degC)')} = {x}[{X.T_ground}]",
               f"{sig('T_undisturbed', 'degC', 'undisturbed ground temperature at the collector depth')} = {T_u}",
               f"{sig('T_sup', 'degC', 'brine leaving the collector to the lab (the bench set-point)')} = {T_sup}",
               f"{sig('Q_flow', 'W', 'heat the brine takes from the ground node (to the lab)')} = {Q}",
               f"{sig('Q_flow_ground', 'W', 'heat from the undisturbed ground into the ground node')} = {Q_g}",
               f"{sig('E', 'J', 'heat delivered to the brine since the start')} = {x}[{X.E}]",
               f"{sig('E_ground', 'J', 'heat from the undisturbed ground since the start')} = {x}[{X.E_ground}]")


KINDS_ADDED = (GroundKind(),)


def register() -> None:
    """Add the PHIL kinds to the house compiler's registry (idempotent)."""
    from plant.kinds import KINDS

    for kind in KINDS_ADDED:
        KINDS.setdefault(kind.name, kind)


register()
