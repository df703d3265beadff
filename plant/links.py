"""Links: the keys of an instance's table that are not its parameters (other instances, signal
names, heights in a storage, a data set, tables), declared by its kind like a parameter:

    LINKS = {"storage": link(REQUIRED, "the storage the coil is in", type=Instance, range=("storage",)),
             "top": link(REQUIRED, "height of the coil inlet [m]", type=Height)}

The type says what the value is, the range what it may be. The declaration (plant/declaration.py,
`_check_links`) checks every link of every instance in one place, in the kind's LINKS order:
a name of another instance (`Instance`, `list[Instance]`; range = the roles it may have, checked
there because only the declaration knows every instance), an integer (`int`, range = (lo, hi)),
one of a few words (`str`, `DataSet`: range = the allowed values), a signal name (`SignalName`;
whether the signal exists the compiler checks once its catalogue is complete). A height
(`Height`, `Valve`) is checked by the compiler where the kind asks for its layer, against the
storage's height. Tables and lists (`dict`, `list`, `Path`) are the kind's own to check in its
`check()`: their messages name what their entries mean. A bad value is reported and replaced
by its default (None for a required link), so the rest of the house is still checked.
"""
from __future__ import annotations

from typing import NamedTuple

REQUIRED = object()   # a link's default when the house file must give it


class SignalName:
    """A signal's name ("storage.T_sensor_5", `twin signals` lists them)."""


class DataSet:
    """The name of a shipped data set (range: the allowed names)."""


class Height:
    """A height in m above the bottom of the storage the instance is in (the compiler checks it
    against the storage's height)."""


class Valve:
    """A height, or a three-way valve's { upper = ..., lower = ... } heights."""


class Link(NamedTuple):
    """A link as a kind declares it (`link(...)`)."""

    default: object
    meaning: str
    type: object = None
    range: tuple | None = None
    example: str | None = None


def link(default, meaning: str, type=None, range: tuple | None = None, example: str | None = None) -> Link:
    """Declare a link: default (REQUIRED: must be given), meaning, type and range (see the module
    docstring). `example` ("{storage}.T_sensor_5", filled from the instance's other links) is
    shown when a SignalName link holds no name."""
    return Link(default, meaning, type, range, example)


def link_problem(spec: Link, value, options: dict | None = None) -> str | None:
    """What is wrong with a link's value by its type alone (the message after "key = value"), or
    None. Names of instances need the other instances: the declaration checks those."""
    if spec.type is int:
        lo, hi = spec.range
        if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
            return f"must be an integer {lo} … {hi}"
    elif spec.type is str and value not in spec.range:
        return f"unknown; allowed: {', '.join(spec.range)}"
    elif spec.type is DataSet and value not in spec.range:
        return f"unknown data set; allowed: {', '.join(spec.range)}"
    elif spec.type is SignalName and not isinstance(value, str):
        if spec.example:
            return f"must name a signal, e.g. \"{spec.example.format(**(options or {}))}\""
        return "expected a signal name"
    return None
