"""Map lint: consistency checks that go beyond loading, including bindings against the plant.

Errors make a map unusable (overlaps, unknown signals, CANopen clashes); notes are information
(bindings skipped because the map targets another house). The catalogue is the real house's
`house.catalogue`, so a renamed plant signal breaks lint, as it must.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from gateway.maps.model import CO_AREAS, DeviceMap
from plant import units
from plant.errors import ConfigError, closest

PDO_BYTES = {"bool": 1, "uint16": 2, "int16": 2, "bits16": 2, "uint32": 4, "int32": 4, "float32": 4}


@dataclass(frozen=True)
class Problem:
    level: str        # "error" | "note"
    text: str

    def __str__(self) -> str:
        return f"{self.level}: {self.text}"


def lint_map(dmap: DeviceMap, catalogue: Any = None, house: str = "house1") -> list[Problem]:
    """Check one map; with a catalogue, also its plant bindings (if the map is for `house`)."""
    out: list[Problem] = []
    where = str(dmap.path)

    def err(text: str) -> None:
        out.append(Problem("error", f"{where} {text}"))

    names: set[str] = set()
    used: dict[tuple[str, int], str] = {}
    co_used: dict[tuple[int, int], str] = {}
    pdo_bytes: dict[str, int] = {}
    for p in dmap.points:
        if p.name in names:
            err(f"[point {p.name}]: duplicate name; point names must be unique")
        names.add(p.name)
        for a in range(p.address, p.address + p.words):
            if (p.table, a) in used:
                err(f"[point {p.name}]: {p.table} address {a} overlaps {used[(p.table, a)]}; "
                    "move one of them")
            used[(p.table, a)] = p.name
        if p.writable and p.type not in ("string", "bool") and not p.range and not p.enum:
            err(f"[point {p.name}]: writable number without range; add range = [low, high]")
        if not p.ref.strip():
            err(f"[point {p.name}]: empty ref; name the imitated source or 'assumed'")
        if p.co_index is not None:
            if not any(lo <= p.co_index <= hi for lo, hi in CO_AREAS):
                err(f"[point {p.name}] co_index = {p.co_index:#06x}: outside 0x2000…0x9FFF")
            key = (p.co_index, p.co_sub or 0)
            if key in co_used:
                err(f"[point {p.name}]: CANopen {key[0]:#06x}.{key[1]} also used by {co_used[key]}")
            co_used[key] = p.name
            if not 1 <= (p.co_sub or 0) <= 254:
                err(f"[point {p.name}] co_sub = {p.co_sub}: must be 1…254")
        if p.type not in ("string", "bool"):
            try:
                units.factors(p.si_unit, p.unit, span=True)
            except ConfigError as exc:
                err(f"[point {p.name}] unit = {p.unit!r}, si_unit = {p.si_unit!r}: {exc}")
        if p.pdo:
            pdo_bytes[p.pdo] = pdo_bytes.get(p.pdo, 0) + PDO_BYTES.get(p.type, 99)
    for tag, size in sorted(pdo_bytes.items()):
        if size > 8:
            err(f"[map]: PDO {tag} maps {size} bytes; at most 8, move points to another PDO")
    if dmap.watchdog:
        for name in dmap.watchdog.refresh_on:
            if name != "*" and name not in names:
                err(f"[watchdog] refresh_on {name!r}: no such point; use one of {_close(name, names)}")
    reset = dmap.fault.reset_point
    if reset and reset not in names:
        err(f"[fault] reset_point {reset!r}: no such point; use one of {_close(reset, names)}")
    if dmap.fault.trip_forces and not reset:
        err("[fault]: trip_forces without reset_point; a trip must be resettable by a write")
    if catalogue is not None:
        out += _bindings(dmap, catalogue, house)
    return out


def lint_all(maps: dict[str, DeviceMap], catalogue: Any = None, house: str = "house1") -> list[Problem]:
    """Lint every map plus cross-map checks (unit ids and CANopen node ids unique per house)."""
    out: list[Problem] = []
    for dmap in maps.values():
        out += lint_map(dmap, catalogue, house)
    for attr, label in (("unit_id", "Modbus unit id"), ("node_id", "CANopen node id")):
        seen: dict[tuple[str, int], str] = {}
        for dmap in maps.values():
            value = dmap.unit_id if attr == "unit_id" else dmap.canopen.node_id
            for house_name in served(dmap):
                key = (house_name, value)
                if key in seen:
                    out.append(Problem("error", f"{dmap.path}: {label} {value} also used by "
                                       f"{seen[key]} in {house_name}; give each device of a house its own"))
                seen[key] = dmap.id
    return out


def served(dmap: DeviceMap) -> list[str]:
    """The houses a map serves: its `house`, several separated by '/' (as the runtime reads it)."""
    return dmap.house.split("/")


def _bindings(dmap: DeviceMap, catalogue: Any, house: str) -> list[Problem]:
    if house not in served(dmap):
        return [Problem("note", f"{dmap.path}: map is for {dmap.house!r}, bindings not checked "
                        f"against {house!r}")]
    out: list[Problem] = []
    names = list(catalogue.names)
    refs = [(p.name, "signal", p.signal) for p in dmap.points if p.signal]
    refs += [(p.name, "command", p.command) for p in dmap.points if p.command]
    refs += [(f"status bit {b}", "signal", s) for b, s in dmap.status_bits if not s.startswith("@")]
    refs += [("fault trip_forces", "command", c) for c, _ in dmap.fault.trip_forces]
    for owner, kind, name in refs:
        if name not in catalogue:
            out.append(Problem("error", f"{dmap.path} [point {owner}] {kind} = {name!r}: not in the "
                               f"{house} catalogue; closest: {_close(name, names)}"))
            continue
        sig = catalogue.signal(name)
        if kind == "command" and sig.causality != "input":
            out.append(Problem("error", f"{dmap.path} [point {owner}] command = {name!r}: is a "
                               f"plant {sig.causality}, not an input; bind it as signal"))
    for p in dmap.points:
        bound = p.signal or p.command
        if bound and bound in catalogue and p.type != "bool":
            unit = catalogue.signal(bound).unit
            if not _same_unit(unit, p.si_unit):
                out.append(Problem("error", f"{dmap.path} [point {p.name}]: plant unit of {bound} "
                                   f"is {unit!r}, map converts from {p.si_unit!r}; set si_unit"))
    return out


def _same_unit(a: str, b: str) -> bool:
    """Two names of one unit (degC and °C, 1 and ''), by the unit table."""
    return a == b or units.convertible(a, b) and units.factors(a, b) == (1.0, 0.0)


def _close(name: str, names: Any) -> str:
    return ", ".join(closest(name, list(names), n=3)) or "none close"
