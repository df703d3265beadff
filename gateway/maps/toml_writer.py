"""A DeviceMap written as devices/<id>.toml text, the form gateway.maps.model loads (used by import-table)."""
from __future__ import annotations

from gateway.maps.model import DeviceMap, Point
from plant.toml_text import value as _val


def _point(dmap: DeviceMap, p: Point) -> str:
    invalid = dict(dmap.invalid)
    fields: list[tuple[str, object]] = [("name", p.name), ("table", p.table), ("address", p.address),
                                         ("type", p.type)]
    optional: list[tuple[str, object, bool]] = [
        ("length", p.length, p.type == "string"),
        ("access", p.access, p.access != "R"),
        ("scale", p.scale, p.scale != 1.0), ("offset", p.offset, p.offset != 0.0),
        ("unit", p.unit, bool(p.unit)), ("si_unit", p.si_unit, bool(p.unit) or p.si_unit != "1"),
        ("word_order", p.word_order, p.word_order != dmap.word_order),
        ("range", list(p.range or ()), p.range is not None),
        ("on_bad", p.on_bad, p.on_bad != "exception"),
        ("enum", {v: label for v, label in p.enum}, bool(p.enum)),
        ("default", p.default, p.default is not None),
        ("release_value", p.release_value, p.release_value is not None),
        ("signal", p.signal, p.signal is not None), ("command", p.command, p.command is not None),
        ("state", p.state, p.state is not None), ("const", p.const, p.const is not None),
        ("invalid", p.invalid, p.invalid is not None and p.invalid != invalid.get(p.type)),
        ("ref", p.ref, True), ("desc", p.desc, bool(p.desc)),
    ]
    fields += [(k, v) for k, v, keep in optional if keep]
    text = ", ".join(f"{k} = {_val(v)}" for k, v in fields)
    if p.co_index is not None:
        text += f", co_index = {p.co_index:#06x}" + (f", co_sub = {p.co_sub}" if p.co_sub is not None else "")
    if p.pdo:
        text += f", pdo = {_val(p.pdo)}"
    return "  { " + text + " },"


def to_toml(dmap: DeviceMap, source: str = "") -> str:
    """The map as TOML: the sections of devices/README.md, one inline table per point."""
    ident, co, fault = dmap.identity, dmap.canopen, dmap.fault
    lines = [f"# {dmap.vendor} {dmap.model}" + (f", imported from {source}" if source else "") + ".", ""]

    def section(name: str, pairs: list[tuple[str, object]]) -> None:
        lines.append(f"[{name}]")
        lines.extend(f"{k} = {v if isinstance(v, _Raw) else _val(v)}" for k, v in pairs)
        lines.append("")

    section("device", [("id", dmap.id), ("kind", dmap.kind), ("house", dmap.house),
                       ("vendor", dmap.vendor), ("model", dmap.model), ("style", dmap.style),
                       ("imitates", dmap.imitates), ("map_version", dmap.map_version)])
    section("device.identity", [("vendor", ident.vendor), ("product", ident.product),
                                ("serial", ident.serial), ("firmware", ident.firmware),
                                ("product_code", ident.product_code), ("revision", ident.revision)])
    section("modbus", [("unit_id", dmap.unit_id), ("functions", sorted(dmap.functions)),
                       ("doc_offset", dmap.doc_offset), ("doc_prefix", dmap.doc_prefix),
                       ("word_order", dmap.word_order),
                       *((f"invalid_{t}", v) for t, v in dmap.invalid)])
    section("canopen", [("node_id", _Raw(f"{co.node_id:#04x}")),
                        ("device_type", _Raw(f"{co.device_type:#010x}")),
                        ("heartbeat_ms", co.heartbeat_ms)])
    if dmap.watchdog:
        section("watchdog", [("timeout_s", dmap.watchdog.timeout_s),
                             ("refresh_on", list(dmap.watchdog.refresh_on)),
                             ("on_expire", dmap.watchdog.on_expire)])
    section("status", [("bits", {b: s for b, s in dmap.status_bits})])
    pairs: list[tuple[str, object]] = [("codes", {c: t for c, t in fault.codes}),
                                       ("trip_code", fault.trip_code), ("sensor_code", fault.sensor_code)]
    if fault.reset_point:
        pairs.append(("reset_point", fault.reset_point))
    if fault.trip_forces:
        pairs.append(("trip_forces", dict(fault.trip_forces)))
    section("fault", pairs)
    lines += ["[map]", "points = ["] + [_point(dmap, p) for p in dmap.points] + ["]"]
    return "\n".join(lines) + "\n"


class _Raw(str):
    """Text written as is (hex numbers)."""
