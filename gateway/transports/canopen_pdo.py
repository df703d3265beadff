"""A node's PDOs as its object dictionary configures them (CiA 301, 0x1400-0x1BFF): one PDO's
communication and mapping parameters with its run-time timers (Pdo), and the check of a PDO
remapping written by SDO (mapping_abort). The node (gateway/transports/canopen_node.py) passes
its stored values in; nothing here talks to the bus.
"""
from __future__ import annotations

from collections.abc import Callable
from typing import Any

from gateway.transports.canopen_od import PDO_INVALID

#: SDO abort codes of a remapping that cannot be: too long for a PDO, object not mappable.
ABORT_PDO_LENGTH, ABORT_NOT_MAPPABLE = 0x06040042, 0x06040041


class Pdo:
    """One PDO's configuration as read from 0x14xx-0x1Bxx, plus its run-time timers."""

    def __init__(self, stored: Callable[[int, int], Any], comm: int, mapping: int) -> None:
        cob = stored(comm, 1)
        self.cob_id, self.enabled = cob & 0x7FF, not cob & PDO_INVALID
        self.trans_type, self.event_s = stored(comm, 2), stored(comm, 5) / 1000.0
        self.entries = []
        for i in range(1, stored(mapping, 0) + 1):
            value = stored(mapping, i)
            if value >> 16:
                self.entries.append((value >> 16, (value >> 8) & 0xFF, value & 0xFF))
        self.size = sum(bits for _, _, bits in self.entries) // 8
        self.due = 0.0            # next event-timer transmission (TPDO)
        self.last_rx = None       # last reception (RPDO deadline)
        self.syncs = 0


def mapping_abort(index: int, subindex: int, value: int, stored: Callable[[int, int], Any],
                  find_object: Callable[[int, int], Any]) -> int | None:
    """The SDO abort code for writing `value` to the mapping parameter index/subindex (0x16xx
    receive, 0x1Axx transmit), None when it may be written. `find_object` raises the node's
    abort for an object that does not exist."""
    receive = index < 0x1800
    if subindex == 0:
        entries = [stored(index, i) for i in range(1, min(value, 8) + 1)]
        if value > 8 or sum(e & 0xFF for e in entries) > 64:
            return ABORT_PDO_LENGTH   # mapped objects exceed the PDO length
        return None
    target, sub, bits = value >> 16, (value >> 8) & 0xFF, value & 0xFF
    if target == 0:
        return None
    obj = find_object(target, sub)
    if not obj.pdo_mappable or bits != len(obj) or (obj.writable if receive else obj.readable) is False:
        return ABORT_NOT_MAPPABLE   # object cannot be mapped to the PDO
    return None
