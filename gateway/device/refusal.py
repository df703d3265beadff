"""Refusal: why a device did not accept a request, and the one table mapping reasons to bus codes.

Every transport answers a refused request through REASONS, so Modbus and CANopen report the same
situation consistently (device-interfaces §2.5). Modbus codes: 01 illegal function, 02 illegal
data address, 03 illegal data value, 04 server device failure, 06 server device busy.
"""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Reason:
    """Bus answers for one refusal reason. `modbus` None means: send no reply at all."""

    modbus: int | None
    sdo_abort: int
    meaning: str


#: The single reason → (Modbus exception, SDO abort code) table.
REASONS: dict[str, Reason] = {
    "function": Reason(0x01, 0x05040001, "function code not supported by this device"),
    "address": Reason(0x02, 0x06020000, "address or object not mapped"),
    "subindex": Reason(0x02, 0x06090011, "sub-index does not exist"),
    "read_only": Reason(0x02, 0x06010002, "write to a read-only point"),
    "write_only": Reason(0x02, 0x06010001, "read of a write-only point"),
    "length": Reason(0x03, 0x06070010, "quantity or byte count out of range / type length mismatch"),
    "partial": Reason(0x02, 0x06070010, "write covers only part of a multi-register point"),
    "range": Reason(0x03, 0x06090030, "value outside the point's range or enumeration"),
    "too_high": Reason(0x03, 0x06090031, "value above the point's range"),
    "too_low": Reason(0x03, 0x06090032, "value below the point's range"),
    "locked": Reason(0x01, 0x08000021, "gateway is read-only (local control)"),
    "client": Reason(None, 0x08000021, "client not in the allow-list"),
    "state": Reason(0x06, 0x08000022, "device state forbids it (fault lockout)"),
    "failure": Reason(0x04, 0x08000020, "injected internal failure"),
}


@dataclass(frozen=True)
class Refusal:
    """A refused request as a value: `reason` is a key of REASONS, `detail` says what exactly."""

    reason: str
    detail: str = ""

    def __post_init__(self) -> None:
        if self.reason not in REASONS:
            raise ValueError(f"refusal reason {self.reason!r}: must be one of {', '.join(REASONS)}")

    @property
    def modbus_code(self) -> int | None:
        return REASONS[self.reason].modbus

    @property
    def sdo_abort(self) -> int:
        return REASONS[self.reason].sdo_abort

    def __str__(self) -> str:
        return f"{self.reason}: {self.detail or REASONS[self.reason].meaning}"
