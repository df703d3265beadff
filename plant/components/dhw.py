"""Domestic hot-water draw with a thermostatic mixing valve at the tap.

The draw profile gives the flow of mixed water at the set temperature (45 degC). The mixing valve
takes just enough hot water from the top of the DHW storage to reach the set temperature:
    m_hot = m_demand (T_set - T_cold)/(T_hot - T_cold)      if T_hot >= T_set,
otherwise all of the draw is hot water and it arrives too cold (a service failure; the missing
heat is reported). The same mass of cold water enters the storage bottom. Heat delivered to the
tap = m_hot cp (T_hot - T_cold) (reference section 10.1, with T_tol folded into the failure rule).
"""
from __future__ import annotations

from dataclasses import dataclass

from numba import njit

from ..component import REQUIRED, Height, Instance, Kind as ComponentKind, indices, is_number, link, pack, param
from ..water import CP

STATES = ()


@dataclass(frozen=True)
class Params:
    T_set: float = param(45.0, "degC", "tap (mixed) temperature", 30, 70)
    T_cold: float = param(10.0, "degC", "cold-water temperature", 1, 30)


# positions in the packed parameter vector, from the declaration
P = indices(Params)


@njit(cache=True)
def draw(p, m_demand, T_hot):
    """Returns (m_hot from the storage, T_tap delivered, Q_missing [W] short of the set temperature)."""
    if m_demand <= 0.0:
        return 0.0, T_hot, 0.0
    T_set, T_cold = p[P.T_set], p[P.T_cold]
    if T_hot > T_set:
        m_hot = m_demand * (T_set - T_cold) / (T_hot - T_cold)
        return m_hot, T_set, 0.0
    return m_demand, T_hot, m_demand * CP * (T_set - max(T_hot, T_cold))


class Kind(ComponentKind):
    """The hot-water draw (profile) through a storage: hot water leaves at the `hot` height, cold
    water enters at the `cold` height [m above the storage bottom]."""

    name = "dhw_draw"
    Params = Params
    role = "draw"
    UNMEASURED = ("Q_flow_missing",)
    LINKS = {"storage": link(REQUIRED, "the storage the hot water is drawn from", type=Instance,
                             range=("storage",)),
             "hot": link(REQUIRED, "height of the hot-water outlet [m]", type=Height),
             "cold": link(REQUIRED, "height of the cold-water inlet [m]", type=Height)}

    def take(self, c, inst, m_hot_of):
        """The storage ports of the draw: m_hot_of(p, T_hot) -> (lines computing the hot-water
        flow into its first name, that name), T_hot the start-of-step temperature at the hot
        outlet; returns the heat-to-tap local."""
        p = c.param(inst, pack(inst.params))
        st = inst.options["storage"]
        ports = c.storage_ports(st)
        i_in = ports.add_inlet(inst, "cold", c.port_layer(inst, "cold", st))
        i_out = ports.add_outlet(inst, "hot", c.port_layer(inst, "hot", st))
        a = ports.array
        lines, m_hot = m_hot_of(p, f"{c.state_of(inst, c.instances[st])}[{a('out_layer')}[{i_out}]]")
        Q_dhw = c.var("Q_dhw")
        c.emit("draws", *lines, f"{a('in_m')}[{i_in}] = {m_hot}", f"{a('in_T')}[{i_in}] = {p}[{P.T_cold}]",
               f"{a('out_m')}[{i_out}] = {m_hot}")
        c.emit("signals", f"{Q_dhw} = {m_hot} * CP * ({a('out_T')}[{i_out}] - {p}[{P.T_cold}])",
               f"{c.ledger_entry(inst, 'dhw')} += {Q_dhw} * h")
        return Q_dhw

    def emit(self, c, inst):
        m_hot, T_tap, Q_miss = (c.var(v) for v in ("m_hot", "T_tap", "Q_miss"))
        mod = c.module(__name__)
        Q_dhw = self.take(c, inst, lambda p, T_hot: (
            [f"{m_hot}, {T_tap}, {Q_miss} = {mod}.draw({p}, m_draw, {T_hot})"], m_hot))
        sig = lambda local, unit, desc: c.signal(inst, local, unit, "output", desc)  # noqa: E731
        c.emit("signals",
               f"{sig('m_flow_demand', 'kg/s', 'tap draw at the set temperature (profile)')} = m_draw",
               f"{sig('m_flow_hot', 'kg/s', 'hot water taken from the storage')} = {m_hot}",
               f"{sig('T_tap', 'degC', 'temperature delivered at the tap')} = {T_tap}",
               f"{sig('Q_flow', 'W', 'heat delivered to the tap water')} = {Q_dhw}",
               f"{sig('Q_flow_missing', 'W', 'heat missing to reach the tap set temperature')} = {Q_miss}",
               f"{c.ledger_entry(inst, 'missing')} += {Q_miss} * h")


class CoilKind(Kind):
    """Hot water heated on its way through a coil in a storage (a fresh-water coil, SF4): cold
    water enters the coil at the `inlet` height and rises to the `outlet` height; a thermostatic
    valve after the coil adds cold water down to T_set. The coil flow for this step is set from
    the outlet temperature of the last one (the valve's position follows what it sees), so the
    exchange itself stays the storage kernel's exact segment-wise one."""

    name = "dhw_coil_draw"
    LINKS = {"storage": link(REQUIRED, "the storage the coil is in", type=Instance, range=("storage",)),
             "inlet": link(REQUIRED, "height of the coil's cold-water inlet [m] (the lower end)", type=Height),
             "outlet": link(REQUIRED, "height of the coil's hot-water outlet [m] (the upper end)", type=Height),
             # > 0 W/K, checked where the kind emits (its message names the quantity)
             "UA": link(2000.0, "coil conductance [W/K] (area x heat-transfer coefficient)", type=float)}

    def emit(self, c, inst):
        p = c.param(inst, pack(inst.params))
        st = inst.options["storage"]
        ua = inst.options["UA"]
        if not is_number(ua) or not ua > 0:
            c.problems.append(f"{inst.at('UA')} = {ua!r}: a conductance > 0 W/K")
            ua = 1.0
        ports = c.storage_ports(st)
        k = ports.add_coil(inst, c.port_layer(inst, "inlet", st), c.port_layer(inst, "outlet", st))
        a = ports.array
        m, T_out, T_tap, Q, Q_miss = (c.var(v) for v in ("m_coil", "T_coil", "T_tap", "Q_dhw", "Q_miss"))
        c.emit("draws",
               f"{T_out} = {a('coil_Tout')}[{k}]",  # the last step's outlet: what the valve saw
               f"{m} = m_draw if {T_out} <= {p}[{P.T_set}] else "
               f"m_draw * ({p}[{P.T_set}] - {p}[{P.T_cold}]) / ({T_out} - {p}[{P.T_cold}])",
               f"{a('coil_m')}[{k}] = {m}", f"{a('coil_Tin')}[{k}] = {p}[{P.T_cold}]",
               f"{a('coil_UA')}[{k}] = {float(ua)!r}")
        sig = lambda local, unit, desc: c.signal(inst, local, unit, "output", desc)  # noqa: E731
        c.emit("signals",
               f"{Q} = {m} * CP * ({a('coil_Tout')}[{k}] - {p}[{P.T_cold}]) if {m} > 0.0 else 0.0",
               f"{T_tap} = ({m} * {a('coil_Tout')}[{k}] + (m_draw - {m}) * {p}[{P.T_cold}]) / m_draw "
               f"if m_draw > 0.0 else {a('coil_Tout')}[{k}]",
               f"{Q_miss} = max(m_draw * CP * ({p}[{P.T_set}] - {p}[{P.T_cold}]) - {Q}, 0.0)",
               f"{sig('m_flow_demand', 'kg/s', 'tap draw at the set temperature (profile)')} = m_draw",
               f"{sig('m_flow_hot', 'kg/s', 'water heated through the coil')} = {m}",
               f"{sig('T_tap', 'degC', 'temperature delivered at the tap')} = {T_tap}",
               f"{sig('Q_flow', 'W', 'heat delivered to the tap water')} = {Q}",
               f"{sig('Q_flow_missing', 'W', 'heat missing to reach the tap set temperature')} = {Q_miss}",
               f"{c.ledger_entry(inst, 'dhw')} += {Q} * h",
               f"{c.ledger_entry(inst, 'missing')} += {Q_miss} * h")
