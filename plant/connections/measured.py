"""Measured boundaries: a subsystem cut out of a house runs against recorded signals.

Kinds: measured_consumer (primary flow and return on a coupling point), measured_circuit (a
heating circuit measured on its building side), measured_generator (flow and outlet temperature),
measured_draw (hot water taken), measured_zone (room temperature), measured_supply (an emitter fed
live by a bench's measured flow and supply temperature: PHIL, phil/).

`measured_consumer` stands on a coupling point where a consumer was: it draws the flow of its
input `<name>.m_flow` from the supply header and returns it at `<name>.T_return` (bind both to a
recording: House.bind). `measured_draw` takes hot water from a storage at the measured flow
`<name>.m_flow_hot` and lets cold water in. What they take leaves the house through the ledger
as heat to the building / to hot water, so a cut closes its energy balance like the whole house.
"""
from __future__ import annotations

import numpy as np

from ..component import REQUIRED, Instance, Kind as ComponentKind, link, pack
from ..components import dhw


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


class DrawKind(dhw.Kind):
    """The hot-water draw with its flow measured (`<name>.m_flow_hot`) instead of the profile."""

    name = "measured_draw"

    def emit(self, c, inst):
        m = c.signal(inst, "m_flow_hot", "kg/s", "input", "measured hot water taken from the storage")
        mv = c.var("m_hot")
        Q = self.take(c, inst, lambda p, T_hot: ([f"{mv} = max({m}, 0.0)"], mv))
        c.emit("signals", f"{c.signal(inst, 'Q_flow', 'W', 'output', 'heat drawn with the hot water')} = {Q}")


class GeneratorKind(ComponentKind):
    """A generator whose outlet is measured: it delivers `<name>.m_flow` at `<name>.T_sup` (the
    storage driven by measured generator flows and outlet temperatures)."""

    name = "measured_generator"
    role = "generator"

    def pump_stood(self, c, inst) -> str:
        # its measured flow holds whatever the network pushed through it
        return "False"

    def emit_generator(self, c, inst, T_in, m_ext, m_pump=None):
        m_in = c.signal(inst, "m_flow", "kg/s", "input", "measured generator flow")
        T_in_meas = c.signal(inst, "T_sup", "degC", "input", "measured generator outlet temperature")
        m, T, Q = c.var("m_gen_meas"), c.var("T_gen_meas"), c.var("Q_gen_meas")
        c.emit("hydraulics", f"{m} = max({m_in}, {m_ext}, 0.0)", f"{T} = {T_in_meas} if {m} > 0.0 else {T_in}")
        c.emit("signals", f"{Q} = {m} * CP * ({T} - {T_in})",
               f"{c.signal(inst, 'T_ret', 'degC', 'output', 'return temperature the generator receives')} = {T_in}",
               f"{c.signal(inst, 'Q_flow', 'W', 'output', 'heat delivered to the coupling point')} = {Q}",
               f"{c.ledger_entry(inst, 'fuel')} += {Q} * h",
               f"{c.ledger_entry(inst, 'heat')} += {Q} * h")
        return m, T


class CircuitKind(ComponentKind):
    """A heating circuit behind a mixing valve, measured on its building side: flow
    `<name>.m_flow`, mixed supply `<name>.T_sup` and return `<name>.T_return`. The primary flow it
    draws follows from the valve's mixing balance at the coupling point's supply temperature:
    m_primary = m (T_sup - T_return) / (T_supply_header - T_return), within 0 ... m."""

    name = "measured_circuit"
    role = "consumer"

    def emit_consumer(self, c, inst, T_sup):
        m = c.signal(inst, "m_flow", "kg/s", "input", "measured building-side flow")
        T_mix = c.signal(inst, "T_sup", "degC", "input", "measured supply temperature after mixing")
        T_ret = c.signal(inst, "T_return", "degC", "input", "measured return temperature")
        mp, Tr, Q = c.var("m_primary"), c.var("T_circ_ret"), c.var("Q_circ")
        c.emit("hydraulics", f"{Tr} = {T_ret}",
               f"{mp} = max({m}, 0.0) * min(max(({T_mix} - {Tr}) / ({T_sup} - {Tr}), 0.0), 1.0) "
               f"if {T_sup} - {Tr} > 0.1 else max({m}, 0.0)")
        c.emit("signals", f"{Q} = {mp} * CP * ({T_sup} - {Tr})",
               f"{c.signal(inst, 'm_flow_primary', 'kg/s', 'output', 'primary flow drawn from the coupling point')} = {mp}",
               f"{c.signal(inst, 'Q_flow', 'W', 'output', 'heat taken from the coupling point')} = {Q}",
               f"{c.ledger_entry(inst, 'building')} += {Q} * h")
        return mp, Tr


class ZoneKind(ComponentKind):
    """A room whose temperature is measured (`<name>.T_room`, an input to bind): its emitters give
    their heat against it, its thermostat reads it; the set-point schedule is the zone's."""

    name = "measured_zone"
    role = "zone"

    @property
    def Params(self):
        from ..components.zone import Params

        return Params

    def emit(self, c, inst):
        from ..components import zone

        x = c.state(inst, np.array([inst.params.T_init]))
        p = c.param(inst, pack(inst.params))
        T_room = c.signal(inst, "T_room", "degC", "input", "measured room temperature")
        T_set = c.var("T_set_room")
        c.values[f"{inst.name}.T_set"] = T_set
        c.emit("sense", f"{x}[0] = {T_room}")  # what the emitters see this step
        c.emit("setpoints", f"{T_set} = {c.module(zone.__name__)}.setpoint({p}, tau)")
        c.emit("signals", f"{c.signal(inst, 'T_set', 'degC', 'output', 'room set-point (with night reduction)')} = {T_set}")


class SupplyKind(ComponentKind):
    """An emitter fed by a measured supply, with no station of its own: the water arrives at the
    live measured flow `<name>.m_flow` and temperature `<name>.T_sup` (a PHIL bench's readings,
    set each step) and leaves at the emitter's return. The requests the building's thermostat
    makes (`<name>.T_sup_set`, `<name>.m_flow_set`) are inputs the PHIL loop sends to the bench.
    The heat the water brings, m cp (T_sup - T_return), enters the ledger as heat in."""

    name = "measured_supply"
    role = "connection"
    LINKS = {"emitter": link(REQUIRED, "the emitter the measured supply feeds (a radiator or floor heating)",
                             type=Instance, range=("emitter",))}

    def emit(self, c, inst):
        emitter = c.instances[inst.options["emitter"]]
        m = c.signal(inst, "m_flow", "kg/s", "input", "measured supply flow (live boundary)")
        T_sup = c.signal(inst, "T_sup", "degC", "input", "measured supply temperature (live boundary)")
        c.signal(inst, "T_sup_set", "degC", "input", "supply temperature the building requests")
        c.signal(inst, "m_flow_set", "kg/s", "input", "flow the building requests")
        mv, Q = c.var("m_supply"), c.var("Q_supply")
        c.emit("hydraulics", f"{mv} = max({m}, 0.0)")
        T_ret = c.kinds[emitter.kind].emit_emitter(c, emitter, mv, T_sup)
        sig = lambda local, unit, desc: c.signal(inst, local, unit, "output", desc)  # noqa: E731
        c.emit("signals", f"{Q} = {mv} * CP * ({T_sup} - {T_ret})",
               f"{sig('T_ret', 'degC', 'return temperature of the emitter (leaving this step)')} = {T_ret}",
               f"{sig('Q_flow', 'W', 'heat the measured supply brings to the emitter')} = {Q}",
               f"{c.ledger_entry(inst, 'fuel')} += {Q} * h",
               f"{c.ledger_entry(inst, 'heat')} += {Q} * h")
