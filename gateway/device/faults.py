"""Injected faults of one device: sensor faults, a latched generator trip, and link faults.

The Device consults FaultState for what it serves; transports consult `link` for how they answer
(silent, late, dropped connection, corrupted CRC). Injection happens through Device methods so
every fault is reported as an event.
"""
from __future__ import annotations

from dataclasses import dataclass, field

LINK_MODES = ("none", "silent", "late", "drop", "bad_crc")
SENSOR_KINDS = ("open", "drift")


@dataclass(frozen=True)
class LinkFault:
    """How transports must (mis)behave for this device.

    silent: read the request, send nothing; late: answer after `delay_s`; drop: close the
    connection (TCP) / discard the frame (RTU); bad_crc: corrupt the RTU CRC of every answer.
    """

    mode: str = "none"
    delay_s: float = 0.0

    def __post_init__(self) -> None:
        if self.mode not in LINK_MODES:
            raise ValueError(f"link fault {self.mode!r}: must be one of {', '.join(LINK_MODES)}")


@dataclass
class FaultState:
    """Mutable fault flags of one device (guarded by the device's lock)."""

    sensors: dict[str, tuple[str, float]] = field(default_factory=dict)  # point -> (kind, delta)
    trip_code: int = 0
    link: LinkFault = field(default_factory=LinkFault)

    @property
    def tripped(self) -> bool:
        return self.trip_code != 0

    @property
    def sensor_fault(self) -> bool:
        return any(kind == "open" for kind, _ in self.sensors.values())
