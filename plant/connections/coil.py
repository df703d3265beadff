"""A coil through a storage, fed from a coupling point by its own pump (the DHW charging loop).

The coil spans the storage layers between the heights `top` and `bottom`; its fluid enters at
the top at the coupling point's supply temperature and returns to the coupling point's return at
the coil outlet temperature (the storage kernel's exact segment-wise exchanger). The pump runs at
`m_flow` while the input `<name>.on` is 1. With no flow the return sees the supply temperature,
so no heat is moved.
"""
from __future__ import annotations

from dataclasses import dataclass

from ..component import REQUIRED, Height, Instance, Kind as ComponentKind, Knob, indices, link, pack, param


@dataclass(frozen=True)
class Params:
    UA: float = param(640.0, "W/K", "coil conductance (area x heat-transfer coefficient)", 0.0, 1e6)
    m_flow: float = param(0.333, "kg/s", "pump flow when on", 0.0, 10.0)


# positions in the packed parameter vector, from the declaration
P = indices(Params)


class Kind(ComponentKind):
    name = "coil"
    Params = Params
    role = "consumer"
    RUN = ("on", 0.5)
    # The coil's transfer sets how fast a charge heats its tank and how far up; house 1's rig
    # description gives 640 W/K within 480 ... 800 (a coil's fouling state, its real area). Drawn
    # within that range, labsim's rig left a -3 K "offset" on the DHW tank's top sensor in a case
    # with no effect. Calibrated first on its tank's sensors alone, once; a coil fouled far beyond
    # that (labsim's fouled_dhw_coil: x 0.3) stays outside.
    KNOBS = (Knob("UA", "W/K", "coil heat transfer (area, fouling): how fast and how high a charge heats "
                  "its tank", rel=0.25, rank=7, joint=False, signals=("storage.*",)),)
    LINKS = {"storage": link(REQUIRED, "the storage the coil is in", type=Instance, range=("storage",)),
             "top": link(REQUIRED, "height of the coil inlet [m above the storage bottom]", type=Height),
             "bottom": link(REQUIRED, "height of the coil outlet [m]", type=Height)}

    def emit_consumer(self, c, inst, T_sup):
        p = c.param(inst, pack(inst.params))
        st = inst.options["storage"]
        top, bottom = c.port_layer(inst, "top", st), c.port_layer(inst, "bottom", st)
        if isinstance(inst.options["top"], (int, float)) and isinstance(inst.options["bottom"], (int, float)) \
                and inst.options["top"] < inst.options["bottom"]:
            c.problems.append(f"{inst.where} top = {inst.options['top']}: must be above bottom = "
                              f"{inst.options['bottom']}")
        ports = c.storage_ports(st)
        k, a = ports.add_coil(inst, top, bottom), ports.array
        on = c.signal(inst, "on", "1", "input", "charging pump command (0/1)")
        m = c.var("m_coil")
        c.emit("hydraulics",
               f"{m} = {p}[{P.m_flow}] if {on} > 0.5 else 0.0",
               f"{a('coil_m')}[{k}] = {m}",
               f"{a('coil_Tin')}[{k}] = {T_sup}",
               f"{a('coil_UA')}[{k}] = {p}[{P.UA}]")
        Q = ports.coil_heat(k)  # the storage says, once it knows all its coils (storage_kind.allocate)
        c.emit("signals",
               f"{c.signal(inst, 'm_flow', 'kg/s', 'output', 'charging flow through the coil')} = {m}",
               f"{c.signal(inst, 'Q_flow', 'W', 'output', 'heat given by the coil to the storage')} = {Q}")
        return m, f"({a('coil_Tout')}[{k}] if {m} > 0.0 else {T_sup})"
