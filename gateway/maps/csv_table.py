"""A device map read from a CSV register table, the form `twin devices export-table --format csv` writes.

The file is the device block (rows `section.key,value[,value...]`, the TOML keys flattened), then
the register table: a header row naming its columns (gateway.maps.export.COLUMNS, any order) and
one row per point. This module turns cells into the TOML document shape and hands it to
gateway.maps.model.build_map, so a CSV map passes the same checks as a TOML map. Every problem,
cell syntax included, is reported at once as one DeviceMapError, each line
'<file>:<line> [point NAME] column "<column>": <what is wrong>; <fix>'.
"""
from __future__ import annotations

import csv
import re
from pathlib import Path
from typing import Any

from gateway.maps.export import BINDINGS, COLUMNS, DERIVED, RANGE_SEP
from gateway.maps.model import TYPES, WORDS, DeviceMap, build_map
from plant.errors import DeviceMapError, closest

#: Device-block keys and how their cells read: one value (str/int/float) or several (ints/strs).
KEYS = {
    "device.id": "str", "device.kind": "str", "device.house": "str", "device.vendor": "str",
    "device.model": "str", "device.style": "str", "device.imitates": "str",
    "device.map_version": "str", "device.identity.vendor": "str", "device.identity.product": "str",
    "device.identity.serial": "str", "device.identity.firmware": "str",
    "device.identity.product_code": "int", "device.identity.revision": "int",
    "modbus.unit_id": "int", "modbus.functions": "ints", "modbus.doc_offset": "int",
    "modbus.doc_prefix": "str", "modbus.word_order": "str",
    "canopen.node_id": "int", "canopen.device_type": "int", "canopen.heartbeat_ms": "int",
    "watchdog.timeout_s": "float", "watchdog.refresh_on": "strs", "watchdog.on_expire": "str",
    "fault.trip_code": "int", "fault.sensor_code": "int", "fault.reset_point": "str",
}
#: Keyed families: prefix -> (how the value reads, what the rest of the key must be).
FAMILIES = {
    "modbus.invalid_": ("int", "type"), "status.bits.": ("str", "int"),
    "fault.codes.": ("str", "int"), "fault.trip_forces.": ("float", "name"),
}
REQUIRED = ("table", "address", "name", "type", "binding", "ref")
HOW = {
    "int": "a whole number like 5 (or hex like 0x15)", "float": "a decimal like 0.1",
    "ints": "whole numbers, one per cell", "strs": "names, one per cell", "str": "text",
}
_TYPE = re.compile(r"^(\w+)(?:\[(\d+)\])?$")


def load_csv(path: str | Path) -> DeviceMap:
    """Load and check one CSV register table; raise one DeviceMapError listing every problem."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")     # spreadsheets often write a BOM
    except (OSError, UnicodeDecodeError) as exc:
        raise DeviceMapError(f"{path}: cannot read register table ({exc}); save it as UTF-8 CSV") from exc
    first = next((line for line in text.splitlines() if line.strip()), "")
    delimiter = ";" if first.count(";") > first.count(",") else ","
    reader = csv.reader(text.splitlines(keepends=True), delimiter=delimiter)
    problems: list[str] = []
    doc: dict[str, Any] = {"point": []}
    key_lines: dict[str, int] = {}
    lines: list[int] = []
    derived: list[dict[str, str]] = []
    clean: list[bool] = []
    header: list[str] | None = None
    end = 0
    for cells in reader:
        line, end = end + 1, reader.line_num
        cells = [c.strip() for c in cells]
        while cells and not cells[-1]:
            cells.pop()
        if not cells:
            continue
        if header is None and "." in cells[0] and " " not in cells[0]:
            _device_row(path, line, cells, doc, key_lines, problems)
        elif header is None:
            header = _header(path, line, cells, problems)
            if header is None:
                break
        else:
            row = dict(zip(header, cells))
            before = len(problems)
            doc["point"].append(_row(f"{path}:{line}", row, len(cells) - len(header), problems))
            # a row with a bad cell got neutral stand-ins; its derived cells are not compared
            derived.append({c: row[c] for c in DERIVED if row.get(c)} if len(problems) == before else {})
            clean.append(len(problems) == before)
            lines.append(line)
    if header is None:
        if not problems:
            problems.append(f"{path}: no register table; after the device rows and a blank row, add "
                            f"a header row ({', '.join(REQUIRED)}, ...) and one row per point")
        raise DeviceMapError("\n".join(problems))
    _duplicates(path, [r for r, ok in zip(doc["point"], clean) if ok],
                [n for n, ok in zip(lines, clean) if ok], problems)

    def locate(section: str, key: str) -> str:
        line = key_lines.get(f"{section}.{key}")
        return f"{path}:{line} [{section}]" if line else f"{path} [{section}]"

    try:
        dmap = build_map(path, doc, problems, locate, [f"{path}:{n}" for n in lines])
    except (KeyError, TypeError, ValueError) as exc:
        problems.append(f"{path}: malformed entry ({exc!r}); see devices/README.md for the columns")
        raise DeviceMapError("\n".join(problems)) from exc
    for p, cells, line in zip(dmap.points, derived, lines):
        if p.type not in TYPES:
            continue                                   # reported above; it has no word count
        for column, actual in (("printed", dmap.printed_address(p)), ("words", str(p.words))):
            if cells.get(column, actual) != actual:
                problems.append(f'{path}:{line} [point {p.name}] column "{column}": "{cells[column]}" '
                                f"but the point gives {actual}; change address or type instead, or "
                                "clear the cell")
    if problems:
        raise DeviceMapError("\n".join(problems))
    return dmap


def _device_row(path: Path, line: int, cells: list[str], doc: dict, key_lines: dict[str, int],
                problems: list[str]) -> None:
    key, values = cells[0], cells[1:]
    where = f"{path}:{line} {key}"
    family = next((f for f in FAMILIES if key.startswith(f) and len(key) > len(f)), None)
    if key not in KEYS and family is None:
        known = list(KEYS) + [f + "..." for f in FAMILIES]
        close = closest(key, known, n=2)
        problems.append(f"{where}: unknown device key; closest: {', '.join(close) or 'none'} "
                        "(the keys are listed in devices/README.md)")
        return
    if key in key_lines:
        problems.append(f"{where}: also on line {key_lines[key]}; keep one row per key")
        return
    key_lines[key] = line
    kind = KEYS[key] if family is None else FAMILIES[family][0]
    if family:
        rest = key[len(family):]
        must = FAMILIES[family][1]
        if must == "int" and not re.fullmatch(r"\d+", rest):
            problems.append(f"{where}: {rest!r} is not a number; write e.g. {family}0")
            return
        if must == "type" and rest not in TYPES:
            close = closest(rest, TYPES, n=1)
            problems.append(f"{where}: {rest!r} is not a point type; use one of {', '.join(TYPES)}"
                            + (f" (closest: {close[0]})" if close else ""))
            return
    if kind not in ("ints", "strs") and len(values) > 1:
        problems.append(f"{where}: {len(values)} values; this key takes one, in the second cell")
        return
    if kind in ("ints", "strs"):
        parsed = [_parse(v, kind[:-1]) for v in values]
        bad = [v for v, p in zip(values, parsed) if p is None]
        if bad:
            problems.append(f'{where}: "{bad[0]}" is not a whole number; write {HOW[kind]}')
        value: Any = [p for p in parsed if p is not None]
    elif not values:
        if kind != "str":
            return                                     # empty number = the default
        value = ""
    else:
        value = _parse(values[0], kind)
        if value is None:
            problems.append(f'{where}: "{values[0]}" is not a number; write {HOW[kind]}')
            value = 1                                  # a stand-in every numeric key accepts
    if family and family.endswith("."):          # status.bits.3 -> [status] bits = { 3 = ... }
        section, name = family[:-1], key[len(family):]
    elif family:                                 # modbus.invalid_int16 -> [modbus] invalid_int16
        section, name = key.split(".", 1)
    else:                                        # device.identity.vendor -> [device.identity] vendor
        section, _, name = key.rpartition(".")
    node = doc
    for part in section.split("."):
        node = node.setdefault(part, {})
    node[name] = value


def _header(path: Path, line: int, cells: list[str], problems: list[str]) -> list[str] | None:
    where = f"{path}:{line} register table header"
    for i, name in enumerate(cells):
        if name not in COLUMNS:
            close = closest(name, COLUMNS, n=2)
            problems.append(f'{where} column "{name}": unknown column; rename it to a known one '
                            f"(closest: {', '.join(close) or 'none'}) or delete it")
        elif name in cells[:i]:
            problems.append(f'{where} column "{name}": appears twice; keep one')
    missing = [c for c in REQUIRED if c not in cells]
    if missing:
        problems.append(f"{where}: missing column(s) {', '.join(missing)}; add them "
                        f"(required: {', '.join(REQUIRED)})")
        return None
    return cells


def _row(at: str, row: dict[str, str], extra: int, problems: list[str]) -> dict:
    """One table row as a TOML point; a bad cell is reported and replaced by a neutral stand-in
    (required ones) or left out (optional ones), so the row's other problems are still found."""
    raw: dict[str, Any] = {}
    where = at + (f" [point {row['name']}]" if row.get("name") else "")
    if extra > 0:
        problems.append(f"{where}: {extra} cell(s) beyond the header's columns; remove them or "
                        "name their column")

    def bad(column: str, text: str) -> None:
        problems.append(f'{where} column "{column}": "{row[column]}" {text}')

    for column, cell in row.items():
        if not cell or column not in COLUMNS or column in DERIVED:
            continue
        if column in ("table", "name", "access", "unit", "si_unit", "on_bad", "word_order", "pdo",
                      "ref", "desc"):
            raw[column] = cell
        elif column == "type":
            m = _TYPE.match(cell)
            if not m:
                bad(column, "is not a type; write e.g. int16, or string[16] for 16 characters")
                raw["type"] = "bool" if row.get("table") in ("coil", "discrete") else "uint16"
                continue
            raw["type"] = m.group(1)
            if m.group(2):
                raw["length"] = int(m.group(2))
        elif column in ("address", "invalid"):
            if (v := _parse(cell, "int")) is None:
                bad(column, "is not a whole number; write " + ("the 0-based wire address, e.g. 12"
                            if column == "address" else "the raw value served, e.g. -32768"))
                raw[column] = 0
            else:
                raw[column] = v
        elif column in ("scale", "offset", "release_value"):
            if (v := _parse(cell, "number")) is None:
                bad(column, "is not a number; write a decimal like 0.1")
            else:
                raw[column] = v
        elif column == "default":
            raw[column] = _scalar(cell)
        elif column == "range":
            parts = re.split(rf"\s*(?:{RANGE_SEP}|\.\.)\s*", cell)
            nums = [_parse(p, "float") for p in parts]
            if len(nums) != 2 or None in nums:
                bad(column, f"is not low{RANGE_SEP}high; write e.g. 0{RANGE_SEP}100 (or 0..100)")
            else:
                raw["range"] = nums
        elif column == "enum":
            items = [i.strip().partition("=") for i in cell.split(";") if i.strip()]
            if any(not sep or _parse(v.strip(), "int") is None for v, sep, _ in items):
                bad(column, "is not value=label pairs; write e.g. 0=off; 1=on")
            else:
                raw["enum"] = {str(_parse(v.strip(), "int")): label.strip() for v, _, label in items}
        elif column == "binding":
            word, _, rest = cell.partition(" ")
            field = next((f for f, w in BINDINGS.items() if w == word), None)
            if field is None or not rest.strip():
                close = closest(word, list(BINDINGS.values()), n=1)
                bad(column, f"is not '<how> <what>'; <how> is one of {', '.join(BINDINGS.values())}"
                    + (f" (closest: {close[0]})" if close else "") + ", e.g. reads boiler.T_sup")
                raw["const"] = 0
            else:
                raw[field] = _scalar(rest.strip()) if field == "const" else rest.strip()
        elif column == "canopen":
            m = re.fullmatch(r"(0[xX][0-9a-fA-F]+)(?:[.:](\d+))?", cell)
            if not m:
                bad(column, "is not an object; write index.sub in hex, e.g. 0x2100.3")
            else:
                raw["co_index"] = int(m.group(1), 16)
                if m.group(2):
                    raw["co_sub"] = int(m.group(2))
    return raw


def _duplicates(path: Path, raws: list[dict], lines: list[int], problems: list[str]) -> None:
    """Two rows on one address or with one name: a copied spreadsheet row, usually."""
    names: dict[str, int] = {}
    used: dict[tuple[str, int], tuple[int, str]] = {}
    for raw, line in zip(raws, lines):
        name = raw.get("name", "?")
        if name in names:
            problems.append(f'{path}:{line} [point {name}] column "name": also on line {names[name]}; '
                            "point names must be unique")
        names.setdefault(name, line)
        if not isinstance(raw.get("address"), int) or "table" not in raw:
            continue
        words = ((raw.get("length", 0) + 1) // 2 if raw.get("type") == "string"
                 else WORDS.get(raw.get("type", ""), 1))
        for a in range(raw["address"], raw["address"] + max(words, 1)):
            if (raw["table"], a) in used:
                other_line, other = used[(raw["table"], a)]
                problems.append(f'{path}:{line} [point {name}] column "address": {raw["table"]} '
                                f"address {a} is also used by line {other_line} ({other}); "
                                "give each point its own address")
                break
        for a in range(raw["address"], raw["address"] + max(words, 1)):
            used.setdefault((raw["table"], a), (line, name))


def _parse(text: str, kind: str) -> Any:
    """The cell as int, float or number (int if whole-looking); None if it is not one."""
    text = text.strip()
    if kind in ("int", "number"):
        try:
            return int(text, 10)
        except ValueError:
            try:
                return int(text, 0)
            except ValueError:
                if kind == "int":
                    return None
    if kind in ("float", "number"):
        try:
            return float(text)
        except ValueError:
            return None
    return text


def _scalar(text: str) -> int | float | str:
    """A default or const cell: a number when it reads as one, else the text."""
    v = _parse(text, "number")
    return text if v is None else v
