"""A generator piped straight to a storage (no coupling point), optionally through a three-way
valve to two storage heights (the lab's SwitchPort, reference §8.4).

The generator draws water from the storage at the `return` height and feeds it back at the
`supply` height, with its own pump's flow. With `supply = { upper = 1.4, lower = 0.7 }` (and
likewise `return`) the input `<name>.upper` (0/1) routes the whole flow to the upper or to the
lower port pair: no proportional mixing, as the original. The generator sees the start-of-step
temperature of the layer it draws from, so the storage kernel's port bookkeeping keeps the
ledger exact.

A valve that does not close (`leak`, the share 0 ... 0.5 of the flow that still goes through the
port pair it is not set to: a worn seat, an actuator short of its end stop) feeds both inlets and
draws from both outlets in those shares; the generator sees the mix of the two outlets' layers.
`leak = 0` (the default) is the original's valve.
"""
from __future__ import annotations

import numpy as np

from ..component import REQUIRED, Instance, Kind as ComponentKind, Valve, is_number, link


class Kind(ComponentKind):
    name = "branch"
    role = "connection"
    LINKS = {"generator": link(REQUIRED, "the generator on this branch", type=Instance, range=("generator",)),
             "storage": link(REQUIRED, "the storage it charges", type=Instance, range=("storage",)),
             "supply": link(REQUIRED, "height of the supply inlet [m], or { upper = ..., lower = ... }", type=Valve),
             "return": link(REQUIRED, "height of the return outlet [m], or { upper = ..., lower = ... }",
                            type=Valve),
             "leak": link(0.0, "share of the flow through the port pair the three-way valve is not set to "
                          "(0 ... 0.5; 0 = it closes)", type=float)}

    def check(self, inst, problems):
        leak = inst.options.get("leak", 0.0)
        if not is_number(leak) or not 0.0 <= leak <= 0.5:
            problems.append(f"{inst.at('leak')} = {leak!r}: must be a share 0 … 0.5 (0: the valve closes)")
            inst.options["leak"] = 0.0
        elif leak and not (isinstance(inst.options.get("supply"), dict) or isinstance(inst.options.get("return"), dict)):
            problems.append(f"{inst.at('leak')} = {leak!r}: only a three-way valve leaks; give supply or return "
                            "as { upper = ..., lower = ... }")

    def emit(self, c, inst):
        st, gen = inst.options["storage"], c.instances[inst.options["generator"]]
        sup = c.port_layers(inst, "supply", st)
        ret = c.port_layers(inst, "return", st)
        valve = isinstance(inst.options["supply"], dict) or isinstance(inst.options["return"], dict)
        ports = c.storage_ports(st)
        a = ports.array
        if not valve:
            p = c.param(inst, np.array([*sup, *ret], dtype=np.float64))
            i, j = ports.add_inlet(inst, "supply", None), ports.add_outlet(inst, "return", None)
            T_in = c.var("T_in")
            c.emit("hydraulics",
                   f"{a('in_layer')}[{i}] = int({p}[0])",
                   f"{a('out_layer')}[{j}] = int({p}[2])",
                   f"{T_in} = {c.state_of(inst, c.instances[st])}[{a('out_layer')}[{j}]]")
            m, T = c.kinds[gen.kind].emit_generator(c, gen, T_in, "0.0")
            c.emit("hydraulics", f"{a('in_m')}[{i}] = {m}", f"{a('in_T')}[{i}] = {T} if {m} > 0.0 else {T_in}",
                   f"{a('out_m')}[{j}] = {m}")
            return
        p = c.param(inst, np.array([*sup, *ret, float(inst.options.get("leak", 0.0))], dtype=np.float64))
        # the port pair the valve is set to (i, j) and the other (i2, j2), through which the leak goes
        i, i2 = ports.add_inlet(inst, "supply", None), ports.add_inlet(inst, "supply_leak", None)
        j, j2 = ports.add_outlet(inst, "return", None), ports.add_outlet(inst, "return_leak", None)
        up = c.signal(inst, "upper", "1", "input", "three-way valve: 1 = upper port pair, 0 = lower")
        T_in, side, x = c.var("T_in"), c.var("upper"), c.state_of(inst, c.instances[st])
        c.emit("hydraulics",
               f"{side} = {up} > 0.5",
               f"{a('in_layer')}[{i}] = int({p}[0]) if {side} else int({p}[1])",
               f"{a('in_layer')}[{i2}] = int({p}[1]) if {side} else int({p}[0])",
               f"{a('out_layer')}[{j}] = int({p}[2]) if {side} else int({p}[3])",
               f"{a('out_layer')}[{j2}] = int({p}[3]) if {side} else int({p}[2])",
               f"{T_in} = {x}[{a('out_layer')}[{j}]] if {p}[4] == 0.0 else "
               f"(1.0 - {p}[4]) * {x}[{a('out_layer')}[{j}]] + {p}[4] * {x}[{a('out_layer')}[{j2}]]")
        m, T = c.kinds[gen.kind].emit_generator(c, gen, T_in, "0.0")
        c.emit("hydraulics",
               f"{a('in_m')}[{i}] = {m} * (1.0 - {p}[4])", f"{a('in_m')}[{i2}] = {m} * {p}[4]",
               f"{a('in_T')}[{i}] = {T} if {m} > 0.0 else {T_in}", f"{a('in_T')}[{i2}] = {a('in_T')}[{i}]",
               f"{a('out_m')}[{j}] = {m} * (1.0 - {p}[4])", f"{a('out_m')}[{j2}] = {m} * {p}[4]")
