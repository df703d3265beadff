"""What a Device answers to Modbus requests, as plain values: the pymodbus-free half of the Modbus
server (gateway/transports/modbus_server.py, the pymodbus adapter, wraps these in its types).

  table_span(device, table)    the address span of a table's mapped points (the simulator's block)
  read_into(...)               a simulator block read: registers filled from the Device, coil and
                               discrete bits packed into the block's 16-bit words
  identification(...)          the FC43/14 device identification objects of a read code

A refused read is returned as the Device's Refusal; the adapter answers its Modbus code.
"""
from __future__ import annotations

from gateway.device.device import Device
from gateway.device.refusal import Refusal
from gateway.maps.model import BIT_TABLES

#: FC43/14 object 3, the vendor URL, is the same for every device.
VENDOR_URL = "https://github.com/ (CoSES house twin)"


def table_span(device: Device, table: str) -> tuple[int, int] | None:
    """(first address, count) spanning the table's mapped points, in bits for the coil and
    discrete tables and in 16-bit words for the register tables; None when nothing is mapped."""
    points = [p for p in device.map.points if p.table == table]
    if not points:
        return None
    lo = min(p.address for p in points)
    if table in BIT_TABLES:
        return lo, max(p.address for p in points) - lo + 1
    return lo, max(p.address + p.words for p in points) - lo


def read_into(device: Device, table: str, start: int, address: int, count: int, registers: list[int],
              bits: int) -> Refusal | None:
    """Fill the block `registers` (first word at `start`) from the Device at `address`: `count`
    words of a register table, or `bits` bits (at least one) of a bit table."""
    if table in BIT_TABLES:
        result = device.read_registers(table, address, max(bits, 1))
        if not isinstance(result, list):
            return result
        for i, bit in enumerate(result):
            reg, pos = divmod(address + i, 16)
            reg -= start
            registers[reg] = (registers[reg] | (1 << pos)) if bit else (registers[reg] & ~(1 << pos))
        return None
    result = device.read_registers(table, address, count)
    if not isinstance(result, list):
        return result
    registers[address - start:address - start + count] = result
    return None


def identification(device: Device, read_code: int, object_id: int) -> dict[int, str] | None:
    """The objects a FC43/14 request reads: read code 1 basic (0-2), 2 and 3 regular (0-6), 4 the
    one object `object_id`; None when that object does not exist (exception 02)."""
    ident = device.map.identity
    objects = {0: ident.vendor, 1: str(ident.product_code), 2: ident.firmware, 3: VENDOR_URL,
               4: ident.product, 5: device.map.model, 6: device.id}
    if read_code == 4:
        if object_id not in objects:
            return None
        return {object_id: objects[object_id]}
    return {k: v for k, v in objects.items() if k < (3 if read_code == 1 else 7)}
