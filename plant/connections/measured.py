"""Measured boundaries: a subsystem cut out of a house runs against recorded signals.

`measured_consumer` stands on a coupling point where a consumer was: it draws the flow of its
input `<name>.m_flow` from the supply header and returns it at `<name>.T_return` (bind both to a
recording: House.bind). `measured_draw` takes hot water from a storage at the measured flow
`<name>.m_flow_hot` and lets cold water in. What they take leaves the house through the ledger
as heat to the building / to hot water, so a cut closes its energy balance like the whole house.
"""
from __future__ import annotations

from dataclasses import dataclass

from ..component import REQUIRED, Kind as ComponentKind, pack, param


class ConsumerKind(ComponentKind):
    name = "measured_consumer"
    role = "consumer"

    def emit_consumer(self, c, inst, T_sup):
        m = c.signal(inst, "m_flow", "kg/s", "input", "measured flow drawn from the coupling point")
        T_ret = c.signal(inst, "T_return", "degC", "input", "measured return temperature")
        mv, Tv, Q = c.var("m_meas"), c.var("T_meas"), c.var("Q_meas")
        c.emit("hydraulics", f"{mv} = max({m}, 0.0)", f"{Tv} = {T_ret}")
        c.emit("signals", f"{Q} = {mv} * CP * ({T_sup} - {Tv})",
               f"{c.signal(inst, 'Q_flow', 'W', 'output', 'heat taken from the coupling point')} = {Q}",
               f"{c.ledger_entry(inst, 'building')} += {Q} * h")
        return mv, Tv


@dataclass(frozen=True)
class DrawParams:
    T_cold: float = param(10.0, "degC", "cold-water temperature", 1, 30)


class DrawKind(ComponentKind):
    name = "measured_draw"
    Params = DrawParams
    role = "draw"
    REFS = {"storage": "storage"}
    LINKS = {"storage": (REQUIRED, "the storage the hot water is drawn from"),
             "hot": (REQUIRED, "height of the hot-water outlet [m]"),
             "cold": (REQUIRED, "height of the cold-water inlet [m]")}

    def emit(self, c, inst):
        p = c.param(inst, pack(inst.params))
        st = inst.options["storage"]
        ports = c.storage_ports(st)
        i_in = ports.add_inlet(inst, "cold", c.port_layer(inst, "cold", st))
        i_out = ports.add_outlet(inst, "hot", c.port_layer(inst, "hot", st))
        m = c.signal(inst, "m_flow_hot", "kg/s", "input", "measured hot water taken from the storage")
        mv, Q = c.var("m_hot"), c.var("Q_dhw")
        c.emit("draws", f"{mv} = max({m}, 0.0)", f"{st}_in_m[{i_in}] = {mv}", f"{st}_in_T[{i_in}] = {p}[0]",
               f"{st}_out_m[{i_out}] = {mv}")
        c.emit("signals", f"{Q} = {mv} * CP * ({st}_out_T[{i_out}] - {p}[0])",
               f"{c.signal(inst, 'Q_flow', 'W', 'output', 'heat drawn with the hot water')} = {Q}",
               f"{c.ledger_entry(inst, 'dhw')} += {Q} * h")
