"""A generator piped straight to a storage (no coupling point), optionally through a three-way
valve to two storage heights (the lab's SwitchPort, reference §8.4).

The generator draws water from the storage at the `return` height and feeds it back at the
`supply` height, with its own pump's flow. With `supply = { upper = 1.4, lower = 0.7 }` (and
likewise `return`) the input `<name>.upper` (0/1) routes the whole flow to the upper or to the
lower port pair: no proportional mixing, as the original. The generator sees the start-of-step
temperature of the layer it draws from, so the storage kernel's port bookkeeping keeps the
ledger exact.
"""
from __future__ import annotations

import numpy as np

from ..component import REQUIRED, Instance, Kind as ComponentKind, Valve, link


class Kind(ComponentKind):
    name = "branch"
    role = "connection"
    LINKS = {"generator": link(REQUIRED, "the generator on this branch", type=Instance, range=("generator",)),
             "storage": link(REQUIRED, "the storage it charges", type=Instance, range=("storage",)),
             "supply": link(REQUIRED, "height of the supply inlet [m], or { upper = ..., lower = ... }", type=Valve),
             "return": link(REQUIRED, "height of the return outlet [m], or { upper = ..., lower = ... }",
                            type=Valve)}

    def emit(self, c, inst):
        st, gen = inst.options["storage"], c.instances[inst.options["generator"]]
        sup = c.port_layers(inst, "supply", st)
        ret = c.port_layers(inst, "return", st)
        valve = isinstance(inst.options["supply"], dict) or isinstance(inst.options["return"], dict)
        p = c.param(inst, np.array([*sup, *ret], dtype=np.float64))
        ports = c.storage_ports(st)
        i, j = ports.add_inlet(inst, "supply", None), ports.add_outlet(inst, "return", None)
        a = ports.array
        up = c.signal(inst, "upper", "1", "input", "three-way valve: 1 = upper port pair, 0 = lower") if valve else "1.0"
        T_in, side = c.var("T_in"), c.var("upper")
        c.emit("hydraulics",
               f"{side} = {up} > 0.5",
               f"{a('in_layer')}[{i}] = int({p}[0]) if {side} else int({p}[1])",
               f"{a('out_layer')}[{j}] = int({p}[2]) if {side} else int({p}[3])",
               f"{T_in} = {c.state_of(inst, c.instances[st])}[{a('out_layer')}[{j}]]")
        m, T = c.kinds[gen.kind].emit_generator(c, gen, T_in, "0.0")
        c.emit("hydraulics", f"{a('in_m')}[{i}] = {m}", f"{a('in_T')}[{i}] = {T} if {m} > 0.0 else {T_in}",
               f"{a('out_m')}[{j}] = {m}")
