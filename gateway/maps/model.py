"""Device maps as immutable data: DeviceMap and Point, loaded and checked from devices/<id>.toml.

A map describes one emulated device's bus face: its points (registers, coils, CANopen objects),
identification, watchdog rule, status word and fault codes. It holds no live state; that lives in
gateway.device.device.Device. Addresses are 0-based wire (PDU) addresses; `doc_offset` and
`doc_prefix` only change the printed number. The field reference is devices/README.md.

Loading checks everything a map can get wrong on its own and reports all problems at once as one
DeviceMapError, each line shaped '<file> [point NAME]: <what is wrong>; <fix>'; a CSV register table
(gateway.maps.csv_table) goes through the same checks. Checks that need the plant live in lint.
"""
from __future__ import annotations

import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from plant.errors import ConfigError, DeviceMapError, closest
from plant.units import si_unit as _si_unit

#: Where shipped maps live (the repository's devices/ folder).
DEVICES_DIR = Path(__file__).resolve().parents[2] / "devices"

TABLES = ("coil", "discrete", "input", "holding")
BIT_TABLES = ("coil", "discrete")
#: Number of 16-bit registers per type ("string" is computed from `length`).
WORDS = {"bool": 1, "uint16": 1, "int16": 1, "bits16": 1, "uint32": 2, "int32": 2, "float32": 2}
TYPES = tuple(WORDS) + ("string",)
ACCESS = ("R", "RW", "W")
WORD_ORDERS = ("hi_lo", "lo_hi")
ON_BAD = ("exception", "clamp")
#: Gateway-internal values a point can serve instead of a plant signal.
STATES = (
    "status", "fault_code", "fault_reset", "heartbeat", "watchdog_timeout",
    "identity.vendor", "identity.product", "identity.serial", "identity.firmware",
)
#: Sources a status-word bit can show: gateway flags (prefixed '@') or a plant signal (nonzero = set).
STATUS_FLAGS = ("@remote", "@watchdog", "@fault", "@tripped", "@sensor_fault", "@read_only", "@link_fault")
#: Allowed CANopen manufacturer area for map-defined objects (CiA 301); profile objects 0x6000-0x9FFF.
CO_AREAS = ((0x2000, 0x5FFF), (0x6000, 0x9FFF))


@dataclass(frozen=True)
class Point:
    """One datum of a device: where it sits on the bus, how it is encoded, what it binds to.

    value (device unit) = raw * scale + offset. Exactly one of `signal` (read from the plant),
    `command` (drives a plant input; also readable), `state` (gateway-internal) or `const` gives
    the value. For CANopen: object `co_index`:`co_sub`, PDO tag `pdo` ("T1".."T4", "R1".."R4").
    """

    name: str
    table: str
    address: int
    type: str
    access: str = "R"
    scale: float = 1.0
    offset: float = 0.0
    unit: str = ""
    si_unit: str = "1"
    length: int = 0                       # characters, for type "string"
    word_order: str = "hi_lo"
    range: tuple[float, float] | None = None
    on_bad: str = "exception"             # out-of-range write: refuse (exception 03) or clamp
    enum: tuple[tuple[int, str], ...] = ()
    default: float | str | None = None
    signal: str | None = None
    command: str | None = None
    state: str | None = None
    const: float | str | None = None
    release_value: float | None = None    # writing this value hands the command back (ISM8 "0 = no preset")
    invalid: int | None = None            # raw served while the sensor is faulted
    co_index: int | None = None
    co_sub: int | None = None
    pdo: str | None = None
    desc: str = ""
    ref: str = "assumed"

    @property
    def words(self) -> int:
        """Registers the point occupies (1 for coils and discrete inputs)."""
        if self.type == "string":
            return (self.length + 1) // 2
        return WORDS[self.type]

    @property
    def readable(self) -> bool:
        return self.access in ("R", "RW")

    @property
    def writable(self) -> bool:
        return self.access in ("RW", "W")


@dataclass(frozen=True)
class Identity:
    """Identification strings (Modbus FC43/14, CANopen 0x1008/0x100A/0x1018)."""

    vendor: str
    product: str
    serial: str
    firmware: str
    product_code: int = 0
    revision: int = 0


@dataclass(frozen=True)
class CanopenSpec:
    node_id: int
    device_type: int = 0
    heartbeat_ms: int = 1000


@dataclass(frozen=True)
class WatchdogRule:
    """Remote commands expire unless one of `refresh_on` is written within `timeout_s`.

    On expiry every command point returns to its default, the plant input is released to the
    built-in controller ("internal control") and the status flag @watchdog is set.
    `refresh_on = ("*",)` means any accepted write refreshes.
    """

    timeout_s: float
    refresh_on: tuple[str, ...]
    on_expire: str = "internal"


@dataclass(frozen=True)
class FaultSpec:
    """Fault codes of the device and what a generator trip does.

    A trip shows `trip_code`, forces each `trip_forces` command to its value and latches until
    `reset_point` is written with 1. A sensor fault shows `sensor_code` while no trip is active.
    """

    codes: tuple[tuple[int, str], ...] = ()
    trip_code: int = 0
    sensor_code: int = 0
    reset_point: str | None = None
    trip_forces: tuple[tuple[str, float], ...] = ()


@dataclass(frozen=True)
class DeviceMap:
    """One device's complete bus description, as loaded from devices/<id>.toml."""

    id: str
    path: Path
    kind: str
    house: str
    vendor: str
    model: str
    style: str
    imitates: str
    map_version: str
    identity: Identity
    unit_id: int
    functions: frozenset[int]
    doc_offset: int
    doc_prefix: str
    word_order: str
    canopen: CanopenSpec
    watchdog: WatchdogRule | None
    status_bits: tuple[tuple[int, str], ...]
    fault: FaultSpec
    points: tuple[Point, ...]
    invalid: tuple[tuple[str, int], ...] = ()   # [modbus] invalid_<type>: the per-type default
    _by_name: dict[str, Point] = field(default_factory=dict, repr=False, compare=False)

    def __post_init__(self) -> None:
        self._by_name.update({p.name: p for p in self.points})

    def point(self, name: str) -> Point:
        """The point called `name`; DeviceMapError with the closest names otherwise."""
        try:
            return self._by_name[name]
        except KeyError:
            close = closest(name, self._by_name, n=3)
            raise DeviceMapError(
                f"{self.id}: no point {name!r}; closest: {', '.join(close) or 'none'}"
            ) from None

    def __contains__(self, name: object) -> bool:
        return name in self._by_name

    def printed_address(self, point: Point) -> str:
        """The number as the imitated manual prints it (documentation only)."""
        return f"{self.doc_prefix}{point.address + self.doc_offset}"

    @property
    def commands(self) -> tuple[Point, ...]:
        return tuple(p for p in self.points if p.command)


def map_path(name: str, directory: Path | None = None) -> Path:
    """Path of the map `name` (file stem) in `directory` (default: the shipped devices/)."""
    directory = directory or DEVICES_DIR
    path = directory / f"{name}.toml"
    if not path.exists():
        known = sorted(p.stem for p in directory.glob("*.toml"))
        close = closest(name, known, n=3)
        raise DeviceMapError(
            f"{path}: no such device map; known: {', '.join(known)}"
            + (f" (closest: {', '.join(close)})" if close else "")
        )
    return path


def load_toml(path: Path) -> DeviceMap:
    """Load and check one TOML map; one DeviceMapError lists every problem (gateway/maps/loader.py
    picks the reader by suffix)."""
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise DeviceMapError(f"{path}: cannot read map ({exc}); fix the TOML syntax") from exc
    problems: list[str] = []
    try:
        dmap = build_map(path, doc, problems)
    except (KeyError, TypeError, ValueError) as exc:
        problems.append(f"{path}: malformed entry ({exc!r}); see devices/README.md for the fields")
        dmap = None
    if problems or dmap is None:
        raise DeviceMapError("\n".join(problems))
    return dmap


def _need(section: dict, key: str, where: str, problems: list[str], default: Any = None) -> Any:
    if key not in section:
        problems.append(f"{where}: missing key {key!r}; add it (see devices/README.md)")
        return default
    return section[key]


def _default_si_unit(unit: str) -> str | None:
    """The plant-side unit of a device unit (plant/units.py: `kW` -> `W`); None if unknown."""
    try:
        return _si_unit(unit)
    except ConfigError:
        return None


def _not_one_of(where: str, key: str, value: Any, allowed: tuple[str, ...]) -> str:
    close = "".join(f" (closest: {c})" for c in closest(str(value), allowed, n=1))
    return f"{where} {key} = {value!r}: must be one of {', '.join(allowed)}{close}"


def build_map(path: Path, doc: dict, problems: list[str], locate: Any = None,
              point_where: list[str] | None = None) -> DeviceMap:
    """A DeviceMap from a TOML-shaped document, appending problems; locate/point_where add lines."""
    loc = locate or (lambda section, key: f"{path} [{section}]")
    dev = doc.get("device", {})
    where = loc("device", "id")
    dev_id = _need(dev, "id", where, problems, path.stem)
    if dev_id != path.stem:
        problems.append(f"{where} id = {dev_id!r}: must equal the file stem; use {path.stem!r}")
    ident = dev.get("identity", {})
    identity = Identity(
        vendor=ident.get("vendor", ""), product=ident.get("product", ""),
        serial=str(ident.get("serial", "")), firmware=ident.get("firmware", ""),
        product_code=int(ident.get("product_code", 0)), revision=int(ident.get("revision", 0)))
    mb = doc.get("modbus", {})
    word_order = mb.get("word_order", "hi_lo")
    if word_order not in WORD_ORDERS:
        problems.append(_not_one_of(loc("modbus", "word_order"), "word_order", word_order, WORD_ORDERS))
    unit_id = _need(mb, "unit_id", loc("modbus", "unit_id"), problems, 1)
    if not isinstance(unit_id, int) or not 1 <= unit_id <= 247:
        problems.append(f"{loc('modbus', 'unit_id')} unit_id = {unit_id!r}: must be an integer 1…247")
    invalid = {k.removeprefix("invalid_"): v for k, v in mb.items() if k.startswith("invalid_")}
    co = doc.get("canopen", {})
    canopen = CanopenSpec(
        node_id=int(_need(co, "node_id", loc("canopen", "node_id"), problems, 0)),
        device_type=int(co.get("device_type", 0)), heartbeat_ms=int(co.get("heartbeat_ms", 1000)),
    )
    if not 1 <= canopen.node_id <= 127:
        problems.append(f"{loc('canopen', 'node_id')} node_id = {canopen.node_id}: must be 1…127")
    points = tuple(_point(point_where[i] if point_where else path, i, raw, word_order, invalid, problems)
                   for i, raw in enumerate(doc.get("map", {}).get("points", []) + doc.get("point", [])))
    if not points:
        problems.append(f"{path}: no points; add [map] points = [...] (or [[point]] blocks)")
    watchdog, wd = None, doc.get("watchdog")
    if wd is not None:
        refresh = wd.get("refresh_on", ["*"])
        watchdog = WatchdogRule(
            timeout_s=float(_need(wd, "timeout_s", loc("watchdog", "timeout_s"), problems, 60.0)),
            refresh_on=tuple([refresh] if isinstance(refresh, str) else refresh),
            on_expire=wd.get("on_expire", "internal"),
        )
        if watchdog.timeout_s <= 0:
            problems.append(f"{loc('watchdog', 'timeout_s')} timeout_s = {watchdog.timeout_s}: must be > 0 s")
        if watchdog.on_expire != "internal":
            problems.append(f"{loc('watchdog', 'on_expire')} on_expire = {wd['on_expire']!r}: only 'internal'")
    status_bits = tuple(sorted((int(k), v) for k, v in doc.get("status", {}).get("bits", {}).items()))
    for bit, source in status_bits:
        if not 0 <= bit <= 15:
            problems.append(f"{loc('status', f'bits.{bit}')} bit {bit}: must be 0…15")
        if source.startswith("@") and source not in STATUS_FLAGS:
            problems.append(_not_one_of(loc("status", f"bits.{bit}"), f"bit {bit}", source, STATUS_FLAGS)
                            + " or a plant signal name")
    fl = doc.get("fault", {})
    fault = FaultSpec(
        codes=tuple(sorted((int(k), v) for k, v in fl.get("codes", {}).items())),
        trip_code=int(fl.get("trip_code", 0)), sensor_code=int(fl.get("sensor_code", 0)),
        reset_point=fl.get("reset_point"),
        trip_forces=tuple((k, float(v)) for k, v in fl.get("trip_forces", {}).items()),
    )
    return DeviceMap(
        id=dev_id, path=path, kind=dev.get("kind", ""), house=dev.get("house", "house1"),
        vendor=dev.get("vendor", ""), model=dev.get("model", ""), style=dev.get("style", ""),
        imitates=_need(dev, "imitates", where, problems, ""),
        map_version=dev.get("map_version", "0.0.0"), identity=identity, unit_id=unit_id,
        functions=frozenset(mb.get("functions", [1, 2, 3, 4, 5, 6, 15, 16, 43])),
        doc_offset=int(mb.get("doc_offset", 0)), doc_prefix=str(mb.get("doc_prefix", "")),
        word_order=word_order, canopen=canopen, watchdog=watchdog, status_bits=status_bits,
        fault=fault, points=points, invalid=tuple(sorted(invalid.items())),
    )


_POINT_KEYS = {
    "name", "table", "address", "type", "access", "scale", "offset", "unit", "si_unit", "length",
    "word_order", "range", "on_bad", "enum", "default", "signal", "command", "state", "const",
    "release_value", "invalid", "co_index", "co_sub", "pdo", "desc", "ref",
}


def _point(path: Path | str, index: int, raw: dict, word_order: str, invalid: dict,
           problems: list[str]) -> Point:
    name = raw.get("name", f"#{index}")
    where = f"{path} [point {name}]"
    for key in sorted(set(raw) - _POINT_KEYS):
        close = closest(key, _POINT_KEYS, n=1)
        problems.append(f"{where}: unknown field {key!r}; did you mean {close[0] if close else '?'}")
    for key in ("name", "table", "address", "type", "ref"):
        _need(raw, key, where, problems)
    table, ptype, access = raw.get("table", "input"), raw.get("type", "uint16"), raw.get("access", "R")
    if table not in TABLES:
        problems.append(_not_one_of(where, "table", table, TABLES))
    if ptype not in TYPES:
        problems.append(_not_one_of(where, "type", ptype, TYPES))
    if access not in ACCESS:
        problems.append(_not_one_of(where, "access", access, ACCESS))
    if (table in BIT_TABLES) != (ptype == "bool"):
        problems.append(f"{where}: type {ptype!r} in table {table!r}; coils and discrete inputs are "
                        "type 'bool', registers are not")
    if table in ("input", "discrete") and access != "R":
        problems.append(f"{where}: {table} points are read-only on Modbus; set access = 'R'")
    address = raw.get("address", 0)
    if not isinstance(address, int) or not 0 <= address <= 65535:
        problems.append(f"{where} address = {address!r}: must be a wire address 0…65535")
    sources = [k for k in ("signal", "command", "state", "const") if k in raw]
    if len(sources) != 1:
        problems.append(f"{where}: has {sources or 'no value source'}; give exactly one of "
                        "signal, command, state, const")
    if "command" in raw and access == "R":
        problems.append(f"{where}: command point must be writable; set access = 'RW'")
    if raw.get("state") is not None and raw["state"] not in STATES:
        problems.append(_not_one_of(where, "state", raw["state"], STATES))
    rng = raw.get("range")
    if rng is not None and (len(rng) != 2 or rng[0] > rng[1]):
        problems.append(f"{where} range = {rng!r}: must be [low, high] with low <= high")
    if raw.get("word_order", word_order) not in WORD_ORDERS:
        problems.append(_not_one_of(where, "word_order", raw["word_order"], WORD_ORDERS))
    if raw.get("on_bad", "exception") not in ON_BAD:
        problems.append(_not_one_of(where, "on_bad", raw["on_bad"], ON_BAD))
    if ptype == "string" and int(raw.get("length", 0)) <= 0:
        problems.append(f"{where}: string point needs length > 0 (characters, 2 per register)")
    if raw.get("scale", 1.0) == 0:
        problems.append(f"{where} scale = 0: must be nonzero")
    unit = raw.get("unit", "")
    si_unit = raw.get("si_unit", _default_si_unit(unit))
    if si_unit is None:
        problems.append(f"{where} unit = {unit!r}: no default SI unit; add si_unit = '...'")
    enum = tuple(sorted((int(k), str(v)) for k, v in raw.get("enum", {}).items()))
    co_index = raw.get("co_index")
    return Point(
        name=name, table=table, address=address if isinstance(address, int) else 0, type=ptype,
        access=access, scale=float(raw.get("scale", 1.0)), offset=float(raw.get("offset", 0.0)),
        unit=unit, si_unit=si_unit or "1", length=int(raw.get("length", 0)),
        word_order=raw.get("word_order", word_order),
        range=(float(rng[0]), float(rng[1])) if rng is not None and len(rng) == 2 else None,
        on_bad=raw.get("on_bad", "exception"), enum=enum, default=raw.get("default"),
        signal=raw.get("signal"), command=raw.get("command"), state=raw.get("state"),
        const=raw.get("const"), release_value=raw.get("release_value"),
        invalid=raw.get("invalid", invalid.get(ptype)),
        co_index=int(co_index, 0) if isinstance(co_index, str) else co_index,
        co_sub=raw.get("co_sub"), pdo=raw.get("pdo"), desc=raw.get("desc", ""),
        ref=raw.get("ref", "assumed"),
    )
