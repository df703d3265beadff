"""Register tables of a map as CSV or Markdown: one row per point, wire address and printed number.

The CSV form is complete: a block of device rows (`section.key,value[,value...]`, the TOML sections
flattened), a blank row, then the register table. gateway.maps.csv_table reads it back into the
same map; devices/README.md describes it for spreadsheet users.
"""
from __future__ import annotations

import csv
import io

from gateway.maps.model import DeviceMap, Point

COLUMNS = ("table", "address", "printed", "name", "type", "words", "access", "scale", "offset",
           "unit", "si_unit", "range", "on_bad", "default", "release_value", "enum", "binding",
           "invalid", "word_order", "canopen", "pdo", "ref", "desc")
#: Written for reading only; on import a filled cell must agree with the point.
DERIVED = ("printed", "words")
FUNCTIONS = {"coil": "1/5/15", "discrete": "2", "input": "4", "holding": "3/6/16"}
BINDINGS = {"signal": "reads", "command": "drives", "state": "gateway", "const": "const"}
RANGE_SEP = "…"


def number(x: float | int) -> str:
    """Shortest text that reads back as the same number (0.1, 100.0 stays 100.0 for floats)."""
    if isinstance(x, int) and not isinstance(x, bool):
        return str(x)
    short = f"{x:g}"
    return short if float(short) == x and "e" not in short else repr(float(x))


def value(x: float | int | str | None) -> str:
    """A default/const cell: the TOML value as text (ints stay ints, floats keep their point)."""
    if x is None:
        return ""
    return repr(x) if isinstance(x, float) else str(x)


def rows(dmap: DeviceMap, map_order: bool = False) -> list[dict[str, str]]:
    """Table rows in address order per table (or the map's own order, which fixes PDO layouts)."""
    order = {"coil": 0, "discrete": 1, "input": 2, "holding": 3}
    invalid = dict(dmap.invalid)
    out = []
    points = dmap.points if map_order else sorted(dmap.points, key=lambda q: (order[q.table], q.address))
    for p in points:
        out.append({
            "table": p.table, "address": str(p.address), "printed": dmap.printed_address(p),
            "name": p.name, "type": p.type + (f"[{p.length}]" if p.type == "string" else ""),
            "words": str(p.words), "access": p.access, "scale": number(p.scale),
            "offset": number(p.offset), "unit": p.unit,
            "si_unit": "" if p.unit == "" and p.si_unit == "1" else p.si_unit,
            "range": f"{number(p.range[0])}{RANGE_SEP}{number(p.range[1])}" if p.range else "",
            "on_bad": "" if p.on_bad == "exception" else p.on_bad,
            "default": value(p.default), "release_value": value(p.release_value),
            "enum": "; ".join(f"{v}={label}" for v, label in p.enum),
            "binding": _binding(p),
            "invalid": "" if p.invalid == invalid.get(p.type) else value(p.invalid),
            "word_order": "" if p.word_order == dmap.word_order else p.word_order,
            "canopen": (f"{p.co_index:#06x}" + ("" if p.co_sub is None else f".{p.co_sub}")
                        if p.co_index is not None else ""),
            "pdo": p.pdo or "", "ref": p.ref, "desc": p.desc,
        })
    return out


def _binding(p: Point) -> str:
    for field, word in BINDINGS.items():
        if getattr(p, field) is not None:
            return f"{word} {value(getattr(p, field))}"
    return ""


def device_rows(dmap: DeviceMap) -> list[list[str]]:
    """The device block: one row per TOML key, `section.key` then its value(s)."""
    ident, co, fault = dmap.identity, dmap.canopen, dmap.fault
    out = [
        ["device.id", dmap.id], ["device.kind", dmap.kind], ["device.house", dmap.house],
        ["device.vendor", dmap.vendor], ["device.model", dmap.model], ["device.style", dmap.style],
        ["device.imitates", dmap.imitates], ["device.map_version", dmap.map_version],
        ["device.identity.vendor", ident.vendor], ["device.identity.product", ident.product],
        ["device.identity.serial", ident.serial], ["device.identity.firmware", ident.firmware],
        ["device.identity.product_code", str(ident.product_code)],
        ["device.identity.revision", str(ident.revision)],
        ["modbus.unit_id", str(dmap.unit_id)],
        ["modbus.functions", *(str(f) for f in sorted(dmap.functions))],
        ["modbus.doc_offset", str(dmap.doc_offset)], ["modbus.doc_prefix", dmap.doc_prefix],
        ["modbus.word_order", dmap.word_order],
        *([f"modbus.invalid_{t}", str(v)] for t, v in dmap.invalid),
        ["canopen.node_id", f"{co.node_id:#04x}"], ["canopen.device_type", f"{co.device_type:#010x}"],
        ["canopen.heartbeat_ms", str(co.heartbeat_ms)],
    ]
    if dmap.watchdog:
        out += [["watchdog.timeout_s", number(dmap.watchdog.timeout_s)],
                ["watchdog.refresh_on", *dmap.watchdog.refresh_on],
                ["watchdog.on_expire", dmap.watchdog.on_expire]]
    out += [[f"status.bits.{bit}", source] for bit, source in dmap.status_bits]
    out += [[f"fault.codes.{code}", text] for code, text in fault.codes]
    out += [["fault.trip_code", str(fault.trip_code)], ["fault.sensor_code", str(fault.sensor_code)]]
    if fault.reset_point:
        out.append(["fault.reset_point", fault.reset_point])
    out += [[f"fault.trip_forces.{cmd}", number(v)] for cmd, v in fault.trip_forces]
    return out


def to_csv(dmap: DeviceMap) -> str:
    """The complete map as one CSV file: device block, blank row, register table in map order."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerows(device_rows(dmap))
    writer.writerow([])
    table = csv.DictWriter(buf, fieldnames=COLUMNS, lineterminator="\n")
    table.writeheader()
    table.writerows(rows(dmap, map_order=True))
    return buf.getvalue()


def to_markdown(dmap: DeviceMap) -> str:
    cols = ("table", "address", "printed", "name", "type", "scale", "unit", "access", "range",
            "binding", "canopen", "ref")
    lines = [
        f"# {dmap.id}: {dmap.model} (Modbus unit {dmap.unit_id}, CANopen node {dmap.canopen.node_id})",
        "",
        f"Style: {dmap.style}. Imitates: {dmap.imitates}.",
        f"Addresses are 0-based wire addresses; 'printed' is the manual's number. Function codes: "
        f"{', '.join(str(f) for f in sorted(dmap.functions))}.",
        "",
        "| " + " | ".join(cols) + " |",
        "|" + "---|" * len(cols),
    ]
    for row in rows(dmap):
        lines.append("| " + " | ".join(row[c].replace("|", "\\|") for c in cols) + " |")
    return "\n".join(lines) + "\n"
