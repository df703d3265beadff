"""The district file: houses, grid nodes and pipes, substation attachments, exchange step.

    [district]
    name = "coses"
    start = "2021-01-10"
    step = 60.0                  # s between two exchanges of houses and grid
    T_env = 10.0                 # degC around the buried pipes
    modbus_port_base = 5020      # twin district serve: house k (from 1) gets base + k

    [plant]                      # the grid's own heat source at the root node
    node = "plant"
    T_supply = 70.0              # degC it sends into the supply line
    T_return = 40.0              # degC it returns when it takes the district's net feed-in

    [grid]                       # optional: node water volume and initial temperatures
    node_volume = 0.05           # m3 per node and line
    T_init_supply = 60.0
    T_init_return = 40.0

    [pipes.p1]                   # one pipe pair (supply and return line)
    from = "plant"               # the end nearer the plant
    to = "n1"
    length = 20.0                # m
    diameter = 0.1               # m
    U = 0.19                     # W/(m K)
    # optional, default off (plant/grid/pipe.py): wall_capacity = 0.0 (J/K, the steel wall's mass x cp,
    # lumped at the ends), wall_share_b = 0.5 (its share at end `to`), dispersion = 0.0 (m2/s, axial)

    [houses.house1]
    file = "house1"              # a shipped house (or alias) or a path relative to this file
    node = "n1"
    substation = "rules"         # the house's substation_rules controller on; "off": the substation idles
    controller = "built-in"      # or "external": a real controller attached to its devices
    overrides = { "storage.UA_loss" = 5.0 }
    modbus_port = 5031           # optional: fixed port for twin district serve
    can = "socketcand:127.0.0.1:29536:can0"   # optional: its CANopen nodes' bus (default: the
                                 # house process's own virtual bus, which no other process sees)

Every problem is listed at once with file:line, key, value and the fix (ConfigError).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from plant.errors import ConfigError, closest
from plant.housefile import line_of, resolve, tomllib

from .grid import GridSpec, PipeSpec

DISTRICTS = Path(__file__).resolve().parent / "districts"

KEYS = {
    "district": {"name", "description", "start", "step", "T_env", "modbus_port_base"},
    "plant": {"node", "T_supply", "T_return"},
    "grid": {"node_volume", "T_init_supply", "T_init_return"},
    "pipe": {"from", "to", "length", "diameter", "U", "roughness", "wall_capacity", "wall_share_b", "dispersion"},
    "house": {"file", "node", "substation", "controller", "overrides", "modbus_port", "can"},
}
SUBSTATION = ("rules", "off")
CONTROLLER = ("built-in", "external")


@dataclass(frozen=True)
class HouseEntry:
    name: str
    file: Path
    node: str
    substation: str = "rules"
    controller: str = "built-in"
    overrides: dict = field(default_factory=dict)
    modbus_port: int = 0
    can: str = ""

    def house_overrides(self) -> dict:
        """The overrides the house is loaded with: the file's, plus the substation controller."""
        return {"substation_control.active": 1.0 if self.substation == "rules" else 0.0, **self.overrides}


@dataclass(frozen=True)
class District:
    path: Path
    name: str
    start: str
    step: float
    houses: tuple[HouseEntry, ...]
    grid: GridSpec
    modbus_port_base: int = 5020
    description: str = ""

    def house(self, name: str) -> HouseEntry:
        for h in self.houses:
            if h.name == name:
                return h
        raise ConfigError(f"{self.path}: no house {name!r}; houses: {', '.join(h.name for h in self.houses)}")

    def can_bus(self, name: str) -> str:
        """The house's CANopen bus: its own, or a virtual bus inside its process."""
        return self.house(name).can or f"virtual:{self.name}-{name}"

    def modbus_port(self, name: str) -> int:
        for k, h in enumerate(self.houses, 1):
            if h.name == name:
                return h.modbus_port or self.modbus_port_base + k
        raise ConfigError(f"{self.path}: no house {name!r}")


def shipped() -> list[str]:
    return sorted(p.stem for p in DISTRICTS.glob("*.toml"))


def resolve_district(name_or_path: str | Path) -> Path:
    p = Path(name_or_path)
    if p.suffix == ".toml" and p.exists():
        return p.resolve()
    q = DISTRICTS / f"{p.name}.toml"
    if q.exists():
        return q
    raise ConfigError(f"district {str(name_or_path)!r}: no such file; shipped districts: {', '.join(shipped())}")


class _Reader:
    """The district file being read, and the problems found in it so far."""

    def __init__(self, path: Path, text: str, doc: dict):
        self.path, self.text, self.doc = path, text, doc
        self.problems: list[str] = []

    def where(self, section: str, key: str | None = None) -> str:
        return f"{self.path}:{line_of(self.text, section, key)}"

    def table(self, name: str, required: bool) -> dict:
        t = self.doc.get(name, {})
        if required and name not in self.doc:
            self.problems.append(f"{self.path}: [{name}] missing; add it (see district/declaration.py)")
        if not isinstance(t, dict):
            self.problems.append(f"{self.where(name)}: [{name}] must be a table")
            return {}
        return t

    def unknown(self, section: str, t: dict, allowed: set) -> None:
        for k in t:
            if k not in allowed:
                close = closest(k, sorted(allowed), 1)
                hint = f"did you mean {close[0]!r}?" if close else f"allowed: {', '.join(sorted(allowed))}"
                self.problems.append(f"{self.where(section, k)}: [{section}] {k}: unknown key; {hint}")

    def number(self, section: str, t: dict, key: str, default: float, lo: float, hi: float) -> float:
        v = t.get(key, default)
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not lo <= v <= hi:
            self.problems.append(f"{self.where(section, key)}: [{section}] {key} = {v!r}: must be a number in "
                                 f"[{lo}, {hi}]")
            return default
        return float(v)


def load_district(name_or_path: str | Path) -> District:
    path = resolve_district(name_or_path)
    text = path.read_text()
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{path}: not valid TOML: {exc}") from None
    r = _Reader(path, text, doc)
    for top in doc:
        if top not in ("district", "plant", "grid", "pipes", "houses"):
            close = closest(top, ["district", "plant", "grid", "pipes", "houses"], 1)
            r.problems.append(f"{r.where(top)}: [{top}]: unknown table" + (f"; did you mean [{close[0]}]?" if close else ""))
    d = r.table("district", True)
    r.unknown("district", d, KEYS["district"])
    step = r.number("district", d, "step", 60.0, 1.0, 3600.0)
    T_env = r.number("district", d, "T_env", 10.0, -30.0, 40.0)
    port_base = int(r.number("district", d, "modbus_port_base", 5020, 1024, 65000))
    plant = r.table("plant", True)
    r.unknown("plant", plant, KEYS["plant"])
    grid = r.table("grid", False)
    r.unknown("grid", grid, KEYS["grid"])
    plant_node = plant.get("node", "plant")
    pipes, nodes, parents = _pipes(r, plant_node)
    _check_tree(r, plant_node, pipes, nodes, parents)
    houses = []
    for name, t in (doc.get("houses") or {}).items():
        entry = _house(r, name, t, nodes)
        if entry is not None:
            houses.append(entry)
    if not houses:
        r.problems.append(f"{path}: no [houses.<name>] table; a district needs at least one house")
    if r.problems:
        raise ConfigError(f"district file {path}: {len(r.problems)} problem(s):\n  " + "\n  ".join(r.problems))
    spec = GridSpec(plant_node, tuple(nodes), tuple(pipes), {h.name: h.node for h in houses},
                    r.number("plant", plant, "T_supply", 70.0, 0.0, 150.0),
                    r.number("plant", plant, "T_return", 40.0, 0.0, 150.0),
                    r.number("grid", grid, "T_init_supply", 60.0, 0.0, 150.0),
                    r.number("grid", grid, "T_init_return", 40.0, 0.0, 150.0), T_env,
                    r.number("grid", grid, "node_volume", 0.05, 1e-4, 100.0))
    return District(path, str(d.get("name", path.stem)), str(d.get("start", "2021-01-10")), step,
                    tuple(houses), spec, port_base, str(d.get("description", "")))


def _pipes(r: _Reader, plant_node: str) -> tuple[list, list, dict]:
    """(pipes, nodes from the plant's on, node -> the first pipe into it) of [pipes.*]."""
    pipes, nodes, parents = [], [plant_node], {}
    for name, p in (r.doc.get("pipes") or {}).items():
        sec = f"pipes.{name}"
        if not isinstance(p, dict):
            r.problems.append(f"{r.where(sec)}: [{sec}] must be a table")
            continue
        r.unknown(sec, p, KEYS["pipe"])
        a, b = p.get("from"), p.get("to")
        if not isinstance(a, str) or not isinstance(b, str):
            r.problems.append(f"{r.where(sec)}: [{sec}] needs from = \"node\" and to = \"node\" (from nearer the plant)")
            continue
        if b in parents:
            r.problems.append(f"{r.where(sec, 'to')}: [{sec}] to = {b!r}: node already fed by pipe {parents[b]!r}; "
                              f"the grid must be a tree from the plant (one pipe into each node)")
        if b == plant_node:
            r.problems.append(f"{r.where(sec, 'to')}: [{sec}] to = {b!r} is the plant's node; write the pipe from it")
        parents.setdefault(b, name)
        for n in (a, b):
            if n not in nodes:
                nodes.append(n)
        pipes.append(PipeSpec(name, a, b, r.number(sec, p, "length", 20.0, 0.1, 1e5),
                              r.number(sec, p, "diameter", 0.1, 0.005, 2.0), r.number(sec, p, "U", 0.19, 0.0, 100.0),
                              r.number(sec, p, "roughness", 1e-4, 0.0, 0.01),
                              r.number(sec, p, "wall_capacity", 0.0, 0.0, 1e9),
                              r.number(sec, p, "wall_share_b", 0.5, 0.0, 1.0),
                              r.number(sec, p, "dispersion", 0.0, 0.0, 10.0)))
    return pipes, nodes, parents


def _check_tree(r: _Reader, plant_node: str, pipes: list, nodes: list, parents: dict) -> None:
    """Every node must hang from the plant."""
    for n in nodes:
        seen, m = set(), n
        while m != plant_node and m in parents and m not in seen:
            seen.add(m)
            m = next(p.a for p in pipes if p.name == parents[m])
        if m != plant_node:
            r.problems.append(f"{r.path}: node {n!r} is not connected to the plant's node {plant_node!r} "
                              f"(or lies on a loop); add a pipe from a node nearer the plant")


def _house(r: _Reader, name: str, h, nodes: list) -> HouseEntry | None:
    """The entry of [houses.<name>], None if it is no table."""
    sec = f"houses.{name}"
    if not isinstance(h, dict):
        r.problems.append(f"{r.where(sec)}: [{sec}] must be a table")
        return None
    r.unknown(sec, h, KEYS["house"])
    file = h.get("file", name)
    try:
        fp = resolve(r.path.parent / file) if str(file).endswith(".toml") else resolve(file)
    except ConfigError as exc:
        r.problems.append(f"{r.where(sec, 'file')}: [{sec}] file = {file!r}: {exc}")
        fp = Path(str(file))
    node = h.get("node")
    if node not in nodes:
        close = closest(node, nodes, 1)
        r.problems.append(f"{r.where(sec, 'node')}: [{sec}] node = {node!r}: not a node of the grid"
                          + (f"; did you mean {close[0]!r}?" if close else f"; nodes: {', '.join(nodes)}"))
    sub, ctl = h.get("substation", "rules"), h.get("controller", "built-in")
    if sub not in SUBSTATION:
        r.problems.append(f"{r.where(sec, 'substation')}: [{sec}] substation = {sub!r}: allowed {', '.join(SUBSTATION)}")
    if ctl not in CONTROLLER:
        r.problems.append(f"{r.where(sec, 'controller')}: [{sec}] controller = {ctl!r}: allowed {', '.join(CONTROLLER)}")
    ov = h.get("overrides", {})
    if not isinstance(ov, dict):
        r.problems.append(f"{r.where(sec, 'overrides')}: [{sec}] overrides must be a table of \"instance.key\" = value")
        ov = {}
    port = int(r.number(sec, h, "modbus_port", 0, 0, 65535))
    bus = h.get("can", "")
    if not isinstance(bus, str):
        r.problems.append(f"{r.where(sec, 'can')}: [{sec}] can = {bus!r}: a bus spec such as "
                          f"\"socketcand:127.0.0.1:29536:can0\" or \"socketcan:can0\"")
        bus = ""
    return HouseEntry(name, fp, str(node), sub, ctl, dict(ov), port, bus)
