"""The one codec: plant value (SI) ↔ device value (the map's unit) ↔ raw value ↔ 16-bit registers.

Units convert through the one unit table, plant/units.py (volume flows as water, plant/water.py).

Raw values are what a point's type holds on the wire: int for integer types, float for float32,
bool for coils, str for strings. Integer raws saturate at the type limits, because a real device
clips or reports invalid, it never wraps around.
"""
from __future__ import annotations

import math
import struct
from functools import cache

from gateway.maps.model import Point
from plant.errors import ConfigError
from plant.units import factors

LIMITS = {
    "uint16": (0, 0xFFFF), "bits16": (0, 0xFFFF), "int16": (-0x8000, 0x7FFF),
    "uint32": (0, 0xFFFFFFFF), "int32": (-0x80000000, 0x7FFFFFFF), "bool": (0, 1),
}


def _factor(point: Point) -> tuple[float, float]:
    """(factor, offset): device = si * factor + offset, from the one unit table (plant/units.py);
    span=True admits the 0-10 V as 0-100 % convention of control inputs."""
    return _unit_factor(point.si_unit, point.unit)


@cache
def _unit_factor(si_unit: str, unit: str) -> tuple[float, float]:
    try:
        return factors(si_unit, unit, span=True)
    except ConfigError:  # not convertible: the value passes as is (the map lint reports it)
        return 1.0, 0.0


def to_device(point: Point, si: float) -> float:
    """Plant value (SI) → device value in the point's unit."""
    factor, offset = _factor(point)
    return si * factor + offset


def to_si(point: Point, value: float) -> float:
    """Device value in the point's unit → plant value (SI)."""
    factor, offset = _factor(point)
    return (value - offset) / factor


def round_half_away(x: float) -> int:
    return int(math.floor(abs(x) + 0.5)) * (1 if x >= 0 else -1)


def to_raw(point: Point, value: float | str | bool) -> int | float | str | bool:
    """Device value → raw, saturating integers at the type limits (NaN gives the invalid raw)."""
    if point.type == "string":
        return str(value)[: point.length]
    if point.type == "float32":
        return float(value) * 1.0
    if point.type == "bool":
        return bool(value)
    lo, hi = LIMITS[point.type]
    x = (float(value) - point.offset) / point.scale
    if math.isnan(x):
        return point.invalid if point.invalid is not None else hi
    if math.isinf(x):
        return hi if x > 0 else lo
    return min(hi, max(lo, round_half_away(x)))


def from_raw(point: Point, raw: int | float | str | bool) -> float | str:
    """Raw → device value."""
    if point.type == "string":
        return str(raw)
    if point.type in ("float32",):
        return float(raw)
    if point.type == "bool":
        return 1.0 if raw else 0.0
    return float(raw) * point.scale + point.offset


def to_registers(point: Point, raw: int | float | str | bool) -> list[int]:
    """Raw → the point's 16-bit registers in its word order (coils: [0] or [1])."""
    if point.type == "string":
        data = str(raw).encode("ascii", "replace")[: point.words * 2].ljust(point.words * 2, b"\0")
        return [int.from_bytes(data[i:i + 2], "big") for i in range(0, len(data), 2)]
    if point.type == "bool":
        return [1 if raw else 0]
    if point.type == "float32":
        data = struct.pack(">f", float(raw))
    elif point.words == 2:
        data = int(raw).to_bytes(4, "big", signed=point.type == "int32")
    else:
        return [int(raw) & 0xFFFF]
    words = [int.from_bytes(data[0:2], "big"), int.from_bytes(data[2:4], "big")]
    return words if point.word_order == "hi_lo" else words[::-1]


def from_registers(point: Point, words: list[int]) -> int | float | str | bool:
    """The point's registers (in its word order) → raw."""
    if point.type == "string":
        data = b"".join(w.to_bytes(2, "big") for w in words)
        return data.rstrip(b"\0").decode("ascii", "replace")
    if point.type == "bool":
        return bool(words[0])
    if point.words == 1:
        w = words[0] & 0xFFFF
        return w - 0x10000 if point.type == "int16" and w & 0x8000 else w
    hi, lo = (words[0], words[1]) if point.word_order == "hi_lo" else (words[1], words[0])
    data = hi.to_bytes(2, "big") + lo.to_bytes(2, "big")
    if point.type == "float32":
        return struct.unpack(">f", data)[0]
    return int.from_bytes(data, "big", signed=point.type == "int32")


def encode(point: Point, si: float) -> list[int]:
    """Plant value (SI) straight to registers."""
    return to_registers(point, to_raw(point, to_device(point, si)))


def decode(point: Point, words: list[int]) -> float | str:
    """Registers straight to plant value (SI); strings come back as text."""
    value = from_raw(point, from_registers(point, words))
    return value if isinstance(value, str) else to_si(point, value)
