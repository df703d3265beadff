"""What the generator kinds (boiler, chp, heat_pump) share: the operating modes they report and
the signals, counters and energy-ledger lines every one of them emits.

Modes
-----
`Mode` names the codes of a generator's `mode` signal; other packages compare against its
members (`mode > Mode.RUN_ON + 0.5`), never against bare numbers. The signal stays a float, so the
kernels use the float constants below (`mode = STEADY`): numba freezes a module's globals as
constants, which is the same machine code as `mode = 3.0`, whereas an IntEnum member inside
njit code is not. A kind lists the codes its kernel returns (`MODES`); the mode signal's
description ("0 idle, 1 start-up, ...") is made from them.

The shared signals
------------------
`Generator.emit_outputs` declares, in this order: T_sup, T_ret, m_flow; the kind's `POWER`
signals; y, mode, starts, run_hours; the kind's `ENERGIES`; then the ledger lines fuel, el,
heat. A kind declares only what differs: its noun, the order of its power and energy signals,
descriptions of its own (`DESCRIPTIONS`) and signals only it has (`own`). The order is the
catalogue's and every recording's column order, so a kind's tuples keep the order it had.
"""
from __future__ import annotations

from enum import IntEnum
from typing import NamedTuple

from ..component import Kind as ComponentKind


class Mode(IntEnum):
    """Codes of a generator's `mode` signal."""

    def __new__(cls, code: int, word: str, meaning: str):
        member = int.__new__(cls, code)
        member._value_ = code
        member.word, member.meaning = word, meaning
        return member

    IDLE = 0, "idle", "off, nothing requested"
    START_UP = 1, "start-up", "started: the tabulated start-up or the start delay, little or no heat"
    WARM_UP = 2, "warm-up", "running, the heat withheld after a long stop not yet made up (CHP)"
    STEADY = 3, "steady", "running in steady state: the heat of the measured tables"
    RUN_ON = 4, "run-on", "stopped, the pump runs on (boiler run-on, CHP cool-down)"
    LOCKED_OUT = 5, "locked out", "requested but blocked (return too hot, brine too cold)"
    ANTI_CYCLE = 6, "anti-cycle wait", "requested, waiting out the minimum time from a stop to the next start"
    DEFROST = 7, "defrost", "running, defrosting the evaporator: no heat (air heat pump)"
    FAULT = 8, "fault", "reported as a fault (named for the devices; no kernel returns it)"


IDLE = float(Mode.IDLE)
START_UP = float(Mode.START_UP)
WARM_UP = float(Mode.WARM_UP)
STEADY = float(Mode.STEADY)
RUN_ON = float(Mode.RUN_ON)
LOCKED_OUT = float(Mode.LOCKED_OUT)
ANTI_CYCLE = float(Mode.ANTI_CYCLE)
DEFROST = float(Mode.DEFROST)
FAULT = float(Mode.FAULT)


def describe(modes, words=None) -> str:
    """The mode signal's description: '0 idle, 1 start-up, ...' over `modes`, a kind's own word
    for a code (`words`) where its device calls it so."""
    words = words or {}
    return ", ".join(f"{int(m)} {words.get(m, m.word)}" for m in modes)


# unit and description of the signals every generator has ({noun}: the kind's NOUN)
SHARED = {
    "T_sup": ("degC", "{noun} supply temperature"),
    "T_ret": ("degC", "{noun} return temperature"),
    "m_flow": ("kg/s", "water flow through the {noun}"),
    "Q_flow": ("W", "heat delivered to the circuit"),
    "P_fuel": ("W", "fuel power (LHV)"),
    "P_el": ("W", "electric power (- consumed)"),
    "y": ("1", "effective modulation"),
    "mode": ("1", ""),  # made from the kind's MODES
    "starts": ("1", "number of starts"),
    "run_hours": ("h", "operating hours"),
    "E_el": ("J", "electric energy (- consumed)"),
    "E_heat": ("J", "heat released into the water"),
    "E_fuel": ("J", "fuel energy used"),
}


class Outlet(NamedTuple):
    """The locals a generator's step returns into, in the kernels' order (P_fuel None when the
    kernel returns no fuel power)."""

    m: str
    T: str
    P_el: str
    P_fuel: str | None
    P_heat: str
    mode: str

    @classmethod
    def new(cls, c, fuel: bool = True) -> "Outlet":
        m, T, P_el = c.var("m"), c.var("T"), c.var("P_el")
        P_fuel = c.var("P_fuel") if fuel else None
        return cls(m, T, P_el, P_fuel, c.var("P_heat"), c.var("mode"))

    def targets(self) -> str:
        """The left-hand side of the kernel call."""
        return ", ".join(v for v in self if v is not None)


class Generator(ComponentKind):
    """Base of the generator kinds: the shared output signals, counters and ledger lines."""

    role = "generator"
    NOUN = "generator"                # in the shared signals' descriptions
    MODES: tuple = ()                 # the Mode codes the kernel returns (and 8 where a device reports faults)
    MODE_WORDS: dict = {}             # a code's word where the kind's device names it otherwise
    POWER: tuple = ("Q_flow", "P_el")             # between m_flow and y, in this order
    ENERGIES: tuple = ("E_el", "E_heat")          # after run_hours, in this order
    DESCRIPTIONS: dict = {}           # a shared signal's description where the kind's differs

    def _expression(self, local, out, x, X, T_in, T_idle, y):
        """The value a shared signal takes; the counters are the state's (X.starts, X.E_heat ...)."""
        return {"T_sup": f"{out.T} if {out.m} > 0.0 else {T_idle}", "T_ret": T_in, "m_flow": out.m,
                "Q_flow": f"{out.m} * CP * ({out.T} - {T_in})", "P_fuel": out.P_fuel, "P_el": out.P_el,
                "y": y or f"{x}[{X.y}]", "mode": out.mode,
                "run_hours": f"{x}[{X.run_seconds}] / 3600.0"}.get(local) or f"{x}[{getattr(X, local)}]"

    def emit_outputs(self, c, inst, x, X, out: Outlet, T_in, *, T_idle=None, y=None, fuel=None,
                     own=None) -> None:
        """The shared signals and ledger lines into `signals`. x, X: the state view and its
        positions; T_idle: T_sup without flow (default T_in); y: the modulation (default x[X.y]);
        fuel: the energy into the system this step (default P_fuel h); own: {local: (unit,
        description, expression)} of signals only this kind has, named in POWER."""
        own = own or {}
        order = ("T_sup", "T_ret", "m_flow", *self.POWER, "y", "mode", "starts", "run_hours", *self.ENERGIES)
        lines = []
        for local in order:
            if local in own:
                unit, desc, expr = own[local]
            else:
                unit, desc = SHARED[local]
                desc = describe(self.MODES, self.MODE_WORDS) if local == "mode" else \
                    self.DESCRIPTIONS.get(local, desc.format(noun=self.NOUN))
                expr = self._expression(local, out, x, X, T_in, T_idle or T_in, y)
            lines.append(f"{c.signal(inst, local, unit, 'output', desc)} = {expr}")
        c.emit("signals", *lines,
               f"{c.ledger_entry(inst, 'fuel')} += {fuel or out.P_fuel + ' * h'}",
               f"{c.ledger_entry(inst, 'el')} += {out.P_el} * h",
               f"{c.ledger_entry(inst, 'heat')} += {out.P_heat} * h")

    # A kind that can run at a recording's outlet (its `outlet = "measured"` link) takes its outlet
    # flow and temperature as these inputs; a cut binds each to the recorded shared signal named
    # beside it (plant/diagnose/derive.py).
    MEASURED_OUTLET = (("m_flow_measured", "m_flow", "kg/s", "measured {noun} flow"),
                       ("T_sup_measured", "T_sup", "degC", "measured {noun} outlet temperature"))

    def measured_outlet(self, c, inst) -> tuple[str, ...]:
        """The MEASURED_OUTLET inputs declared on `inst`: their expressions (flow, temperature)."""
        return tuple(c.signal(inst, local, unit, "input", desc.format(noun=self.NOUN))
                     for local, _, unit, desc in self.MEASURED_OUTLET)

    def emit_own(self, c, inst, *signals) -> None:
        """Output signals only this kind has, (local, unit, description, expression) each."""
        c.emit("signals", *(f"{c.signal(inst, local, unit, 'output', desc)} = {expr}"
                            for local, unit, desc, expr in signals))
