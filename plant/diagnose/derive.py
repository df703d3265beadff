"""The cut variant of any house file, derived from what a recording measures.

A recording that measures a heating circuit on its building side (its flow, the supply after
mixing, the return) and the hot water taken lets the diagnosis replay the plant without the
twin's building, room and hot-water profiles: the cut keeps the generators, coupling points,
storages and coils and puts measured boundaries where the circuits and draws were
(plant/connections/measured.py). A recording that measures a circuit on its primary side (the
flow it draws from its coupling point and its return) cuts at the coupling point instead.

What goes follows from the house's links, never from its instance names: a mixing station takes
its emitter with it, the emitter its zone, and a controller whose every output drives a removed
instance (the room thermostat) goes too. The measured boundary keeps the station's name, so the
coupling point that listed it needs no change. An instance left behind that still names a
removed one (a rule set reading the room) makes the cut impossible, said with the instance and
the link.

The variant is a house file (`[house] base = ...`, `remove = [...]`) written into the plant
cache under the name a shipped cut would have (`house1_cut_circuit.toml`), so it can be read and
loaded like any other. plant/houses/house1_cut_circuit.toml and house1_cut_storage.toml are
examples the derivation reproduces (tests/diagnose/test_derive.py).
"""
from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, NamedTuple

from .. import cache_dir
from ..components.generator import Generator
from ..declaration import load, read
from ..errors import ConfigError
from ..kinds import KINDS
from ..toml_text import key as toml_key, value as toml_value


class Side(NamedTuple):
    """Where a heating circuit is cut: the measured kind put in its station's place and the
    cut's inputs bound to recorded signals of the station (input local -> recorded local)."""

    kind: str
    bind: tuple
    words: str


SIDES = {
    "circuit": Side("measured_circuit", (("m_flow", "m_flow"), ("T_sup", "T_sup"), ("T_return", "T_ret")),
                    "heating circuit (measured flow, supply and return) and hot-water draw (measured) as "
                    "boundaries: the storage no longer depends on the twin's building, room, weather and DHW "
                    "profiles"),
    "switch": Side("measured_consumer", (("m_flow", "m_flow_primary"), ("T_return", "T_ret")),
                   "heating circuit (measured primary flow and return) and hot-water draw (measured) as "
                   "boundaries at the coupling point: the mixing station, building, room, weather and DHW "
                   "profiles are outside the replayed plant"),
}
STATION, DRAW = "mixing_station", "dhw_draw"
# a generator at its measured outlet (its kind's `outlet = "measured"`): input local -> recorded local
OUTLET = tuple((local, recorded) for local, recorded, _, _ in Generator.MEASURED_OUTLET)
# the kinds that can run there: those with an `outlet` link (the boiler's)
OUTLET_KINDS = tuple(k for k, kind in sorted(KINDS.items()) if "outlet" in kind.LINKS)


@dataclass(frozen=True)
class DerivedCut:
    name: str              # "circuit" or "switch" (SIDES)
    house: Path            # the house file it cuts
    house_name: str        # its [house] name
    removes: tuple         # instances of the house the measured boundaries replace or drop
    tables: dict           # instance -> its table in the variant (the measured boundaries)
    bindings: dict         # input of the cut house -> the recorded signal it follows
    why: str
    generators: tuple = ()  # generators kept, at their measured outlet and flow

    @property
    def label(self) -> str:
        """The name a shipped cut of this house would have (house1_cut_circuit; with a generator
        at its measured outlet: house1_cut_circuit_boiler)."""
        return f"{self.house.stem}_cut_{self.name}" + "".join(f"_{g}" for g in self.generators)

    def missing(self, has: Callable[[str], bool]) -> list[str]:
        """The recorded signals this cut follows that a recording lacks."""
        return [s for s in self.bindings.values() if not has(s)]

    def text(self) -> str:
        head = {"name": self.house_name, "base": str(self.house.resolve()), "remove": list(self.removes),
                "description": f"{self.house_name} cut at its {self.name}: derived from what a recording measures"}
        lines = [f"# {self.label}: derived by the diagnosis (plant/diagnose/derive.py) from {self.house}",
                 f"# Bind {', '.join(f'{k} (recorded {v})' for k, v in self.bindings.items())}.", "", "[house]"]
        lines += [f"{toml_key(k)} = {toml_value(v)}" for k, v in head.items()]
        for name, table in self.tables.items():
            lines += ["", f"[{toml_key(name)}]"] + [f"{toml_key(k)} = {toml_value(v)}" for k, v in table.items()]
        return "\n".join(lines) + "\n"

    def path(self) -> Path:
        """The variant as a house file in the plant cache, written once per content (atomically:
        parallel replays load it)."""
        text = self.text()
        path = cache_dir() / "cuts" / hashlib.sha256(text.encode()).hexdigest()[:16] / f"{self.label}.toml"
        if not path.exists():
            path.parent.mkdir(parents=True, exist_ok=True)
            tmp = path.with_suffix(f".{os.getpid()}.tmp")
            tmp.write_text(text)
            os.replace(tmp, path)
        return path


def derive(house, name: str = "circuit", generators=()) -> DerivedCut:
    """The cut of `house` (a name or a house file) at every heating circuit's `name` side
    (SIDES) and every hot-water draw, and at the outlet of each of `generators` (its kind's
    `outlet = "measured"`: its outlet temperature and flow follow the recording, its commands,
    efficiency and counters stay; for a unit run otherwise than the twin's model runs it,
    pipeline.outlets). A house with no mixing station, or one whose remaining instances
    name a removed one, cannot be cut: a ConfigError says which and why."""
    if name not in SIDES:
        raise ConfigError(f"cut {name!r}: unknown; cuts: {', '.join(SIDES)}")
    side = SIDES[name]
    spec = load(house)
    doc = read(spec.path)
    inst = spec.instances
    stations = [i for i in inst.values() if i.kind == STATION]
    if not stations:
        raise ConfigError(f"{spec.path}: no {STATION} to cut at: a heating circuit is cut at its mixing station "
                          "(the recording then measures its flow, supply and return)")
    removes, tables, bindings = [], {}, {}
    for st in stations:
        emitter = inst[st.options["emitter"]]
        removes += [st.name, emitter.name] + ([emitter.options["zone"]] if emitter.options.get("zone") else [])
        tables[st.name] = {"kind": side.kind}
        bindings.update({f"{st.name}.{local}": f"{st.name}.{rec}" for local, rec in side.bind})
    for i in inst.values():  # a controller whose every output drives a removed instance (the thermostat)
        targets = {str(v).split(".", 1)[0] for v in (i.options.get("outputs") or {}).values()}
        if KINDS[i.kind].role == "controller" and targets and targets <= set(removes):
            removes.append(i.name)
    for d in (i for i in inst.values() if i.kind == DRAW):
        removes.append(d.name)
        tables[d.name] = {"kind": "measured_draw", **{k: v for k, v in doc[d.name].items() if k != "kind"}}
        bindings[f"{d.name}.m_flow_hot"] = f"{d.name}.m_flow_hot"
    for g in generators:
        if g not in inst or KINDS[inst[g].kind].role != "generator":
            raise ConfigError(f"{spec.path}: {g!r} is no generator of {spec.name}; a cut puts a generator's "
                              "measured outlet and flow in its model's place")
        if inst[g].kind not in OUTLET_KINDS:
            raise ConfigError(f"{spec.path}: {g} ({inst[g].kind}) cannot run at a measured outlet; kinds that can: "
                              + ", ".join(OUTLET_KINDS))
        # the unit stays (its commands, efficiency and counters); its outlet follows the recording
        tables[g] = {"outlet": "measured"}
        bindings.update({f"{g}.{local}": f"{g}.{rec}" for local, rec in OUTLET})
    gone = set(removes) - set(tables)
    for i in inst.values():
        if i.name in removes:
            continue
        for k, v in i.options.items():
            named = _named(v) & gone
            if named:
                raise ConfigError(f"{i.at(k)}: names {', '.join(sorted(named))}, which the cut at the {name} removes "
                                  f"(with {', '.join(st.name for st in stations)}); a recording of this house is "
                                  "replayed whole")
    why = side.words + "".join(f"; {g} at its measured outlet temperature and flow (its gas from its efficiency)"
                               for g in generators)
    return DerivedCut(name, spec.path, spec.name, tuple(removes), tables, bindings, why, tuple(generators))


def _named(value) -> set:
    """Instance names a link's value refers to (a name, 'instance.signal', or lists and tables of them)."""
    if isinstance(value, str):
        return {value.split(".", 1)[0]}
    if isinstance(value, (list, tuple)):
        return set().union(*(_named(v) for v in value)) if value else set()
    if isinstance(value, dict):
        return set().union(*(_named(v) for v in value.values())) if value else set()
    return set()
