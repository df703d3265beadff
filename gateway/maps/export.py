"""Register tables of a map as CSV or Markdown: one row per point, wire address and printed number."""
from __future__ import annotations

import csv
import io

from gateway.maps.model import DeviceMap, Point

COLUMNS = ("device", "unit_id", "table", "address", "printed", "name", "type", "words", "scale",
           "offset", "unit", "access", "range", "default", "binding", "canopen", "pdo", "ref", "desc")
FUNCTIONS = {"coil": "1/5/15", "discrete": "2", "input": "4", "holding": "3/6/16"}


def rows(dmap: DeviceMap) -> list[dict[str, str]]:
    """Table rows in address order per table; addresses are 0-based wire addresses."""
    order = {"coil": 0, "discrete": 1, "input": 2, "holding": 3}
    out = []
    for p in sorted(dmap.points, key=lambda q: (order[q.table], q.address)):
        out.append({
            "device": dmap.id, "unit_id": str(dmap.unit_id), "table": p.table,
            "address": str(p.address), "printed": dmap.printed_address(p), "name": p.name,
            "type": p.type + (f"[{p.length}]" if p.type == "string" else ""),
            "words": str(p.words), "scale": f"{p.scale:g}", "offset": f"{p.offset:g}",
            "unit": p.unit, "access": p.access,
            "range": f"{p.range[0]:g}…{p.range[1]:g}" if p.range else "",
            "default": "" if p.default is None else str(p.default),
            "binding": _binding(p),
            "canopen": f"{p.co_index:#06x}.{p.co_sub}" if p.co_index is not None else "",
            "pdo": p.pdo or "", "ref": p.ref, "desc": p.desc,
        })
    return out


def _binding(p: Point) -> str:
    if p.signal:
        return f"reads {p.signal}"
    if p.command:
        return f"drives {p.command}"
    if p.state:
        return f"gateway {p.state}"
    return f"const {p.const}"


def to_csv(dmap: DeviceMap) -> str:
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=COLUMNS, lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows(dmap))
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
