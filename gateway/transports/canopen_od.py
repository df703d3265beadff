"""The CANopen object dictionary and EDS (CiA 306) of a device, built from its DeviceMap.

`build_object_dictionary(dmap)` generates 0x1000/0x1001/0x1003/0x1008-0x100A/0x1014/0x1017/0x1018/
0x1200, four RPDOs and four TPDOs (0x1400/0x1600/0x1800/0x1A00) with the pre-defined connection set,
and the map's points in the manufacturer area (their `co_index`/`co_sub`, device-interfaces §2.7).
`export_eds` writes it with canopen's exporter.

Kept apart from `canopen_node` because it is built once from the map and needs no bus: the EDS
export, tests and masters use it without the node runtime.
"""
from __future__ import annotations

import zlib

import canopen
from canopen.objectdictionary import ODArray, ODRecord, ODVariable, ObjectDictionary, datatypes as dt

from gateway.maps import codec
from gateway.maps.model import DeviceMap, Point
from plant.errors import DeviceMapError

CO_TYPE = {"bool": dt.BOOLEAN, "uint16": dt.UNSIGNED16, "int16": dt.INTEGER16, "bits16": dt.UNSIGNED16,
           "uint32": dt.UNSIGNED32, "int32": dt.INTEGER32, "float32": dt.REAL32, "string": dt.VISIBLE_STRING}
ACCESS = {"R": "ro", "RW": "rw", "W": "wo"}
#: Record names of the manufacturer area (device-interfaces §2.7); PDO variables read "group.point".
AREA_NAMES = {0x2000: "status", 0x2100: "measurements", 0x2200: "commands", 0x2300: "counters",
              0x2400: "parameters", 0x2F00: "gateway"}
N_PDO, DEFAULT_TPDO_EVENT_MS = 4, 1000
PDO_INVALID = 1 << 31


# ---------------------------------------------------------------------------- object dictionary
def _var(od_parent, name: str, index: int, sub: int, dtype: int, access: str, default=None,
         mappable: bool = False, description: str = "") -> ODVariable:
    var = ODVariable(name, index, sub)
    var.data_type, var.access_type, var.default = dtype, access, default
    var.pdo_mappable, var.description = mappable, description
    od_parent.add_member(var) if isinstance(od_parent, (ODRecord, ODArray)) else od_parent.add_object(var)
    return var


def _record(od: ObjectDictionary, name: str, index: int, subs: list[tuple], array: bool = False):
    """A RECORD/ARRAY whose sub 0 holds the highest sub-index; subs = (sub, name, type, access, default)."""
    rec = (ODArray if array else ODRecord)(name, index)
    _var(rec, "Highest sub-index supported", index, 0, dt.UNSIGNED8,
         "rw" if index in range(0x1600, 0x1800) or index in range(0x1A00, 0x1C00) else "const",
         max(s[0] for s in subs))
    for sub, sub_name, dtype, access, default in subs:
        _var(rec, sub_name, index, sub, dtype, access, default)
    od.add_object(rec)
    return rec


def _point_var(parent, p: Point, index: int, sub: int) -> None:
    # One line, no ';' (an inline comment in EDS): unit, scale and provenance for the reader.
    notes = [p.desc, f"unit {p.unit or '1'}", f"scale {p.scale:g}"]
    if p.offset:
        notes.append(f"offset {p.offset:g}")
    notes.append(f"ref {p.ref}")
    mappable = p.type != "string" and (p.pdo is not None or p.table == "input" or p.command is not None)
    var = _var(parent, p.name, index, sub, CO_TYPE[p.type], ACCESS[p.access],
               mappable=mappable,
               description=", ".join(n for n in notes if n).replace(";", ",").replace("\n", " "))
    var.unit, var.factor = p.unit, p.scale
    if p.type in ("uint16", "int16", "uint32", "int32", "bits16") and p.range is not None:
        var.min, var.max = (int(codec.to_raw(p, v)) for v in p.range)
    if isinstance(p.default, (int, float)) and p.type != "string":
        var.default = codec.to_raw(p, float(p.default))


def point_objects(dmap: DeviceMap) -> dict[tuple[int, int], Point]:
    """(index, sub-index) of every point that has a CANopen object."""
    return {(p.co_index, p.co_sub or 0): p for p in dmap.points if p.co_index is not None}


def build_object_dictionary(dmap: DeviceMap) -> ObjectDictionary:
    """The CiA 301 object dictionary of one device, generated from its map."""
    co, ident, node_id = dmap.canopen, dmap.identity, dmap.canopen.node_id
    od = ObjectDictionary()
    od.node_id = node_id
    od.comments = (f"Generated from devices/{dmap.id}.toml (map {dmap.map_version}) by the CoSES twin\n"
                   f"Style: {dmap.style}".replace(";", ","))
    info = od.device_information
    info.vendor_name, info.product_name = ident.vendor, ident.product
    info.product_number, info.revision_number = ident.product_code, ident.revision
    info.nr_of_RXPDO = info.nr_of_TXPDO = N_PDO
    info.allowed_baudrates = {125_000, 250_000, 500_000}
    _var(od, "Device type", 0x1000, 0, dt.UNSIGNED32, "ro", co.device_type)
    _var(od, "Error register", 0x1001, 0, dt.UNSIGNED8, "ro", 0)
    history = [(i, f"Standard error field {i}", dt.UNSIGNED32, "ro", 0) for i in range(1, 9)]
    _record(od, "Pre-defined error field", 0x1003, history, array=True)["Highest sub-index supported"].access_type = "rw"
    _var(od, "Manufacturer device name", 0x1008, 0, dt.VISIBLE_STRING, "const", ident.product or dmap.model)
    _var(od, "Manufacturer hardware version", 0x1009, 0, dt.VISIBLE_STRING, "const", dmap.map_version)
    _var(od, "Manufacturer software version", 0x100A, 0, dt.VISIBLE_STRING, "const", ident.firmware or "0")
    _var(od, "COB-ID EMCY", 0x1014, 0, dt.UNSIGNED32, "ro", 0x80 + node_id)
    _var(od, "Producer heartbeat time", 0x1017, 0, dt.UNSIGNED16, "rw", co.heartbeat_ms)
    serial = int(ident.serial) if ident.serial.isdigit() and int(ident.serial) < 2**32 \
        else zlib.crc32(ident.serial.encode())
    _record(od, "Identity object", 0x1018, [
        (1, "Vendor-ID", dt.UNSIGNED32, "ro", 0), (2, "Product code", dt.UNSIGNED32, "ro", ident.product_code),
        (3, "Revision number", dt.UNSIGNED32, "ro", ident.revision), (4, "Serial number", dt.UNSIGNED32, "ro", serial)])
    _record(od, "SDO server parameter", 0x1200, [
        (1, "COB-ID client to server", dt.UNSIGNED32, "ro", 0x600 + node_id),
        (2, "COB-ID server to client", dt.UNSIGNED32, "ro", 0x580 + node_id)])
    deadline_ms = int(dmap.watchdog.timeout_s * 1000) if dmap.watchdog else 0
    for n in range(N_PDO):
        for kind, comm, mapping, base in (("R", 0x1400, 0x1600, 0x200), ("T", 0x1800, 0x1A00, 0x180)):
            mapped = [p for p in dmap.points if p.pdo == f"{kind}{n + 1}" and p.co_index is not None]
            entries = [(p.co_index << 16) | ((p.co_sub or 0) << 8) | pdo_bits(p) for p in mapped]
            if sum(pdo_bits(p) for p in mapped) > 64:
                raise DeviceMapError(f"{dmap.path} [point {mapped[-1].name}] pdo = '{kind}{n + 1}': "
                                     f"{sum(pdo_bits(p) for p in mapped)} bits mapped; one CAN frame "
                                     "holds 64; move points to another PDO")
            cob_id = base + 0x100 * n + node_id | (0 if entries else PDO_INVALID)
            # The RPDO event timer is the deadline monitor; UNSIGNED16 ms cannot hold a longer watchdog.
            event = DEFAULT_TPDO_EVENT_MS if kind == "T" else (deadline_ms if deadline_ms <= 0xFFFF else 0)
            _record(od, f"{kind}PDO{n + 1} communication parameter", comm + n, [
                (1, "COB-ID", dt.UNSIGNED32, "rw", cob_id), (2, "Transmission type", dt.UNSIGNED8, "rw", 0xFE),
                (3, "Inhibit time", dt.UNSIGNED16, "rw", 0), (5, "Event timer", dt.UNSIGNED16, "rw", event)])
            rec = _record(od, f"{kind}PDO{n + 1} mapping parameter", mapping + n, [
                (i, f"Mapped object {i}", dt.UNSIGNED32, "rw", entries[i - 1] if i <= len(entries) else 0)
                for i in range(1, 9)])
            rec[0].default = len(entries)
    groups: dict[int, list[tuple[int, Point]]] = {}
    for (index, sub), p in point_objects(dmap).items():
        groups.setdefault(index, []).append((sub, p))
    for index, members in sorted(groups.items()):
        if len(members) == 1 and members[0][0] == 0:
            _point_var(od, members[0][1], index, 0)
            continue
        rec = ODRecord(AREA_NAMES.get(index, f"objects_{index:04X}"), index)
        _var(rec, "Highest sub-index supported", index, 0, dt.UNSIGNED8, "const", max(s for s, _ in members))
        for sub, p in sorted(members, key=lambda m: m[0]):
            _point_var(rec, p, index, sub)
        od.add_object(rec)
    return od


def pdo_bits(p: Point) -> int:
    """Bits a point takes in a PDO (its CANopen type's size)."""
    return 8 if p.type == "bool" else 32 if p.type in ("uint32", "int32", "float32") else 16


def export_eds(dmap: DeviceMap, dest) -> None:
    """Write the device's EDS (CiA 306) to a path or text stream."""
    canopen.objectdictionary.export_od(build_object_dictionary(dmap), dest, "eds")
