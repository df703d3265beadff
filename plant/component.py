"""Component conventions: parameter declaration with units and limits, and parameter packing.

A component module holds
  * `Params`, a frozen dataclass whose fields are declared with `param(...)` (SI units, range);
  * `STATES`, the names of its state vector entries, and `initial_state(params) -> ndarray`;
  * `P = indices(Params)` and `X = indices(STATES)`: the positions in the packed parameter vector
    and in the state vector, derived from those declarations (never written by hand);
  * `tables()` (if it has measured data), loaded once from `plant/data/<model>/`;
  * one `@njit` kernel `step(...)` that advances its state by dt and returns its outputs.
Kernels take and return plain floats and numpy arrays so that the house's system model can call
them from its own compiled loop (one compiled loop per topology keeps a 1 s step in microseconds).
"""
from __future__ import annotations

import dataclasses
from collections import namedtuple
from dataclasses import dataclass, field, fields

import numpy as np

from .errors import ConfigError, did_you_mean
from .links import REQUIRED, DataSet, Height, Link, SignalName, Valve, link, link_problem  # noqa: F401 (kinds import them here)


@dataclass(frozen=True)
class Knob:
    """A parameter a kind declares uncertain in a house file and able to set a replayed signal
    directly, so the diagnosis re-fits it within narrow bounds before any effect is judged
    (plant/diagnose/calibration.py). Names are the instance's own parameters or options, or
    `link.name`: a parameter of the instance that link names."""
    key: str                     # what is re-fitted
    unit: str
    why: str
    rel: float = 0.0             # bounds: the file value x (1 -+ rel) ...
    bounds: tuple | None = None  # ... or absolute (a file value of 0: the ideal)
    rank: int = 0                # the order of the re-fit's coordinate descent over the house's knobs
    joint: bool = True           # re-fitted again with each simulate candidate
    signals: tuple = ()          # calibrated first on these outputs alone ("link.*": that storage's sensors)


def param(default, unit: str, doc: str, lo: float | None = None, hi: float | None = None):
    """Declare a parameter field: default value, unit ('1' for fractions, 'degC', 'W', ...), meaning, range."""
    return field(default=default, metadata={"unit": unit, "doc": doc, "lo": lo, "hi": hi})


def is_number(value) -> bool:
    """An int or float as TOML gives them; true and false are not numbers here."""
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def describe(params_cls) -> list[dict]:
    """Parameter table of a Params class: name, default, unit, range, meaning."""
    rows = []
    for f in fields(params_cls):
        rows.append({"name": f.name, "default": f.default, **f.metadata})
    return rows


def build_params(params_cls, values: dict, where: str):
    """Build a Params instance from a mapping; report every unknown key and out-of-range value at once.

    `where` is the location prefix used in messages (e.g. 'plant/houses/house1.toml [chp]').
    """
    known = {f.name: f for f in fields(params_cls)}
    problems = []
    kwargs = {}
    for key, value in values.items():
        if key not in known:
            hint = did_you_mean(key, known, f"allowed: {', '.join(sorted(known))}")
            problems.append(f"{where} {key}: unknown parameter; {hint}")
            continue
        f = known[key]
        if isinstance(f.default, bool):
            if not isinstance(value, bool):
                problems.append(f"{where} {key} = {value!r}: must be true or false")
                continue
        elif isinstance(f.default, (int, float)):
            if not is_number(value):
                problems.append(f"{where} {key} = {value!r}: must be a number [{f.metadata['unit']}]")
                continue
            lo, hi = f.metadata.get("lo"), f.metadata.get("hi")
            if (lo is not None and value < lo) or (hi is not None and value > hi):
                problems.append(
                    f"{where} {key} = {value}: out of range; allowed {lo} … {hi} {f.metadata['unit']}"
                )
                continue
            if isinstance(f.default, int) and not isinstance(f.default, bool):
                if int(value) != value:
                    problems.append(f"{where} {key} = {value}: must be an integer")
                    continue
                value = int(value)
            else:
                value = float(value)
        kwargs[key] = value
    if problems:
        raise ConfigError("\n".join(problems))
    return params_cls(**kwargs)


def pack(params) -> np.ndarray:
    """Parameters as a float64 vector in field order (what a kernel receives)."""
    return np.array([float(getattr(params, f.name)) for f in fields(params)], dtype=np.float64)


def index_of(params_cls) -> dict[str, int]:
    """Field name -> position in the packed vector."""
    return {f.name: i for i, f in enumerate(fields(params_cls))}


def indices(declaration, name: str = ""):
    """Positions of a kind's declared names, as a frozen namespace of int constants.

    `declaration` is a Params dataclass (its fields in declaration order: the order `pack()` uses)
    or a tuple of state names (STATES): `P = indices(Params)` gives `P.P_el_max == 0`,
    `X = indices(STATES)` gives `X.T_w == 1`. A field inserted in the middle moves every later
    position with it, in the kernels and in the code the kinds generate alike.

    The namespace is a namedtuple instance. numba freezes a module-global tuple into the compiled
    code, so `p[P.P_el_max]` in an @njit kernel is `p[0]`: the same machine code. Checked when the
    kinds were converted (issue #27): identical assembly for a loop over `p[P.a]` and over `p[0]`,
    and the same time; the 35 kernels the shipped houses compile have the same assembly before and
    after the conversion, and the generated step of each house is the same text. `cache=True`
    kernels load from the cache as before. In code generated as source text, interpolate the int:
    `f"{x}[{X.T_w}]"` gives `x_chp[1]`.
    """
    if dataclasses.is_dataclass(declaration):
        names = [f.name for f in fields(declaration)]
        name = name or f"{declaration.__name__}Index"
    else:
        names = list(declaration)
        name = name or "StateIndex"
    return namedtuple(name, names)(*range(len(names)))


__all__ = ["param", "link", "Link", "link_problem", "REQUIRED", "Instance", "SignalName", "DataSet", "Height",
           "Valve", "names_instances", "is_number", "describe", "build_params", "pack", "index_of",
           "indices", "dataclass", "dataclasses"]


@dataclass
class Instance:
    """One declared component or connection: its name, kind, parameters and link options."""

    name: str
    kind: str
    params: object            # the kind's frozen Params instance (or None)
    options: dict             # link keys (instance names, heights, shares ...), validated by the kind
    where: str                # "file:line [name]" for messages
    order: int = 0            # declaration order (catalogue grouping)
    lines: dict = field(default_factory=dict)  # key -> line in the house file

    def at(self, key: str) -> str:
        """"file:line [name] key" of one key (its own line when known)."""
        path, _, rest = self.where.partition(":")
        line = self.lines.get(key)
        return f"{path}:{line} {rest.split(' ', 1)[1]} {key}" if line else f"{self.where} {key}"


class Kind:
    """A component kind as the compiler sees it (plant/compiler.py): its parameters, the link
    keys a house file may give beside them, and the code it emits into the step's phases.

    LINKS maps each link key to `link(default, meaning, type=..., range=...)` (plant/links.py);
    a default of REQUIRED must be given. The declaration checks each link by its type (the
    instances it names have a role of its range), then calls `check(inst, problems)` for what
    spans several links or lies inside a table. A kind that carries water between others
    implements the protocol its role needs:
      generator  emit_generator(c, inst, T_in, m_ext) -> (m_flow, T_out) locals; pump_stood(c, inst)
                 -> an expression true while its own pump stood (a coupling point's idle flow)
      consumer   emit_consumer(c, inst, T_sup) -> (m_flow, T_return expression for `volumes`)
      emitter    emit_emitter(c, inst, m_flow, T_sup) -> T_return local
    """

    name = ""
    Params = None
    LINKS: dict = {}
    role = "component"       # generator | consumer | storage | emitter | zone | controller | ...
    ROLES: tuple = ()        # every role a kind may be named in, when more than its `role`
    # what the diagnosis reads of an instance of the kind (plant/diagnose/roles.py), by local name:
    RUN: tuple | None = None      # (command input, value above which the unit runs): its operating mode
    RAN: tuple | None = None      # (output, value above which it ran): the running state a lab measures
    PIPES: tuple = ()             # outputs read by pipe sensors on its branch (which flows by its m_flow)
    COUNTER: str | None = None    # output counting what it delivered since the start: it rises between
    #                               two samples only if the unit ran between them
    SOURCE_PIPES: dict = {}       # output read by a pipe sensor on another loop it runs -> that loop's
    #                               flow, `link.output` (a brine heat pump's brine sensors: collector.m_flow)
    SUBSTITUTES: dict = {}        # command input -> the output a recording may give instead (the RUN
    #                               command standing in for a modulation: 1 while on)
    UNMEASURED: tuple = ()        # outputs no lab measures (book-keeping, set-points): never compared
    KNOBS: tuple = ()             # Knob: calibration the diagnosis may re-fit before judging effects
    COMMANDS: tuple = ()          # inputs the kind's own control writes (a solar station's pump): a
    #                               recording that carries them drives them, else the kind decides

    def initial_state(self, inst) -> np.ndarray:
        return np.zeros(0)

    def check(self, inst, problems: list) -> None:
        """Append what is wrong between the instance's links (each is of its declared type and
        a named instance exists with the right role by now; a bad one is its default or None).
        What needs another instance's parameters (a height inside a storage) is the
        compiler's to check, where the kind emits."""

    def emit(self, c, inst) -> None:
        """Code of the instance's own phases (a generator or consumer emits when its coupling
        point calls it)."""

    def stored_energy(self, inst, x: np.ndarray) -> float:
        """Heat held in the instance's water relative to 0 degC [J] (energy ledger)."""
        return 0.0


def names_instances(spec: Link) -> bool:
    """Whether a link names other instances (type Instance or list[Instance])."""
    return spec.type in (Instance, list[Instance])
