"""Signals and the signal catalogue: stable dotted names, units and causality, each with an index.

Names are used at the edges (CLI, device maps, recordings, FMU bindings); the compiled loop uses
the indices. The catalogue is frozen when a house is assembled; renaming a signal is a breaking
change (listed in CHANGES.md).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from .errors import SignalError, did_you_mean

CAUSALITIES = ("input", "output", "parameter", "state")


@dataclass(frozen=True)
class Signal:
    name: str
    unit: str
    causality: str
    description: str
    index: int = -1

    def input_value(self, value, inputs) -> float:
        """`value` as a float if this signal is an input and the value finite; else SignalError
        naming the allowed `inputs`."""
        if self.causality != "input":
            raise SignalError(f"{self.name}: is an {self.causality}, only inputs can be set; inputs: "
                              + ", ".join(inputs))
        value = float(value)
        if not math.isfinite(value):
            raise SignalError(f"{self.name} = {value}: must be a finite number [{self.unit}]")
        return value

    def require_input(self) -> None:
        if self.causality != "input":
            raise SignalError(f"{self.name}: is an {self.causality}, not an input")


class SignalCatalogue:
    """An ordered, immutable set of signals with name -> index lookup."""

    def __init__(self, signals: list[Signal]):
        seen = {}
        out = []
        for i, s in enumerate(signals):
            if s.name in seen:
                raise SignalError(f"signal {s.name!r} declared twice")
            if s.causality not in CAUSALITIES:
                raise SignalError(f"signal {s.name!r}: causality {s.causality!r}; allowed {CAUSALITIES}")
            s = Signal(s.name, s.unit, s.causality, s.description, i)
            seen[s.name] = s
            out.append(s)
        self._by_name = seen
        self._signals = tuple(out)

    @property
    def names(self) -> list[str]:
        return [s.name for s in self._signals]

    def __iter__(self):
        return iter(self._signals)

    def __len__(self) -> int:
        return len(self._signals)

    def __contains__(self, name: object) -> bool:
        return name in self._by_name

    def signal(self, name: str) -> Signal:
        try:
            return self._by_name[name]
        except KeyError:
            hint = did_you_mean(name, self._by_name, "list them with `twin signals HOUSE`")
            raise SignalError(f"unknown signal {name!r}; {hint}") from None

    def index(self, name: str) -> int:
        return self.signal(name).index

    def inputs(self) -> list[Signal]:
        return [s for s in self._signals if s.causality == "input"]
